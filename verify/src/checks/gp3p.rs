//! The checks of the generalized three-point pose: its generated elimination against a
//! numeric resultant computed another way, the true depth as a root, and the solver's poses
//! (on their rays, the true one among them, as many as an independent root count says).
//!
//! Random instances: three rays from three camera centres spread by a baseline of 0.1 to 2
//! (in units of the world triangle's longest side, the solver's scaled units), each through a
//! world point 0.2 to 3 of those units away, the rig at any rotation.

use super::companion_roots;
use crate::reference::{det_with_bound, hadamard};
use crate::report::{Measurement, Tracker};
use crate::strategies as st;
use eopnp::internals::gp3p::gp3p;
use eopnp::internals::kernels as k;
use nalgebra::{DMatrix, Matrix3, Point3, Vector3};

/// A random instance: the coefficients `e` of the three distance quadrics (the kernel's input)
/// and the true depths; also the geometry, for the solver.
struct Instance {
    e: [f64; 12],
    depths: [f64; 3],
    world: [Point3<f64>; 3],
    centres: [Point3<f64>; 3],
    directions: [Vector3<f64>; 3],
    r: Matrix3<f64>,
    t: Vector3<f64>,
}

const PAIRS: [(usize, usize); 3] = [(0, 1), (0, 2), (1, 2)];

fn instance(rng: &mut rand_pcg::Pcg64) -> Instance {
    let baseline = 0.1 + 1.9 * rand::Rng::random::<f64>(rng);
    let r = st::rotation(rng);
    let t = Vector3::new(st::normal(rng), st::normal(rng), st::normal(rng));
    let mut world = [Point3::origin(); 3];
    let mut centres = [Point3::origin(); 3];
    let mut directions = [Vector3::zeros(); 3];
    let mut depths = [0.0; 3];
    for i in 0..3 {
        let c = st::unit_vector(rng) * baseline * rand::Rng::random::<f64>(rng);
        let v = st::unit_vector(rng);
        let l = 0.2 + 2.8 * rand::Rng::random::<f64>(rng);
        let p = c + v * l;
        world[i] = Point3::from(r.transpose() * (p - t));
        centres[i] = Point3::from(c);
        directions[i] = v;
        depths[i] = l;
    }
    // The coefficients as the solver forms them: a_ij = v_i . v_j, b_ij = v_i . (c_i - c_j),
    // c_ij = v_j . (c_j - c_i), d_ij = |c_i - c_j|^2 - |X_i - X_j|^2 (here unscaled: the
    // elimination is homogeneous in the lengths, so any scale checks it).
    let mut e = [0.0; 12];
    for (n, (i, j)) in PAIRS.into_iter().enumerate() {
        let dc = centres[i].coords - centres[j].coords;
        e[4 * n] = directions[i].dot(&directions[j]);
        e[4 * n + 1] = directions[i].dot(&dc);
        e[4 * n + 2] = -directions[j].dot(&dc);
        e[4 * n + 3] = dc.norm_squared() - (world[i] - world[j]).norm_squared();
    }
    Instance {
        e,
        depths,
        world,
        centres,
        directions,
        r,
        t,
    }
}

/// The coefficients `(lj^2, lj, 1)` of `E_ij` (pair `n`) as a quadratic in its second depth at
/// the first depth `li`.
fn quadratic_in_second(e: &[f64; 12], n: usize, li: f64) -> [f64; 3] {
    let (a, b, c, d) = (e[4 * n], e[4 * n + 1], e[4 * n + 2], e[4 * n + 3]);
    [1.0, 2.0 * c - 2.0 * a * li, li * li + 2.0 * b * li + d]
}

/// The Sylvester matrix of two polynomials given by descending coefficients.
fn sylvester(p: &[f64], q: &[f64]) -> DMatrix<f64> {
    let (m, n) = (p.len() - 1, q.len() - 1);
    let size = m + n;
    let mut s = DMatrix::zeros(size, size);
    for row in 0..n {
        for (k, c) in p.iter().enumerate() {
            s[(row, row + k)] = *c;
        }
    }
    for row in 0..m {
        for (k, c) in q.iter().enumerate() {
            s[(n + row, row + k)] = *c;
        }
    }
    s
}

