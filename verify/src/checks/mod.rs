//! The checks: each samples seeded random inputs, compares one generated kernel with an
//! independent numeric evaluation, and returns a [`Measurement`] (worst error in a stated norm,
//! worst error / bound). The tests assert `passed()`; the report prints the same numbers.
//!
//! Norms and tolerances (see `reference` for the absolute-value scales):
//!
//! - `TOL_POLY = 1e-12` relative to the absolute-value scale of the compared quantity. Both sides
//!   are straight-line polynomial evaluations of depth <= ~40, whose forward error is at most
//!   `gamma_40 ~ 4.4e-15` times that scale (Higham 3.1); 1e-12 leaves a factor ~200 over this
//!   worst-case first-order bound. It is the right scale, not `|C|`, because `C = |K rbar|^2`
//!   can cancel to ~0 while the rounding of any evaluation stays at `u` times the scale; and it
//!   is tighter than `|M|_F (1 + |s|^2)^2` (e.g. at `s = 0` only the 6 entries `M_ab`,
//!   a, b in {0, 4, 8}, enter it). A wrong term shows up at its own size relative to the scale.
//! - Finite differences: the bound is derived per sample (truncation from a bound on the next
//!   derivative, rounding from the absolute-value scale, see `crate::fd`); the check asserts
//!   `error <= bound` and reports the worst `error / bound`.
//! - Determinants: `error <= kernel rounding + reference rounding`, derived per sample from the
//!   permanent of the absolute-value Bezout / entry matrix and nalgebra's LU a-posteriori bound
//!   (`reference::det_with_bound`); the error is reported relative to Hadamard's bound of the
//!   absolute-value matrix.
//!
//! One file per kernel family: `cost.rs` (the cost's coefficients, value, gradient and Hessian),
//! `local_model.rs` (`newton`'s local model and its affine part for the generalized cost), `nullspace.rs` (the cases' cubics, resultants and
//! determinants), `gp3p.rs` (the generalized three-point pose), `up2p.rs` (the upright two-point pose),
//! `p4pf.rs` (the four-point pose with unknown focal length and its three-quadric elimination); [`all`] lists every check in
//! report order.

use crate::reference::gamma;
use crate::report::Measurement;
use nalgebra::{DMatrix, Matrix3};
use num_complex::Complex;

mod cost;
mod gp3p;
mod local_model;
mod nullspace;
mod p4pf;
mod up2p;

pub use cost::{cost_coefficients, cost_value, gradient, hessian, Against, Variant};
pub use gp3p::{gp3p_known_root, gp3p_octic, gp3p_solutions};
pub use local_model::{hessian_directions, local_affine, local_model, LocalAgainst, LocalKernel};
pub use nullspace::{
    case2_cubics, case2_known_root, case2_resultant, case3_cubics, case3_known_root, case3_quartic,
    case3_resultant, case4_determinant, case4_known_root, case4_known_system, case4_matrix,
};
pub use p4pf::{
    e3q3_determinant, e3q3_known_root, e3q3_solutions, p4pf_quadrics, p4pf_solutions, N_P4PF,
};
pub use up2p::{up2p_determinant, up2p_known_root, up2p_solutions};

/// 1e-12 relative to the absolute-value scale (module doc).
pub const TOL_POLY: f64 = 1e-12;

/// Rounding allowance for one generated kernel output in units of its absolute-value scale:
/// `gamma_64` (depth <= 64 covers every kernel's straight-line code plus the evaluation of its
/// coefficients at a point).
#[must_use]
pub fn g64() -> f64 {
    gamma(64)
}

/// Rays of a minimal solver's instance: world points, centres, directions.
type Rays<'a> = (
    &'a [nalgebra::Point3<f64>],
    &'a [nalgebra::Point3<f64>],
    &'a [nalgebra::Vector3<f64>],
);

/// A minimal solver's poses against its rays: the largest sine of the angle between
/// `R X_j + t - c_j` and the ray `v_j` over every pose and point (infinite for a point behind its
/// centre), and whether the true pose `(r, t)` is among the poses (to 1e-8).
fn poses_on_rays(
    poses: &[eopnp::p3p::P3pPose],
    (world, centres, directions): Rays<'_>,
    (r, t): (&Matrix3<f64>, &nalgebra::Vector3<f64>),
) -> (f64, bool) {
    let mut worst = 0.0f64;
    for s in poses {
        for j in 0..world.len() {
            let q = s.rotation * world[j].coords + s.translation - centres[j].coords;
            let sine = q.cross(&directions[j]).norm() / q.norm();
            let behind = q.dot(&directions[j]) <= 0.0;
            worst = worst.max(if behind { f64::INFINITY } else { sine });
        }
    }
    let found = poses
        .iter()
        .any(|s| (s.rotation - r).norm() + (s.translation - t).norm() / (1.0 + t.norm()) < 1e-8);
    (worst, found)
}

