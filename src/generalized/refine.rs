//! The maximum-likelihood refinement of a rig's pose: Levenberg-Marquardt on the pixel error of
//! every observation through its own camera (its pose in the rig, its model and distortion),
//! with the solver's robust loss by iteratively reweighted steps, and the pose covariance from
//! the same normal equations.

use nalgebra::{Matrix3, Matrix6, Vector3, Vector6};

use super::rays::Rays;
use crate::covariance::{NoiseModel, PoseCovariance};
use crate::pipeline::refine_rig::{refine_rig, RigPixels};
use crate::pipeline::vertical::{Vertical, VerticalCheck};
use crate::pipeline::Loss;
use crate::rig::Rig;

/// The outcome of a refinement.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Refined {
    pub r: Matrix3<f64>,
    pub t: Vector3<f64>,
    /// `sum w rho(|e|^2)`, pixels^2.
    pub cost: f64,
    /// `sum w |e|^2` and `sum w` (for the RMS error).
    pub squared: f64,
    pub weight_sum: f64,
    /// Observations in front of their camera, and their number.
    pub in_front: usize,
    pub iterations: u32,
    pub converged: bool,
    /// With a known vertical, its test at the maximum-likelihood pose.
    pub vertical: Option<VerticalCheck>,
}

/// The normal equations of the pose's pixel error, `J^T W J` and `J^T W e`, `W` the weights
/// times the loss's IRLS weights: every observation's pixel residual (a point behind its camera
/// projects through `(x / z, y / z)` like the others, the central `refine`'s residual: its
/// error keeps a wrong pose from fitting the other points alone; one at depth 0 is left out)
/// and its Jacobian in `(omega, delta t)` (`R <- Exp(omega) R`, `t <- t + delta t`) in closed
/// form,
/// `J = [q x a_r, a_r]` per row `r` of `A = J_pi d(x/z, y/z)/dp R_c` (`q = R X`), the 21
/// entries of the symmetric `J^T W J` summed directly.
#[allow(clippy::too_many_arguments)]
fn normal_equations(
    rays: &Rays,
    rig: &Rig,
    loss: Loss,
    r: &Matrix3<f64>,
    t: &Vector3<f64>,
) -> (Matrix6<f64>, Vector6<f64>) {
    let mut h = [0.0; 21];
    let mut g = [0.0; 6];
    for (k, ry) in rays.rays.iter().enumerate() {
        let (rk, tk) = rig.pose(ry.camera);
        let q = r * rays.obs.world[k].coords;
        let p = rk * (q + t) + tk;
        if !(p.z != 0.0) {
            continue;
        }
        let iz = 1.0 / p.z;
        let (x, y) = (p.x * iz, p.y * iz);
        let ((u, v), jp) = rig.projector(ry.camera).project_with_jacobian(x, y);
        let obs = rays.obs.pixels[k];
        let (e0, e1) = (u - obs.x, v - obs.y);
        let w = ry.weight * loss.eval(e0 * e0 + e1 * e1).1;
        // Rows of J_pi d(x/z, y/z)/dp, then times R_c (a^T R_c = (R_c^T a)^T).
        let b0 = Vector3::new(jp[0] * iz, jp[1] * iz, -(jp[0] * x + jp[1] * y) * iz);
        let b1 = Vector3::new(jp[2] * iz, jp[3] * iz, -(jp[2] * x + jp[3] * y) * iz);
        let a0 = rk.tr_mul(&b0);
        let a1 = rk.tr_mul(&b1);
        let (c0, c1) = (q.cross(&a0), q.cross(&a1));
        let j0 = [c0.x, c0.y, c0.z, a0.x, a0.y, a0.z];
        let j1 = [c1.x, c1.y, c1.z, a1.x, a1.y, a1.z];
        let mut k = 0;
        for i in 0..6 {
            let (wi0, wi1) = (w * j0[i], w * j1[i]);
            g[i] += wi0 * e0 + wi1 * e1;
            for jj in i..6 {
                h[k] += wi0 * j0[jj] + wi1 * j1[jj];
                k += 1;
            }
        }
    }
    let mut jtj = Matrix6::zeros();
    let mut k = 0;
    for i in 0..6 {
        for jj in i..6 {
            jtj[(i, jj)] = h[k];
            jtj[(jj, i)] = h[k];
            k += 1;
        }
    }
    (jtj, Vector6::from_column_slice(&g))
}

/// The squared pixel error of ray `k` at the pose (`x_rig = R X + t`), infinite behind its
/// camera.
pub(crate) fn pixel_error2(
    rays: &Rays,
    rig: &Rig,
    k: usize,
    r: &Matrix3<f64>,
    t: &Vector3<f64>,
) -> f64 {
    let ry = &rays.rays[k];
    let (rk, tk) = rig.pose(ry.camera);
    let p = rk * (r * rays.obs.world[k].coords + t) + tk;
    if !(p.z > 0.0) {
        return f64::INFINITY;
    }
    let (u, v) = rig.projector(ry.camera).project(p.x / p.z, p.y / p.z);
    let obs = rays.obs.pixels[k];
    (u - obs.x).powi(2) + (v - obs.y).powi(2)
}