/// `F(l1)` computed without the generated elimination: `R(l2) = Res_l3(E13(l1), E23(l2))` as a
/// 4 x 4 Sylvester determinant at five values of `l2`, interpolated to its five coefficients
/// (a quartic in `l2`), then `Res_l2(E12(l1), R)`, the 6 x 6 Sylvester determinant. Returns
/// the value and the Hadamard bound of the 6 x 6 matrix of absolute values (the scale its
/// determinant is compared in).
fn octic_by_sylvester(e: &[f64; 12], l1: f64) -> (f64, f64) {
    let e13 = quadratic_in_second(e, 1, l1); // in l3
                                             // E23 in l3 at l2: l3^2 + (2 c23 - 2 a23 l2) l3 + (l2^2 + 2 b23 l2 + d23).
    let r_at = |l2: f64| {
        let e23 = [
            1.0,
            2.0 * e[10] - 2.0 * e[8] * l2,
            l2 * l2 + 2.0 * e[9] * l2 + e[11],
        ];
        det_with_bound(&sylvester(&e13, &e23)).0
    };
    // Chebyshev nodes on [-h, h], h the size of the coefficients' roots (Cauchy's bound of
    // E12 in l2), so the interpolation is well conditioned.
    let e12 = quadratic_in_second(e, 0, l1);
    let h = 1.0 + e12[1].abs().max(e12[2].abs()).max(1.0);
    let nodes: Vec<f64> = (0..5)
        .map(|k| h * (std::f64::consts::PI * (2.0 * k as f64 + 1.0) / 10.0).cos())
        .collect();
    let v = DMatrix::from_fn(5, 5, |i, j| nodes[i].powi(4 - j as i32));
    let y = DMatrix::from_fn(5, 1, |i, _| r_at(nodes[i]));
    let Some(coef) = v.lu().solve(&y) else {
        return (f64::NAN, f64::NAN);
    };
    let r: Vec<f64> = coef.iter().copied().collect(); // descending, l2^4 .. 1
    let s = sylvester(&e12, &r);
    let sa = s.map(f64::abs);
    (det_with_bound(&s).0, hadamard(&sa))
}

/// `F` and its absolute-value scale `sum |f_n| |x|^n` at `x`.
fn octic_at(f: &[f64], x: f64) -> (f64, f64) {
    f.iter()
        .rev()
        .fold((0.0, 0.0), |(v, a), &c| (v * x + c, a * x.abs() + c.abs()))
}

/// Tolerance of the resultant comparison, relative to the Hadamard bound of the numeric
/// Sylvester matrix: both sides are exact in exact arithmetic; the numeric side interpolates
/// five 4 x 4 determinants (Chebyshev nodes: a Vandermonde condition number below 10^2) and
/// takes a 6 x 6 LU determinant, so its relative error is a few hundred `u` of the scale; the
/// kernel's straight-line evaluation (depth below 64) adds `gamma_64`. 1e-10 leaves a factor
/// above 10^3 over both.
const TOL_SYLVESTER: f64 = 1e-10;

/// `gp3p_elimination`'s octic at a random `l1` against the resultant computed numerically by
/// another route ([`octic_by_sylvester`]).
#[must_use]
pub fn gp3p_octic(n: usize) -> Measurement {
    let seed = 301;
    let mut rng = st::rng(seed);
    let mut t = Tracker::new(
        "gp3p_elimination",
        "octic vs numeric Res_l2(E12, Res_l3(E13, E23)) (Sylvester, interpolation)",
        "|dF| / Hadamard(|Syl6|)",
        format!("{TOL_SYLVESTER:e}"),
    );
    for i in 0..n {
        let inst = instance(&mut rng);
        let l1 = st::normal(&mut rng) * 2.0;
        let out = k::gp3p_elimination(&inst.e);
        let (f, _) = octic_at(&out[0..9], l1);
        let (reference, scale) = octic_by_sylvester(&inst.e, l1);
        let err = (f - reference).abs() / scale;
        t.record(err, TOL_SYLVESTER, || {
            format!("seed {seed} sample {i}: e {:?}, l1 {l1:e}", inst.e)
        });
    }
    t.finish()
}

/// Tolerance of the known-root check, relative to `sum |f_n| |l1*|^n`: the true depth is a
/// root of the exact octic of the exact coefficients; the coefficients `e` are rounded once
/// from the geometry (relative `u`) and the kernel evaluates its octic (depth below 64), so
/// the octic at the root is a few `gamma_64` of its scale unless the root is ill-conditioned;
/// 1e-11 leaves a factor above 10^3.
const TOL_ROOT: f64 = 1e-11;

