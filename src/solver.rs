//! The EOPnP pipeline (ALGORITHM.md S1-S9) and its public entry points.

use crate::accumulate::{self, System};
use crate::bounds::{converged, limit, Bound};
use crate::certify;
use crate::error::PnpError;
use crate::frame::{self, WorkingFrame};
use crate::linalg;
use crate::nullspace::{self, Candidate, CandidateSource, Candidates, MAX_CANDIDATES};
use crate::refine::{self, NewtonOptions};
use crate::reproj::{self, ReprojOptions};
use arrayvec::ArrayVec;
use nalgebra::{Isometry3, Matrix3, Point2, Point3, SMatrix, SVector, Translation3, Vector3};

/// Which cost the returned pose minimises.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Refinement {
    /// EOPnP (S0-S8) followed by Levenberg-Marquardt on the reprojection error (S9): the
    /// maximum-likelihood pose for isotropic Gaussian image noise. Default.
    #[default]
    Reprojection,
    /// EOPnP alone (S0-S8): the minimiser of the paper's depth-weighted algebraic cost.
    Algebraic,
}

/// How the planar branch (S4') is chosen.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum PlanarDetection {
    /// From the planarity ratio `sv2 / sv0` of the centred world points (ALGORITHM.md S3):
    /// non-planar branch if `ratio >= 1e-6`, planar branch if `ratio < 1e-3`, both in between.
    /// Default.
    #[default]
    Auto,
    /// Planar branch only (the world points are treated as lying on their best-fit plane).
    Planar,
    /// Non-planar branch only.
    NonPlanar,
}

/// Pinhole intrinsics: `px = fx x + skew y + cx`, `py = fy y + cy` for normalised `(x, y)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Intrinsics {
    /// Focal length in x, pixels.
    pub fx: f64,
    /// Focal length in y, pixels.
    pub fy: f64,
    /// Principal point x, pixels.
    pub cx: f64,
    /// Principal point y, pixels.
    pub cy: f64,
    /// Skew, pixels (0 for almost every camera).
    pub skew: f64,
}

impl Intrinsics {
    /// Normalised image coordinates of a pixel.
    #[must_use]
    pub fn normalize(&self, px: &Point2<f64>) -> Point2<f64> {
        let y = (px.y - self.cy) / self.fy;
        let x = (px.x - self.cx - self.skew * y) / self.fx;
        Point2::new(x, y)
    }

    /// Pixel of a normalised image point.
    #[must_use]
    pub fn project(&self, p: &Point2<f64>) -> Point2<f64> {
        Point2::new(
            self.fx * p.x + self.skew * p.y + self.cx,
            self.fy * p.y + self.cy,
        )
    }
}

/// A camera pose and how it was found.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct Solution {
    /// World-to-camera pose: `x_cam = R X + t`.
    pub pose: Isometry3<f64>,
    /// The rotation `R` as a matrix (the same rotation as `pose.rotation`, without the
    /// quaternion round trip).
    pub rotation: Matrix3<f64>,
    /// The minimised cost: the (weighted) sum of squared normalised reprojection residuals in
    /// [`Refinement::Reprojection`] mode, `f / trace(M)` in [`Refinement::Algebraic`] mode.
    pub cost: f64,
    /// `f / trace(M)`, the paper's algebraic cost of the returned rotation (ALGORITHM.md S7).
    pub algebraic_cost: f64,
    /// Root-mean-square normalised reprojection residual (weighted), in units of the focal
    /// length: multiply by `f` for pixels. `f64::INFINITY` if a point lies in the focal plane
    /// (depth 0) of the returned pose, which can happen only in [`Refinement::Algebraic`] mode
    /// (in the default mode such a pose is never returned).
    pub reprojection_rmse: f64,
    /// More than half of the points (with non-zero weight) are in front of the camera.
    pub cheirality_ok: bool,
    /// More than four eigenvalues of `M` are below `1e-10 trace(M)`: the configuration is close
    /// to degenerate and the pose may be ambiguous (ALGORITHM.md S7, section 6).
    pub degenerate: bool,
    /// Whether the planar branch produced this pose's starting candidate.
    pub planar: bool,
    /// The candidate generator of the winning start.
    pub source: CandidateSource,
    /// Damped-Newton iterations (S6) of the winning candidate.
    pub newton_iterations: u32,
    /// Levenberg-Marquardt iterations of the reprojection refinement (S9; 0 in algebraic mode).
    pub reprojection_iterations: u32,
}

