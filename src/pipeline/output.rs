//! The `output` stage of docs/algorithm.md, with `refine` before it in the default mode: a
//! refined minimum in the working frame becomes the returned [`Solution`]. `refine` moves it to
//! the minimum of the reprojection error ([`super::refine`]); the pose is carried back to the
//! world frame, and its
//! costs, cheirality and diagnostics are filled in. The only way out of the solver: a pose that
//! is not finite in the world frame is [`PnpError::NoSolution`], never an `Ok`.

use core::convert::Infallible;
use core::ops::ControlFlow;

use arrayvec::ArrayVec;
use nalgebra::{Isometry3, Matrix3, Point2, Point3, Translation3, Vector3};

use super::frame::WorkingFrame;
use super::newton;
use super::nullspace::{CandidateSource, MAX_CANDIDATES};
use super::options::Refinement;
use super::refine::{self, Composed, ReprojOptions, ReprojOutcome};
use super::refine_pixels::{self, PixelInputs};
use super::select::{in_front, Minimum};
use super::vertical;
use crate::covariance::PoseCovariance;
use crate::error::PnpError;
use crate::numeric::lanes::{blocks, dispatched, lane_sum, Block, LANES};
use crate::numeric::rotation::to_unit_quaternion;

/// A camera pose and how it was found. The pose maps world to camera, `x_cam = R X + t`:
/// [`Solution::rotation`] is `R` (the matrix the solver computed), [`Solution::translation`]
/// is `t`; [`Solution::pose`] gives them as an `Isometry3`, [`Solution::rvec`] as OpenCV's
/// rotation vector.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct Solution {
    /// The rotation `R` of the world-to-camera pose `x_cam = R X + t`.
    pub rotation: Matrix3<f64>,
    /// The translation `t` of the world-to-camera pose `x_cam = R X + t` (the world origin in
    /// the camera frame).
    pub translation: Vector3<f64>,
    /// The minimised cost: in [`Refinement::Reprojection`] mode the (weighted) sum of squared
    /// reprojection residuals, normalised for normalised input and in pixels^2 for pixel input
    /// (through the camera model), each passed through the [`crate::Loss`] when one is set
    /// (saturated at `f64::MAX` when weights near the top of the f64 range make it overflow);
    /// `f / trace(M)` in [`Refinement::Algebraic`] mode.
    pub cost: f64,
    /// `f / trace(M)`, the paper's algebraic cost of the returned rotation (docs/algorithm.md,
    /// `select`).
    pub algebraic_cost: f64,
    /// Root-mean-square normalised reprojection residual (weighted, without the loss), in units
    /// of the focal length: multiply by `f` for pixels (pixel input: the RMS pixel residual
    /// through the camera divided by `max(fx, fy)`). `f64::INFINITY` if a point lies in the focal plane
    /// (depth 0) of the returned pose, which can happen only in [`Refinement::Algebraic`] mode
    /// (in the default mode such a pose is never returned).
    pub reprojection_rmse: f64,
    /// More than half of the points (with non-zero weight) are in front of the camera.
    pub cheirality_ok: bool,
    /// The configuration is close to degenerate and the pose may be ambiguous or wrong: more
    /// than four eigenvalues of `M` are below `1e-10 trace(M)`, or the image points span less
    /// than `1e-6 max(1, max |m|)` (RMS, normalised units), too little for f64 to resolve
    /// the perspective that fixes the rotation (docs/algorithm.md, `frame`, `select`, section 6).
    pub degenerate: bool,
    /// Whether the planar branch produced this pose's starting candidate.
    pub planar: bool,
    /// The candidate generator of the winning start.
    pub source: CandidateSource,
    /// Damped-Newton iterations (the `newton` stage) of the winning candidate (0 when `newton` was
    /// skipped: an exact fit, whose start is already the minimum of the algebraic cost to
    /// rounding).
    pub newton_iterations: u32,
    /// Levenberg-Marquardt iterations of the reprojection refinement (the `refine` stage; 0 in
    /// algebraic mode).
    pub reprojection_iterations: u32,
    /// The reprojection refinement stopped at a minimum: its gradient or step test passed, or
    /// no step lowered the cost any more. `false` when it ran out of iterations
    /// ([`crate::Solver::reprojection_iterations`]) or could not start (a point at depth 0);
    /// `true` in algebraic mode.
    pub converged: bool,
    /// Correspondences that entered the solve (those with a weight > 0).
    pub used: usize,
    /// Correspondences left out because their pixel could not be undistorted
    /// ([`crate::Problem::pixels`]; 0 for normalised input).
    pub skipped: usize,
    /// The pose's covariance, when [`crate::Solver::covariance`] asks for it (and the normal
    /// equations at the pose are positive definite); see [`crate::covariance`].
    pub covariance: Option<PoseCovariance>,
    /// With estimated intrinsics ([`crate::Problem::unknown_focal`],
    /// [`crate::Problem::refine_principal_point`], [`crate::Problem::refine_distortion`]): the
    /// estimated camera, the given one with those intrinsics replaced; `None` otherwise.
    pub camera: Option<crate::camera::Camera>,
}

