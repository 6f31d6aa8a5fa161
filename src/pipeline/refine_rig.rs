//! The `refine_rig` stage: Levenberg-Marquardt on the pixel error of a rig's observations, each
//! through its own camera (its pose in the rig, its model and distortion).
//!
//! It is `refine_pixels` per camera: `refine`'s Levenberg-Marquardt iteration
//! ([`super::refine::levenberg_marquardt`]: damping, depth-sign guard, reuse of `J^T W J`, final
//! step) over the rig's pose, and each pass is `refine`'s vectorised pass ([`pass`]) over each
//! camera's observations (contiguous) with that camera's metric ([`CameraMetric`]; for a camera
//! without distortion and the squared loss, `refine`'s row weights on the undistorted points,
//! [`RigCamera::rows`]), composed into the rig's normal equations. With the rig's pose
//! `(R, t)` (`x_rig = R X + t`) and camera `k`'s pose in the rig `(R_k, t_k)`, the camera sees
//! `x_k = R_k R X + R_k t + t_k`, a central pose; the rig's update `R <- Exp(w) R`,
//! `t <- t + tau` is that camera's update by `(R_k w, R_k tau)`, since
//! `R_k Exp(w) = Exp(R_k w) R_k`. So with the camera's normal equations `H_k`, `g_k` (in its own
//! update), the rig's are `D_k^T H_k D_k` and `D_k^T g_k` summed over the cameras,
//! `D_k = diag(R_k, R_k)`. Depth signs, the depth range, the lever arms `|q_i|`
//! (`|R_k q| = |q|`) and the points in front carry over, so the final-step rule of `refine`
//! holds as it is: a depth `z = e_3^T x_k` moves by at most `|delta| (|q_i| + 1)`.
//!
//! The working frame: `P_i = (X_i - c) / d` (the caller's: the centroid of the world points and
//! their RMS distance from it), the pose `x_rig / d = R P_i + t_w`, so every camera's translation
//! enters as `t_k / d`. No allocation.

use core::ops::Range;

use nalgebra::{Matrix3, Point2, Point3, Vector3};

use super::options::Loss;
use super::refine::pass::{pass, Metric, PassInputs, RowWeights};
use super::refine::{
    levenberg_marquardt, Composed, Hessian, Normal, ReprojOptions, ReprojStop, Residuals,
};
use super::refine_pixels::{weight_unit, CameraMetric};
use super::vertical::{Vertical, VerticalCheck};
use crate::camera::{Project, ProjectionJob, Projector};

/// One camera of a rig and its observations (a range of [`RigPixels`]' arrays).
#[derive(Clone, Debug)]
pub(crate) struct RigCamera {
    /// The camera's projection.
    pub projector: Projector,
    /// `(fx^2, fy^2)` for a camera without distortion: its pixel error is the normalised
    /// error `m - (x / z, y / z)` with these row weights (`m` the undistorted pixel), the
    /// central `refine`'s residual, cheaper per point than the camera's projection and its
    /// Jacobian. With a robust loss every camera's error goes through its projection.
    pub rows: Option<(f64, f64)>,
    /// `cam_from_rig`: `x_k = rotation x_rig + translation`.
    pub rotation: Matrix3<f64>,
    pub translation: Vector3<f64>,
    /// Its observations in [`RigPixels`]' arrays.
    pub range: Range<usize>,
}

/// A rig's observations grouped by camera: world points, pixels and weights (all > 0), each
/// camera's a contiguous range.
#[derive(Clone, Copy)]
pub(crate) struct RigPixels<'a> {
    pub world: &'a [Point3<f64>],
    pub pixels: &'a [Point2<f64>],
    /// The pixels undistorted (normalised image points).
    pub normalised: &'a [Point2<f64>],
    /// `None`: every weight 1.
    pub weights: Option<&'a [f64]>,
    pub cameras: &'a [RigCamera],
    pub loss: Loss,
}