/// The real roots of `c[0] + c[1] x + ...` (degree <= 8, leading coefficient non-zero) as
/// eigenvalues of the companion matrix (nalgebra's Schur decomposition), and the smallest
/// distance of any root, real or complex, to the real axis: real means `|Im z| <= 1e-7 (1 + |z|)`.
pub(super) fn companion_roots(c: &[f64]) -> (Vec<f64>, f64) {
    let deg = c.iter().rposition(|x| *x != 0.0).unwrap_or(0);
    if deg == 0 {
        return (Vec::new(), f64::INFINITY);
    }
    let lead = c[deg];
    let m = DMatrix::from_fn(deg, deg, |i, j| {
        if i == 0 {
            -c[deg - 1 - j] / lead
        } else if i == j + 1 {
            1.0
        } else {
            0.0
        }
    });
    let eig: Vec<Complex<f64>> = m.complex_eigenvalues().iter().copied().collect();
    let mut real = Vec::new();
    let mut closest_complex = f64::INFINITY;
    for z in eig {
        let tol = 1e-7 * (1.0 + z.norm());
        if z.im.abs() <= tol {
            real.push(z.re);
        } else {
            closest_complex = closest_complex.min(z.im.abs() / (1.0 + z.norm()));
        }
    }
    (real, closest_complex)
}

/// Symmetric 3 x 3 from `[H00, H01, H02, H11, H12, H22]`.
#[must_use]
pub fn sym3(h: &[f64; 6]) -> Matrix3<f64> {
    Matrix3::new(h[0], h[1], h[2], h[1], h[3], h[4], h[2], h[4], h[5])
}

/// Number of samples for the cost / gradient / Hessian / local-model checks.
pub const N_COST: usize = 10_000;
/// Number of samples for the resultant checks.
pub const N_RESULTANT: usize = 5_000;
/// Number of samples for the generalized three-point pose's checks.
pub const N_GP3P: usize = 5_000;
/// Samples of the upright two-point checks (the solver's independent count scans every tenth).
pub const N_UP2P: usize = 5_000;

/// Every check, in report order.
#[must_use]
pub fn all() -> Vec<Measurement> {
    let mut out = Vec::new();
    for v in [Variant::Full, Variant::Planar] {
        out.push(cost_coefficients(v, N_COST));
    }
    out.push(cost_value(Variant::Full, N_COST));
    out.push(cost_value(Variant::Planar, N_COST));
    for v in [Variant::Full, Variant::Planar] {
        for a in [
            Against::Direct,
            Against::FiniteDifference,
            Against::ComplexStep,
        ] {
            out.push(gradient(v, a, N_COST));
        }
        for a in [
            Against::Direct,
            Against::FiniteDifference,
            Against::ComplexStep,
        ] {
            out.push(hessian(v, a, N_COST));
        }
    }
    for a in [
        LocalAgainst::Value,
        LocalAgainst::Explicit,
        LocalAgainst::FdGradient,
        LocalAgainst::FdHessian,
        LocalAgainst::CsGradient,
        LocalAgainst::CsHessian,
    ] {
        out.push(local_model(a, N_COST));
    }
    for a in [
        LocalAgainst::Value,
        LocalAgainst::Explicit,
        LocalAgainst::FdGradient,
        LocalAgainst::FdHessian,
        LocalAgainst::CsGradient,
        LocalAgainst::CsHessian,
    ] {
        out.push(local_affine(a, N_COST));
    }
    out.push(case2_resultant(N_RESULTANT));
    out.extend(case2_known_root(N_RESULTANT));
    out.push(case2_cubics(N_RESULTANT));
    out.push(case3_quartic(N_RESULTANT));
    out.push(case3_resultant(N_RESULTANT));
    out.extend(case3_known_root(N_RESULTANT));
    out.push(case3_cubics(N_RESULTANT));
    out.push(case4_matrix(N_RESULTANT));
    out.push(case4_determinant(N_RESULTANT));
    out.extend(case4_known_root(N_RESULTANT));
    out.push(gp3p_octic(N_GP3P));
    out.push(gp3p_known_root(N_GP3P));
    out.push(gp3p_solutions(N_GP3P));
    out.push(up2p_determinant(N_UP2P));
    out.push(up2p_known_root(N_UP2P));
    out.push(up2p_solutions(N_UP2P));
    out.push(p4pf_quadrics(N_P4PF));
    out.push(e3q3_determinant(N_P4PF));
    out.push(e3q3_known_root(N_P4PF));
    out.push(e3q3_solutions(N_P4PF));
    out.push(p4pf_solutions(N_P4PF));
    out
}