/// Every distinct local minimum found, best first (see [`Solver::solve_all`]).
pub type Solutions = ArrayVec<Solution, MAX_CANDIDATES>;

/// Solver options. `Solver::default()` is the recommended configuration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Solver {
    refinement: Refinement,
    newton: NewtonOptions,
    reproj: ReprojOptions,
    planar: PlanarDetection,
    align_world_axes: bool,
    exhaustive: bool,
}

impl Default for Solver {
    fn default() -> Self {
        Solver {
            refinement: Refinement::Reprojection,
            newton: NewtonOptions::default(),
            reproj: ReprojOptions::default(),
            planar: PlanarDetection::Auto,
            align_world_axes: true,
            exhaustive: false,
        }
    }
}

/// Relative eigenvalue level below which an eigenvalue of `M` counts as zero for the
/// `degenerate` diagnostic (ALGORITHM.md S0).
const DEGENERATE_EIG: f64 = 1e-10;
/// S6 step tolerance in reprojection mode (CGR units, ~ radians / 2): S6 stops when a step is
/// this small, or when quadratic convergence predicts the next step below a thousandth of it,
/// so the minimum of f is located to ~1e-9 before S9 takes over.
const S6_TOLERANCE_BEFORE_S9: f64 = 1e-6;
/// Planarity thresholds (ALGORITHM.md S3).
const NONPLANAR_MIN_RATIO: f64 = 1e-6;
const PLANAR_MAX_RATIO: f64 = 1e-3;
/// Two refined rotations closer than this (Frobenius norm of the difference, ~ radians) are the
/// same local minimum.
const SAME_MINIMUM: f64 = 1e-8;
/// Radius (Frobenius norm of the rotation difference; 0.05 is about 2 degrees) of the
/// neighbourhood of a refined local minimum that is taken to lie in its basin: a start or a
/// Newton iterate that comes this close to a known minimum converges to it (the cost is a
/// quadratic form in the entries of R, whose distinct minima are tens of degrees apart), so its
/// refinement is skipped or stopped.
const IN_BASIN: f64 = 0.05;
/// Hard bound on the symmetric eigen-decomposition sweeps.
pub(crate) const EIGEN_MAX_ITER: usize = 1000;

/// The four fixed extra starting rotations of S4'' (working frame).
const EXTRA_STARTS: [[f64; 3]; 4] = [
    [1.0, 1.0, 1.0],
    [1.0, -1.0, -1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0],
];

impl Solver {
    /// Which cost to minimise. Default: [`Refinement::Reprojection`].
    #[must_use]
    pub fn refinement(mut self, r: Refinement) -> Self {
        self.refinement = r;
        self
    }

    /// Maximum damped-Newton iterations per candidate in S6. Default: `50`.
    #[must_use]
    pub fn newton_iterations(mut self, n: u32) -> Self {
        self.newton.max_iterations = n;
        self
    }

    /// S6 stops when the step norm (radians, roughly) falls to this. Default: `1e-12`. When S9
    /// follows (the default [`Refinement::Reprojection`]), S6 uses at least `1e-6` (the minimum
    /// of the algebraic cost located to ~1e-9): S9 then moves the pose on to the
    /// maximum-likelihood one and converges to its own tolerance.
    #[must_use]
    pub fn newton_step_tolerance(mut self, tol: f64) -> Self {
        self.newton.step_tolerance = tol;
        self
    }