/// `refine_rig`'s result.
#[derive(Clone, Copy, Debug)]
pub(crate) struct RigOutcome {
    /// The rig's pose, `x_rig = r X + t`.
    pub r: Matrix3<f64>,
    pub t: Vector3<f64>,
    pub iterations: u32,
    pub converged: bool,
    /// With the squared loss, when the iteration ran: the pixel cost `sum w |e|^2` at the
    /// returned pose (after a final step taken unverified, the linear model's prediction of it,
    /// as `refine`'s), and the observations in front of their camera (those at the start: no
    /// step moves a point across its camera's plane).
    pub squared: Option<(f64, usize)>,
    /// With a known vertical, its test at the maximum-likelihood pose.
    pub vertical: Option<VerticalCheck>,
}

/// The residuals of a rig ([`Residuals`]).
struct RigResiduals<'a> {
    px: &'a RigPixels<'a>,
    /// `1 / w_unit`.
    inv_weight: f64,
    c: Vector3<f64>,
    /// `1 / d`: the cameras' translations in the working frame's unit.
    inv_d: f64,
}

/// One camera's pass, its lens model fixed at compile time.
struct CameraPass<'a> {
    world: &'a [Point3<f64>],
    pixels: &'a [Point2<f64>],
    weights: Option<&'a [f64]>,
    /// (By reference: the job is moved by value into the lens model's dispatch.)
    k: &'a PassInputs,
    loss: Loss,
    check: bool,
    h: Option<&'a mut Hessian>,
}

impl ProjectionJob for CameraPass<'_> {
    type Output = Option<Normal>;

    fn run<P: Project + Copy>(self, projection: P) -> Option<Normal> {
        if self.loss == Loss::Squared {
            self.with(&CameraMetric::<P, false> {
                projection,
                loss: Loss::Squared,
            })
        } else {
            let loss = self.loss;
            self.with(&CameraMetric::<P, true> { projection, loss })
        }
    }
}

impl CameraPass<'_> {
    fn with<M: Metric>(self, metric: &M) -> Option<Normal> {
        let (k, w, m, wt) = (self.k, self.world, self.pixels, self.weights);
        match (self.check, self.h) {
            (true, Some(h)) => pass::<true, true, M>(k, metric, w, m, wt, Some(h)),
            (false, Some(h)) => pass::<false, true, M>(k, metric, w, m, wt, Some(h)),
            (true, None) => pass::<true, false, M>(k, metric, w, m, wt, None),
            (false, None) => pass::<false, false, M>(k, metric, w, m, wt, None),
        }
    }
}

