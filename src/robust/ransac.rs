//! Robust pose estimation: RANSAC with the [`crate::p3p`] minimal solver, EOPnP local
//! optimisation and a final fit that keeps every good point.
//!
//! ```
//! use eopnp::ransac::Ransac;
//! use eopnp::{Problem, Solver};
//! use nalgebra::{Point2, Point3, Vector3};
//!
//! // 40 points seen by a camera at (0, 0, -6); every fourth correspondence is wrong.
//! let mut world = Vec::new();
//! let mut image = Vec::new();
//! for i in 0..40 {
//!     let x = Point3::new((i % 7) as f64 - 3.0, (i % 5) as f64 - 2.0, (i % 3) as f64);
//!     let p = x.coords + Vector3::new(0.0, 0.0, 6.0);
//!     let obs = if i % 4 == 0 { Point2::new(0.3, -0.2) } else { Point2::new(p.x / p.z, p.y / p.z) };
//!     world.push(x);
//!     image.push(obs);
//! }
//! // Normalised image points, focal length 1000 px, 2 px threshold.
//! let r = Ransac::default().threshold_px(2.0).seed(7);
//! let sol = r.estimate(&Solver::default(), &Problem::normalised(&world, &image).focal(1000.0, 1000.0))?;
//! assert_eq!(sol.num_inliers, 30);
//! assert!((sol.solution.translation - Vector3::new(0.0, 0.0, 6.0)).norm() < 1e-9);
//! # Ok::<(), eopnp::PnpError>(())
//! ```
//!
//! # Method
//!
//! 1. Hypotheses: three distinct correspondences drawn uniformly by a seeded PCG generator
//!    (`rand_pcg::Pcg64`: the same seed gives the same samples on every platform), solved by
//!    P3P (up to four poses each).
//! 2. Scoring: MSAC, the truncated quadratic cost `sum_i min(e_i^2, T^2)` of the pixel
//!    reprojection errors `e_i` (`T` = [`Ransac::threshold_px`]; a point behind the camera costs
//!    `T^2`). Scoring a hypothesis stops as soon as its partial cost exceeds the best one.
//! 3. Local optimisation: every new best hypothesis is refitted by EOPnP (the given
//!    [`Solver`], i.e. by default the maximum-likelihood pose) on its inliers, repeated while
//!    the MSAC cost drops (at most 4 times).
//! 4. Adaptive stopping: after `k = ln(1 - p) / ln(1 - w^3)` iterations, `w` the best inlier
//!    ratio and `p` = [`Ransac::confidence`], clamped to
//!    [`Ransac::min_iterations`]..=[`Ransac::max_iterations`].
//! 5. Final fit: EOPnP on the inliers, re-classify, refit, until the inlier set stops changing
//!    (at most 10 refits). The final classification uses the threshold
//!    `T * final_threshold_factor` (default 2): a fixed threshold `T` tuned for scoring noisy
//!    three-point hypotheses cuts the tail of the true inliers' residual distribution off the
//!    accurate final pose (on the bundled model, 4 px drops good observations that COLMAP kept
//!    and the pose error rises several-fold), while wrong correspondences are typically tens to
//!    hundreds of pixels off and are not readmitted.
//!
//! 6. Consensus: the final inliers must be more than wrong poses reach by chance (a
//!    contrario RANSAC). Under the null hypothesis that the correspondences say nothing about
//!    the pose, a point is within the final threshold `T_f` of a wrong pose's projection with
//!    probability `p = pi T_f^2 / A` (`A` the pixel area the observations cover). `k` inliers
//!    of `N` are accepted only if their number of false alarms
//!    `4 (N - 3) C(N, k) C(k, 3) p^(k - 3)` is at most 1, and at least 6 (every point when
//!    N < 6); otherwise [`PnpError::NoConsensus`] says how many inliers were found and how
//!    many are needed. Pure noise, 99 % outliers and COLMAP images whose correspondences are
//!    all wrong are `NoConsensus`; clean N = 4 and 5 problems spread over more than about
//!    60 x 60 px pass (`tests/ransac_consensus.rs`).
//!
//! Every loop is bounded. Unlike [`Solver::solve`], this path allocates (the inlier mask and
//! per-call scratch buffers, `O(N)`, once per call; nothing per iteration).

use std::time::Instant;

use nalgebra::{Point2, Point3, Vector3};
use rand_core::SeedableRng;
use rand_pcg::Pcg64;