    /// Maximum Levenberg-Marquardt iterations of the reprojection refinement (S9). Default: `50`.
    #[must_use]
    pub fn reprojection_iterations(mut self, n: u32) -> Self {
        self.reproj.max_iterations = n;
        self
    }

    /// Planar branch selection. Default: [`PlanarDetection::Auto`].
    #[must_use]
    pub fn planar_detection(mut self, p: PlanarDetection) -> Self {
        self.planar = p;
        self
    }

    /// `true` runs every candidate generator and refines every start to convergence for every
    /// problem (ALGORITHM.md S4-S6 literally: no certified early exit, no skipping of starts
    /// that lie near an already refined minimum). Default: `false`: the case-1 (planar: p1) start is refined
    /// first, and accepted without the rest of the search when a Lagrangian dual certificate
    /// proves it is the global minimum of the cost and more than half of the points are in
    /// front of it; S7 would select the same minimum.
    #[must_use]
    pub fn exhaustive(mut self, exhaustive: bool) -> Self {
        self.exhaustive = exhaustive;
        self
    }

    /// Test hook: `false` keeps the user's world axes instead of the principal axes in the
    /// working frame (only valid for non-planar scenes). Default: `true`.
    #[doc(hidden)]
    #[must_use]
    pub fn align_world_axes(mut self, align: bool) -> Self {
        self.align_world_axes = align;
        self
    }

    /// The pose from `world` points and their normalised image points `(x/z, y/z)`.
    ///
    /// # Errors
    /// [`PnpError`] for too few points, mismatched lengths, non-finite values and degenerate
    /// configurations; see its variants.
    pub fn solve(
        &self,
        world: &[Point3<f64>],
        image: &[Point2<f64>],
    ) -> Result<Solution, PnpError> {
        self.run(world, image, None, self.reproj, None)
    }

    /// As [`Solver::solve`] with a non-negative weight per point (a point of weight 0 is
    /// ignored; weights scale each point's squared residuals).
    ///
    /// # Errors
    /// As [`Solver::solve`], plus [`PnpError::WeightsLength`], [`PnpError::InvalidWeight`] and
    /// [`PnpError::NonFinite`] for the weights.
    pub fn solve_weighted(
        &self,
        world: &[Point3<f64>],
        image: &[Point2<f64>],
        weights: &[f64],
    ) -> Result<Solution, PnpError> {
        self.run(world, image, Some(weights), self.reproj, None)
    }

    /// Every distinct local minimum of the cost, best first: cheirality-valid poses before the
    /// others, then by increasing reprojection error. For N <= 6 and for planar scenes several
    /// poses can explain the data about equally well; this lists them. Bounded (at most 32), no
    /// allocation.
    ///
    /// # Errors
    /// As [`Solver::solve`].
    pub fn solve_all(
        &self,
        world: &[Point3<f64>],
        image: &[Point2<f64>],
    ) -> Result<Solutions, PnpError> {
        let mut all = Solutions::new();
        self.run(world, image, None, self.reproj, Some(&mut all))?;
        Ok(all)
    }

    /// The pose from pixel coordinates and pinhole intrinsics (no lens distortion). In the
    /// default mode the reprojection error is measured in pixels (rows weighted by `fx^2` and
    /// `fy^2`; the skew term is not weighted).
    ///
    /// # Errors
    /// [`PnpError::InvalidIntrinsics`] for non-finite or non-positive focal lengths, and as
    /// [`Solver::solve`].
    pub fn solve_pixels(
        &self,
        world: &[Point3<f64>],
        pixels: &[Point2<f64>],
        k: &Intrinsics,
    ) -> Result<Solution, PnpError> {
        let ok = [k.fx, k.fy, k.cx, k.cy, k.skew]
            .iter()
            .all(|x| x.is_finite())
            && k.fx > 0.0
            && k.fy > 0.0;
        if !ok {
            return Err(PnpError::InvalidIntrinsics);
        }
        if world.len() != pixels.len() {
            return Err(PnpError::LengthMismatch {
                world: world.len(),
                image: pixels.len(),
            });
        }
        // Normalise on the stack in chunks is not possible for arbitrary N without allocating;
        // the normalised points are needed by every pass, so this entry point allocates once.
        let image: Vec<Point2<f64>> = pixels.iter().map(|p| k.normalize(p)).collect();
        let scale = k.fx.max(k.fy);
        let mut opts = self.reproj;
        opts.row_weights = ((k.fx / scale).powi(2), (k.fy / scale).powi(2));
        self.run(world, &image, None, opts, None)
    }

