//! The `refine_focal` stage: Levenberg-Marquardt on the pixel error over the pose and the focal
//! length together, through the camera model (the maximum-likelihood pose and focal length
//! when the focal length is unknown, [`crate::Problem::unknown_focal`]).
//!
//! Minimises `E(R, t, a) = sum_i w_i |m_i - c - a (K(pi(R (X_i - x0) + t)) - c)|^2`: `K` the
//! given camera's projection (distortion included, its focal length the starting guess), `c` its
//! principal point, `a` the focal length's scale (all focal lengths of the camera scaled alike:
//! square pixels stay square), `x0` the weighted centroid of the world points (conditioning).
//! Steps `R := Exp(w) R`, `t := t + dt`, `a := a exp(da)`: seven parameters, Marquardt's
//! scaling of the damping by the diagonal of `J^T W J`, a step accepted only if it lowers `E` and
//! keeps the sign of every depth (as `refine`'s). A pixel whose distortion at the current scale is outside the
//! model's domain costs nothing here: the caller passes the correspondences that undistort.
//!
//! O(N) per pass (the depth signs of the start kept in one vector); simpler than `refine`'s vectorised pass (this stage runs
//! once per solve with an unknown focal length, after a search that costs far more).

use nalgebra::{Matrix3, Point2, Point3, SMatrix, SVector, Vector3};

use crate::camera::Camera;
use crate::numeric::rotation::exp_so3;

/// The result of [`refine_focal`].
#[derive(Clone, Copy, Debug)]
pub(crate) struct FocalOutcome {
    /// The world-to-camera rotation.
    pub r: Matrix3<f64>,
    /// The translation, `x_cam = R X + t`.
    pub t: Vector3<f64>,
    /// The focal length's scale over the camera's.
    pub scale: f64,
    /// `E` at the returned parameters (pixels^2, the caller's weights).
    pub cost: f64,
    /// Levenberg-Marquardt iterations.
    pub iterations: u32,
    /// Whether a convergence test stopped it (not the iteration cap).
    pub converged: bool,
}

/// Iteration cap of a refinement to convergence.
pub(crate) const MAX_ITERATIONS: u32 = 200;
/// Stop when the step is below this relative to the parameters (`|t| + 1` and 1 for the
/// rotation and the log-scale).
const XTOL: f64 = 1e-12;
/// Stop when the relative decrease of the cost is below this.
const FTOL: f64 = 1e-15;

/// The problem's data.
pub(crate) struct FocalInputs<'a> {
    pub world: &'a [Point3<f64>],
    pub pixels: &'a [Point2<f64>],
    pub weights: Option<&'a [f64]>,
    pub camera: &'a Camera,
}

/// The normal equations at one point of the parameter space: `E`, `J^T W J` and `J^T W r` (the
/// residuals `r = model - m`), or `None` if the depth of a point with a positive weight is 0
/// or has another sign than in `front` (`front[i]`: point `i` in front at the start; `None`: the
/// start itself, whose signs are recorded), or a residual is not finite.
fn normal(
    inp: &FocalInputs<'_>,
    x0: &Vector3<f64>,
    (r, t, a): (&Matrix3<f64>, &Vector3<f64>, f64),
    front: &mut [bool],
    record: bool,
) -> Option<(f64, SMatrix<f64, 7, 7>, SVector<f64, 7>)> {
    let with_h = true;
    let (cx, cy) = inp.camera.principal_point();
    let proj = inp.camera.projector();
    let mut e = 0.0;
    let mut h = SMatrix::<f64, 7, 7>::zeros();
    let mut g = SVector::<f64, 7>::zeros();
    for (i, (x, m)) in inp.world.iter().zip(inp.pixels).enumerate() {
        let w = inp.weights.map_or(1.0, |w| w[i]);
        if !(w > 0.0) {
            continue;
        }
        let q = r * (x.coords - x0);
        let p = q + t;
        if !(p.z != 0.0) {
            return None;
        }
        if record {
            front[i] = p.z > 0.0;
        } else if front[i] != (p.z > 0.0) {
            return None;
        }
        let (nx, ny) = (p.x / p.z, p.y / p.z);
        let ((px, py), jc) = proj.project_with_jacobian(nx, ny);
        let (dx, dy) = (px - cx, py - cy);
        let res = [cx + a * dx - m.x, cy + a * dy - m.y];
        if !(res[0].is_finite() && res[1].is_finite()) {
            return None;
        }
        e += w * (res[0] * res[0] + res[1] * res[1]);
        // d pixel / d p = a J_cam (1 / z) [[1, 0, -nx], [0, 1, -ny]].
        let iz = 1.0 / p.z;
        let dn = nalgebra::Matrix2x3::new(iz, 0.0, -nx * iz, 0.0, iz, -ny * iz);
        let jcm = nalgebra::Matrix2::new(jc[0], jc[1], jc[2], jc[3]) * a;
        let dp = jcm * dn;
        // Rows: [dp (-[q]x), dp, (dx, dy)].
        let dw = -(dp * q.cross_matrix());
        let mut rows = [[0.0; 7]; 2];
        for k in 0..3 {
            rows[0][k] = dw[(0, k)];
            rows[1][k] = dw[(1, k)];
            rows[0][3 + k] = dp[(0, k)];
            rows[1][3 + k] = dp[(1, k)];
        }
        rows[0][6] = a * dx;
        rows[1][6] = a * dy;
        for (row, ri) in rows.iter().zip(res) {
            for j in 0..7 {
                g[j] += w * row[j] * ri;
                if with_h {
                    for k in j..7 {
                        h[(j, k)] += w * row[j] * row[k];
                    }
                }
            }
        }
    }
    if with_h {
        for j in 0..7 {
            for k in 0..j {
                h[(j, k)] = h[(k, j)];
            }
        }
    }
    e.is_finite().then_some((e, h, g))
}

