//! The `refine` stage of docs/algorithm.md: Levenberg-Marquardt refinement of the reprojection
//! error.
//!
//! Minimises `E(R, t) = sum_i w_i (wx e_ix^2 + wy e_iy^2)`, `e_i = m_i - pi(R P_i + t)`,
//! `pi(x, y, z) = (x / z, y / z)`, over the working-frame pose `(R, t)` with the update
//! `R := Exp(w) R`, `t := t + tau`. Nielsen's damping rule; a step is accepted only if it lowers
//! `E` and keeps the sign of every depth, so `E` never increases and no point crosses `z = 0`
//! (a tiny final step is accepted on proof of both instead of evaluation, see below).
//! Reference: the `refine` function of the numpy reference prototype (docs/algorithm.md, `refine`).
//!
//! The working-frame points `P_i = Rw (X_i - c) / d` (`frame`) are never materialised: every pass
//! composes the frame into the pose, `p_i = A (X_i - c) + t` with `A = R Rw / d`, and
//! `q_i = R P_i = A (X_i - c)` is the lever arm of the rotation Jacobian. Each pass is O(N)
//! and allocation-free; the 6 x 6 normal equations keep their 21 unique entries.
//!
//! `J^T W J` is reused while the pose stays close to where it was computed: a candidate pose
//! within `HESSIAN_REUSE_REL (|t| + 1)` (sum of the step norms since) is evaluated by a pass
//! that sums only the cost, the gradient and the depths (7 sums per point instead of 27), and
//! the step is solved with the earlier `J^T W J`. The gradient is always exact, so the
//! stationary point and the stopping tests are those of plain LM; only the step's matrix is
//! off, by about the relative distance moved (at most 1e-3), which changes the linear
//! convergence rate of Gauss-Newton on a non-zero residual (about sigma / f) by as much. From
//! the algebraic start usually only the first pass forms `J^T W J` (callgrind probe, general
//! scenes, sigma = 2 px: 370 later passes did in 2,000 solves at N = 10, none at N = 100 and
//! N = 1000).
//!
//! The final step is taken unverified when it is tiny and the run has converged to the point
//! where the next step would be negligible anyway: a step `delta` with
//! - `|delta| <= FINAL_STEP_REL (|t| + 1)` (`FINAL_STEP_REL = 1e-7`),
//! - `|delta|^2 / |delta_prev| <= xtol (|t| + 1)`, where `delta_prev` is the step accepted in
//!   the iteration just before (none after a rejected step or a failed factorisation): near the
//!   minimum LM converges linearly with the ratio `|delta| / |delta_prev|`, so the left side
//!   is the predicted size of the next step, the one that would end the run by the `xtol` test,
//! - `|delta| (max_i |q_i| + 1) < min_i |z_i| / 2`,
//!
//! is applied without the O(N) pass that would evaluate it, and the refinement stops
//! ([`ReprojStop::FinalStep`], converged). It saves the last of the (typically four) passes:
//! that pass would only confirm the step and compute a next step below `xtol`. Why this is safe:
//! - Depths keep their signs. With `delta = (w, tau)`, a depth moves by
//!   `|z_i' - z_i| <= |Exp(w) q_i - q_i| + |tau| <= |w| |q_i| + |tau| <= |delta| (|q_i| + 1)`,
//!   less than half the smallest `|z_i|`; the other half is the margin for rounding. `|q_i| =
//!   |X_i - c| / d` does not depend on the pose: it is measured once, in the first pass.
//! - The cost does not go up. The predicted decrease `pred = -(2 g.delta + delta.H.delta)` of
//!   the damped Gauss-Newton model (computed as `lam |delta|^2 - g.delta`, equal since
//!   `(H + lam I) delta = -g`) is positive, and the true decrease differs from it by the
//!   residual-curvature term, a fraction of `pred` of the order of the linear convergence
//!   ratio (below 1 here: the second condition with `|delta| > xtol (|t| + 1)` gives
//!   `|delta| / |delta_prev| < 1`), plus `O(|delta|^3)`. The returned cost is the prediction,
//!   `E - pred` clamped to `[0, E]`, so the reported `e` still never exceeds `e0`.
//! - The accuracy is that of the `xtol` stop: that stop leaves the last (unapplied) step, at
//!   most `xtol (|t| + 1)`, as the distance to the minimum; this one leaves the predicted next
//!   step, bounded alike.
//!
//! From an exact fit ([`ReprojOptions::exact_start`]: `newton` was skipped because the start's
//! algebraic cost is at the rounding level, docs/algorithm.md, the driver) the `xtol` stop
//! applies its step instead of dropping it, when it cannot flip a depth sign (the third
//! condition above). The residuals are at the rounding level, where Gauss-Newton converges
//! quadratically: the step corrects the start's error (the rounding of M's null vector, up to
//! about 1e-9 in quasi-singular scenes) to second order, which the dropped step would leave
//! in the pose.