impl Solution {
    /// A solution of the pose `(rotation, translation)` with its diagnostics at their neutral
    /// values (cost 0, everything converged and in front), for the solvers outside the
    /// pipeline (rigs) to fill in.
    pub(crate) fn from_parts(rotation: Matrix3<f64>, translation: Vector3<f64>) -> Solution {
        Solution {
            rotation,
            translation,
            cost: 0.0,
            algebraic_cost: 0.0,
            reprojection_rmse: 0.0,
            cheirality_ok: true,
            degenerate: false,
            planar: false,
            source: CandidateSource::Initial,
            newton_iterations: 0,
            reprojection_iterations: 0,
            converged: true,
            used: 0,
            skipped: 0,
            covariance: None,
            camera: None,
        }
    }

    /// The world-to-camera pose as an isometry (`x_cam = pose * X`): the rotation as a unit
    /// quaternion (closed form from [`Solution::rotation`], renormalised), the translation.
    ///
    /// ```
    /// use eopnp::solve;
    /// use nalgebra::{Point2, Point3, Vector3};
    ///
    /// let t = Vector3::new(0.1, -0.2, 6.0);
    /// let world = [
    ///     Point3::new(-1.0, -1.0, 0.5), Point3::new(1.0, -1.0, -0.5), Point3::new(1.0, 1.0, 0.2),
    ///     Point3::new(-1.0, 1.0, -0.1), Point3::new(0.3, 0.2, 1.0), Point3::new(-0.4, 0.6, -0.8),
    /// ];
    /// let image: Vec<Point2<f64>> = world
    ///     .iter()
    ///     .map(|x| { let p = x.coords + t; Point2::new(p.x / p.z, p.y / p.z) })
    ///     .collect();
    /// let sol = solve(&world, &image)?;
    /// // The first point in the camera frame.
    /// let x_cam = sol.pose() * world[0];
    /// assert!((x_cam - (world[0] + t)).norm() < 1e-9);
    /// # Ok::<(), eopnp::PnpError>(())
    /// ```
    #[must_use]
    pub fn pose(&self) -> Isometry3<f64> {
        Isometry3::from_parts(
            Translation3::from(self.translation),
            to_unit_quaternion(&self.rotation),
        )
    }