    /// As [`Solver::solve_weighted`] (weights optional) with the x and y residual rows of the
    /// reprojection refinement weighted by `row_weights` (e.g. `(fx^2, fy^2)` normalised, as
    /// in [`Solver::solve_pixels`]). Used by `colmap::register_image`. Non-finite or
    /// non-positive row weights fall back to `(1, 1)`.
    pub(crate) fn solve_with_row_weights(
        &self,
        world: &[Point3<f64>],
        image: &[Point2<f64>],
        weights: Option<&[f64]>,
        row_weights: (f64, f64),
    ) -> Result<Solution, PnpError> {
        let mut opts = self.reproj;
        let ok = |w: f64| w.is_finite() && w > 0.0;
        if ok(row_weights.0) && ok(row_weights.1) {
            opts.row_weights = row_weights;
        }
        self.run(world, image, weights, opts, None)
    }

    fn run(
        &self,
        world: &[Point3<f64>],
        image: &[Point2<f64>],
        weights: Option<&[f64]>,
        reproj_opts: ReprojOptions,
        all: Option<&mut Solutions>,
    ) -> Result<Solution, PnpError> {
        // S1.
        let fr = frame::working_frame(world, image, weights, self.align_world_axes)?;
        // S2.
        let acc = fr.sums;
        let sys = acc.system(false).ok_or(PnpError::NoSolution)?;
        let m45 = accumulate::m_upper(&sys.m);
        let scale = sys.trace;
        if !(scale > 0.0 && scale.is_finite()) {
            return Err(PnpError::NoSolution);
        }
        // S3.
        let (nonplanar, planar) = match self.planar {
            PlanarDetection::Auto => (fr.ratio >= NONPLANAR_MIN_RATIO, fr.ratio < PLANAR_MAX_RATIO),
            PlanarDetection::Planar => (false, true),
            PlanarDetection::NonPlanar => (true, false),
        };
        // More than four eigenvalues of M at or below DEGENERATE_EIG trace(M). A Cholesky
        // factorisation of M - tau I proves that there are none (the common case from N = 6 on)
        // and is reused by the fast path's inverse iteration; the inertia count runs otherwise.
        let tau = DEGENERATE_EIG * scale * (1.0 + f64::EPSILON);
        let shifted = linalg::cholesky(&(sys.m - SMatrix::<f64, 9, 9>::identity() * tau));
        let degenerate = shifted.is_none() && linalg::count_eigenvalues_below(&sys.m, tau) > 4;

        let n_active = fr.n_active;
        let ctx = Ctx {
            world,
            image,
            weights,
            fr: &fr,
            m45: &m45,
            degenerate,
            scale,
        };
        let planar_sys = if planar { acc.system(true) } else { None };
        // When S9 follows, S6 only has to identify and certify the minimum of f: S9 moves the
        // pose on by the algebraic-vs-reprojection difference (~noise level) and converges to
        // its own tolerance from anywhere in the basin.
        let newton = match self.refinement {
            Refinement::Reprojection => NewtonOptions {
                step_tolerance: self.newton.step_tolerance.max(S6_TOLERANCE_BEFORE_S9),
                ..self.newton
            },
            Refinement::Algebraic => self.newton,
        };
        let mut minima: ArrayVec<Minimum, MAX_CANDIDATES> = ArrayVec::new();
        let refine_start = |r0: &Matrix3<f64>,
                            source: CandidateSource,
                            minima: &ArrayVec<Minimum, MAX_CANDIDATES>|
         -> Option<Minimum> {
            let known: ArrayVec<Matrix3<f64>, MAX_CANDIDATES> =
                minima.iter().map(|m| m.r).collect();
            let refined = refine::refine_so3_until(&m45, scale, r0, &newton, &mut |r| {
                !self.exhaustive && known.iter().any(|k| (k - r).norm() <= IN_BASIN)
            });
            if refined.stopped_early
                || !refined.f.is_finite()
                || !refined.r.iter().all(|x| x.is_finite())
                || minima
                    .iter()
                    .any(|m| (m.r - refined.r).norm() <= SAME_MINIMUM)
            {
                return None;
            }
            Some(Minimum {
                r: refined.r,
                t: translation(&sys, &refined.r),
                f: refined.f,
                source,
                planar: matches!(source, CandidateSource::Planar1 | CandidateSource::Planar2),
                iterations: refined.iterations,
                cheirality: None,
            })
        };

        // Certified fast path (not in `solve_all` or exhaustive mode): refine the case-1 (or
        // p1) start; if a Lagrangian dual certificate proves the minimum it reaches is the
        // global minimum of f over O(3) (see `certify`) and more than half of the points are in
        // front of it, no other candidate can be selected by S7, so the search stops here.
        let early_exit = !self.exhaustive && all.is_none();
        let is_certified = |r: &Matrix3<f64>| {
            certify::global_minimum(&sys.m, r, scale)
                || (planar
                    && planar_sys
                        .as_ref()
                        .is_some_and(|sp| certify::global_minimum_planar(&sp.m, r, scale)))
        };
        if early_exit {
            let start = if nonplanar && !planar {
                match &shifted {
                    Some(l) => linalg::inverse_iteration(&sys.m, l),
                    None => linalg::smallest_eigenvector(&sys.m, scale),
                }
                .and_then(|v1| {
                    crate::rotation::candidate_to_rotation(&v1.into())
                        .map(|r| (r, CandidateSource::Case1))
                })
            } else if planar && !nonplanar {
                planar_sys.as_ref().and_then(|sp| {
                    let v1 = linalg::smallest_eigenvector(&planar_m(sp), scale)?;
                    planar_start(&v1, sp, world, weights, &fr)
                        .map(|r| (r, CandidateSource::Planar1))
                })
            } else {
                None
            };
            if let Some((r0, source)) = start {
                if let Some(mut m) = refine_start(&r0, source, &minima) {
                    if is_certified(&m.r) && in_front(world, weights, &fr, &m.r, &m.t, n_active) {
                        m.cheirality = Some(true);
                        return ctx.finish(&m, self.refinement, &reproj_opts);
                    }
                    minima.push(m);
                }
            }
        }

        let mut cands = Candidates::new();
        // S4.
        if nonplanar {
            let eig = nalgebra::SymmetricEigen::try_new(sys.m, f64::EPSILON, limit(Bound::MEigen));
            let eig = converged(eig, Bound::MEigen).ok_or(PnpError::NoSolution)?;
            let mut order: [usize; 9] = std::array::from_fn(|i| i);
            order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
            let v: [SVector<f64, 9>; 4] =
                std::array::from_fn(|i| eig.eigenvectors.column(order[i]).into_owned());
            nullspace::nonplanar_candidates(&v, &mut cands);
        }
        // S4'.
        if let Some((sp, vecs)) = planar_sys
            .as_ref()
            .and_then(|sp| planar_eigen(sp).map(|(_, v)| (sp, v)))
        {
            nullspace::planar_vectors(&vecs, |r6, source| {
                if let Some(r) = planar_start(&r6, sp, world, weights, &fr) {
                    if !cands.is_full() {
                        cands.push(Candidate { r, source });
                    }
                }
            });
        }
        // S4''.
        for d in EXTRA_STARTS {
            if !cands.is_full() {
                cands.push(Candidate {
                    r: Matrix3::from_diagonal(&Vector3::from(d)),
                    source: CandidateSource::ExtraStart,
                });
            }
        }

        // S6: refine every candidate, in order of increasing initial cost.
        let f_of = |r: &Matrix3<f64>| refine::cost_at(&m45, r);
        let mut init: ArrayVec<(f64, usize), MAX_CANDIDATES> = cands
            .iter()
            .enumerate()
            .map(|(i, c)| (f_of(&c.r), i))
            .collect();
        init.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        for &(_, i) in &init {
            let c = cands[i];
            // A start already inside the basin of a known minimum would only find it again.
            if !self.exhaustive && minima.iter().any(|m| (m.r - c.r).norm() <= IN_BASIN) {
                continue;
            }
            if let Some(mut m) = refine_start(&c.r, c.source, &minima) {
                // A certified global minimum with most points in front is S7's pick.
                if early_exit
                    && is_certified(&m.r)
                    && in_front(world, weights, &fr, &m.r, &m.t, n_active)
                {
                    m.cheirality = Some(true);
                    return ctx.finish(&m, self.refinement, &reproj_opts);
                }
                if !minima.is_full() {
                    minima.push(m);
                }
            }
        }
        if minima.is_empty() {
            return Err(PnpError::NoSolution);
        }
        if let Some(all) = all {
            // Every distinct minimum, refined and ranked.
            for m in minima.iter_mut() {
                m.cheirality = Some(in_front(world, weights, &fr, &m.r, &m.t, n_active));
            }
            for m in &minima {
                let Ok(s) = ctx.finish(m, self.refinement, &reproj_opts) else {
                    continue;
                };
                if !all.iter().any(|o: &Solution| {
                    (o.rotation - s.rotation).norm() <= 1e-6
                        && (o.pose.translation.vector - s.pose.translation.vector).norm()
                            <= 1e-6 * (1.0 + s.pose.translation.vector.norm())
                }) {
                    all.push(s);
                }
            }
            all.sort_by(|a, b| {
                (!a.cheirality_ok)
                    .cmp(&!b.cheirality_ok)
                    .then(a.reprojection_rmse.total_cmp(&b.reprojection_rmse))
            });
            return all.first().copied().ok_or(PnpError::NoSolution);
        }

        // S7: the smallest f among the minima with more than half of the points in front;
        // depths are counted lazily, in order of f, until one passes.
        minima.sort_by(|a, b| a.f.total_cmp(&b.f));
        let mut pick = 0;
        for (i, m) in minima.iter_mut().enumerate() {
            let ok = in_front(world, weights, &fr, &m.r, &m.t, n_active);
            m.cheirality = Some(ok);
            if ok {
                pick = i;
                break;
            }
        }
        ctx.finish(&minima[pick], self.refinement, &reproj_opts)
    }
}