use nalgebra::{Matrix3, Point2, Point3, Vector3};

pub(super) mod pass;

use pass::{pass, Metric, PassInputs, RowWeights};

use super::frame::WorkingFrame;
use super::vertical::{self, PriorTerm, Vertical, VerticalCheck};
use crate::numeric::linalg::solve_damped6;
use crate::numeric::rotation::exp_so3;

/// Options of the reprojection refinement (`refine`). The defaults are docs/algorithm.md's values.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct ReprojOptions {
    /// Hard cap on LM iterations (rejected steps and failed factorisations count). Default 200,
    /// the bound of the tests' reference LM: with 50, runs in the flat valleys of some N = 4
    /// problems stopped above the minimum (docs/algorithm.md, `search`).
    pub max_iterations: u32,
    /// Initial damping relative to the largest diagonal entry of `J^T J`. Default `1e-6`.
    pub tau: f64,
    /// Stop when `|delta| <= xtol (|t| + 1)`. Default `1e-10`.
    pub xtol: f64,
    /// Stop when `max_k |g_k| <= gtol sqrt(trace(J^T J) E)`. Default `1e-13`.
    pub gtol: f64,
    /// Weights of the x and y residual rows, e.g. `(fx^2, fy^2)` to minimise the pixel error
    /// for anisotropic intrinsics. Default `(1, 1)`.
    pub row_weights: (f64, f64),
    /// The start is an exact fit (f at the rounding level, `newton` skipped): the step of the
    /// `xtol` stop, Gauss-Newton on residuals at the rounding level, is applied (module docs).
    /// Default `false`.
    pub exact_start: bool,
    /// A known vertical: [`levenberg_marquardt`] continues from the maximum-likelihood pose to
    /// the maximum a posteriori pose with the vertical as a prior ([`super::vertical`]).
    /// Default `None`.
    pub vertical: Option<Vertical>,
}

impl Default for ReprojOptions {
    fn default() -> Self {
        Self {
            max_iterations: 200,
            tau: 1e-6,
            xtol: 1e-10,
            gtol: 1e-13,
            row_weights: (1.0, 1.0),
            exact_start: false,
            vertical: None,
        }
    }
}

/// Why the refinement stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum ReprojStop {
    /// The gradient test passed (converged).
    Gradient,
    /// The step became negligible (converged).
    Step,
    /// A tiny final step was applied without evaluating it (converged; see the module docs).
    FinalStep,
    /// The damping grew beyond `1e16 max_k H_kk` without an acceptable step.
    Damping,
    /// The iteration cap was reached.
    MaxIterations,
    /// Some starting depth is zero (`|z_i| <= 1e-12 max |z|`): nothing was done.
    SkippedZeroDepth,
    /// The caller's predicate stopped the run at a [`Checkpoint`] (the small-N search: the
    /// iterate entered the basin of a minimum already found, or the next step's predicted
    /// decrease says the run cannot end below the best pose found).
    Abandoned,
}