use super::p3p::{p3p, P3pSolutions};
use crate::camera::Camera;
use crate::covariance::Metric;
use crate::error::{InputKind, PnpError};
use crate::gravity::Gravity;
use crate::pipeline::PixelInputs;
use crate::problem::{Observations, Problem};
use crate::solver::undistort_all;
use crate::{Solution, Solver};

/// Maximum EOPnP refits per local optimisation.
pub(crate) const LO_STEPS: u32 = 4;
/// Maximum refits of the final fit.
pub(crate) const FINAL_STEPS: u32 = 10;
/// Attempts to draw three distinct indices before giving up on one iteration (only reachable
/// with absurdly few points).
const SAMPLE_ATTEMPTS: u32 = 64;
/// SPRT decision threshold: a good hypothesis is rejected with probability about `1 / SPRT_A`
/// (accounted for in the adaptive iteration count).
const SPRT_A: f64 = 1000.0;
/// Initial and bounds of the SPRT's `delta` (fraction of points consistent with a bad model),
/// re-estimated as the mean over the rejected hypotheses.
const SPRT_DELTA0: f64 = 0.05;
/// Lower bound of the SPRT's `eps` (inlier ratio of a good model) once a best hypothesis
/// exists. Without it, a bad first best hypothesis (a few consistent points, an inlier ratio
/// near 0) disables the test in practice until a good sample is drawn: on the bundled model
/// at 80 % outliers, image 4 draws its first good sample at iteration 523 and scored about
/// 1330 of its 2203 points per rejected hypothesis, about four times the time of the other
/// images (callgrind: 129 M instructions in `estimate` against 23-34 M; 18 M with this bound). A good model whose inlier ratio is below this bound is still
/// accepted by the test's drift as long as its ratio exceeds about
/// `ln((1 - delta) / (1 - eps)) / ln(eps / delta * (1 - delta) / (1 - eps))` (about 3 % for
/// `delta` = 0.002); below about 9 % inliers the adaptive count exceeds the default
/// [`Ransac::max_iterations`] anyway.
const SPRT_EPS_MIN: f64 = 0.1;
/// Inliers an EOPnP fit needs: EOPnP needs four points, and local optimisation wants more than
/// the three of the sample; a problem with fewer points (N = 4, 5) needs all of them.
const MIN_FIT_POINTS: usize = 6;

/// RANSAC options. `Ransac::default()` is the recommended configuration; set options with the
/// builder methods (`Ransac::default().threshold_px(2.0).seed(7)`), which document each
/// default. The fields are public for reading (bindings show and copy them).
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct Ransac {
    /// [`Ransac::threshold_px`].
    pub threshold_px: f64,
    /// [`Ransac::confidence`].
    pub confidence: f64,
    /// [`Ransac::max_iterations`].
    pub max_iterations: u32,
    /// [`Ransac::min_iterations`].
    pub min_iterations: u32,
    /// [`Ransac::seed`].
    pub seed: u64,
    /// [`Ransac::local_optimisation`].
    pub local_optimisation: bool,
    /// [`Ransac::final_threshold_factor`].
    pub final_threshold_factor: f64,
}

impl Default for Ransac {
    fn default() -> Self {
        Ransac {
            threshold_px: 4.0,
            confidence: 0.999,
            max_iterations: 10_000,
            min_iterations: 20,
            seed: 0,
            local_optimisation: true,
            final_threshold_factor: 2.0,
        }
    }
}

/// Statistics of a RANSAC run.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[non_exhaustive]
pub struct RansacStats {
    /// Samples drawn.
    pub iterations: u32,
    /// P3P poses scored.
    pub hypotheses: u32,
    /// EOPnP fits in local optimisation.
    pub local_fits: u32,
    /// EOPnP fits in the final fit.
    pub final_fits: u32,
    /// Inliers of the returned pose (final threshold).
    pub inliers: usize,
    /// `inliers / N`.
    pub inlier_ratio: f64,
    /// Wall time, microseconds.
    pub micros: f64,
}

/// The result of [`Ransac::estimate`].
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Clone, Debug)]
#[non_exhaustive]
pub struct RansacSolution {
    /// The pose, fitted by EOPnP on the inliers.
    pub solution: Solution,
    /// `inliers[i]`: correspondence `i` is an inlier of the returned pose.
    pub inliers: Vec<bool>,
    /// Number of inliers.
    pub num_inliers: usize,
    /// Run statistics.
    pub stats: RansacStats,
}