/// A refined local minimum of f (working frame).
#[derive(Clone, Copy, Debug)]
struct Minimum {
    r: Matrix3<f64>,
    t: Vector3<f64>,
    f: f64,
    source: CandidateSource,
    planar: bool,
    iterations: u32,
    cheirality: Option<bool>,
}

struct Ctx<'a> {
    world: &'a [Point3<f64>],
    image: &'a [Point2<f64>],
    weights: Option<&'a [f64]>,
    fr: &'a WorkingFrame,
    /// Upper triangle of M (`accumulate::m_upper`).
    m45: &'a [f64; 45],
    degenerate: bool,
    scale: f64,
}

impl Ctx<'_> {
    /// S9 (optional) and S8 for one minimum. The only way out of the solver: a pose that is not
    /// finite in the world frame (e.g. a translation that overflows when the working-frame
    /// scale is undone) is [`PnpError::NoSolution`], never an `Ok`.
    fn finish(
        &self,
        m: &Minimum,
        mode: Refinement,
        opts: &ReprojOptions,
    ) -> Result<Solution, PnpError> {
        let (mut r, mut t) = (m.r, m.t);
        let mut iters = 0;
        // What S9 already knows at its final pose: the cost (equal to the reprojection error
        // when the two residual rows are not reweighted) and the depth signs, which it never
        // changes (a step that moves a point across z = 0 is rejected).
        let mut s9_error = None;
        let mut depth_signs_kept = false;
        if mode == Refinement::Reprojection {
            let out = reproj::refine_reprojection(
                self.world,
                self.image,
                self.weights,
                &self.fr.c,
                self.fr.d,
                &self.fr.rw,
                &r,
                &t,
                opts,
            );
            if out.r.iter().all(|x| x.is_finite()) && out.t.iter().all(|x| x.is_finite()) {
                r = out.r;
                t = out.t;
                if out.stop != reproj::ReprojStop::SkippedZeroDepth {
                    depth_signs_kept = true;
                    if opts.row_weights == (1.0, 1.0) && out.e.is_finite() {
                        s9_error = Some(out.e);
                    }
                }
            }
            iters = out.iterations;
        }
        // M is positive semi-definite, so f >= 0 in exact arithmetic. With wildly scaled input
        // (found by fuzzing: an image coordinate of 3e9) the accumulated M is not PSD to
        // working precision and r^T M r comes out negative; the nearest admissible value is 0.
        let f = refine::cost_at(self.m45, &r).max(0.0);
        let cheirality = match m.cheirality {
            Some(c) if mode == Refinement::Algebraic || depth_signs_kept => c,
            _ => in_front(self.world, self.weights, self.fr, &r, &t, self.fr.n_active),
        };
        let (rw, tw) = self.fr.to_world(&r, &t);
        let (e, wsum) = match s9_error {
            Some(e) => (
                e,
                self.weights
                    .map_or(self.fr.n_active as f64, |w| w.iter().sum::<f64>()),
            ),
            None => reprojection_error(self.world, self.image, self.weights, &rw, &tw),
        };
        let rot = crate::rotation::to_unit_quaternion(&rw);
        let sol = Solution {
            pose: Isometry3::from_parts(Translation3::from(tw), rot),
            rotation: rw,
            cost: if mode == Refinement::Algebraic {
                f / self.scale
            } else {
                e
            },
            algebraic_cost: f / self.scale,
            // Infinite (not NaN) when a point lies in the focal plane (depth 0) of the pose,
            // which only an algebraic-mode pose can do (see below).
            reprojection_rmse: if e.is_finite() && wsum > 0.0 {
                (e / wsum).sqrt()
            } else {
                f64::INFINITY
            },
            cheirality_ok: cheirality,
            degenerate: self.degenerate,
            planar: m.planar,
            source: m.source,
            newton_iterations: m.iterations,
            reprojection_iterations: iters,
        };
        // Reprojection mode promises the maximum-likelihood pose; a pose with a point at depth
        // 0 has an infinite reprojection error and is not one (found by fuzzing, with an image
        // coordinate of 3.5e16).
        if mode == Refinement::Reprojection && !e.is_finite() {
            return Err(PnpError::NoSolution);
        }
        let finite = sol.rotation.iter().all(|x| x.is_finite())
            && sol.pose.translation.vector.iter().all(|x| x.is_finite())
            && sol.pose.rotation.coords.iter().all(|x| x.is_finite());
        if finite {
            Ok(sol)
        } else {
            Err(PnpError::NoSolution)
        }
    }
}