    /// The rotation as OpenCV's rotation vector (`rvec` of `cv2.solvePnP`,
    /// `cv2.Rodrigues`): the axis times the angle in radians, the angle in `[0, pi]`. Accurate
    /// at every angle (computed from the unit quaternion as `2 atan2(|v|, |w|)`, not from an
    /// arc cosine), 180 degrees included.
    ///
    /// ```
    /// use eopnp::solve;
    /// use nalgebra::{Point2, Point3, Rotation3, Vector3};
    ///
    /// let rvec_true = Vector3::new(0.3, -0.2, 0.1);
    /// let r = Rotation3::new(rvec_true);
    /// let t = Vector3::new(0.1, -0.2, 6.0);
    /// let world = [
    ///     Point3::new(-1.0, -1.0, 0.5), Point3::new(1.0, -1.0, -0.5), Point3::new(1.0, 1.0, 0.2),
    ///     Point3::new(-1.0, 1.0, -0.1), Point3::new(0.3, 0.2, 1.0), Point3::new(-0.4, 0.6, -0.8),
    /// ];
    /// let image: Vec<Point2<f64>> = world
    ///     .iter()
    ///     .map(|x| { let p = r * x + t; Point2::new(p.x / p.z, p.y / p.z) })
    ///     .collect();
    /// let sol = solve(&world, &image)?;
    /// assert!((sol.rvec() - rvec_true).norm() < 1e-9);
    /// # Ok::<(), eopnp::PnpError>(())
    /// ```
    #[must_use]
    pub fn rvec(&self) -> Vector3<f64> {
        let pose = self.pose();
        let q = pose.rotation.quaternion();
        let (w, v) = (q.w, q.imag());
        let n = v.norm();
        if n == 0.0 {
            return Vector3::zeros();
        }
        let sign = if w < 0.0 { -1.0 } else { 1.0 };
        v * (sign * 2.0 * n.atan2(w.abs()) / n)
    }
}

/// Every distinct local minimum found, best first (see [`crate::Solver::solve_all`]): a
/// fixed-capacity list ([`arrayvec::ArrayVec`], re-exported as [`crate::ArrayVec`]), no heap
/// allocation.
pub type Solutions = ArrayVec<Solution, MAX_CANDIDATES>;

/// What `refine`, `refine_pixels` and `output` need of the problem.
pub(crate) struct Output<'a> {
    pub world: &'a [Point3<f64>],
    pub image: &'a [Point2<f64>],
    pub weights: Option<&'a [f64]>,
    /// `refine_pixels`' observations (pixel input, or a robust loss).
    pub pixel: Option<&'a PixelInputs<'a>>,
    pub fr: &'a WorkingFrame,
    /// Upper triangle of M (`moments::m_upper`).
    pub m45: &'a [f64; 45],
    pub degenerate: bool,
    /// `trace(M)`.
    pub scale: f64,
}