/// Iterations needed for `confidence` with inlier ratio `w` and samples of `size` (3, or 2 with
/// a known vertical).
fn needed_iterations(confidence: f64, w: f64, size: i32) -> f64 {
    let good = w.powi(size);
    if good >= 1.0 {
        return 0.0;
    }
    if good <= 0.0 {
        return f64::INFINITY;
    }
    // A good sample is found and survives the SPRT with probability about w^size (1 - 1/A).
    let good = good * (1.0 - 1.0 / SPRT_A);
    (1.0 - confidence).ln() / (1.0 - good).ln()
}

impl Ransac {
    /// The inlier threshold on the reprojection error, in pixels (for normalised input, in
    /// units of [`Problem::focal`]'s focal lengths). Default: `4.0`.
    #[must_use]
    pub fn threshold_px(mut self, px: f64) -> Self {
        self.threshold_px = px;
        self
    }

    /// The probability that at least one all-inlier sample is drawn (adaptive stopping).
    /// Default: `0.999`.
    #[must_use]
    pub fn confidence(mut self, p: f64) -> Self {
        self.confidence = p;
        self
    }

    /// A hard bound on the iterations (samples). Default: `10_000`.
    #[must_use]
    pub fn max_iterations(mut self, n: u32) -> Self {
        self.max_iterations = n;
        self
    }

    /// The iterations always done. Default: `20`.
    #[must_use]
    pub fn min_iterations(mut self, n: u32) -> Self {
        self.min_iterations = n;
        self
    }

    /// The seed of the sampling generator. Default: `0`.
    #[must_use]
    pub fn seed(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }

    /// Local optimisation of every new best hypothesis by EOPnP. Default: `true`.
    #[must_use]
    pub fn local_optimisation(mut self, on: bool) -> Self {
        self.local_optimisation = on;
        self
    }

    /// The final inlier classification uses `threshold_px * final_threshold_factor` (see the
    /// module documentation). Default: `2.0`; `1.0` keeps the scoring threshold.
    #[must_use]
    pub fn final_threshold_factor(mut self, f: f64) -> Self {
        self.final_threshold_factor = f;
        self
    }

    /// [`PnpError::InvalidOption`] for the first option out of its range.
    fn check(&self) -> Result<(), PnpError> {
        let bad = |option| Err(PnpError::InvalidOption { option });
        // The scores compare squared errors with the squared threshold: it must be a normal
        // number (a threshold below about 1e-154 px squares to a subnormal or to 0).
        let th2 = self.threshold_px * self.threshold_px;
        if !(self.threshold_px.is_finite() && self.threshold_px > 0.0 && th2.is_normal()) {
            return bad("threshold_px");
        }
        if !(self.confidence > 0.0 && self.confidence < 1.0) {
            return bad("confidence");
        }
        if self.max_iterations == 0 {
            return bad("max_iterations");
        }
        let final_th = self.threshold_px * self.final_threshold_factor;
        if !(self.final_threshold_factor.is_finite()
            && self.final_threshold_factor >= 1.0
            && (final_th * final_th).is_normal())
        {
            return bad("final_threshold_factor");
        }
        Ok(())
    }