impl ReprojStop {
    /// The run ended at a minimum: its gradient or step test passed, or no step lowered the
    /// cost any more.
    pub(crate) fn converged(self) -> bool {
        matches!(
            self,
            ReprojStop::Gradient | ReprojStop::Step | ReprojStop::FinalStep | ReprojStop::Damping
        )
    }
}

/// Result of [`refine_reprojection`]: the working-frame pose and diagnostics.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ReprojOutcome {
    /// Refined working-frame rotation.
    pub r: Matrix3<f64>,
    /// Refined working-frame translation.
    pub t: Vector3<f64>,
    /// Cost `E` at the start (NaN when skipped).
    #[cfg_attr(not(test), allow(dead_code))]
    pub e0: f64,
    /// Cost `E` at the returned pose (NaN when skipped); never above `e0`. After
    /// [`ReprojStop::FinalStep`], the linear model's prediction of it.
    pub e: f64,
    /// Iterations performed (0 when skipped).
    pub iterations: u32,
    /// Stop reason.
    pub stop: ReprojStop,
    /// The number of active points in front of the camera (positive depth) at the starting
    /// pose, counted by the first pass (`None` if it did not run).
    pub start_in_front: Option<usize>,
    /// With [`ReprojOptions::vertical`]: the measured vertical against the maximum-likelihood
    /// pose's (`None` without one, or if the maximum a posteriori run could not start).
    pub vertical: Option<VerticalCheck>,
}

/// Relative depth below which a starting depth counts as zero.
const ZERO_DEPTH_REL: f64 = 1e-12;
/// Give up once the damping exceeds this multiple of the largest diagonal entry of `J^T J`.
const DAMPING_LIMIT_REL: f64 = 1e16;
/// Reuse of `J^T W J` (module docs): a pass evaluates only the cost and the gradient while
/// the candidate pose is within `HESSIAN_REUSE_REL (|t| + 1)` (sum of step norms) of the pose
/// where `J^T W J` was last computed.
const HESSIAN_REUSE_REL: f64 = 1e-3;
/// Bound on a step taken without evaluating it: `|delta| <= FINAL_STEP_REL (|t| + 1)` (one of
/// the three conditions of the module docs).
const FINAL_STEP_REL: f64 = 1e-7;

/// A pose with the working frame composed in: `p_i = a (X_i - c) + t`.
#[derive(Clone, Copy)]
pub(super) struct Composed {
    pub(super) a: Matrix3<f64>,
    pub(super) t: Vector3<f64>,
}

impl Composed {
    pub(super) fn new(r: &Matrix3<f64>, rw: &Matrix3<f64>, d: f64, t: &Vector3<f64>) -> Self {
        Self {
            a: (r * rw) / d,
            t: *t,
        }
    }
}

/// `J^T W J` at one pose (upper triangle filled, then mirrored). A pass writes it into a
/// buffer of the caller's ([`Residuals::accumulate`]): Levenberg-Marquardt keeps two and
/// switches between them, where moving a [`Normal`] with its `H` had copied 384 bytes per
/// accepted step (a `memcpy` call; 500 general N = 4 solves 28.49M -> 27.56M instructions).
pub(super) type Hessian = [[f64; 6]; 6];

/// The rest of the normal equations at one pose: `g = J^T W e`, `e = E`, the extreme
/// absolute depths and the largest lever arm `|q_i|` (`J^T W J` is a [`Hessian`] beside it).
#[derive(Clone, Copy)]
pub(super) struct Normal {
    pub(super) g: [f64; 6],
    pub(super) e: f64,
    pub(super) min_abs_z: f64,
    pub(super) max_abs_z: f64,
    /// `max_i |q_i|` over the active points. Only the pass without reference pose computes it
    /// (NaN otherwise): `|q_i| = |X_i - c| / d` does not depend on the pose.
    pub(super) max_abs_q: f64,
    /// The active points with positive depth; only the pass without reference pose counts
    /// them (`None` otherwise).
    pub(super) in_front: Option<usize>,
}