impl RigResiduals<'_> {
    /// The pass of every camera at `pose`, composed into the rig's normal equations (module
    /// docs); `h` is `J^T W J`'s buffer (`None`: not formed).
    // Index loops fill the blocks of H by position.
    #[allow(clippy::needless_range_loop)]
    fn passes(
        &self,
        pose: &Composed,
        reference: Option<&Composed>,
        mut h: Option<&mut Hessian>,
    ) -> Option<Normal> {
        let mut total = Normal {
            g: [0.0; 6],
            e: 0.0,
            min_abs_z: f64::INFINITY,
            max_abs_z: 0.0,
            max_abs_q: if reference.is_some() { f64::NAN } else { 0.0 },
            in_front: reference.is_none().then_some(0),
        };
        if let Some(h) = h.as_deref_mut() {
            *h = [[0.0; 6]; 6];
        }
        let at = |p: &Composed, cam: &RigCamera| Composed {
            a: cam.rotation * p.a,
            t: cam.rotation * p.t + cam.translation * self.inv_d,
        };
        // Each camera's `J^T W J`: every entry written by its pass, so one buffer serves all.
        let mut hk: Hessian = [[0.0; 6]; 6];
        for cam in self.px.cameras {
            if cam.range.is_empty() {
                continue;
            }
            let pose_k = at(pose, cam);
            let ref_k = reference.map(|rf| at(rf, cam));
            let k = PassInputs::new(&self.c, self.inv_weight, &pose_k, ref_k.as_ref());
            // A camera without distortion, with the squared loss: `refine`'s residual on its
            // undistorted points ([`RigCamera::rows`]); otherwise its projection's.
            let rows = cam.rows.filter(|_| self.px.loss == Loss::Squared);
            let r = cam.range.clone();
            let job = CameraPass {
                world: &self.px.world[r.clone()],
                pixels: if rows.is_some() {
                    &self.px.normalised[r.clone()]
                } else {
                    &self.px.pixels[r.clone()]
                },
                weights: self.px.weights.map(|w| &w[r]),
                k: &k,
                loss: self.px.loss,
                check: reference.is_some(),
                h: h.is_some().then_some(&mut hk),
            };
            let nk = match rows {
                Some((wx, wy)) => job.with(&RowWeights { wx, wy }),
                None => cam.projector.with_projection(job),
            }?;
            let rk = &cam.rotation;
            // g += D^T g_k, H += D^T H_k D (3 x 3 blocks).
            for b in 0..2 {
                let gb = rk.tr_mul(&Vector3::from_column_slice(&nk.g[3 * b..3 * b + 3]));
                for i in 0..3 {
                    total.g[3 * b + i] += gb[i];
                }
            }
            if let Some(h) = h.as_deref_mut() {
                for bi in 0..2 {
                    for bj in bi..2 {
                        let blk = Matrix3::from_fn(|i, j| hk[3 * bi + i][3 * bj + j]);
                        let out = rk.tr_mul(&blk) * rk;
                        for i in 0..3 {
                            for j in 0..3 {
                                h[3 * bi + i][3 * bj + j] += out[(i, j)];
                            }
                        }
                    }
                }
            }
            total.e += nk.e;
            total.min_abs_z = total.min_abs_z.min(nk.min_abs_z);
            total.max_abs_z = total.max_abs_z.max(nk.max_abs_z);
            if reference.is_none() {
                total.max_abs_q = total.max_abs_q.max(nk.max_abs_q);
            }
            if let (Some(a), Some(b)) = (total.in_front.as_mut(), nk.in_front) {
                *a += b;
            }
        }
        if let Some(h) = h {
            for i in 3..6 {
                for j in 0..3 {
                    h[i][j] = h[j][i];
                }
            }
        }
        Some(total)
    }
}

impl Residuals for RigResiduals<'_> {
    fn accumulate(
        &self,
        pose: &Composed,
        reference: Option<&Composed>,
        h: &mut Hessian,
    ) -> Option<Normal> {
        self.passes(pose, reference, Some(h))
    }

    fn accumulate_gradient(&self, pose: &Composed, reference: &Composed) -> Option<Normal> {
        self.passes(pose, Some(reference), None)
    }
}

/// Levenberg-Marquardt on the pixel error of the rig's observations from the rig's pose
/// `(r, t)` (`x_rig = r X + t`) in the working frame `P_i = (X_i - c) / d` (`d > 0`), at most `max_iterations` iterations (`refine`'s options
/// otherwise; `exact_start`: the start is an exact fit, [`ReprojOptions::exact_start`];
/// `vertical`: on to the maximum a posteriori pose, the `vertical` stage). A starting depth at
/// zero (relative to the others) leaves the pose as it is (not converged).
pub(crate) fn refine_rig(
    px: &RigPixels<'_>,
    (c, d): (Vector3<f64>, f64),
    r: &Matrix3<f64>,
    t: &Vector3<f64>,
    max_iterations: u32,
    exact_start: bool,
    vertical: Option<Vertical>,
) -> RigOutcome {
    let unit = weight_unit(px.weights);
    let prob = RigResiduals {
        px,
        inv_weight: 1.0 / unit,
        c,
        inv_d: 1.0 / d,
    };
    let opts = ReprojOptions {
        max_iterations,
        exact_start,
        vertical,
        ..ReprojOptions::default()
    };
    let t_work = (r * c + t) / d;
    let out = levenberg_marquardt(&prob, &Matrix3::identity(), d, r, &t_work, &opts);
    let squared = match (px.loss, out.start_in_front) {
        (Loss::Squared, Some(front)) if out.stop != ReprojStop::SkippedZeroDepth => {
            Some((out.e * unit, front))
        }
        _ => None,
    };
    RigOutcome {
        r: out.r,
        t: out.t * d - out.r * c,
        iterations: out.iterations,
        converged: out.stop.converged(),
        squared,
        vertical: out.vertical,
    }
}