    /// The robust pose of a [`Problem`]: RANSAC with P3P samples, EOPnP (`solver`) for the
    /// local optimisation and the final fit.
    ///
    /// The pixel reprojection error of point `i` is `sqrt(w_i (fx^2 dx^2 + fy^2 dy^2))`,
    /// `(dx, dy)` the normalised residual and `w_i` the point's weight (1 without weights):
    /// for [`Problem::pixels`], `(fx, fy)` are the camera's and the pixels are undistorted and
    /// weighted by the lens distortion's local scale as in [`Solver::solve`] (the threshold
    /// then applies to first-order pixel errors through the distortion; a pixel that cannot
    /// be undistorted is an outlier, `false` in the mask); for [`Problem::normalised`], they
    /// are [`Problem::focal`]'s. The fits minimise the same error (and, in the default mode,
    /// the final fit the pixel error through the camera). A point of weight 0 is never an
    /// inlier of a fit. The time in the statistics includes the undistortion.
    ///
    /// When `solver` asks for the pose covariance ([`Solver::covariance`]), the returned
    /// solution carries the covariance of the returned pose from its inliers (with their
    /// weights), exactly what [`Solver::solve`] with that option reports for the same pose and
    /// points.
    ///
    /// # Errors
    /// [`PnpError::LengthMismatch`], [`PnpError::WeightsLength`], [`PnpError::TooFewPoints`]
    /// (fewer than 4), [`PnpError::NonFinite`], [`PnpError::InvalidWeight`],
    /// [`PnpError::InvalidOption`] for an option out of its range (checked first) and for a
    /// focal length that is not finite and positive (`"focal"`), and
    /// [`PnpError::NoConsensus`] if no hypothesis has enough inliers for an EOPnP fit, or if
    /// the final pose's inliers are no more than wrong poses reach by chance at this threshold
    /// (see "Consensus" in the module documentation).
    pub fn estimate(
        &self,
        solver: &Solver,
        problem: &Problem<'_>,
    ) -> Result<RansacSolution, PnpError> {
        let (world, weights) = (problem.world, problem.weights);
        if let Some((points, camera, free)) = crate::solver::intrinsics_input(problem)? {
            let out = match free.range {
                Some(range) => {
                    self.estimate_focal(solver, camera, world, points, weights, range)?
                }
                None => self.estimate_pixels(solver, camera, world, points, weights, None)?,
            };
            if !(free.free.principal_point || free.free.distortion) {
                return Ok(out);
            }
            return self.refit_intrinsics(solver, (world, points, weights), camera, free, out);
        }
        match problem.observations {
            Observations::Normalised { points, focal } => {
                self.estimate_normalised(solver, world, points, focal, weights, problem.gravity)
            }
            Observations::Pixels { points, camera } => {
                self.estimate_pixels(solver, camera, world, points, weights, problem.gravity)
            }
            Observations::Rig {
                points,
                cameras,
                rig,
            } => self.estimate_rig(
                solver,
                &crate::generalized::RigInput {
                    world,
                    pixels: points,
                    cameras,
                    rig,
                    weights,
                    gravity: problem.gravity,
                },
            ),
        }
    }

    /// [`Ransac::estimate`] of normalised image points.
    fn estimate_normalised(
        &self,
        solver: &Solver,
        world: &[Point3<f64>],
        image: &[Point2<f64>],
        focal: (f64, f64),
        weights: Option<&[f64]>,
        gravity: Option<Gravity>,
    ) -> Result<RansacSolution, PnpError> {
        let pixel = solver.normalised_loss(image, weights);
        let mut sol = self.estimate_with(solver, world, image, focal, weights, pixel, gravity)?;
        let weight = |i: usize| inlier_weight(&sol.inliers, weights, i);
        sol.solution =
            solver.with_covariance(sol.solution, world, image, &weight, Metric::Identity);
        Ok(sol)
    }