/// The residuals one Levenberg-Marquardt run minimises ([`levenberg_marquardt`]): `refine`'s
/// normalised residuals ([`Problem`]) or `refine_pixels`' pixel residuals through the camera
/// ([`super::refine_pixels`]).
pub(super) trait Residuals {
    /// One O(N) pass at `pose`: cost, `J^T W J` (into `h`), gradient and depth range (and,
    /// without `reference`, `max_abs_q`). With `reference`, `None` as soon as a depth differs
    /// in sign from its depth under `reference` (`h` then undefined).
    fn accumulate(
        &self,
        pose: &Composed,
        reference: Option<&Composed>,
        h: &mut Hessian,
    ) -> Option<Normal>;

    /// As [`Residuals::accumulate`] with a reference pose, without `J^T W J`: the caller
    /// keeps its `J^T W J` from a nearby pose (see [`HESSIAN_REUSE_REL`]).
    fn accumulate_gradient(&self, pose: &Composed, reference: &Composed) -> Option<Normal>;
}

fn max_diag(h: &Hessian) -> f64 {
    (0..6).fold(f64::NEG_INFINITY, |acc, k| acc.max(h[k][k]))
}

fn trace(h: &Hessian) -> f64 {
    (0..6).map(|k| h[k][k]).sum()
}

/// The inputs of one refinement, borrowed from the caller: `refine`'s (normalised points, row
/// weights) or `refine_pixels`' (pixels, the camera's metric, [`super::refine_pixels`]).
pub(super) struct Problem<'a, M> {
    pub(super) world: &'a [Point3<f64>],
    /// The observations: normalised image points (`refine`) or pixels (`refine_pixels`).
    pub(super) image: &'a [Point2<f64>],
    pub(super) weights: Option<&'a [f64]>,
    /// `1 / w_unit` (a power-of-two weight unit): the passes use the weights in that unit,
    /// so that the sums neither overflow nor underflow for any scale of the weights.
    pub(super) inv_weight: f64,
    pub(super) c: Vector3<f64>,
    /// How a residual is measured ([`pass::Metric`]).
    pub(super) metric: M,
}

impl<M: Metric> Residuals for Problem<'_, M> {
    /// One O(N) pass at `pose`: cost, normal equations and depth range. With `reference`,
    /// returns `None` as soon as a depth differs in sign from its depth under `reference`.
    /// Points of weight 0 are skipped entirely (bit-identical to dropping them).
    ///
    /// Uses the structure of the Jacobian rows `r = [a x q; -a]` (`a` = `A_p`'s row, `q` the
    /// rotated point): with `N = sum_ab C_ab a_a a_b^T` per point (`a_x = (1/z)(1, 0, -u)`,
    /// `a_y = (1/z)(0, 1, -v)`, `C` the metric) and `K = [q]x N`,
    /// `H = sum [[K [q]x^T, K], [K^T, N]]` and, with `b = e~x a_x + e~y a_y`,
    /// `g = -sum [[q]x b; b]`. `K` and `K [q]x^T` are formed from the two vectors
    /// `q x (1, 0, -u)` and `q x (0, 1, -v)` (see `pass::lane`): about 60 % of the
    /// multiply-adds of the 21-entry outer products.
    ///
    /// Vectorised across points, in safe code built twice (baseline and AVX2, `lanes::dispatched`,
    /// the same bits): the active points
    /// (non-zero weight), in order, are gathered into blocks of `LANES` transposed values;
    /// lane `l` of the block goes into its own partial sums, so the compiler runs the
    /// per-point code on packed registers. The lanes are added once at the end. The sequence
    /// of active points, and so the result to the bit, does not depend on the points of
    /// weight 0; the depth-sign test is the scalar one, lane by lane.
    fn accumulate(
        &self,
        pose: &Composed,
        reference: Option<&Composed>,
        h: &mut Hessian,
    ) -> Option<Normal> {
        let k = PassInputs::new(&self.c, self.inv_weight, pose, reference);
        let (w, m, wt) = (self.world, self.image, self.weights);
        if reference.is_some() {
            pass::<true, true, M>(&k, &self.metric, w, m, wt, Some(h))
        } else {
            pass::<false, true, M>(&k, &self.metric, w, m, wt, Some(h))
        }
    }

    /// Cost, gradient and depth range only (7 sums per point instead of 27).
    fn accumulate_gradient(&self, pose: &Composed, reference: &Composed) -> Option<Normal> {
        let k = PassInputs::new(&self.c, self.inv_weight, pose, Some(reference));
        let (w, m, wt) = (self.world, self.image, self.weights);
        pass::<true, false, M>(&k, &self.metric, w, m, wt, None)
    }
}

