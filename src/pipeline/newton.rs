//! The `newton` stage of docs/algorithm.md: damped Newton on SO(3) in moving CGR coordinates.
//!
//! Minimises `f(R) = vec(R)^T M vec(R)` from a starting rotation. Every iteration works in the
//! CGR chart centred on the current estimate `R_k` (`s -> R(s) R_k`, `s = 0` at `R_k`), so the
//! 180-degree singularity of the CGR map never matters (trap T1) and the iteration converges
//! to a stationary point of `f` itself, not of the chart-dependent `C(s)` (T2).
//!
//! | symbol | meaning |
//! |---|---|
//! | `f, g, H_C` | local model at `R_k` (the quantities of `crate::kernels::so3_local_model`, computed by [`local_model`]) |
//! | `H` | `H_C - 4 f I`, the exact Hessian of `F_k(s) = f(R(s) R_k)` at 0 (T3) |
//! | `shift` | `max(0, -lambda_min(H))`, smallest eigenvalue by 3 x 3 Jacobi (T4) |
//! | `mu` | damping: `lambda = mu * scale + shift`, `scale = trace(M)` |
//! | `d` | step `-(H + lambda I)^-1 g` (hand-written 3 x 3 `L D L^T`, [`ldl3`]) |
//!
//! Acceptance: `f' < f`, or `f' <= f + accept_floor * scale` and `|g'| < |g|` (the rounding
//! floor of T5, needed to reach ~1e-13 deg on noise-free data). `mu` x10 after a rejected step
//! (or a failed factorisation), /10 (floor 1e-15) after an accepted one; stop when no step is
//! accepted before `mu > mu_max`, when `|d| <= step_tolerance`, when quadratic convergence
//! predicts the next step at or below `step_tolerance / 1000` (`|d_k|^3 / |d_k-1|^2` for two
//! consecutive undamped Newton steps (H positive definite, mu <= mu0), with
//! `|d_k| < |d_k-1| / 10`: saves the last, confirming iteration), or at `max_iterations`.
//! Every loop is bounded: at most `max_iterations` outer iterations, each with at most
//! `bounds::NEWTON_MAX_DAMPING_STEPS` trial steps. A trial step first evaluates only `f'` (the
//! quadratic form, 45 entries of M); the local model runs for a step within the rounding floor
//! (to compare gradients) and at an accepted iterate the iteration goes on from, never at the
//! one it stops at. Over half of the trial steps of the N = 4 search are rejected.

use nalgebra::{Matrix3, SMatrix, Vector3};

use crate::numeric::bounds::{Bound, Budget};
use crate::numeric::lanes::dispatched;
use crate::numeric::mat3::{ldl3, ldl3_solve, min_eigenvalue_sym3};
use crate::numeric::rotation::cgr_to_rotation;

/// Options of [`refine_so3`] (docs/algorithm.md, the table of constants and tolerances).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct NewtonOptions {
    /// Maximum number of iterations. Default: 50.
    pub max_iterations: u32,
    /// Stop when the accepted step has norm `<= step_tolerance` (CGR units ~ radians / 2).
    /// Default: 1e-12.
    pub step_tolerance: f64,
    /// Initial damping factor (relative to `scale`). Default: 1e-6.
    pub mu0: f64,
    /// Give up (stop) when the damping factor exceeds this. Default: 1e8.
    pub mu_max: f64,
    /// Acceptance floor relative to `scale`. Default: 1e-13.
    pub accept_floor: f64,
}

impl Default for NewtonOptions {
    fn default() -> Self {
        Self {
            max_iterations: 50,
            step_tolerance: 1e-12,
            mu0: 1e-6,
            mu_max: 1e8,
            accept_floor: 1e-13,
        }
    }
}

/// Result of [`refine_so3`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Refined {
    /// The refined rotation.
    pub r: Matrix3<f64>,
    /// `f(r) = vec(r)^T M vec(r)`.
    pub f: f64,
    /// Number of iterations run (each evaluates one or more trial steps).
    pub iterations: u32,
    /// True if the iteration cap stopped the refinement (neither the step tolerance nor the
    /// damping limit did).
    pub hit_limit: bool,
    /// True if the caller's stop predicate ended the refinement.
    pub stopped_early: bool,
}

/// Row-major `vec(R)`.
fn row_major(r: &Matrix3<f64>) -> [f64; 9] {
    [
        r[(0, 0)],
        r[(0, 1)],
        r[(0, 2)],
        r[(1, 0)],
        r[(1, 1)],
        r[(1, 2)],
        r[(2, 0)],
        r[(2, 1)],
        r[(2, 2)],
    ]
}