/// Levenberg-Marquardt over pose and focal scale from `(r0, t0, a0)` (`x_cam = R X + t`, the
/// focal lengths `a0` times the camera's), at most `max_iterations` iterations ([`MAX_ITERATIONS`]
/// to convergence; RANSAC's local fits take a few, their result only re-scored). Returns `None`
/// if the start has a point at depth 0 (or a non-finite residual).
pub(crate) fn refine_focal(
    inp: &FocalInputs<'_>,
    r0: &Matrix3<f64>,
    t0: &Vector3<f64>,
    a0: f64,
    max_iterations: u32,
) -> Option<FocalOutcome> {
    // Conditioning: world points relative to their weighted centroid.
    let (mut sum, mut wsum) = (Vector3::zeros(), 0.0);
    for (i, x) in inp.world.iter().enumerate() {
        let w = inp.weights.map_or(1.0, |w| w[i]);
        if w > 0.0 {
            sum += x.coords * w;
            wsum += w;
        }
    }
    if !(wsum > 0.0) {
        return None;
    }
    let x0 = sum / wsum;
    let mut r = *r0;
    let mut t = t0 + r0 * x0;
    let mut a = a0;
    // The depth signs at the start, which no accepted step changes (as `refine`'s).
    let mut front = vec![false; inp.world.len()];
    let (mut e, mut h, mut g) = normal(inp, &x0, (&r, &t, a), &mut front, true)?;
    let mut lam = 1e-6;
    let mut converged = false;
    let mut iterations = 0;
    for it in 1..=max_iterations {
        iterations = it;
        // Marquardt: the damping scaled by the diagonal.
        let mut hd = h;
        for j in 0..7 {
            hd[(j, j)] += lam * h[(j, j)].max(1e-300);
        }
        let Some(chol) = hd.cholesky() else {
            lam *= 10.0;
            if lam > 1e16 {
                break;
            }
            continue;
        };
        let delta = chol.solve(&(-g));
        let w = Vector3::new(delta[0], delta[1], delta[2]);
        let dt = Vector3::new(delta[3], delta[4], delta[5]);
        let scale = t.norm() + 1.0;
        if w.norm() + dt.norm() / scale + delta[6].abs() <= XTOL {
            converged = true;
            break;
        }
        let r_new = exp_so3(&w) * r;
        let t_new = t + dt;
        let a_new = a * delta[6].exp();
        match normal(inp, &x0, (&r_new, &t_new, a_new), &mut front, false) {
            Some((e_new, h_new, g_new)) if e_new < e => {
                let small = (e - e_new) <= FTOL * e;
                (r, t, a, e, h, g) = (r_new, t_new, a_new, e_new, h_new, g_new);
                lam = (lam / 10.0).max(1e-12);
                if small {
                    converged = true;
                    break;
                }
            }
            _ => {
                lam *= 10.0;
                if lam > 1e16 {
                    // No step lowers the cost: a minimum to working precision.
                    converged = true;
                    break;
                }
            }
        }
    }
    Some(FocalOutcome {
        r,
        t: t - r * x0,
        scale: a,
        cost: e,
        iterations,
        converged,
    })
}

#[cfg(test)]
#[path = "../../tests/unit/pipeline/refine_focal.rs"]
mod tests;