impl Output<'_> {
    /// `refine` (optional) and `output` for one minimum. The only way out of the solver: a pose
    /// that is not finite in the world frame (e.g. a translation that overflows when the
    /// working-frame scale is undone) is [`PnpError::NoSolution`], never an `Ok`.
    pub(crate) fn finish(
        &self,
        m: &Minimum,
        mode: Refinement,
        opts: &ReprojOptions,
    ) -> Result<Solution, PnpError> {
        self.finish_with(m, mode, opts, None, false)
            .and_then(|s| s.ok_or(PnpError::NoSolution))
    }

    /// [`Output::finish`] for a minimum whose `select` depth test (more than half of the points
    /// in front, [`in_front`]) is still to be made: `Ok(None)` if it fails. In the default mode
    /// the first pass of `refine` (or `refine_pixels`), which evaluates every depth at the
    /// minimum anyway,
    /// counts them (the same count: the same operations on the same points), so the test
    /// costs no pass of its own; in the algebraic mode the pass of the reported reprojection
    /// error counts them (the same operations again).
    pub(crate) fn finish_if_in_front(
        &self,
        m: &Minimum,
        mode: Refinement,
        opts: &ReprojOptions,
    ) -> Result<Option<Solution>, PnpError> {
        self.finish_with(m, mode, opts, None, true)
    }

    /// [`Output::finish`] in the default mode for a pose `refine` has already refined: `refined`
    /// is `refine`'s outcome from `m` (the small-N `search` runs `refine` from several starts to
    /// choose among them; it is not run again). `refine_pixels`, when it applies, still runs,
    /// from `refined`'s pose.
    pub(crate) fn finish_refined(
        &self,
        m: &Minimum,
        opts: &ReprojOptions,
        refined: &ReprojOutcome,
    ) -> Result<Solution, PnpError> {
        self.finish_with(m, Refinement::Reprojection, opts, Some(refined), false)
            .and_then(|s| s.ok_or(PnpError::NoSolution))
    }

    /// `refine` or `refine_pixels`, then `output`; `front_check`: `select`'s depth test at `m`
    /// first (`Ok(None)` if it fails; see [`Output::finish_if_in_front`]).
    fn finish_with(
        &self,
        m: &Minimum,
        mode: Refinement,
        opts: &ReprojOptions,
        refined: Option<&ReprojOutcome>,
        front_check: bool,
    ) -> Result<Option<Solution>, PnpError> {
        let mut m = *m;
        // `refine` (or `refine_pixels`) is told whether `m` is an exact fit, and the number of
        // correspondences of the vertical's prior (the `vertical` stage).
        let opts = &ReprojOptions {
            exact_start: m.exact,
            vertical: opts.vertical.map(|v| v.with_points(self.fr.n_active)),
            ..*opts
        };
        // `select`'s depth test at `m`, when it is still to be made (`front_check`): counted by
        // the first pass of `refine` or `refine_pixels`, which start from `m`, in the default
        // mode, by the pass of the reported error in the algebraic mode. `refine_pixels`' count
        // is `select`'s when its weights are `select`'s (pixels: the caller's, or
        // none); otherwise (RANSAC's fits: the first-order weights for `frame` to `select`,
        // whose zeros may differ where a product underflows) `select` counts before
        // `refine_pixels`.
        let refines_pixels = self.pixel.is_some_and(|px| px.refine);
        let pixel_weights_are_selects =
            self.pixel
                .is_some_and(|px| match (px.weights, self.weights) {
                    (None, None) => true,
                    (Some(a), Some(b)) => core::ptr::eq(a, b),
                    _ => false,
                });
        let refinement_counts = front_check
            && mode == Refinement::Reprojection
            && (!refines_pixels || pixel_weights_are_selects);
        let error_counts = front_check && mode == Refinement::Algebraic;
        if front_check && !refinement_counts && !error_counts {
            if !in_front(self.world, self.weights, self.fr, &m.r, &m.t) {
                return Ok(None);
            }
            m.cheirality = Some(true);
        }
        // The test from a first pass's count at `m` (`None`: the pass did not count).
        let front_at_m = |count: Option<usize>| match count {
            Some(count) => self.fr.most_in_front(count),
            None => in_front(self.world, self.weights, self.fr, &m.r, &m.t),
        };
        let (mut r, mut t) = (m.r, m.t);
        if let Some(o) = refined.filter(|_| refines_pixels) {
            // `refine_pixels` starts from `refine`'s pose.
            if o.r.iter().all(|x| x.is_finite()) && o.t.iter().all(|x| x.is_finite()) {
                (r, t) = (o.r, o.t);
            }
        }
        let mut iters = 0;
        let mut converged = true;
        // What `refine` (or `refine_pixels`) already knows at its final pose: the cost (for
        // `refine`, equal to the reprojection error when the two residual rows are not
        // reweighted) and the depth signs, which it never changes (a step that moves a point
        // across z = 0 is rejected).
        //
        // `refine_pixels`: the pixel error through the camera (or a robust loss), from
        // `select`'s minimum (`refine`, on the first-order error, would only bring the start
        // closer by about as much as one `refine_pixels` pass does, at a comparable cost). Its
        // cost and RMS residual replace `refine`'s; it keeps the depth signs as `refine` does.
        // If it cannot run (a point at depth 0, a non-finite result), `refine` runs instead.
        let mut refine_error = None;
        let mut depth_signs_kept = false;
        let mut pixel_refined = None;
        if mode == Refinement::Reprojection {
            if let Some(px) = self.pixel.filter(|px| px.refine) {
                let po = refine_pixels::refine_pixels(self.world, px, self.fr, &r, &t, opts);
                let out = &po.out;
                vertical::verdict(out.vertical)?;
                // `refine_pixels` ran from `m` (with `front_check`: not from a `refine` outcome).
                if refinement_counts {
                    if !front_at_m(out.start_in_front) {
                        return Ok(None);
                    }
                    m.cheirality = Some(true);
                }
                let finite = out.r.iter().all(|x| x.is_finite())
                    && out.t.iter().all(|x| x.is_finite())
                    && out.e.is_finite();
                if finite && out.stop != refine::ReprojStop::SkippedZeroDepth {
                    r = out.r;
                    t = out.t;
                    iters = out.iterations;
                    converged = out.stop.converged();
                    let rmse = if po.weight_sum > 0.0 {
                        po.squared_scale * (po.squared / po.weight_sum).sqrt() / px.scale
                    } else {
                        f64::INFINITY
                    };
                    pixel_refined = Some(((out.e * po.unit).min(f64::MAX), rmse));
                    depth_signs_kept = true;
                }
            }
        }
        // `refine` when `refine_pixels` did not run: the normalised reprojection error.
        if mode == Refinement::Reprojection && pixel_refined.is_none() {
            let out = match refined {
                Some(o) if opts.vertical.is_some() => refine::refine_reprojection_vertical(
                    self.world,
                    self.image,
                    self.weights,
                    self.fr,
                    o,
                    opts,
                ),
                Some(o) => *o,
                None => refine::refine_reprojection(
                    self.world,
                    self.image,
                    self.weights,
                    self.fr,
                    &r,
                    &t,
                    opts,
                ),
            };
            vertical::verdict(out.vertical)?;
            if refinement_counts && !refines_pixels {
                // `refine` ran from `m`: its first pass counted the depths there.
                if !front_at_m(out.start_in_front) {
                    return Ok(None);
                }
                m.cheirality = Some(true);
            }
            if out.r.iter().all(|x| x.is_finite()) && out.t.iter().all(|x| x.is_finite()) {
                r = out.r;
                t = out.t;
                if out.stop != refine::ReprojStop::SkippedZeroDepth {
                    depth_signs_kept = true;
                    if opts.row_weights == (1.0, 1.0) && out.e.is_finite() {
                        refine_error = Some(out.e);
                    }
                }
            }
            iters = out.iterations;
            converged = out.stop.converged();
        }
        // M is positive semi-definite, so f >= 0 in exact arithmetic. With wildly scaled input
        // (found by fuzzing: an image coordinate of 3e9) the accumulated M is not PSD to
        // working precision and r^T M r comes out negative; the nearest admissible value is 0.
        let f = newton::cost_at(self.m45, &r).max(0.0);
        let (rw, tw) = self.fr.to_world(&r, &t);
        // In `frame`'s weight unit (exact powers of two): `e * weight_unit` is the caller's
        // cost.
        // (With the pass of the reprojection error, its count of the points in front.)
        let (e, front) = match (refine_error, pixel_refined) {
            (Some(e), None) => (e, None),
            (_, Some(_)) => (0.0, None), // `refine_pixels`' cost and RMS residual are reported
            (None, None) => {
                let pose = Composed::new(&r, &self.fr.rw, self.fr.d, &t);
                let (e, front) = reprojection_error(
                    self.world,
                    self.image,
                    self.weights,
                    1.0 / self.fr.weight_unit,
                    &pose,
                    &self.fr.c,
                );
                if error_counts {
                    // `select`'s depth test at m (the algebraic mode: the pose is m's).
                    if !self.fr.most_in_front(front) {
                        return Ok(None);
                    }
                    m.cheirality = Some(true);
                }
                (e, Some(front))
            }
        };
        let cheirality = match m.cheirality {
            Some(c) if mode == Refinement::Algebraic || depth_signs_kept => c,
            _ => match front {
                Some(front) => self.fr.most_in_front(front),
                None => in_front(self.world, self.weights, self.fr, &r, &t),
            },
        };
        let wsum = self.fr.weight_sum;
        let sol = Solution {
            rotation: rw,
            translation: tw,
            cost: if mode == Refinement::Algebraic {
                f / self.scale
            } else if let Some((cost, _)) = pixel_refined {
                cost
            } else {
                // The caller's cost (with pixel input in pixels: `refine`'s residuals times the
                // camera's scale); weights near the top of the f64 range can make it overflow
                // while the pose is exact: it saturates at f64::MAX.
                let to_pixels = self.pixel.map_or(1.0, |px| px.scale * px.scale);
                (e * self.fr.weight_unit * to_pixels).min(f64::MAX)
            },
            algebraic_cost: f / self.scale,
            // Infinite (not NaN) when a point lies in the focal plane (depth 0) of the pose,
            // which only an algebraic-mode pose can do (see below).
            reprojection_rmse: match pixel_refined {
                Some((_, rmse)) => rmse,
                None if e.is_finite() && wsum > 0.0 => (e / wsum).sqrt(),
                None => f64::INFINITY,
            },
            cheirality_ok: cheirality,
            degenerate: self.degenerate,
            planar: m.planar,
            source: m.source,
            newton_iterations: m.iterations,
            reprojection_iterations: iters,
            converged,
            used: self.fr.n_active,
            skipped: 0,
            covariance: None,
            camera: None,
        };
        // Reprojection mode promises the maximum-likelihood pose; a pose with a point at depth
        // 0 has an infinite reprojection error and is not one (found by fuzzing, with an image
        // coordinate of 3.5e16).
        if mode == Refinement::Reprojection && !e.is_finite() {
            return Err(PnpError::NoSolution);
        }
        let finite = sol.rotation.iter().all(|x| x.is_finite())
            && sol.translation.iter().all(|x| x.is_finite())
            && to_unit_quaternion(&rw).coords.iter().all(|x| x.is_finite());
        if finite {
            Ok(Some(sol))
        } else {
            Err(PnpError::NoSolution)
        }
    }
}

