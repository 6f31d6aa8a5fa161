//! S10: Levenberg-Marquardt on the pixel residuals through the camera model.
//!
//! With a camera (pixel input), S1-S9 solve on undistorted points: S9 minimises the normalised
//! residuals weighted by the lens distortion's local scale, a first-order stand-in for the
//! pixel error. S10 then minimises the pixel error itself,
//! `E(R, t) = sum_i w_i rho(|u_i - K(pi(R P_i + t))|^2)`, with `u_i` the observed pixel, `K`
//! the camera's projection (distortion included, [`Projector`]), `pi(x, y, z) = (x/z, y/z)`,
//! `w_i` the caller's weight and `rho` the [`Loss`]: for the squared loss the
//! maximum-likelihood pose under isotropic Gaussian pixel noise, for any camera model. With a
//! robust loss the weights are iteratively reweighted (`rho'(r2)` per point), and the step is
//! accepted only if `E` itself decreases.
//!
//! It runs the same Levenberg-Marquardt iteration as S9
//! ([`super::reprojection::levenberg_marquardt`]: damping, depth-sign guard, reuse of
//! `J^T W J`, final step), in S1's working frame, from S9's pose: S9 has already brought the
//! pose to within the first-order difference of the pixel minimum, so S10 typically takes
//! two or three passes. Per point, the Jacobian row of residual `k` is
//! `[g_k x q, -g_k]` with `g_k = d K_k / d p = (J_k / z) [[1, 0, -x], [0, 1, -y]]`, `J` the
//! camera's 2 x 2 Jacobian at the normalised point `(x, y)` and `q` the rotated point.
//!
//! S10 does not run for a pinhole camera with the squared loss: S9 with the row weights
//! `(fx^2, fy^2)` already minimises exactly that cost. With normalised input and a robust loss,
//! S10 runs with the identity camera (residuals in normalised units).

use nalgebra::{Matrix3, Point2, Point3, Vector3};

use super::frame::{WorkingFrame, MIN_UNIT};
use super::options::Loss;
use super::reprojection::{
    levenberg_marquardt, Composed, Normal, ReprojOptions, ReprojOutcome, Residuals,
};
use crate::camera::Projector;
use crate::numeric::mat3::pow2_scale;

/// What S10 needs beyond the solve's inputs: the observations in the camera's units.
#[derive(Clone, Copy)]
pub(crate) struct PixelInputs<'a> {
    /// The observed pixels, parallel to the solve's world points.
    pub pixels: &'a [Point2<f64>],
    /// The caller's weights, parallel (`None`: all 1).
    pub weights: Option<&'a [f64]>,
    /// The camera's projection.
    pub projector: Projector,
    /// The loss of the refinement.
    pub loss: Loss,
    /// Whether S10 runs; `false` when S9 already minimises this cost (a pinhole camera, the
    /// squared loss): the reported cost is then S9's, converted to pixels.
    pub refine: bool,
    /// Pixels per normalised unit of S9's residuals (`max(fx, fy)`; 1 for normalised input).
    pub scale: f64,
}

/// S10's result: the refinement and the sums the solution reports.
pub(crate) struct PixelOutcome {
    pub out: ReprojOutcome,
    /// The weight unit: `out.e * unit` is the caller's cost.
    pub unit: f64,
    /// `sum_i w_i |e_i|^2 / unit` at the returned pose (the plain squared error, also for a
    /// robust loss).
    pub squared: f64,
    /// `sum_i w_i / unit` over the points of non-zero weight.
    pub weight_sum: f64,
}

/// The residuals of S10 ([`Residuals`]).
struct PixelProblem<'a> {
    world: &'a [Point3<f64>],
    pixels: &'a [Point2<f64>],
    weights: Option<&'a [f64]>,
    /// `1 / unit`: the weights in a power-of-two unit (largest in `[1, 2)`).
    inv_weight: f64,
    c: Vector3<f64>,
    projector: Projector,
    loss: Loss,
}

/// Number of sums: `E` (1), `J^T W J` (21, upper triangle row-major), `g` (6).
const NSUMS: usize = 28;

