//! The `refine_pixels` stage: Levenberg-Marquardt on the pixel residuals through the camera model.
//!
//! With a camera (pixel input), the stages `frame` to `select` solve on the undistorted points,
//! with the caller's weights only: they give `refine_pixels`' start (the lens distortion's local
//! scale, a first-order stand-in for the pixel error, weights them only in the algebraic mode,
//! where their pose is the result). `refine_pixels` minimises the pixel error itself,
//! `E(R, t) = sum_i w_i rho(|u_i - K(pi(R P_i + t))|^2)`, with `u_i` the observed pixel, `K` the
//! camera's projection (distortion included, [`Projector`]), `pi(x, y, z) = (x/z, y/z)`, `w_i` the
//! caller's weight and `rho` the [`Loss`]: for the squared loss the maximum-likelihood pose under
//! isotropic Gaussian pixel noise, for any camera model. With a robust loss the weights are
//! iteratively reweighted (`rho'(r2)` per point), and a step is accepted only if `E` itself
//! decreases.
//!
//! It runs `refine`'s Levenberg-Marquardt iteration ([`super::refine::levenberg_marquardt`]:
//! damping, depth-sign guard, reuse of `J^T W J`, final step) and `refine`'s vectorised pass
//! ([`super::refine::pass`]) with the camera's metric ([`CameraMetric`]): at the normalised
//! projection of a point, `C = w rho' J^T J` and `e~ = w rho' J^T e` (`J` the camera's Jacobian,
//! `e` the pixel residual) take the place of `refine`'s row weights and normalised residual. The
//! lens model is fixed at compile time ([`Projector::with_projection`]). `refine_pixels` starts
//! from `select`'s minimum, in place of `refine` (which runs only if `refine_pixels` cannot: a
//! point at depth 0, a non-finite result). Starting it from `refine`'s minimum instead saves about
//! one `refine_pixels` pass but costs `refine`'s two or three passes (on the bundled COLMAP model:
//! 17 % more instructions per image, callgrind).
//!
//! `refine_pixels` does not run for a pinhole camera with the squared loss: `refine` with the row
//! weights `(fx^2, fy^2)` already minimises exactly that cost. With normalised input and a robust
//! loss, `refine_pixels` runs with the identity camera (residuals in normalised units).

use nalgebra::{Matrix3, Point2, Point3, Vector3};

use super::frame::{WorkingFrame, MIN_UNIT};
use super::options::Loss;
use super::refine::pass::{LaneMetric, Metric};
use super::refine::{levenberg_marquardt, Composed, Problem, ReprojOptions, ReprojOutcome};
use crate::camera::{Project, ProjectionJob, Projector};
use crate::numeric::mat3::pow2_scale;

/// What `refine_pixels` needs beyond the solve's inputs: the observations in the camera's units.
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
    /// Whether `refine_pixels` runs; `false` when `refine` already minimises this cost (a pinhole
    /// camera, the squared loss): the reported cost is then `refine`'s, converted to pixels.
    pub refine: bool,
    /// Pixels per normalised unit of `refine`'s residuals (`max(fx, fy)`; 1 for normalised input).
    pub scale: f64,
}

/// `refine_pixels`' result: the refinement and the sums the solution reports.
pub(crate) struct PixelOutcome {
    pub out: ReprojOutcome,
    /// The weight unit: `out.e * unit` is the caller's cost.
    pub unit: f64,
    /// `sum_i w_i |e_i|^2 / unit` at the returned pose (the plain squared error, also for a
    /// robust loss), divided by `squared_scale^2`.
    pub squared: f64,
    /// A power of two: with a robust loss, above the largest residual component (so that the sum
    /// cannot overflow while every residual is finite: a robust loss grows slowly enough to
    /// refine residuals whose squares overflow); 1 with the squared loss, whose cost is the sum.
    pub squared_scale: f64,
    /// `sum_i w_i / unit` over the points of non-zero weight.
    pub weight_sum: f64,
}

/// `refine_pixels`' metric ([`Metric`]): the pixel residual through the projection `P`, with the
/// loss when `ROBUST` (the squared loss otherwise, `rho' = 1` compiled in).
pub(super) struct CameraMetric<P, const ROBUST: bool> {
    pub(super) projection: P,
    pub(super) loss: Loss,
}

impl<P: Project, const ROBUST: bool> Metric for CameraMetric<P, ROBUST> {
    const DIAGONAL: bool = false;

    /// At the normalised projection `(u, v)`: the pixel residual `e = m - K(u, v)`, the
    /// camera's Jacobian `J`, `s = w rho'(|e|^2)`; `C = s J^T J`, `e~ = s J^T e`, cost
    /// `w rho(|e|^2)`.
    #[inline(always)]
    fn at(&self, m: [f64; 2], w: f64, u: f64, v: f64) -> LaneMetric {
        let ((px, py), j) = self.projection.project_with_jacobian(u, v);
        let (e0, e1) = (m[0] - px, m[1] - py);
        let r2 = e0 * e0 + e1 * e1;
        let (rho, drho) = if ROBUST {
            self.loss.eval(r2)
        } else {
            (r2, 1.0)
        };
        let s = w * drho;
        LaneMetric {
            cost: w * rho,
            c00: s * (j[0] * j[0] + j[2] * j[2]),
            c01: s * (j[0] * j[1] + j[2] * j[3]),
            c11: s * (j[1] * j[1] + j[3] * j[3]),
            ex: s * (j[0] * e0 + j[2] * e1),
            ey: s * (j[1] * e0 + j[3] * e1),
        }
    }
}