/// `sum w rho(|e|^2)` and `sum w |e|^2` at the pose (infinite if a point is at depth 0; one
/// behind its camera projects through `(x / z, y / z)`, as in [`normal_equations`]) and the number of
/// observations in front of their camera.
fn evaluate(rays: &Rays, rig: &Rig, loss: Loss, r: &Matrix3<f64>, t: &Vector3<f64>) -> Evaluated {
    let mut out = Evaluated {
        cost: 0.0,
        squared: 0.0,
        front: 0,
    };
    for (k, ry) in rays.rays.iter().enumerate() {
        let (rk, tk) = rig.pose(ry.camera);
        let p = rk * (r * rays.obs.world[k].coords + t) + tk;
        let front = p.z > 0.0;
        if !(p.z != 0.0) {
            out.cost = f64::INFINITY;
            continue;
        }
        out.front += usize::from(front);
        let (u, v) = rig.projector(ry.camera).project(p.x / p.z, p.y / p.z);
        let obs = rays.obs.pixels[k];
        let e2 = (u - obs.x).powi(2) + (v - obs.y).powi(2);
        out.cost += ry.weight * loss.eval(e2).0;
        out.squared += ry.weight * e2;
    }
    out
}

/// What [`evaluate`] returns.
#[derive(Clone, Copy)]
struct Evaluated {
    cost: f64,
    squared: f64,
    front: usize,
}

/// Levenberg-Marquardt from `(r, t)` (the original frame), at most `max_iterations`
/// iterations: the central pixel refinement's iteration and pass, per camera
/// ([`crate::pipeline::refine_rig`], in the rays' working frame), on the rays' observations;
/// then the costs, the squared error and the points in front at the returned pose
/// (the iteration's own with the squared loss, otherwise [`evaluate`]). `exact_start`: the start
/// is an exact fit (the object-space cost at its rounding level), from which the last
/// Gauss-Newton step is applied ([`crate::pipeline::ReprojOptions`]).
#[allow(clippy::too_many_arguments)]
pub(crate) fn refine(
    rays: &Rays,
    rig: &Rig,
    loss: Loss,
    (r0, t0): (&Matrix3<f64>, &Vector3<f64>),
    max_iterations: u32,
    exact_start: bool,
    vertical: Option<Vertical>,
) -> Refined {
    let obs = &rays.obs;
    let weight_sum = obs.weight_sum;
    let (mut r, mut t, mut iterations, mut converged) = (*r0, *t0, 0, false);
    let mut check = None;
    if max_iterations > 0 {
        let px = RigPixels {
            world: &obs.world,
            pixels: &obs.pixels,
            normalised: &obs.normalised,
            weights: (!obs.weights.is_empty()).then_some(&obs.weights[..]),
            cameras: &obs.cameras,
            loss,
        };
        let frame = (rays.x_mean, rays.scale);
        let out = refine_rig(&px, frame, r0, t0, max_iterations, exact_start, vertical);
        if out.r.iter().all(|x| x.is_finite()) && out.t.iter().all(|x| x.is_finite()) {
            (r, t, iterations, converged) = (out.r, out.t, out.iterations, out.converged);
            check = out.vertical;
            // The squared loss: the iteration's own cost and count (no further pass).
            if let Some((cost, in_front)) = out.squared.filter(|(c, _)| c.is_finite()) {
                return Refined {
                    r,
                    t,
                    cost,
                    squared: cost,
                    weight_sum,
                    in_front,
                    iterations,
                    converged,
                    vertical: check,
                };
            }
        }
    }
    let e = evaluate(rays, rig, loss, &r, &t);
    Refined {
        r,
        t,
        cost: e.cost,
        squared: e.squared,
        weight_sum,
        in_front: e.front,
        iterations,
        converged,
        vertical: check,
    }
}

/// The pose's covariance (pycolmap's convention, [`crate::covariance`]: `[delta_q, delta_t]`,
/// `R = Exp(2 delta_q) R_hat`) from the Gauss-Newton normal equations of the pixel error at the
/// pose, for the noise `noise` in pixels; `None` if they are singular.
pub(crate) fn covariance(
    rays: &Rays,
    rig: &Rig,
    r: &Matrix3<f64>,
    t: &Vector3<f64>,
    noise: NoiseModel,
) -> Option<PoseCovariance> {
    // The squared loss: `J^T W J` with the weights alone; the sums of [`evaluate`] (infinite
    // if a point is at depth 0: no covariance).
    let (jtj, _) = normal_equations(rays, rig, Loss::Squared, r, t);
    let sums = evaluate(rays, rig, Loss::Squared, r, t);
    if !sums.cost.is_finite() {
        return None;
    }
    let (sq, n) = (sums.squared, rays.rays.len());
    let sigma = match noise {
        NoiseModel::Sigma(s) => s,
        NoiseModel::Estimated => {
            if n <= 3 {
                return None;
            }
            (sq / (2 * n - 6) as f64).sqrt()
        }
    };
    let inv = jtj.cholesky()?.inverse();
    crate::covariance::from_rotation_vector(&(inv * (sigma * sigma)), sigma, None)
}