/// `t = G vec(R)` (working frame).
fn translation(sys: &System, r: &Matrix3<f64>) -> Vector3<f64> {
    let rv = SVector::<f64, 9>::from_row_slice(r.transpose().as_slice());
    sys.g * rv
}

/// Whether more than half of the active points have positive depth (working-frame pose),
/// computed from the world points: `z_i = a . (X_i - c) + t_z`, `a = (R Rw)_3 / d`.
fn in_front(
    world: &[Point3<f64>],
    weights: Option<&[f64]>,
    fr: &WorkingFrame,
    r: &Matrix3<f64>,
    t: &Vector3<f64>,
    n_active: usize,
) -> bool {
    let a = (r * fr.rw).row(2).transpose() / fr.d;
    let mut pos = 0usize;
    for (i, x) in world.iter().enumerate() {
        if weights.is_some_and(|w| w[i] == 0.0) {
            continue;
        }
        if a.dot(&(x.coords - fr.c)) + t.z > 0.0 {
            pos += 1;
        }
    }
    2 * pos > n_active
}

/// Weighted sum of squared normalised reprojection residuals of a world-frame pose, and the
/// weight sum. Points at or behind the camera plane contribute an infinite residual.
fn reprojection_error(
    world: &[Point3<f64>],
    image: &[Point2<f64>],
    weights: Option<&[f64]>,
    r: &Matrix3<f64>,
    t: &Vector3<f64>,
) -> (f64, f64) {
    let (mut e, mut wsum) = (0.0, 0.0);
    for (i, (x, m)) in world.iter().zip(image).enumerate() {
        let w = weights.map_or(1.0, |w| w[i]);
        if w == 0.0 {
            continue;
        }
        let p = r * x.coords + t;
        let (du, dv) = (m.x - p.x / p.z, m.y - p.y / p.z);
        e += w * (du * du + dv * dv);
        wsum += w;
    }
    (e, wsum)
}

