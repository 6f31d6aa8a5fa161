//! The EOPnP pipeline, one file per stage, in the order the data passes through them
//! (docs/algorithm.md, section 3, has a section for each stage under its name):
//!
//! | stage | file | what it does | touches the points |
//! |---|---|---|---|
//! | `frame` | [`frame`] | validates the input; the working frame (centroid, scale, principal axes) | yes (through `moments`' passes) |
//! | `moments` | [`moments`] | the O(N) moment sums in the working frame; `M` (9 x 9) and `G` (3 x 9) | yes |
//! | `branch` | [`run`] (below) | which branch: non-planar, planar or both, from the planarity ratio | no |
//! | `nullspace` | [`nullspace`] | candidate rotations from the null space of `M` (cases 1-4, extra starts) | no |
//! | `planar` | [`planar`] | planar candidates from the 6 x 6 system of the first two columns of `R` | yes (depth signs) |
//! | `search` | [`search`] | default mode, N <= 5: P3P poses of the point triples, scored by the reprojection error | yes |
//! | `newton` | [`newton`] | damped Newton on SO(3) from every start, to local minima of `f(R)` | no |
//! | `certificate` | [`certificate`] | a Lagrangian dual certificate that a minimum is global (early exit) | no |
//! | `select` | [`select`] | the minimum with the smallest `f` among those with most points in front | yes (depth signs) |
//! | `refine` | [`refine`] | default mode: Levenberg-Marquardt on the reprojection error | yes |
//! | `refine_pixels` | [`refine_pixels`] | in place of `refine`, with a camera with distortion (or a robust loss): Levenberg-Marquardt on the pixel error through the camera | yes |
//! | `refine_intrinsics` | [`refine_intrinsics`] | with free intrinsics ([`crate::Problem::unknown_focal`], [`crate::Problem::refine_principal_point`], [`crate::Problem::refine_distortion`]): Levenberg-Marquardt on the pixel error over pose and intrinsics | yes |
//! | `vertical` | [`vertical`] | with a known vertical ([`crate::Gravity`]): from the maximum-likelihood pose to the maximum a posteriori one, and the mismatch test (run by `refine`'s and `refine_pixels`' driver) | yes |
//! | `output` | [`output`] | back to the world frame; the [`Solution`] | yes |
//!
//! [`run`] is the only place that calls the stages. In the default mode with at most five
//! points it searches the reprojection error directly: the `search` stage's starts, `refine`
//! from the best of them, `output`. Otherwise it tries a certified fast path first (the
//! case-1 start through `newton`, the `certificate` and `select`'s depth test) and, when that
//! does not settle the solve, the full search (`nullspace`, `planar`, `newton` from every start,
//! `select`); either ends in `refine` (or, for pixel input through a camera with distortion or
//! with a robust [`Loss`], `refine_pixels`) and `output`.

/// The stages one at a time, for `benches/stages.rs` only: compiled only with
/// `RUSTFLAGS="--cfg eopnp_bench"`, never part of the library's API.
#[cfg(eopnp_bench)]
#[doc(hidden)]
pub mod bench_hooks;
pub(crate) mod certificate;
pub(crate) mod frame;
pub(crate) mod moments;
pub(crate) mod newton;
pub(crate) mod nullspace;
pub(crate) mod options;
pub(crate) mod output;
pub(crate) mod planar;
pub(crate) mod refine;
pub(crate) mod refine_intrinsics;
pub(crate) mod refine_pixels;
pub(crate) mod refine_rig;
pub(crate) mod search;
pub(crate) mod select;
pub(crate) mod vertical;

pub use nullspace::CandidateSource;
pub(crate) use nullspace::MAX_CANDIDATES;
pub(crate) use options::Options;
pub use options::{Loss, PlanarDetection, Refinement};
pub use output::{Solution, Solutions};

pub(crate) use frame::check_lengths;
pub(crate) use refine::ReprojOptions;
pub(crate) use refine_pixels::PixelInputs;

use arrayvec::ArrayVec;
use nalgebra::{Matrix3, Point2, Point3};

use crate::error::PnpError;
use moments::System;
use newton::NewtonOptions;
use nullspace::Candidates;
use output::Output;
use select::Minimum;

/// `newton`'s step tolerance in reprojection mode (CGR units, ~ radians / 2): `newton` stops
/// when a step is this small, or when quadratic convergence predicts the next step below a
/// thousandth of it, so the minimum of f is located to ~1e-9 before `refine` takes over.
const NEWTON_TOLERANCE_BEFORE_REFINE: f64 = 1e-6;
/// An exact fit: the case-1 start's `f` at most this times `trace(M)`. Noise-free input gives
/// about 1e-16 (the rounding of M), sigma = 0.001 px about 1e-11 (N = 10).
pub(crate) const EXACT_FIT: f64 = 1e-14;
/// Planarity thresholds (the `branch` stage).
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

