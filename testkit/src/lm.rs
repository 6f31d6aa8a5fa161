//! The independent Levenberg-Marquardt reference ("LM from ground truth", the
//! maximum-likelihood floor).

use nalgebra::{DMatrix, DVector, Matrix3, Point2, Point3, Vector3};

use crate::rotation::exp_so3;
use crate::{CX, CY, F};

/// Pinhole camera (f, cx, cy) used by the LM reference. `NORMALISED` = (1, 0, 0).
#[derive(Clone, Copy, Debug)]
pub struct Camera {
    /// Focal length.
    pub f: f64,
    /// Principal point x.
    pub cx: f64,
    /// Principal point y.
    pub cy: f64,
}

/// The synthetic camera (f = 800, (320, 240)).
pub const PIXEL_CAMERA: Camera = Camera {
    f: F,
    cx: CX,
    cy: CY,
};
/// Normalised image coordinates.
pub const NORMALISED: Camera = Camera {
    f: 1.0,
    cx: 0.0,
    cy: 0.0,
};

/// Output of [`lm_refine`].
#[derive(Clone, Copy, Debug)]
pub struct LmResult {
    /// Refined rotation.
    pub r: Matrix3<f64>,
    /// Refined translation.
    pub t: Vector3<f64>,
    /// Final sum of squared residuals (in the camera's units).
    pub cost: f64,
    /// Outer iterations.
    pub iterations: usize,
    /// True if a convergence test (not the iteration cap) stopped it.
    pub converged: bool,
}

/// Residuals (model - measurement) and their analytic Jacobian w.r.t. (w, t) for the update
/// R := Exp(w) R, t := t + dt. Dense, world frame: independent of the library's `refine`.
fn residuals_and_jacobian(
    world: &[Point3<f64>],
    obs: &[Point2<f64>],
    r: &Matrix3<f64>,
    t: &Vector3<f64>,
    cam: Camera,
    with_jacobian: bool,
) -> (DVector<f64>, DMatrix<f64>) {
    let n = world.len();
    let mut res = DVector::zeros(2 * n);
    let mut jac = DMatrix::zeros(if with_jacobian { 2 * n } else { 0 }, 6);
    for (i, (x, m)) in world.iter().zip(obs).enumerate() {
        let q = r * x.coords;
        let p = q + t;
        res[2 * i] = cam.f * p.x / p.z + cam.cx - m.x;
        res[2 * i + 1] = cam.f * p.y / p.z + cam.cy - m.y;
        if with_jacobian {
            // d(res)/dp = (f / z) [[1, 0, -x/z], [0, 1, -y/z]];  dp/dw = -[q]x;  dp/dt = I.
            let dp = nalgebra::Matrix2x3::new(1.0, 0.0, -p.x / p.z, 0.0, 1.0, -p.y / p.z)
                * (cam.f / p.z);
            jacobian_rows(&mut jac, i, &dp, &q);
        }
    }
    (res, jac)
}

/// Rows `2 i` and `2 i + 1` of the Jacobian w.r.t. `(w, t)` from `dp = d(res_i) / d p` at the
/// rotated point `q`: `dp/dw = -[q]x`, `dp/dt = I`.
fn jacobian_rows(
    jac: &mut DMatrix<f64>,
    i: usize,
    dp: &nalgebra::Matrix2x3<f64>,
    q: &Vector3<f64>,
) {
    let dw = -(dp * q.cross_matrix());
    for k in 0..3 {
        jac[(2 * i, k)] = dw[(0, k)];
        jac[(2 * i + 1, k)] = dw[(1, k)];
        jac[(2 * i, 3 + k)] = dp[(0, k)];
        jac[(2 * i + 1, 3 + k)] = dp[(1, k)];
    }
}

/// Sum of squared residuals of a pose (in the camera's units).
pub fn reprojection_cost(
    world: &[Point3<f64>],
    obs: &[Point2<f64>],
    r: &Matrix3<f64>,
    t: &Vector3<f64>,
    cam: Camera,
) -> f64 {
    residuals_and_jacobian(world, obs, r, t, cam, false)
        .0
        .norm_squared()
}