/// `refine`: refines the working-frame pose `(r_work, t_work)` by Levenberg-Marquardt on the
/// (weighted) reprojection error of the caller's world points.
///
/// `world`, `image` (normalised coordinates) and `weights` (optional, one per point, >= 0) are the
/// caller's inputs as validated by `frame`; `fr` is `frame`'s working frame
/// (`P_i = rw (X_i - c) / d`). Costs (`e0`, `e`) are in `frame`'s weight unit: the caller's cost is
/// `e * fr.weight_unit` (exact: a power of two). The pose is the working-frame pose in and out
/// (`output` maps it to the world frame). A point of weight 0 contributes nothing and gives
/// bit-identical results to dropping it. If some starting depth is (relatively) zero the pose is
/// returned unchanged with [`ReprojStop::SkippedZeroDepth`]. At most `opts.max_iterations`
/// iterations; no allocation.
#[allow(clippy::too_many_arguments)]
pub(crate) fn refine_reprojection(
    world: &[Point3<f64>],
    image: &[Point2<f64>],
    weights: Option<&[f64]>,
    fr: &WorkingFrame,
    r_work: &Matrix3<f64>,
    t_work: &Vector3<f64>,
    opts: &ReprojOptions,
) -> ReprojOutcome {
    let prob = normalised_problem(world, image, weights, fr, opts);
    levenberg_marquardt(&prob, &fr.rw, fr.d, r_work, t_work, opts)
}

/// Where a run of `refine` asks its caller whether to go on ([`refine_reprojection_until`]).
pub(crate) enum Checkpoint<'a> {
    /// An accepted iterate `(r, t)` (working frame).
    Accepted(&'a Matrix3<f64>, &'a Vector3<f64>),
    /// The first step tried from an iterate of cost `e`: the damped Gauss-Newton model
    /// predicts that it lowers the cost by `pred`.
    Step { e: f64, pred: f64 },
}