    /// [`Ransac::estimate`] with `refine_pixels`' observations of every point (`pixel`) for the
    /// fits; with a known vertical, samples of two points and the final fit with its prior.
    #[allow(clippy::too_many_arguments)]
    fn estimate_with(
        &self,
        solver: &Solver,
        world: &[Point3<f64>],
        image: &[Point2<f64>],
        focal: (f64, f64),
        weights: Option<&[f64]>,
        pixel: Option<PixelInputs<'_>>,
        gravity: Option<Gravity>,
    ) -> Result<RansacSolution, PnpError> {
        let start = Instant::now();
        self.check()?;
        solver.check_loss()?;
        let n = world.len();
        crate::pipeline::check_lengths(n, image.len(), weights)?;
        let (fx, fy) = focal;
        if !(fx.is_finite() && fy.is_finite() && fx > 0.0 && fy > 0.0) {
            return Err(PnpError::InvalidOption { option: "focal" });
        }
        for (i, (x, p)) in world.iter().zip(image).enumerate() {
            if !x.coords.iter().all(|v| v.is_finite()) {
                return Err(PnpError::NonFinite {
                    index: i,
                    input: InputKind::World,
                });
            }
            if !(p.x.is_finite() && p.y.is_finite()) {
                return Err(PnpError::NonFinite {
                    index: i,
                    input: InputKind::Image,
                });
            }
        }
        let weights = match weights {
            Some(w) => {
                for (i, v) in w.iter().enumerate() {
                    if !v.is_finite() {
                        return Err(PnpError::NonFinite {
                            index: i,
                            input: InputKind::Weight,
                        });
                    }
                    if *v < 0.0 {
                        return Err(PnpError::InvalidWeight { index: i });
                    }
                }
                w.to_vec()
            }
            None => vec![1.0; n],
        };
        let fmax = fx.max(fy);
        let prob = ScoringSet {
            world,
            image,
            weights,
            fx2: fx * fx,
            fy2: fy * fy,
            rows: ((fx / fmax).powi(2), (fy / fmax).powi(2)),
            pixel,
        };
        let th = self.threshold_px;
        let th2 = th * th;
        let confidence = self.confidence;
        let bearings: Vec<Vector3<f64>> =
            image.iter().map(|p| Vector3::new(p.x, p.y, 1.0)).collect();
        // With a known vertical: samples of two, solved by up2p.
        let upright = gravity.as_ref().map(Upright::new);
        let size = if upright.is_some() { 2 } else { 3 };
        let origin = Point3::origin();

        let mut stats = RansacStats::default();
        let mut rng = Pcg64::seed_from_u64(self.seed);
        let mut mask = vec![false; n];
        let mut buf = FitBuffers::default();
        let mut best: Option<Scored> = None;
        let mut needed = f64::INFINITY;
        // Random scoring order for the SPRT (the input order may correlate with inlierness).
        let mut order: Vec<usize> = (0..n).collect();
        for i in 0..n.saturating_sub(1) {
            let j = i + index(&mut rng, n - i);
            order.swap(i, j);
        }
        let (mut rej_consistent, mut rej_scored) = (0usize, 0usize);
        let mut delta = SPRT_DELTA0;
        let max_it = self.max_iterations;
        while stats.iterations < max_it
            && (stats.iterations < self.min_iterations || f64::from(stats.iterations) < needed)
        {
            stats.iterations += 1;
            let poses = if let Some(up) = &upright {
                let Some([a, b]) = sample2(&mut rng, n) else {
                    continue;
                };
                let mut poses = P3pSolutions::new();
                let (w, o, v) = (&world, &origin, &bearings);
                poses.extend(up.poses([&w[a], &w[b]], [o, o], [&v[a], &v[b]]));
                poses
            } else {
                let Some(idx) = sample3(&mut rng, n) else {
                    continue;
                };
                let wp = [world[idx[0]], world[idx[1]], world[idx[2]]];
                let bp = [bearings[idx[0]], bearings[idx[1]], bearings[idx[2]]];
                p3p(&wp, &bp)
            };
            for pose in poses {
                stats.hypotheses += 1;
                let bound = best.map_or(f64::INFINITY, |b| b.cost);
                // The SPRT's good-model inlier ratio: the best hypothesis's, but at least
                // SPRT_EPS_MIN (a prior): while the best is still a bad model
                // consistent with a handful of points, its ratio makes the test powerless and
                // every hypothesis is scored on most of the points.
                let eps = best.map_or(0.0, |b| (b.inliers as f64 / n as f64).max(SPRT_EPS_MIN));
                let mut cand = match prob.score_sprt(
                    &pose.rotation,
                    &pose.translation,
                    th2,
                    bound,
                    &order,
                    eps,
                    delta,
                ) {
                    Ok(c) => c,
                    Err((consistent, scored)) => {
                        rej_consistent += consistent;
                        rej_scored += scored;
                        if rej_scored > 0 {
                            delta = (rej_consistent as f64 / rej_scored as f64).clamp(1e-3, 0.2);
                        }
                        continue;
                    }
                };
                if self.local_optimisation {
                    for _ in 0..LO_STEPS {
                        stats.local_fits += 1;
                        let Some(s) = prob.fit(solver, &cand.r, &cand.t, th2, &mut mask, &mut buf)
                        else {
                            break;
                        };
                        let t = s.translation;
                        match prob.score(&s.rotation, &t, th2, cand.cost) {
                            Some(better) if better.cost < cand.cost => cand = better,
                            _ => break,
                        }
                    }
                }
                best = Some(cand);
                needed = needed_iterations(confidence, cand.inliers as f64 / n as f64, size);
            }
        }
        let no_consensus = PnpError::NoConsensus {
            iterations: stats.iterations,
            inliers: best.map_or(0, |b| b.inliers),
            needed: MIN_FIT_POINTS.min(n),
        };
        let best = best.ok_or(no_consensus.clone())?;

        // Final fit: refit and re-classify with the final threshold until the set is stable.
        let factor = self.final_threshold_factor;
        let thf2 = (th * factor).powi(2);
        let (mut r, mut t) = (best.r, best.t);
        let mut solution: Option<Solution> = None;
        let mut prev_mask: Vec<bool> = Vec::new();
        for _ in 0..FINAL_STEPS {
            stats.final_fits += 1;
            let Some(s) = prob.fit(solver, &r, &t, thf2, &mut mask, &mut buf) else {
                break;
            };
            r = s.rotation;
            t = s.translation;
            solution = Some(s);
            let stable = prev_mask == mask;
            prev_mask.clone_from(&mask);
            if stable {
                break;
            }
        }
        let mut solution = solution.ok_or(no_consensus)?;
        // With a known vertical: the final inliers' maximum a posteriori pose (and the test that
        // they agree with the vertical).
        if gravity.is_some() {
            let with_prior = solver.with_gravity(gravity);
            if let Some(s) = prob.fit_result(&with_prior, &r, &t, thf2, &mut mask, &mut buf) {
                solution = s?;
                r = solution.rotation;
                t = solution.translation;
            }
        }
        // The mask of the returned pose.
        for (i, m) in mask.iter_mut().enumerate() {
            *m = prob.sq_err(&r, &t, i) < thf2;
        }
        let num_inliers = mask.iter().filter(|m| **m).count();
        // A consensus no larger than wrong poses reach by chance is none (chance.rs).
        let rate = chance::chance_inlier_rate(image, focal, th * factor);
        let needed = chance::least_consensus(n, rate).max(MIN_FIT_POINTS.min(n));
        if num_inliers < needed {
            return Err(PnpError::NoConsensus {
                iterations: stats.iterations,
                inliers: num_inliers,
                needed,
            });
        }
        stats.inliers = num_inliers;
        stats.inlier_ratio = num_inliers as f64 / n as f64;
        stats.micros = start.elapsed().as_secs_f64() * 1e6;
        Ok(RansacSolution {
            solution,
            inliers: mask,
            num_inliers,
            stats,
        })
    }