/// Levenberg-Marquardt (Moré/MINPACK-style: Marquardt's diagonal scaling D with
/// D_k = max over iterations of |column k of J|, Nielsen's damping update, damped step from
/// the SVD of the augmented least-squares system [J; sqrt(lam) D] delta = [-r; 0]) on the
/// residuals `cam(R X + t) - obs`, parameters R := Exp(w) R, t := t + dt, started at (r0, t0).
/// Stops like scipy `least_squares(method='lm', xtol=ftol=gtol=1e-14)`: relative actual and
/// predicted reductions <= 1e-14 (ftol), scaled step <= 1e-14 scaled parameter norm (xtol), or
/// max cosine between the residual and a Jacobian column <= 1e-14 (gtol); at most 200
/// iterations.
///
/// Validation (scratch checks, recorded here):
/// - against scipy (the reference prototype's `lm_from_gt`,
///   `least_squares(method='lm', xtol=ftol=gtol=1e-14)`) on 40 numpy-generated problems of the
///   paper protocol (N = 4, 5, 6, 10, 15 at sigma = 0.5, 2, 5 px, and planar N = 4, 6, 10 at 2 px):
///   final costs agree to 2.3e-13 relative (ours lower where they differ most), rotations to 2.6e-7
///   deg (typically 1e-9; the minimum is flat to rounding, cf. docs/algorithm.md, `refine`),
///   translations to 7.8e-10 relative; all 40 converged in 4-6 iterations;
/// - noise-free problems (all scenes and rotation kinds, N = 4..100, 1,500 trials): returns
///   the truth to 2.3e-13 deg / 1.9e-15 relative;
/// - paper protocol, N = 10, sigma = 2 px, 1,000 trials of
///   [`Problem::generate`](crate::Problem::generate): mean
///   rotation error 0.384 +- 0.006 deg, mean translation error 0.267 +- 0.005 % (docs/algorithm.md
///   section 7, LM-from-GT: 0.380 / 0.390 deg, 0.26 %); N = 4, 5, 6, 15: 1.05, 0.731, 0.580,
///   0.297 deg (section 7: 1.07, 0.746, 0.592, 0.286); sigma 0.5 / 5 px: 0.0959 / 0.954 deg
///   (0.097 / 0.948).
pub fn lm_refine(
    world: &[Point3<f64>],
    obs: &[Point2<f64>],
    r0: &Matrix3<f64>,
    t0: &Vector3<f64>,
    cam: Camera,
) -> LmResult {
    lm_core(r0, t0, &|r, t, jac| {
        residuals_and_jacobian(world, obs, r, t, cam, jac)
    })
}

/// [`lm_refine`] through any camera projection `project` (normalised point to pixel, lens
/// distortion included): the residuals `project(pi(R X + t)) - obs`, their Jacobian through
/// the camera by central differences of `project` (step `1e-6 max(1, |x|)`), independent of the
/// library's analytic camera Jacobians. (An approximate Jacobian moves the stationary point by
/// O(eps^2) in the cost, eps ~ 1e-9 here.)
pub fn lm_refine_projection(
    world: &[Point3<f64>],
    obs: &[Point2<f64>],
    r0: &Matrix3<f64>,
    t0: &Vector3<f64>,
    project: &dyn Fn(Point2<f64>) -> Point2<f64>,
) -> LmResult {
    lm_core(r0, t0, &|r, t, with_jacobian| {
        projection_residuals(world, obs, r, t, project, with_jacobian)
    })
}