/// [`refine_reprojection`], stopped ([`ReprojStop::Abandoned`]) at the first [`Checkpoint`]
/// for which `abandon` is true (a step is then not evaluated).
#[allow(clippy::too_many_arguments)]
pub(crate) fn refine_reprojection_until(
    world: &[Point3<f64>],
    image: &[Point2<f64>],
    weights: Option<&[f64]>,
    fr: &WorkingFrame,
    r_work: &Matrix3<f64>,
    t_work: &Vector3<f64>,
    opts: &ReprojOptions,
    abandon: &mut dyn FnMut(Checkpoint<'_>) -> bool,
) -> ReprojOutcome {
    let prob = normalised_problem(world, image, weights, fr, opts);
    levenberg_marquardt_until(&prob, &fr.rw, fr.d, r_work, t_work, opts, None, abandon)
}

/// The `vertical` stage ([`vertical_map`]) after a run of [`refine_reprojection_until`] that
/// ended at the maximum-likelihood pose `ml` (the small-N `search`'s).
pub(crate) fn refine_reprojection_vertical(
    world: &[Point3<f64>],
    image: &[Point2<f64>],
    weights: Option<&[f64]>,
    fr: &WorkingFrame,
    ml: &ReprojOutcome,
    opts: &ReprojOptions,
) -> ReprojOutcome {
    let prob = normalised_problem(world, image, weights, fr, opts);
    vertical_map(&prob, &fr.rw, fr.d, ml, opts)
}

/// `refine`'s residuals: the normalised reprojection error with `opts`' row weights.
fn normalised_problem<'a>(
    world: &'a [Point3<f64>],
    image: &'a [Point2<f64>],
    weights: Option<&'a [f64]>,
    fr: &WorkingFrame,
    opts: &ReprojOptions,
) -> Problem<'a, RowWeights> {
    debug_assert_eq!(world.len(), image.len());
    debug_assert!(weights.is_none_or(|w| w.len() == world.len()));
    let n = world
        .len()
        .min(image.len())
        .min(weights.map_or(usize::MAX, <[f64]>::len));
    Problem {
        world: &world[..n],
        image: &image[..n],
        weights: weights.map(|w| &w[..n]),
        inv_weight: 1.0 / fr.weight_unit,
        c: fr.c,
        metric: RowWeights {
            wx: opts.row_weights.0,
            wy: opts.row_weights.1,
        },
    }
}

/// The Levenberg-Marquardt iteration of `refine` (and `refine_pixels`, `refine_rig`) on the
/// residuals of `prob`, from the working-frame pose `(r_work, t_work)` of the working frame
/// `P_i = rw (X_i - c) / d`: the damping rule, the depth-sign guard, the reuse of `J^T W J` and
/// the unverified final step of the module docs. With [`ReprojOptions::vertical`], a second run
/// from the maximum-likelihood pose it reaches minimises the cost with the vertical's prior
/// ([`vertical_map`]).
pub(super) fn levenberg_marquardt<P: Residuals>(
    prob: &P,
    rw: &Matrix3<f64>,
    d: f64,
    r_work: &Matrix3<f64>,
    t_work: &Vector3<f64>,
    opts: &ReprojOptions,
) -> ReprojOutcome {
    let ml = levenberg_marquardt_until(prob, rw, d, r_work, t_work, opts, None, &mut |_| false);
    vertical_map(prob, rw, d, &ml, opts)
}

/// The `vertical` stage ([`super::vertical`]): with [`ReprojOptions::vertical`], the run from
/// the maximum-likelihood outcome `ml` that adds the vertical's prior; `ml` itself without
/// one, or when it did not start (a point at depth 0). The outcome's cost is the reprojection
/// cost alone at the returned pose, its `e0` and depth count `ml`'s, its iterations both runs'.
pub(super) fn vertical_map<P: Residuals>(
    prob: &P,
    rw: &Matrix3<f64>,
    d: f64,
    ml: &ReprojOutcome,
    opts: &ReprojOptions,
) -> ReprojOutcome {
    let Some(v) = &opts.vertical else {
        return *ml;
    };
    let finite = ml.r.iter().chain(ml.t.iter()).all(|x| x.is_finite());
    if ml.stop == ReprojStop::SkippedZeroDepth || !finite {
        return *ml;
    }
    // From an exact fit the first run has already applied its last step.
    let opts = ReprojOptions {
        exact_start: false,
        ..*opts
    };
    let map = levenberg_marquardt_until(prob, rw, d, &ml.r, &ml.t, &opts, Some(v), &mut |_| false);
    if map.stop == ReprojStop::SkippedZeroDepth {
        return *ml;
    }
    ReprojOutcome {
        e0: ml.e0,
        iterations: ml.iterations + map.iterations,
        start_in_front: ml.start_in_front,
        ..map
    }
}