/// `solve_all`: every distinct minimum finished (`refine`, `output`), duplicates (poses within
/// 1e-6) dropped, ranked cheirality-valid first, then by increasing reprojection error.
pub(crate) fn rank_all(
    out: &Output<'_>,
    minima: &[Minimum],
    mode: Refinement,
    opts: &ReprojOptions,
    all: &mut Solutions,
) -> Result<Solution, PnpError> {
    // A vertical the images contradict at every minimum is reported as such.
    let mut mismatch = None;
    for m in minima {
        let s = match out.finish(m, mode, opts) {
            Ok(s) => s,
            Err(e @ PnpError::GravityMismatch { .. }) => {
                mismatch.get_or_insert(e);
                continue;
            }
            Err(_) => continue,
        };
        if !all.iter().any(|o: &Solution| {
            (o.rotation - s.rotation).norm() <= 1e-6
                && (o.translation - s.translation).norm() <= 1e-6 * (1.0 + s.translation.norm())
        }) {
            all.push(s);
        }
    }
    all.sort_by(|a, b| {
        (!a.cheirality_ok)
            .cmp(&!b.cheirality_ok)
            .then(a.reprojection_rmse.total_cmp(&b.reprojection_rmse))
    });
    all.first()
        .copied()
        .ok_or_else(|| mismatch.unwrap_or(PnpError::NoSolution))
}