/// Eigen-decomposition of the 6x6 planar `M_p` (S4' steps 2-3): the two smallest eigenvalues
/// (ascending) and their unit eigenvectors.
fn planar_eigen(sys_p: &System) -> Option<([f64; 2], [SVector<f64, 6>; 2])> {
    let mp = planar_m(sys_p);
    let eig = nalgebra::SymmetricEigen::try_new(mp, f64::EPSILON, limit(Bound::MEigen));
    let eig = converged(eig, Bound::MEigen)?;
    let mut order: [usize; 6] = std::array::from_fn(|i| i);
    order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
    Some((
        [eig.eigenvalues[order[0]], eig.eigenvalues[order[1]]],
        std::array::from_fn(|i| eig.eigenvectors.column(order[i]).into_owned()),
    ))
}

/// The 6x6 planar `M_p`: `M` of the flattened system restricted to the entries of the first two
/// columns of `R` (ALGORITHM.md S4' step 2).
fn planar_m(sys_p: &System) -> SMatrix<f64, 6, 6> {
    const IDX: [usize; 6] = [0, 1, 3, 4, 6, 7];
    SMatrix::<f64, 6, 6>::from_fn(|i, j| sys_p.m[(IDX[i], IDX[j])])
}

/// S4' step 5: the rotation of a planar candidate `r6`, flipped by `diag(-1, -1, 1)` when the
/// majority of the flattened points would lie behind the camera.
fn planar_start(
    r6: &SVector<f64, 6>,
    sys_p: &System,
    world: &[Point3<f64>],
    weights: Option<&[f64]>,
    fr: &WorkingFrame,
) -> Option<Matrix3<f64>> {
    let mut r = nullspace::planar_rotation(r6)?;
    let t = translation(sys_p, &r);
    // Depths of the flattened working-frame points: z = R31 x + R32 y + t_z.
    let mut sum = 0i64;
    for (i, x) in world.iter().enumerate() {
        if weights.is_some_and(|w| w[i] == 0.0) {
            continue;
        }
        let p = fr.to_working(x);
        let z = r[(2, 0)] * p.x + r[(2, 1)] * p.y + t.z;
        sum += i64::from(z > 0.0) - i64::from(z < 0.0);
    }
    if sum < 0 {
        r *= Matrix3::from_diagonal(&Vector3::new(-1.0, -1.0, 1.0));
    }
    Some(r)
}

/// The pose from world points and normalised image points with the default [`Solver`].
///
/// # Errors
/// See [`Solver::solve`].
pub fn solve(world: &[Point3<f64>], image: &[Point2<f64>]) -> Result<Solution, PnpError> {
    Solver::default().solve(world, image)
}