/// [`levenberg_marquardt`], stopped ([`ReprojStop::Abandoned`]) at the first [`Checkpoint`]
/// for which `abandon` is true.
#[allow(clippy::too_many_arguments)]
fn levenberg_marquardt_until<P: Residuals>(
    prob: &P,
    rw: &Matrix3<f64>,
    d: f64,
    r_work: &Matrix3<f64>,
    t_work: &Vector3<f64>,
    opts: &ReprojOptions,
    vertical: Option<&Vertical>,
    abandon: &mut dyn FnMut(Checkpoint<'_>) -> bool,
) -> ReprojOutcome {
    let mut r = *r_work;
    let mut t = *t_work;
    let mut cur = Composed::new(&r, rw, d, &t);
    let skipped = ReprojOutcome {
        r,
        t,
        e0: f64::NAN,
        e: f64::NAN,
        iterations: 0,
        stop: ReprojStop::SkippedZeroDepth,
        start_in_front: None,
        vertical: None,
    };
    // `J^T W J` at the current pose is `hs[hi]`; a full pass at a candidate writes the other.
    let mut hs: [Hessian; 2] = [[[0.0; 6]; 6]; 2];
    let mut hi = 0;
    let Some(mut nrm) = prob.accumulate(&cur, None, &mut hs[0]) else {
        return skipped; // unreachable: no reference pose
    };
    let start_in_front = nrm.in_front;
    if nrm.min_abs_z <= ZERO_DEPTH_REL * nrm.max_abs_z {
        return ReprojOutcome {
            start_in_front,
            ..skipped
        };
    }

    let e0 = nrm.e;
    // The vertical's prior (a run from the maximum-likelihood pose, `vertical_map`): the test
    // at the start, then the term in every pass.
    let check = vertical.map(|v| vertical::check(v, rw, &r, &hs[0], e0));
    let prior = vertical.map(|v| PriorTerm::new(v, rw, e0));
    let add_prior = |r: &Matrix3<f64>, nrm: &mut Normal, h: Option<&mut Hessian>| {
        if let Some(p) = &prior {
            p.add(r, &mut nrm.e, &mut nrm.g, h);
        }
    };
    add_prior(&r, &mut nrm, Some(&mut hs[0]));
    // Pose-independent (see Normal::max_abs_q): measured by this first pass only.
    let max_abs_q = nrm.max_abs_q;
    let mut e_final = None;
    // Norm of the step accepted in the previous iteration (None after anything else).
    let mut prev_step: Option<f64> = None;
    // Distance (sum of accepted step norms) from the pose where `hs[hi]` was computed.
    let mut h_dist = 0.0;
    let mut lam = opts.tau * max_diag(&hs[hi]);
    let mut nu = 2.0;
    let mut stop = ReprojStop::MaxIterations;
    let mut iterations = 0;
    for it in 1..=opts.max_iterations {
        iterations = it;
        let gmax = nrm.g.iter().fold(0.0_f64, |acc, gk| acc.max(gk.abs()));
        if gmax <= opts.gtol * (trace(&hs[hi]) * nrm.e).sqrt() {
            stop = ReprojStop::Gradient;
            break;
        }
        let Some(delta) = solve_damped6(&hs[hi], lam, &nrm.g) else {
            lam *= nu;
            nu *= 2.0;
            prev_step = None;
            continue;
        };
        let step_sq = delta.iter().map(|x| x * x).sum::<f64>();
        let step_norm = step_sq.sqrt();
        let scale = t.norm() + 1.0;
        let w = Vector3::new(delta[0], delta[1], delta[2]);
        if step_norm <= opts.xtol * scale {
            // From an exact fit the residuals stay at the rounding level, where this
            // Gauss-Newton step is exact to second order: it is applied (module docs).
            if opts.exact_start && step_norm * (max_abs_q + 1.0) < 0.5 * nrm.min_abs_z {
                r = exp_so3(&w) * r;
                t += Vector3::new(delta[3], delta[4], delta[5]);
            }
            stop = ReprojStop::Step;
            break;
        }
        let r_new = exp_so3(&w) * r;
        let t_new = t + Vector3::new(delta[3], delta[4], delta[5]);
        let cand = Composed::new(&r_new, rw, d, &t_new);

        // Predicted decrease of the linear model, -(2 g.delta + delta.H.delta), which is
        // lam |delta|^2 - g.delta since (H + lam I) delta = -g: two terms that are both
        // positive for a descent step, so no cancellation (and no 6 x 6 quadratic form).
        let g_d: f64 = (0..6).map(|k| nrm.g[k] * delta[k]).sum();
        let pred = lam * step_sq - g_d;
        // The first step from this iterate (not one shrunk by a rejection): the caller may
        // stop a run that the model says cannot go where it needs to.
        if (it == 1 || prev_step.is_some()) && abandon(Checkpoint::Step { e: nrm.e, pred }) {
            stop = ReprojStop::Abandoned;
            break;
        }

        // A tiny step after which the next one would be below xtol, and that cannot flip a
        // depth sign, ends the run unverified (module docs).
        if step_norm <= FINAL_STEP_REL * scale
            && prev_step.is_some_and(|sp| step_norm * step_norm <= opts.xtol * scale * sp)
            && step_norm * (max_abs_q + 1.0) < 0.5 * nrm.min_abs_z
        {
            r = r_new;
            t = t_new;
            // E - pred clamped to [0, E]; E itself if the prediction is not a decrease (or NaN).
            e_final = Some(if pred > 0.0 {
                (nrm.e - pred).max(0.0)
            } else {
                nrm.e
            });
            stop = ReprojStop::FinalStep;
            break;
        }

        // J^T W J changes by O(distance) relative: within HESSIAN_REUSE_REL (|t| + 1) of the
        // pose where it was computed, the pass only evaluates cost and gradient and keeps it.
        let reuse = h_dist + step_norm <= HESSIAN_REUSE_REL * scale;
        let next = if reuse {
            prob.accumulate_gradient(&cand, &cur).map(|mut n| {
                add_prior(&r_new, &mut n, None);
                n
            })
        } else {
            let h_next = &mut hs[1 - hi];
            prob.accumulate(&cand, Some(&cur), h_next).map(|mut n| {
                add_prior(&r_new, &mut n, Some(h_next));
                n
            })
        };
        match next {
            Some(next) if next.e < nrm.e => {
                if reuse {
                    h_dist += step_norm;
                } else {
                    h_dist = 0.0;
                    hi = 1 - hi;
                }
                let rho = if pred > 0.0 {
                    (nrm.e - next.e) / pred
                } else {
                    0.0
                };
                r = r_new;
                t = t_new;
                cur = cand;
                nrm = next;
                lam *= (1.0_f64 / 3.0).max(1.0 - (2.0 * rho - 1.0).powi(3));
                nu = 2.0;
                prev_step = Some(step_norm);
                if abandon(Checkpoint::Accepted(&r, &t)) {
                    stop = ReprojStop::Abandoned;
                    break;
                }
            }
            _ => {
                lam *= nu;
                nu *= 2.0;
                prev_step = None;
                if lam > DAMPING_LIMIT_REL * max_diag(&hs[hi]) {
                    stop = ReprojStop::Damping;
                    break;
                }
            }
        }
    }
    // The reprojection cost alone: the prior's term taken out.
    let e = e_final.unwrap_or(nrm.e);
    let e = prior.as_ref().map_or(e, |p| (e - p.cost(&r)).max(0.0));
    ReprojOutcome {
        r,
        t,
        e0,
        e,
        iterations,
        stop,
        start_in_front,
        vertical: check,
    }
}

#[cfg(test)]
#[path = "../../tests/unit/pipeline/refine.rs"]
mod tests;