dispatched! {
    /// Weighted sum of squared normalised reprojection residuals at a working-frame pose (`pose`:
    /// `x_cam = a (X - c) + t`, `refine`'s composed form, whose camera coordinates are the world
    /// pose's divided by `frame`'s scale `d`: the same projections, at depths of order 1 whatever
    /// the input's scale), with the weights multiplied by `inv_weight` (`frame`'s weight unit); and
    /// the number of points with non-zero weight and a positive depth, computed as [`in_front`]
    /// computes it (the same operations, so the same count). Vectorised across points like the
    /// passes of `moments` and `refine`: the points with non-zero weight, in order, in blocks of
    /// [`LANES`], one partial sum and count per lane, the lanes added pairwise at the end.
    fn reprojection_error[][](
        world: &[Point3<f64>],
        image: &[Point2<f64>],
        weights: Option<&[f64]>,
        inv_weight: f64,
        pose: &Composed,
        c: &Vector3<f64>,
    ) -> (f64, usize) = reprojection_error_body;
}

#[inline(always)]
fn reprojection_error_body(
    world: &[Point3<f64>],
    image: &[Point2<f64>],
    weights: Option<&[f64]>,
    inv_weight: f64,
    pose: &Composed,
    c: &Vector3<f64>,
) -> (f64, usize) {
    let a = &pose.a;
    let k = (
        [
            [a[(0, 0)], a[(0, 1)], a[(0, 2)]],
            [a[(1, 0)], a[(1, 1)], a[(1, 2)]],
            [a[(2, 0)], a[(2, 1)], a[(2, 2)]],
        ],
        [c.x, c.y, c.z],
        [pose.t.x, pose.t.y, pose.t.z],
    );
    let mut acc = [0.0; LANES];
    let mut front = [0u64; LANES];
    let ControlFlow::Continue((blk, filled)) = blocks::<Infallible>(
        world,
        image,
        weights,
        inv_weight,
        #[inline(always)]
        |full| {
            residuals(&k, full, LANES, &mut acc, &mut front);
            ControlFlow::Continue(())
        },
    );
    partial_residuals(&k, &blk, filled, &mut acc, &mut front);
    (lane_sum(&acc), front.iter().sum::<u64>() as usize)
}