/// [`lm_refine_projection`] with a known vertical as a prior: three more residuals
/// `sqrt(lambda) (R g_world - g_camera)` (Jacobian `-sqrt(lambda) [R g_world]x` in `w`), the
/// maximum a posteriori pose of the library's `vertical` stage, minimised independently of it.
/// The returned cost includes the prior's term.
#[allow(clippy::too_many_arguments)]
pub fn lm_refine_vertical(
    world: &[Point3<f64>],
    obs: &[Point2<f64>],
    r0: &Matrix3<f64>,
    t0: &Vector3<f64>,
    project: &dyn Fn(Point2<f64>) -> Point2<f64>,
    g_world: &Vector3<f64>,
    g_camera: &Vector3<f64>,
    lambda: f64,
) -> LmResult {
    let s = lambda.sqrt();
    lm_core(r0, t0, &|r, t, with_jacobian| {
        let (res, jac) = projection_residuals(world, obs, r, t, project, with_jacobian);
        let m = res.len();
        let mut res = res.resize_vertically(m + 3, 0.0);
        let u = r * g_world;
        let e = (u - g_camera) * s;
        for k in 0..3 {
            res[m + k] = e[k];
        }
        let jac = if with_jacobian {
            let mut jac = jac.resize_vertically(m + 3, 0.0);
            let j = -u.cross_matrix() * s;
            for a in 0..3 {
                for b in 0..3 {
                    jac[(m + a, b)] = j[(a, b)];
                }
            }
            jac
        } else {
            jac
        };
        (res, jac)
    })
}

/// The residuals `project(pi(R X + t)) - obs` and (`with_jacobian`) their Jacobian through
/// `project` by central differences ([`lm_refine_projection`]).
fn projection_residuals(
    world: &[Point3<f64>],
    obs: &[Point2<f64>],
    r: &Matrix3<f64>,
    t: &Vector3<f64>,
    project: &dyn Fn(Point2<f64>) -> Point2<f64>,
    with_jacobian: bool,
) -> (DVector<f64>, DMatrix<f64>) {
    let n = world.len();
    let mut res = DVector::zeros(2 * n);
    let mut jac = DMatrix::zeros(if with_jacobian { 2 * n } else { 0 }, 6);
    for (i, (x, m)) in world.iter().zip(obs).enumerate() {
        let q = r * x.coords;
        let p = q + t;
        let nrm = Point2::new(p.x / p.z, p.y / p.z);
        let u = project(nrm);
        res[2 * i] = u.x - m.x;
        res[2 * i + 1] = u.y - m.y;
        if with_jacobian {
            let h = 1e-6 * nrm.coords.norm().max(1.0);
            let dx = (project(nrm + nalgebra::Vector2::new(h, 0.0))
                - project(nrm - nalgebra::Vector2::new(h, 0.0)))
                / (2.0 * h);
            let dy = (project(nrm + nalgebra::Vector2::new(0.0, h))
                - project(nrm - nalgebra::Vector2::new(0.0, h)))
                / (2.0 * h);
            let jc = nalgebra::Matrix2::new(dx.x, dy.x, dx.y, dy.y);
            let dn = nalgebra::Matrix2x3::new(1.0, 0.0, -nrm.x, 0.0, 1.0, -nrm.y) / p.z;
            jacobian_rows(&mut jac, i, &(jc * dn), &q);
        }
    }
    (res, jac)
}

/// Residuals and (optionally) their Jacobian at a pose.
type ResidualFn<'a> =
    dyn Fn(&Matrix3<f64>, &Vector3<f64>, bool) -> (DVector<f64>, DMatrix<f64>) + 'a;