impl PixelProblem<'_> {
    // Index loops fill the triangle of J^T W J by position.
    #[allow(clippy::needless_range_loop)]
    /// One pass at `pose` with `loss` (see [`Residuals::accumulate`]). `HESS`: form
    /// `J^T W J` (otherwise `h` is zero).
    fn pass<const HESS: bool>(
        &self,
        pose: &Composed,
        reference: Option<&Composed>,
        loss: Loss,
    ) -> Option<Normal> {
        let a = &pose.a;
        let t = &pose.t;
        let mut s = [0.0f64; NSUMS];
        let mut min_abs_z = f64::INFINITY;
        let mut max_abs_z = 0.0f64;
        let mut max_q2 = 0.0f64;
        let ref_row = reference.map(|rf| (rf.a.row(2).transpose(), rf.t.z));
        for (i, (x, u)) in self.world.iter().zip(self.pixels).enumerate() {
            let w = self.weights.map_or(1.0, |w| w[i] * self.inv_weight);
            if w == 0.0 {
                continue;
            }
            let xc = x.coords - self.c;
            let q = a * xc;
            let p = q + t;
            if let Some((ra, rtz)) = &ref_row {
                let z_ref = ra.dot(&xc) + rtz;
                let same_side = if z_ref > 0.0 { p.z > 0.0 } else { p.z < 0.0 };
                if !same_side {
                    return None;
                }
            } else {
                max_q2 = max_q2.max(q.norm_squared());
            }
            let az = p.z.abs();
            min_abs_z = min_abs_z.min(az);
            max_abs_z = max_abs_z.max(az);
            let iz = 1.0 / p.z;
            let (mx, my) = (p.x * iz, p.y * iz);
            let ((px, py), j) = self.projector.project_with_jacobian(mx, my);
            let (ex, ey) = (u.x - px, u.y - py);
            let (rho, drho) = loss.eval(ex * ex + ey * ey);
            s[0] += w * rho;
            let sw = w * drho;
            // g_k = d K_k / d p; the residual rows are [g_k x q, -g_k].
            let g0 = Vector3::new(j[0] * iz, j[1] * iz, -(j[0] * mx + j[1] * my) * iz);
            let g1 = Vector3::new(j[2] * iz, j[3] * iz, -(j[2] * mx + j[3] * my) * iz);
            let c0 = g0.cross(&q);
            let c1 = g1.cross(&q);
            let r0 = [c0.x, c0.y, c0.z, -g0.x, -g0.y, -g0.z];
            let r1 = [c1.x, c1.y, c1.z, -g1.x, -g1.y, -g1.z];
            let (bx, by) = (sw * ex, sw * ey);
            for k in 0..6 {
                s[22 + k] += bx * r0[k] + by * r1[k];
            }
            if HESS {
                let mut idx = 1;
                for k in 0..6 {
                    let (a0, a1) = (sw * r0[k], sw * r1[k]);
                    for l in k..6 {
                        s[idx] += a0 * r0[l] + a1 * r1[l];
                        idx += 1;
                    }
                }
            }
        }
        let mut h = [[0.0f64; 6]; 6];
        if HESS {
            let mut idx = 1;
            for k in 0..6 {
                for l in k..6 {
                    h[k][l] = s[idx];
                    h[l][k] = s[idx];
                    idx += 1;
                }
            }
        }
        Some(Normal {
            h,
            g: core::array::from_fn(|k| s[22 + k]),
            e: s[0],
            min_abs_z,
            max_abs_z,
            max_abs_q: if reference.is_some() {
                f64::NAN
            } else {
                max_q2.sqrt()
            },
        })
    }
}

impl Residuals for PixelProblem<'_> {
    fn accumulate(&self, pose: &Composed, reference: Option<&Composed>) -> Option<Normal> {
        self.pass::<true>(pose, reference, self.loss)
    }

    fn accumulate_gradient(
        &self,
        pose: &Composed,
        reference: &Composed,
        h_prev: &[[f64; 6]; 6],
    ) -> Option<Normal> {
        self.pass::<false>(pose, Some(reference), self.loss)
            .map(|mut nrm| {
                nrm.h = *h_prev;
                nrm
            })
    }
}

/// S10 from the working-frame pose `(r_work, t_work)` (S9's result). `world` are the solve's
/// world points, `px` their observations; `fr` is S1's working frame. No allocation.
pub(crate) fn refine_pixels(
    world: &[Point3<f64>],
    px: &PixelInputs<'_>,
    fr: &WorkingFrame,
    r_work: &Matrix3<f64>,
    t_work: &Vector3<f64>,
    opts: &ReprojOptions,
) -> PixelOutcome {
    debug_assert_eq!(world.len(), px.pixels.len());
    // The caller's weights in a power-of-two unit, so that no sum overflows or underflows.
    let unit = px.weights.map_or(1.0, |w| {
        let wmax = w.iter().fold(0.0f64, |m, &x| m.max(x));
        if wmax > 0.0 {
            pow2_scale(wmax).max(MIN_UNIT)
        } else {
            1.0
        }
    });
    let prob = PixelProblem {
        world,
        pixels: px.pixels,
        weights: px.weights,
        inv_weight: 1.0 / unit,
        c: fr.c,
        projector: px.projector,
        loss: px.loss,
    };
    let out = levenberg_marquardt(&prob, fr, r_work, t_work, opts);
    let weight_sum = px.weights.map_or(world.len() as f64, |w| {
        w.iter().map(|&x| x / unit).sum::<f64>()
    });
    let squared = if px.loss == Loss::Squared {
        out.e
    } else {
        let pose = Composed::new(&out.r, &fr.rw, fr.d, &out.t);
        prob.pass::<false>(&pose, None, Loss::Squared)
            .map_or(f64::NAN, |n| n.e)
    };
    PixelOutcome {
        out,
        unit,
        squared,
        weight_sum,
    }
}