/// One solve: `image` are normalised image points, `weights` optional per-point weights,
/// `reproj` the `refine` options (row weights of pixel input), `pixel` the observations of
/// `refine_pixels` (pixel input, or a robust loss), `all` collects every distinct minimum
/// (`solve_all`).
pub(crate) fn run(
    opts: &Options,
    world: &[Point3<f64>],
    image: &[Point2<f64>],
    weights: Option<&[f64]>,
    reproj: &ReprojOptions,
    pixel: Option<&PixelInputs<'_>>,
    all: Option<&mut Solutions>,
) -> Result<Solution, PnpError> {
    // `frame` + `moments`: the working frame, with the moment sums in it; M and G.
    let prep = prepare(opts, world, image, weights)?;
    let Prepared {
        fr,
        sys,
        m45,
        scale,
        probe,
    } = &prep;
    let scale = *scale;
    // `branch`: which branches run.
    let (nonplanar, planar) = match opts.planar {
        PlanarDetection::Auto => (fr.ratio >= NONPLANAR_MIN_RATIO, fr.ratio < PLANAR_MAX_RATIO),
        PlanarDetection::Planar => (false, true),
        PlanarDetection::NonPlanar => (true, false),
    };
    let planar_sys = if planar { fr.sums.system(true) } else { None };
    let out = prep.output(world, image, weights, pixel);
    let early_exit = !opts.exhaustive && all.is_none();

    // `search` (default mode, at most five points, not in `solve_all` or exhaustive mode): the
    // reprojection error searched from the P3P poses of the point triples; `refine` from the
    // best few, the best refined pose to `output` (`refine_pixels` first if it applies).
    // Without a usable start, the search below runs.
    if early_exit && opts.refinement == Refinement::Reprojection {
        if let Some(sp) = search::SmallProblem::new(world, image, weights, fr, reproj.row_weights) {
            let data = (world, image, weights);
            if let Some((m, refined)) = small_n(opts, &prep, planar_sys.as_ref(), &sp, data, reproj)
            {
                return out.finish_refined(&m, reproj, &refined);
            }
        }
    }

    let mut minima = Minima::new(opts, sys, m45, scale);
    let is_certified = |r: &Matrix3<f64>| {
        certificate::global_minimum(&sys.m, r, scale)
            || planar_sys
                .as_ref()
                .is_some_and(|sp| certificate::global_minimum_planar(&sp.m, r, scale))
    };

    // The certified fast path (not in `solve_all` or exhaustive mode): refine the case-1 (or
    // p1) start; if the certificate proves the minimum it reaches is the global minimum of f
    // over O(3) and more than half of the points are in front of it, no other candidate can be
    // selected by `select`, so the search stops here.
    if early_exit {
        // The case-1 start comes with a bound below the spectrum of M (its factorisation),
        // which certifies an exact fit without the dual certificate.
        let start = if nonplanar && !planar {
            nullspace::first_start(&sys.m, probe, scale)
                .map(|(r, sigma)| (r, CandidateSource::Case1, Some(sigma)))
        } else if planar && !nonplanar {
            planar_sys.as_ref().and_then(|sp| {
                planar::first_start(sp, world, weights, fr, scale)
                    .map(|r| (r, CandidateSource::Planar1, None))
            })
        } else {
            None
        };
        if let Some((r0, source, sigma)) = start {
            let f0 = newton::cost_at(m45, &r0);
            // An exact fit (noise-free input): f at the case-1 start is at the rounding level
            // of its lower bound 0 and below the spectral bound, so the start is the certified
            // global minimum of f to within rounding. In the default mode `newton` is skipped,
            // and `refine` applies the Gauss-Newton step of its `xtol` stop, which makes the pose
            // exact (docs/algorithm.md, the driver).
            let exact = opts.refinement == Refinement::Reprojection
                && f0 <= EXACT_FIT * scale
                && sigma.is_some_and(|s| certificate::below_spectral_bound(f0, s, scale));
            let m = if exact {
                Some(minima.at_start(&r0, f0, source))
            } else {
                minima.newton(&r0, f0, source)
            };
            if let Some(m) = m {
                // An exact fit passed the bound at this very f (m.f = f0) above.
                let bound = m.exact
                    || sigma.is_some_and(|s| certificate::below_spectral_bound(m.f, s, scale));
                if bound || is_certified(&m.r) {
                    if let Some(sol) = out.finish_if_in_front(&m, opts.refinement, reproj)? {
                        return Ok(sol);
                    }
                }
                minima.keep(m);
            }
        }
    }

    // `nullspace` (cases 1-4), `planar`, `nullspace`'s extra starts: the candidate starts.
    let mut cands = Candidates::new();
    if nonplanar {
        nullspace::candidates(&sys.m, &mut cands)?;
    }
    if let Some(sp) = &planar_sys {
        planar::candidates(sp, world, weights, fr, scale, &mut cands);
    }
    nullspace::extra_starts(&mut cands);

    // `newton`: refine every candidate, in order of increasing initial cost.
    let mut init: ArrayVec<(f64, usize), MAX_CANDIDATES> = cands
        .iter()
        .enumerate()
        .map(|(i, c)| (newton::cost_at(m45, &c.r), i))
        .collect();
    init.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    for &(f0, i) in &init {
        let c = cands[i];
        // A start already inside the basin of a known minimum would only find it again.
        if minima.in_known_basin(&c.r) {
            continue;
        }
        if let Some(m) = minima.newton(&c.r, f0, c.source) {
            // A certified global minimum with most points in front is `select`'s pick.
            if early_exit && is_certified(&m.r) {
                if let Some(sol) = out.finish_if_in_front(&m, opts.refinement, reproj)? {
                    return Ok(sol);
                }
            }
            minima.keep(m);
        }
    }
    let minima = &mut minima.found;
    if minima.is_empty() {
        return Err(PnpError::NoSolution);
    }
    if let Some(all) = all {
        select::count_all(minima, world, weights, fr);
        return output::rank_all(&out, minima, opts.refinement, reproj, all);
    }
    // `select`, then `refine` and `output`.
    let pick = select::pick(minima, world, weights, fr);
    out.finish(&minima[pick], opts.refinement, reproj)
}