/// `f(R) = vec(R)^T M vec(R)` from the upper triangle `m45` (row-major `vec`, order of
/// `COST_M_UPPER`): a quarter of the work of the local model; the trial steps, and the
/// solver's values of f.
pub(crate) fn cost_at(m45: &[f64; 45], r: &Matrix3<f64>) -> f64 {
    let v = row_major(r);
    let mut k = 0;
    let mut f = 0.0;
    for i in 0..9 {
        // v_i (M_ii v_i / 2 + sum_{j > i} M_ij v_j), doubled below.
        let mut s = 0.5 * m45[k] * v[i];
        k += 1;
        for vj in &v[i + 1..] {
            s += m45[k] * vj;
            k += 1;
        }
        f += v[i] * s;
    }
    2.0 * f
}

dispatched! {
    /// The local model at `r`: the gradient `g` and the exact Hessian `H = H_C - 4 f I` of
    /// `f(R(s) R)` at `s = 0` (module docs), from the full symmetric `M` (its columns, which
    /// are its rows).
    ///
    /// The generated kernel `so3_local_model` defines these quantities (and `verify/` checks
    /// it); this is the same algebra factored for 4-wide vectors, tested against the kernel
    /// (`tests/unit/pipeline/newton.rs`). With `X = [r, vec([e1]x R), vec([e2]x R),
    /// vec([e3]x R)]` (9 x 4, row-major `vec`, `[e]x R` the derivative of the chart),
    /// `U = M X` and `Q = X^T U` (4 x 4): `f = Q_00`, `g_k = 4 Q_k0` and
    /// `H_kl = 8 Q_kl + 4 (W_kl + W_lk) - 8 f delta_kl`, `W_lk = R_l . Y_k` (`R_l` the rows of
    /// `R`, `Y_k` those of `M r` as a 3 x 3 matrix; `k, l = 1..3`). Every row of `X` and `U`
    /// is one AVX2 register (two SSE2 registers): 630 instructions per call against the
    /// kernel's 1,773 straight-line scalar ones (callgrind, the AVX2 build).
    pub(crate) fn local_model[][](m: &[[f64; 9]; 9], r: &Matrix3<f64>) -> (Vector3<f64>, Matrix3<f64>) = local_model_body;
}

/// `acc += s v`, lane by lane.
#[inline(always)]
fn axpy4(acc: &mut [f64; 4], s: f64, v: &[f64; 4]) {
    *acc = [
        acc[0] + s * v[0],
        acc[1] + s * v[1],
        acc[2] + s * v[2],
        acc[3] + s * v[3],
    ];
}

#[inline(always)]
fn local_model_body(m: &[[f64; 9]; 9], r: &Matrix3<f64>) -> (Vector3<f64>, Matrix3<f64>) {
    let mut x = [[0.0; 4]; 9];
    for j in 0..3 {
        x[j] = [r[(0, j)], 0.0, r[(2, j)], -r[(1, j)]];
        x[3 + j] = [r[(1, j)], -r[(2, j)], 0.0, r[(0, j)]];
        x[6 + j] = [r[(2, j)], r[(1, j)], -r[(0, j)], 0.0];
    }
    // X goes through memory as whole 4-wide rows. Without this the compiler splits the rows
    // around their constant zeros into scalar operations (measured: 2 % slower solves at
    // N = 10 and 100, and an instruction form that valgrind cannot decode).
    let x = *core::hint::black_box(&x);
    let mut u = [[0.0; 4]; 9];
    for (up, mp) in u.iter_mut().zip(m) {
        for (&mpq, xq) in mp.iter().zip(&x) {
            axpy4(up, mpq, xq);
        }
    }
    let mut q = [[0.0; 4]; 4];
    for (xp, up) in x.iter().zip(&u) {
        for (qa, &xpa) in q.iter_mut().zip(xp) {
            axpy4(qa, xpa, up);
        }
    }
    let w = |l: usize, k: usize| {
        r[(l, 0)] * u[3 * k][0] + r[(l, 1)] * u[3 * k + 1][0] + r[(l, 2)] * u[3 * k + 2][0]
    };
    let f = q[0][0];
    let g = Vector3::new(4.0 * q[1][0], 4.0 * q[2][0], 4.0 * q[3][0]);
    let h = Matrix3::from_fn(|k, l| {
        let diag = if k == l { 8.0 * f } else { 0.0 };
        8.0 * q[k.min(l) + 1][k.max(l) + 1] + 4.0 * (w(l, k) + w(k, l)) - diag
    });
    (g, h)
}