/// The iteration of [`lm_refine`] on any residual function.
fn lm_core(r0: &Matrix3<f64>, t0: &Vector3<f64>, resjac: &ResidualFn<'_>) -> LmResult {
    const FTOL: f64 = 1e-14;
    const XTOL: f64 = 1e-14;
    const GTOL: f64 = 1e-14;
    const MAX_ITER: usize = 200;
    let mut r = *r0;
    let mut t = *t0;
    // Accumulated rotation vector (for the xtol test's parameter norm, as scipy's x[:3]).
    let mut w_total = Vector3::<f64>::zeros();
    let (mut res, mut jac) = resjac(&r, &t, true);
    let mut cost = res.norm_squared();
    let mut diag = DVector::<f64>::zeros(6);
    let mut lam = -1.0;
    let mut nu = 2.0;
    let mut converged = false;
    let mut iterations = 0;
    'outer: for it in 1..=MAX_ITER {
        iterations = it;
        if cost == 0.0 {
            converged = true;
            break;
        }
        let col_norms: Vec<f64> = (0..6).map(|k| jac.column(k).norm()).collect();
        for k in 0..6 {
            diag[k] = diag[k].max(col_norms[k]);
            if diag[k] == 0.0 {
                diag[k] = 1.0;
            }
        }
        // gtol: max_k |J_k . r| / (|J_k| |r|).
        let jtr = jac.transpose() * &res;
        let rnorm = cost.sqrt();
        let gcos = (0..6)
            .filter(|&k| col_norms[k] > 0.0)
            .map(|k| (jtr[k] / (col_norms[k] * rnorm)).abs())
            .fold(0.0, f64::max);
        if gcos <= GTOL {
            converged = true;
            break;
        }
        if lam < 0.0 {
            lam = 1e-3
                * (0..6)
                    .map(|k| (col_norms[k] / diag[k]).powi(2))
                    .fold(0.0, f64::max);
        }
        // Inner loop: increase the damping until the step reduces the cost.
        for _ in 0..100 {
            let m = jac.nrows();
            let mut aug = DMatrix::zeros(m + 6, 6);
            aug.view_mut((0, 0), (m, 6)).copy_from(&jac);
            let mut rhs = DVector::zeros(m + 6);
            rhs.rows_mut(0, m).copy_from(&(-&res));
            for k in 0..6 {
                aug[(m + k, k)] = lam.sqrt() * diag[k];
            }
            let delta = match aug.svd(true, true).solve(&rhs, 0.0) {
                Ok(d) => d,
                Err(_) => break 'outer,
            };
            let dw = Vector3::new(delta[0], delta[1], delta[2]);
            let r_new = exp_so3(&dw) * r;
            let t_new = t + Vector3::new(delta[3], delta[4], delta[5]);
            let (res_new, _) = resjac(&r_new, &t_new, false);
            let cost_new = res_new.norm_squared();
            let lin = &res + &jac * &delta;
            let pred = (cost - lin.norm_squared()) / cost;
            let actual = if cost_new.is_finite() {
                1.0 - cost_new / cost
            } else {
                -1.0
            };
            let dnorm = diag.component_mul(&delta).norm();
            let xnorm = Vector3::new(
                diag[0] * w_total[0],
                diag[1] * w_total[1],
                diag[2] * w_total[2],
            )
            .norm()
            .hypot(Vector3::new(diag[3] * t[0], diag[4] * t[1], diag[5] * t[2]).norm());
            if cost_new.is_finite() && cost_new < cost {
                let rho = if pred > 0.0 { actual / pred } else { 0.0 };
                r = r_new;
                t = t_new;
                w_total += dw;
                let (rs, jc) = resjac(&r, &t, true);
                res = rs;
                jac = jc;
                cost = cost_new;
                lam *= (1.0_f64 / 3.0).max(1.0 - (2.0 * rho - 1.0).powi(3));
                nu = 2.0;
                if (actual.abs() <= FTOL && pred <= FTOL) || dnorm <= XTOL * xnorm {
                    converged = true;
                    break 'outer;
                }
                continue 'outer;
            }
            if dnorm <= XTOL * xnorm || (pred.abs() <= FTOL && actual.abs() <= FTOL) {
                converged = true;
                break 'outer;
            }
            lam *= nu;
            nu *= 2.0;
        }
        break;
    }
    LmResult {
        r,
        t,
        cost,
        iterations,
        converged,
    }
}

/// Output of [`lm_refine_focal`].
#[derive(Clone, Copy, Debug)]
pub struct LmFocalResult {
    /// Refined rotation.
    pub r: Matrix3<f64>,
    /// Refined translation.
    pub t: Vector3<f64>,
    /// Refined focal length.
    pub f: f64,
    /// Final sum of squared pixel residuals.
    pub cost: f64,
    /// Iterations.
    pub iterations: usize,
}