/// The caller's world points, normalised image points and optional weights.
type Correspondences<'a> = (&'a [Point3<f64>], &'a [Point2<f64>], Option<&'a [f64]>);

/// `search` and `refine` for at most five active points (default mode): the P3P starts (and,
/// in planar scenes, the minimum of f from the p1 start, `planar` + `newton`), `refine` from
/// the best few, best first; a run is abandoned when its model says it cannot end below the
/// best refined cost ([`search::cannot_reach`]), and a start inside the basin of a pose
/// already refined or of a pose where a run was so abandoned is skipped (a run that enters one
/// is abandoned). The refined pose with the most points in front, then the lowest reprojection
/// error, with its `refine` outcome; `None` if no run gives a finite pose.
fn small_n(
    opts: &Options,
    prep: &Prepared,
    planar_sys: Option<&System>,
    sp: &search::SmallProblem,
    (world, image, weights): Correspondences<'_>,
    reproj: &ReprojOptions,
) -> Option<(Minimum, refine::ReprojOutcome)> {
    let (fr, sys, m45, scale) = (&prep.fr, &prep.sys, &prep.m45, prep.scale);
    let mut starts = search::Starts::new();
    search::starts(sp, &mut starts);
    // Planar scenes: also the minimum of f from the p1 start, which lies in the basin of the
    // global minimum of the reprojection error in about 1 of 3,000 planar N = 4 problems
    // where no P3P pose does.
    if let Some(psys) = planar_sys {
        if let Some(r0) = planar::first_start(psys, world, weights, fr, scale) {
            let (r, it) = Minima::new(opts, sys, m45, scale)
                .newton(&r0, newton::cost_at(m45, &r0), CandidateSource::Planar1)
                .map_or((r0, 0), |m| (m.r, m.iterations));
            let t = sys.translation(&r);
            search::add(sp, &r, &t, (CandidateSource::Planar1, it), &mut starts);
        }
    }
    // Every refined pose (at most one per start, so never more than a `Starts` holds), and
    // every pose where a run was abandoned because it could not end below the best
    // ([`search::cannot_reach`]): a start or a run that comes near one of those heads into
    // the same basin.
    let mut found = search::Starts::new();
    let mut beaten = search::Starts::new();
    let mut best: Option<(search::Start, refine::ReprojOutcome)> = None;
    for s in starts
        .iter()
        .take(search::refined(sp, planar_sys.is_some()))
    {
        if found.iter().chain(&beaten).any(|f| f.near(&s.r, &s.t)) {
            continue;
        }
        if best
            .as_ref()
            .is_some_and(|(b, _)| !s.worth_refining(b, planar_sys.is_some()))
        {
            continue;
        }
        // The cost a run must end below to be picked, unless it has more points in front.
        let to_beat = best
            .as_ref()
            .and_then(|(b, _)| (s.in_front <= b.in_front).then_some(b.cost));
        let mut cannot_reach = false;
        let o = refine::refine_reprojection_until(
            world,
            image,
            weights,
            fr,
            &s.r,
            &s.t,
            reproj,
            &mut |c| match c {
                refine::Checkpoint::Accepted(r, t) => {
                    found.iter().chain(&beaten).any(|f| f.near(r, t))
                }
                refine::Checkpoint::Step { e, pred } => {
                    cannot_reach = to_beat.is_some_and(|b| search::cannot_reach(e, pred, b));
                    cannot_reach
                }
            },
        );
        if cannot_reach && !beaten.is_full() {
            beaten.push(search::Start {
                r: o.r,
                t: o.t,
                cost: o.e,
                ..*s
            });
        }
        let finite = o.r.iter().chain(o.t.iter()).all(|x| x.is_finite()) && o.e.is_finite();
        if !finite
            || matches!(
                o.stop,
                refine::ReprojStop::SkippedZeroDepth | refine::ReprojStop::Abandoned
            )
        {
            continue;
        }
        let refined = search::Start {
            r: o.r,
            t: o.t,
            in_front: s.in_front,
            cost: o.e,
            source: s.source,
            iterations: s.iterations,
        };
        if best.as_ref().is_none_or(|(b, _)| refined.better(b)) {
            best = Some((refined, o));
        }
        if !found.is_full() {
            found.push(refined);
        }
    }
    let (b, o) = best?;
    let m = Minimum {
        r: b.r,
        t: b.t,
        f: newton::cost_at(m45, &b.r),
        source: b.source,
        planar: b.source == CandidateSource::Planar1,
        iterations: b.iterations,
        cheirality: Some(fr.most_in_front(b.in_front)),
        exact: false,
    };
    Some((m, o))
}