/// Adds the weighted squared residual of each of the first `filled` points of `blk` under the
/// pose `(a, c, t)` (rows of `a`) to its lane of `acc`, and 1 to its lane of `front` if its
/// depth is positive. Written stage by stage across the lanes, each stage an array of
/// `LANES` values, the compiler packs each stage into one register; written point by point
/// (the lanes one after the other), it packed them two at a time, with spills (callgrind,
/// the algebraic solve at N = 1,000: 103k -> 95k instructions). The lanes past `filled` (a
/// partial block's stale or empty lanes, whose depth may be 0) are computed and dropped by
/// a select, so that they cannot poison the sums.
#[inline(always)]
fn residuals(
    (a, c, t): &([[f64; 3]; 3], [f64; 3], [f64; 3]),
    blk: &Block,
    filled: usize,
    acc: &mut [f64; LANES],
    front: &mut [u64; LANES],
) {
    use core::array::from_fn;
    let xc: [[f64; LANES]; 3] = from_fn(|i| from_fn(|l| blk.x[i][l] - c[i]));
    // `a . (X - c) + t`: the operations of `in_front` (and of `refine`'s pass).
    let row = |j: usize| -> [f64; LANES] {
        from_fn(|l| a[j][0] * xc[0][l] + a[j][1] * xc[1][l] + a[j][2] * xc[2][l] + t[j])
    };
    let p = [row(0), row(1), row(2)];
    // One division per point, as in `refine`'s pass.
    let iz: [f64; LANES] = from_fn(|l| 1.0 / p[2][l]);
    let du: [f64; LANES] = from_fn(|l| blk.m[0][l] - p[0][l] * iz[l]);
    let dv: [f64; LANES] = from_fn(|l| blk.m[1][l] - p[1][l] * iz[l]);
    for l in 0..LANES {
        front[l] += u64::from((l < filled) & (p[2][l] > 0.0));
    }
    for l in 0..LANES {
        acc[l] += if l < filled {
            blk.w[l] * (du[l] * du[l] + dv[l] * dv[l])
        } else {
            0.0
        };
    }
}

/// [`residuals`] of the last, partial block. Out of line: inlined beside the loop over the
/// full blocks, a second copy of [`residuals`] (with a `filled` the compiler cannot fold)
/// made it pack that loop's stages two lanes at a time again (callgrind, the algebraic solve
/// at N = 1,000: 95k -> 112k instructions). This copy runs once per pass, in the baseline
/// build (the same operations, so the same bits).
#[inline(never)]
fn partial_residuals(
    k: &([[f64; 3]; 3], [f64; 3], [f64; 3]),
    blk: &Block,
    filled: usize,
    acc: &mut [f64; LANES],
    front: &mut [u64; LANES],
) {
    residuals(k, blk, filled, acc, front);
}

#[cfg(test)]
#[path = "../../tests/unit/pipeline/output.rs"]
mod tests;