/// Levenberg-Marquardt over the pose and the focal length of a pinhole camera with principal
/// point `c` (square pixels): residuals `f (x / z, y / z) + c - obs`, `(x, y, z) = R X + t`,
/// parameters `R := Exp(w) R`, `t := t + dt`, `f := f + df`, Marquardt's scaling by the
/// Jacobian's column norms, each step solved by the SVD of the augmented least-squares system;
/// stops on a relative step or cost decrease below 1e-14, or after 500 iterations. Dense and
/// independent of the library's `refine_focal`: the reference of the unknown-focal solve.
pub fn lm_refine_focal(
    world: &[Point3<f64>],
    obs: &[Point2<f64>],
    r0: &Matrix3<f64>,
    t0: &Vector3<f64>,
    f0: f64,
    c: Point2<f64>,
) -> LmFocalResult {
    let n = world.len();
    let eval = |r: &Matrix3<f64>, t: &Vector3<f64>, f: f64, with_jac: bool| {
        let mut res = DVector::zeros(2 * n);
        let mut jac = DMatrix::zeros(if with_jac { 2 * n } else { 0 }, 7);
        for (i, (x, m)) in world.iter().zip(obs).enumerate() {
            let q = r * x.coords;
            let p = q + t;
            res[2 * i] = f * p.x / p.z + c.x - m.x;
            res[2 * i + 1] = f * p.y / p.z + c.y - m.y;
            if with_jac {
                let dp = nalgebra::Matrix2x3::new(1.0, 0.0, -p.x / p.z, 0.0, 1.0, -p.y / p.z)
                    * (f / p.z);
                jacobian_rows(&mut jac, i, &dp, &q);
                jac[(2 * i, 6)] = p.x / p.z;
                jac[(2 * i + 1, 6)] = p.y / p.z;
            }
        }
        (res, jac)
    };
    let (mut r, mut t, mut f) = (*r0, *t0, f0);
    let (mut res, mut jac) = eval(&r, &t, f, true);
    let mut cost = res.norm_squared();
    let mut lam: f64 = 1e-3;
    let mut iterations = 0;
    for it in 1..=500 {
        iterations = it;
        let diag: Vec<f64> = (0..7).map(|k| jac.column(k).norm().max(1e-300)).collect();
        let m = jac.nrows();
        let mut aug = DMatrix::zeros(m + 7, 7);
        aug.view_mut((0, 0), (m, 7)).copy_from(&jac);
        let mut rhs = DVector::zeros(m + 7);
        rhs.rows_mut(0, m).copy_from(&(-&res));
        for k in 0..7 {
            aug[(m + k, k)] = lam.sqrt() * diag[k];
        }
        let Ok(delta) = aug.svd(true, true).solve(&rhs, 0.0) else {
            break;
        };
        let r_new = exp_so3(&Vector3::new(delta[0], delta[1], delta[2])) * r;
        let t_new = t + Vector3::new(delta[3], delta[4], delta[5]);
        let f_new = f + delta[6];
        let (res_new, _) = eval(&r_new, &t_new, f_new, false);
        let cost_new = res_new.norm_squared();
        let step = (0..7)
            .map(|k| (diag[k] * delta[k]).powi(2))
            .sum::<f64>()
            .sqrt();
        if cost_new.is_finite() && cost_new < cost {
            let small = cost - cost_new <= 1e-14 * cost;
            (r, t, f) = (r_new, t_new, f_new);
            let (rs, jc) = eval(&r, &t, f, true);
            (res, jac, cost) = (rs, jc, cost_new);
            lam = (lam / 3.0).max(1e-15);
            if small || step <= 1e-14 * cost.sqrt().max(1e-300) {
                break;
            }
        } else {
            lam *= 4.0;
            if lam > 1e20 {
                break;
            }
        }
    }
    LmFocalResult {
        r,
        t,
        f,
        cost,
        iterations,
    }
}