/// `newton`: refine the rotation `r0` to a stationary point (normally a local minimum) of
/// `f(R) = vec(R)^T M vec(R)` over SO(3).
///
/// `m45` is the upper triangle of M (`crate::pipeline::moments::m_upper`); `scale` is `trace(M)`
/// (values that are not positive and finite are replaced by 1e-300, as in the prototype).
/// `r0` must be a rotation. The returned `f` never exceeds `f(r0) + k * accept_floor * scale`
/// after `k` accepted steps (it decreases except within the rounding floor).
#[cfg(any(test, eopnp_bench))]
pub(crate) fn refine_so3(
    m45: &[f64; 45],
    scale: f64,
    r0: &Matrix3<f64>,
    opts: &NewtonOptions,
) -> Refined {
    let m = crate::pipeline::moments::m_symmetric(m45);
    refine_so3_until(&m, m45, scale, (r0, cost_at(m45, r0)), opts, &mut |_| false)
}

/// As [`refine_so3`] (`m` is M itself, `m45` its upper triangle, `f0` is `cost_at(m45, r0)`,
/// which the solver has already computed), but stops early (with `stopped_early = true`) as
/// soon as `stop` returns true for an accepted iterate. The solver uses it to abandon a
/// trajectory once it has entered the neighbourhood of a local minimum that is already known.
pub(crate) fn refine_so3_until(
    m: &SMatrix<f64, 9, 9>,
    m45: &[f64; 45],
    scale: f64,
    (r0, f0): (&Matrix3<f64>, f64),
    opts: &NewtonOptions,
    stop: &mut dyn FnMut(&Matrix3<f64>) -> bool,
) -> Refined {
    let scale = if scale.is_finite() && scale > 1e-300 {
        scale
    } else {
        1e-300
    };
    let floor = opts.accept_floor * scale;
    let mut r = *r0;
    // The columns of the symmetric M are its rows.
    let rows = &m.data.0;
    // The local model at `r`, when the acceptance test has already computed it; otherwise it
    // is computed when the next iteration needs it (never at the iterate the loop stops at).
    let mut model = None;
    // Acceptance compares values of one evaluation order: `cost_at` throughout.
    let mut f = f0;
    let mut mu = opts.mu0;
    let mut iterations = 0u32;
    let mut hit_limit = true;
    let mut stopped_early = false;
    let mut d_prev = f64::INFINITY;
    for it in 0..opts.max_iterations {
        iterations = it + 1;
        let (g, h) = model.take().unwrap_or_else(|| local_model(rows, &r));
        // shift = max(0, -lambda_min(H)); a successful factorisation of H proves
        // lambda_min > 0 (shift 0), so the eigenvalue is only computed for an indefinite H.
        let shift = if ldl3(&h).is_some() {
            0.0
        } else {
            (-min_eigenvalue_sym3(&h)).max(0.0)
        };
        let gnorm = g.norm();
        let mut accepted = None;
        let mut damping = Budget::new(Bound::NewtonDamping);
        while damping.next() {
            // Also stops on a NaN mu or mu_max.
            if !matches!(
                mu.partial_cmp(&opts.mu_max),
                Some(core::cmp::Ordering::Less | core::cmp::Ordering::Equal)
            ) {
                break;
            }
            let a = h + Matrix3::identity() * (mu * scale + shift);
            let Some(l) = ldl3(&a) else {
                mu *= 10.0;
                continue;
            };
            let d = -ldl3_solve(&l, &g);
            let rn = cgr_to_rotation(&d) * r;
            let fnew = cost_at(m45, &rn);
            if fnew < f {
                accepted = Some((d, rn, fnew, None));
                break;
            }
            if fnew <= f + floor {
                // Within the rounding floor the step must reduce the gradient.
                let (gnew, hnew) = local_model(rows, &rn);
                if gnew.norm() < gnorm {
                    accepted = Some((d, rn, fnew, Some((gnew, hnew))));
                    break;
                }
            }
            mu *= 10.0;
        }
        let Some((d, rn, fnew, at_rn)) = accepted else {
            hit_limit = false;
            break;
        };
        r = rn;
        f = fnew;
        model = at_rn;
        // A Newton step: H positive definite and no damping escalation in this iteration.
        let newton_step = shift == 0.0 && mu <= opts.mu0;
        mu = (mu / 10.0).max(1e-15);
        let dn = d.norm();
        if dn <= opts.step_tolerance {
            hit_limit = false;
            break;
        }
        // Quadratic convergence (|d_k+1| ~ C |d_k|^2, C estimated from the last two Newton
        // steps): when the predicted next step is 1000x below the tolerance (below rounding at
        // the default), it is not computed.
        if newton_step
            && d_prev.is_finite()
            && dn < 0.1 * d_prev
            && dn * (dn / d_prev) * (dn / d_prev) <= 1e-3 * opts.step_tolerance
        {
            hit_limit = false;
            break;
        }
        d_prev = if newton_step { dn } else { f64::INFINITY };
        if stop(&r) {
            hit_limit = false;
            stopped_early = true;
            break;
        }
    }
    Refined {
        r,
        f,
        iterations,
        hit_limit,
        stopped_early,
    }
}

#[cfg(test)]
#[path = "../../tests/unit/pipeline/newton.rs"]
mod tests;