/// What every driver needs from `frame` and `moments`: the working frame, `M` and `G`, the
/// upper triangle of `M`, its scale `trace(M)` and the degeneracy probe.
struct Prepared {
    fr: frame::WorkingFrame,
    sys: System,
    m45: [f64; 45],
    scale: f64,
    probe: nullspace::Probe,
}

/// `frame` + `moments`: the working frame, with the moment sums in it; `M` and `G`.
#[inline(always)]
fn prepare(
    opts: &Options,
    world: &[Point3<f64>],
    image: &[Point2<f64>],
    weights: Option<&[f64]>,
) -> Result<Prepared, PnpError> {
    let fr = frame::working_frame(world, image, weights, opts.align_world_axes)?;
    let sys = fr.sums.system(false).ok_or(PnpError::NoSolution)?;
    let scale = sys.trace;
    if !(scale > 0.0 && scale.is_finite()) {
        return Err(PnpError::NoSolution);
    }
    let m45 = moments::m_upper(&sys.m);
    let probe = nullspace::probe(&sys.m, scale);
    Ok(Prepared {
        fr,
        sys,
        m45,
        scale,
        probe,
    })
}

impl Prepared {
    /// What `refine`, `refine_pixels` and `output` need of the problem.
    fn output<'a>(
        &'a self,
        world: &'a [Point3<f64>],
        image: &'a [Point2<f64>],
        weights: Option<&'a [f64]>,
        pixel: Option<&'a PixelInputs<'a>>,
    ) -> Output<'a> {
        Output {
            world,
            image,
            weights,
            pixel,
            fr: &self.fr,
            m45: &self.m45,
            degenerate: self.probe.degenerate || self.fr.small_image,
            scale: self.scale,
        }
    }
}

/// `Solver::refine`: `frame` and `moments` (validation, the working frame, `M`), `newton` from
/// the caller's rotation `r`, then `refine` or `refine_pixels`, and `output`: the minimum of
/// the reprojection error in the basin of the pose. No search (no `branch`, `nullspace`,
/// `planar`, `search` or `select`).
pub(crate) fn run_from_prior(
    opts: &Options,
    world: &[Point3<f64>],
    image: &[Point2<f64>],
    weights: Option<&[f64]>,
    reproj: &ReprojOptions,
    pixel: Option<&PixelInputs<'_>>,
    (r, t): (&Matrix3<f64>, &nalgebra::Vector3<f64>),
) -> Result<Solution, PnpError> {
    let prep = prepare(opts, world, image, weights)?;
    let (fr, m45) = (&prep.fr, &prep.m45);
    let out = prep.output(world, image, weights, pixel);
    // The world pose in the working frame (the inverse of `WorkingFrame::to_world`).
    let r_work = r * fr.rw.transpose();
    // `newton` from the prior's rotation: damped Newton on the algebraic cost, O(1) per
    // iteration (M is already accumulated), to the algebraic minimum of the prior's basin,
    // whose translation follows from its rotation; `refine` then needs the few passes it needs
    // after a full search. If Newton fails, `refine` starts at the prior itself.
    let f0 = newton::cost_at(m45, &r_work);
    let m = Minima::new(opts, &prep.sys, m45, prep.scale)
        .newton(&r_work, f0, CandidateSource::Initial)
        .unwrap_or_else(|| Minimum {
            r: r_work,
            t: (t + r * fr.c) / fr.d,
            f: f0,
            source: CandidateSource::Initial,
            planar: false,
            iterations: 0,
            cheirality: None,
            exact: false,
        });
    out.finish(&m, Refinement::Reprojection, reproj)
}