/// `refine_pixels` with the camera's model fixed at compile time: the refinement, and the plain
/// squared error at its pose.
struct Job<'a> {
    world: &'a [Point3<f64>],
    px: &'a PixelInputs<'a>,
    fr: &'a WorkingFrame,
    r_work: &'a Matrix3<f64>,
    t_work: &'a Vector3<f64>,
    opts: &'a ReprojOptions,
    inv_weight: f64,
}

impl ProjectionJob for Job<'_> {
    /// The refinement, the plain squared error at its pose and that error's scale (see
    /// [`PixelOutcome::squared_scale`]).
    type Output = (ReprojOutcome, f64, f64);

    fn run<P: Project + Copy>(self, projection: P) -> (ReprojOutcome, f64, f64) {
        let fr = self.fr;
        if self.px.loss == Loss::Squared {
            let squared = self.problem(CameraMetric::<P, false> {
                projection,
                loss: Loss::Squared,
            });
            let out =
                levenberg_marquardt(&squared, &fr.rw, fr.d, self.r_work, self.t_work, self.opts);
            return (out, out.e, 1.0);
        }
        let robust = self.problem(CameraMetric::<P, true> {
            projection,
            loss: self.px.loss,
        });
        let out = levenberg_marquardt(&robust, &fr.rw, fr.d, self.r_work, self.t_work, self.opts);
        // The plain squared error at the pose (for the RMS residual), scaled.
        let pose = Composed::new(&out.r, &fr.rw, fr.d, &out.t);
        let (e, scale) = self.scaled_squared_error(projection, &pose);
        (out, e, scale)
    }
}

impl<'a> Job<'a> {
    /// `(sum_i w_i |e_i / s|^2 / unit, s)` at `pose`, `s` a power of two at least the largest
    /// residual component (1 if all are 0), in one pass: when a component exceeds the scale,
    /// the scale grows to its power of two and the sum so far is rescaled (exactly, by a power
    /// of two, as LAPACK's scaled sums of squares do). `(+inf, 1)` if a residual is not finite
    /// (a point at depth 0).
    fn scaled_squared_error<P: Project + Copy>(
        &self,
        projection: P,
        pose: &Composed,
    ) -> (f64, f64) {
        let n = self.world.len().min(self.px.pixels.len());
        let (mut scale, mut sum) = (0.0f64, 0.0f64);
        for k in 0..n {
            let w = self.px.weights.map_or(1.0, |w| w[k] * self.inv_weight);
            if !(w > 0.0) {
                continue;
            }
            let p = pose.a * (self.world[k].coords - self.fr.c) + pose.t;
            let (px, py) = projection.project(p.x / p.z, p.y / p.z);
            let m = self.px.pixels[k];
            let (ex, ey) = (m.x - px, m.y - py);
            if !(ex.is_finite() && ey.is_finite()) {
                return (f64::INFINITY, 1.0);
            }
            let largest = ex.abs().max(ey.abs());
            if largest >= scale && largest > 0.0 {
                let grown = 2.0 * pow2_scale(largest);
                if scale > 0.0 {
                    let f = scale / grown;
                    sum *= f * f;
                }
                scale = grown;
            }
            if scale > 0.0 {
                let (ex, ey) = (ex / scale, ey / scale);
                sum += w * (ex * ex + ey * ey);
            }
        }
        if scale > 0.0 {
            (sum, scale)
        } else {
            (0.0, 1.0)
        }
    }

    /// The refinement problem of these observations under `metric`.
    fn problem<M>(&self, metric: M) -> Problem<'a, M> {
        Problem {
            world: self.world,
            image: self.px.pixels,
            weights: self.px.weights,
            inv_weight: self.inv_weight,
            c: self.fr.c,
            metric,
        }
    }
}

/// The caller's weights' unit: a power of two near the largest (at least [`MIN_UNIT`]; 1 without
/// weights, or with all 0), so that no sum of weights in that unit overflows or underflows.
pub(super) fn weight_unit(weights: Option<&[f64]>) -> f64 {
    weights.map_or(1.0, |w| {
        let wmax = w.iter().fold(0.0f64, |m, &x| m.max(x));
        if wmax > 0.0 {
            pow2_scale(wmax).max(MIN_UNIT)
        } else {
            1.0
        }
    })
}

/// `refine_pixels` from the working-frame pose `(r_work, t_work)` (`refine`'s result). `world` are
/// the solve's world points, `px` their observations; `fr` is `frame`'s working frame. No
/// allocation.
pub(crate) fn refine_pixels(
    world: &[Point3<f64>],
    px: &PixelInputs<'_>,
    fr: &WorkingFrame,
    r_work: &Matrix3<f64>,
    t_work: &Vector3<f64>,
    opts: &ReprojOptions,
) -> PixelOutcome {
    debug_assert_eq!(world.len(), px.pixels.len());
    let unit = weight_unit(px.weights);
    let weight_sum = px.weights.map_or(world.len() as f64, |w| {
        w.iter().map(|&x| x / unit).sum::<f64>()
    });
    let job = Job {
        world,
        px,
        fr,
        r_work,
        t_work,
        opts,
        inv_weight: 1.0 / unit,
    };
    let (out, squared, squared_scale) = px.projector.with_projection(job);
    PixelOutcome {
        out,
        unit,
        squared,
        squared_scale,
        weight_sum,
    }
}