/// The true first depth is a root of the octic, and the back-substitution gives the true
/// second depth: `|F(l1*)| / sum |f_n| |l1*|^n` and `|r1(l1*) l2* + r0(l1*)| / scale`.
#[must_use]
pub fn gp3p_known_root(n: usize) -> Measurement {
    let seed = 302;
    let mut rng = st::rng(seed);
    let mut t = Tracker::new(
        "gp3p_elimination",
        "known root l1* (and r1(l1*) l2* + r0(l1*) = 0)",
        "max(|F(l1*)|, |r1 l2* + r0|) / their scales",
        format!("{TOL_ROOT:e}"),
    );
    for i in 0..n {
        let inst = instance(&mut rng);
        let [l1, l2, _] = inst.depths;
        let out = k::gp3p_elimination(&inst.e);
        let (f, fa) = octic_at(&out[0..9], l1);
        let (r1, r1a) = octic_at(&out[9..13], l1);
        let (r0, r0a) = octic_at(&out[13..18], l1);
        let back = (r1 * l2 + r0).abs() / (r1a * l2.abs() + r0a);
        let err = (f.abs() / fa).max(back);
        t.record(err, TOL_ROOT, || {
            format!(
                "seed {seed} sample {i}: e {:?}, depths {:?}",
                inst.e, inst.depths
            )
        });
    }
    t.finish()
}

/// The solver: every pose puts the three points on their rays, in front, to 1e-10 (the sine of
/// the angle between `R X + t - c` and the ray); the true pose is among them (1e-8); and the
/// number of poses equals the number of real roots of the octic (by the companion matrix, an
/// independent root finder) whose back-substituted depths are all positive, on every instance
/// whose roots are not within 1e-5 of the real axis' boundary (a nearly double root that one
/// finder may call real and the other complex; counted in the report, not compared).
#[must_use]
pub fn gp3p_solutions(n: usize) -> Measurement {
    let seed = 303;
    let mut rng = st::rng(seed);
    let mut t = Tracker::new(
        "gp3p_elimination",
        "solver: poses on their rays, the true one found, as many as the companion matrix's real roots with positive depths",
        "max ray sine; count mismatch = inf",
        "1e-10".into(),
    );
    let mut ambiguous = 0usize;
    for i in 0..n {
        let inst = instance(&mut rng);
        let sols = gp3p(&inst.world, &inst.centres, &inst.directions);
        let rays = (&inst.world[..], &inst.centres[..], &inst.directions[..]);
        let (mut worst, found) = super::poses_on_rays(&sols, rays, (&inst.r, &inst.t));
        if !found {
            worst = f64::INFINITY;
        }
        // The independent count: real roots of the octic with positive back-substituted depths.
        let out = k::gp3p_elimination(&inst.e);
        let (roots, closest_complex) = companion_roots(&out[0..9]);
        let mut count = 0usize;
        let mut near_boundary = closest_complex < 1e-5;
        for l1 in roots {
            let (r1, _) = octic_at(&out[9..13], l1);
            let (r0, _) = octic_at(&out[13..18], l1);
            let l2 = -r0 / r1;
            let (a13, b13, c13, d13) = (inst.e[4], inst.e[5], inst.e[6], inst.e[7]);
            let (a23, b23, c23, d23) = (inst.e[8], inst.e[9], inst.e[10], inst.e[11]);
            let dp = (2.0 * c13 - 2.0 * a13 * l1) - (2.0 * c23 - 2.0 * a23 * l2);
            let dq = (l1 * l1 + 2.0 * b13 * l1 + d13) - (l2 * l2 + 2.0 * b23 * l2 + d23);
            let l3 = -dq / dp;
            let lmin = l1.min(l2).min(l3);
            if lmin.abs() < 1e-6 * (1.0 + l1.abs().max(l2.abs()).max(l3.abs())) {
                near_boundary = true;
            }
            if lmin > 0.0 {
                count += 1;
            }
        }
        if near_boundary {
            ambiguous += 1;
        } else if count != sols.len() {
            worst = f64::INFINITY;
        }
        t.record(worst, 1e-10, || {
            format!(
                "seed {seed} sample {i}: {} poses, companion count {count}, found {found}",
                sols.len()
            )
        });
    }
    let mut m = t.finish();
    if ambiguous > 0 {
        m.worst_input = format!(
            "{} ({ambiguous} near-boundary instances not counted)",
            m.worst_input
        );
    }
    m
}