/// The refined minima found so far and how a start is refined (`newton`).
struct Minima<'a> {
    sys: &'a System,
    m45: &'a [f64; 45],
    scale: f64,
    newton: NewtonOptions,
    exhaustive: bool,
    found: ArrayVec<Minimum, MAX_CANDIDATES>,
}

impl<'a> Minima<'a> {
    fn new(opts: &Options, sys: &'a System, m45: &'a [f64; 45], scale: f64) -> Self {
        // When `refine` follows, `newton` only has to identify and certify the minimum of f:
        // `refine` moves the pose on by the algebraic-vs-reprojection difference (~noise level)
        // and converges to its own tolerance from anywhere in the basin.
        let newton = match opts.refinement {
            Refinement::Reprojection => NewtonOptions {
                step_tolerance: opts
                    .newton
                    .step_tolerance
                    .max(NEWTON_TOLERANCE_BEFORE_REFINE),
                ..opts.newton
            },
            Refinement::Algebraic => opts.newton,
        };
        Minima {
            sys,
            m45,
            scale,
            newton,
            exhaustive: opts.exhaustive,
            found: ArrayVec::new(),
        }
    }

    /// Whether `r` lies in the basin of a known minimum (never in exhaustive mode).
    fn in_known_basin(&self, r: &Matrix3<f64>) -> bool {
        !self.exhaustive && self.found.iter().any(|m| (m.r - r).norm() <= IN_BASIN)
    }

    /// `newton` from `r0` (`f0 = f(r0)`, `newton::cost_at`'s value): a new local minimum, or
    /// `None` when the refinement entered the basin of a known one, found one already known, or
    /// did not produce a finite rotation.
    fn newton(&self, r0: &Matrix3<f64>, f0: f64, source: CandidateSource) -> Option<Minimum> {
        let known: ArrayVec<Matrix3<f64>, MAX_CANDIDATES> =
            self.found.iter().map(|m| m.r).collect();
        let refined = newton::refine_so3_until(
            &self.sys.m,
            self.m45,
            self.scale,
            (r0, f0),
            &self.newton,
            &mut |r| !self.exhaustive && known.iter().any(|k| (k - r).norm() <= IN_BASIN),
        );
        if refined.stopped_early
            || !refined.f.is_finite()
            || !refined.r.iter().all(|x| x.is_finite())
            || self
                .found
                .iter()
                .any(|m| (m.r - refined.r).norm() <= SAME_MINIMUM)
        {
            return None;
        }
        Some(self.minimum(&refined.r, refined.f, source, refined.iterations))
    }

    /// The start `r0` itself as the minimum (`f0 = f(r0)`), `newton` skipped: an exact fit.
    fn at_start(&self, r0: &Matrix3<f64>, f0: f64, source: CandidateSource) -> Minimum {
        Minimum {
            exact: true,
            ..self.minimum(r0, f0, source, 0)
        }
    }

    /// The minimum at rotation `r` (`f = f(r)`), its translation from `r`, found from a start
    /// of `source` by `iterations` `newton` iterations.
    fn minimum(
        &self,
        r: &Matrix3<f64>,
        f: f64,
        source: CandidateSource,
        iterations: u32,
    ) -> Minimum {
        Minimum {
            r: *r,
            t: self.sys.translation(r),
            f,
            source,
            planar: matches!(source, CandidateSource::Planar1 | CandidateSource::Planar2),
            iterations,
            cheirality: None,
            exact: false,
        }
    }

    /// Records a new minimum (while there is room).
    fn keep(&mut self, m: Minimum) {
        if !self.found.is_full() {
            self.found.push(m);
        }
    }
}

#[cfg(test)]
#[path = "../../tests/unit/pipeline/driver.rs"]
pub(crate) mod tests;