    /// [`Ransac::estimate`] of pixels through a camera.
    fn estimate_pixels(
        &self,
        solver: &Solver,
        camera: &Camera,
        world: &[Point3<f64>],
        pixels: &[Point2<f64>],
        weights: Option<&[f64]>,
        gravity: Option<Gravity>,
    ) -> Result<RansacSolution, PnpError> {
        let start = Instant::now();
        self.check()?;
        solver.check_loss()?;
        let u = undistort_all(world, pixels, camera, weights, true)?;
        let px = solver.camera_loss(&u, camera);
        let mut sol = self.estimate_with(
            solver,
            &u.world,
            &u.image,
            u.focal,
            u.weights.as_deref(),
            Some(px),
            gravity,
        )?;
        // The covariance from the inliers with the caller's weights, not the first-order
        // distortion weights of the fits (as a solve of pixels).
        let weight = |k: usize| inlier_weight(&sol.inliers, u.user_weights.as_deref(), k);
        sol.solution = solver.with_covariance(
            sol.solution,
            &u.world,
            &u.image,
            &weight,
            Metric::Camera(camera),
        );
        if let Some(used) = &u.used {
            let mut full = vec![false; world.len()];
            for (k, &i) in used.iter().enumerate() {
                full[i] = sol.inliers[k];
            }
            sol.inliers = full;
            sol.stats.inlier_ratio = sol.num_inliers as f64 / world.len() as f64;
        }
        sol.solution.skipped = world.len() - u.image.len();
        sol.stats.micros = start.elapsed().as_secs_f64() * 1e6;
        Ok(sol)
    }
}

/// The RANSAC seed of problem `index` of a batch (`Ransac::estimate_batch`, feature
/// `rayon`) whose base seed is `base`: SplitMix64 of the
/// base mixed with SplitMix64 of the index, so that nearby indices and bases give unrelated
/// sample sequences.
#[must_use]
pub fn problem_seed(base: u64, index: usize) -> u64 {
    splitmix64(base ^ splitmix64(index as u64))
}

fn splitmix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// The weight of correspondence `i` in the covariance of a RANSAC pose: its caller's weight
/// (1 without weights) if it is an inlier, 0 otherwise.
fn inlier_weight(inliers: &[bool], weights: Option<&[f64]>, i: usize) -> f64 {
    if inliers[i] {
        weights.map_or(1.0, |w| w[i])
    } else {
        0.0
    }
}

mod chance;
mod focal;
mod intrinsics;
mod rig;
mod score;
mod upright;

pub(crate) use score::index;
use score::{sample2, sample3, FitBuffers, Scored, ScoringSet};
use upright::Upright;

/// `impl sample_consensus::Estimator` (feature `sample-consensus`), so rust-cv's consensus
/// algorithms (e.g. `arrsac::Arrsac`) can drive the [`crate::p3p`] minimal solver; refit the
/// consensus's inliers with [`Solver`] (EOPnP) afterwards, as [`Ransac`] does.
#[cfg(feature = "sample-consensus")]
pub mod consensus;
