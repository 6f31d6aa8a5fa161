//! Generalized EOPnP: the pose of a multi-camera rig (docs/algorithm.md, generalized EOPnP).
//!
//! The data flows through four steps, one file each:
//!
//! | step | file | what it does |
//! |---|---|---|
//! | rays | [`rays`] | checks the problem, undistorts each pixel through its camera into a ray of the rig frame (centre, direction), the working frame |
//! | cost | [`cost`] | the O(N) moments of the generalized object-space cost, `t` eliminated: `f(R) = r^T M r + 2 g^T r + k`; Newton on SO(3) with the generated local models |
//! | search | this file | the starts (the null vector of the homogenised cost, the quadratic part's, gP3P poses of spread triples), Newton from each, the minimum with the most points in front |
//! | refine | [`refine`] | Levenberg-Marquardt on the pixel error of every observation through its own camera ([`crate::pipeline::refine_rig`]); the covariance |
//!
//! A problem whose observations are all in one camera is not solved here: the solver hands it
//! to the central pipeline in that camera and composes the pose with the camera's pose in the
//! rig ([`crate::Solver`]).

mod cost;
mod rays;
mod refine;

pub(crate) use rays::{one_camera, rays, Rays, RigInput};
pub(crate) use refine::{pixel_error2, refine as refine_pixels};

use arrayvec::ArrayVec;
use nalgebra::{Matrix3, Point3, SMatrix, Vector3};

use crate::covariance::NoiseModel;
use crate::error::PnpError;
use crate::numeric::gp3p::gp3p;
use crate::numeric::linalg::smallest_eigenvector;
use crate::numeric::rotation::{candidate_to_rotation, nearest_rotation_polar};
use crate::pipeline::vertical::{self, Vertical, VerticalCheck};
use crate::pipeline::{
    CandidateSource, Loss, Refinement, Solution, Solutions, EXACT_FIT, MAX_CANDIDATES,
};
use cost::{Cost, V9};

/// What a rig solve needs of the solver's options.
#[derive(Clone, Copy, Debug)]
pub(crate) struct RigOptions {
    pub refinement: Refinement,
    pub loss: Loss,
    pub newton_iterations: u32,
    pub newton_step_tolerance: f64,
    pub reprojection_iterations: u32,
    pub exhaustive: bool,
    pub covariance: Option<NoiseModel>,
    /// The known vertical's prior (the `vertical` stage), in the rig's frame.
    pub vertical: Option<Vertical>,
}

/// Two minima closer than this (Frobenius norm of the rotation difference) are the same.
const SAME_MINIMUM: f64 = 1e-6;
/// A start within this of an already refined minimum is in its basin: skipped.
const IN_BASIN: f64 = 0.05;
/// Triples of rays whose gP3P poses start the search.
const GP3P_TRIPLES: usize = 4;
/// The gP3P starts run for at most this many rays (or in the exhaustive mode): the small-N
/// search, as the central solver's P3P starts. Above it the null-vector starts find the same
/// minimum: on 10,500 seeded problems of `examples/rig_compare.rs`'s generator (2-6 cameras,
/// N = 13 to 300, sigma 0 to 3 px, pinhole and distorting cameras) the default pose did not
/// change without them, nor did any result of `tests/rig.rs` (planar rigs of 30 and 100
/// points included); they cost 15 % of the solve at N = 100.
const GP3P_MAX_RAYS: usize = 12;
/// At most this many minima (the order of [`search`]) are refined in pixels in the default mode:
/// the first, and the next ones that rival it ([`PIXEL_RIVAL`]).
const PIXEL_STARTS: usize = 3;
/// A minimum rivals the first if it has as many points in front (more than half) and an
/// object-space cost at most this many times the first's: at small N and high noise the pixel
/// error's global minimum can be in its basin. Others (points behind cameras, costs orders of
/// magnitude above) are not refined: their Levenberg-Marquardt runs are long and never win.
const PIXEL_RIVAL: f64 = 10.0;

/// A local minimum of the object-space cost (working frame).
#[derive(Clone, Copy, Debug)]
struct Minimum {
    r: Matrix3<f64>,
    f: f64,
    /// Points in front of their ray's centre (counted only when the search found several
    /// minima, to rank them; 0 otherwise).
    in_front: usize,
    iterations: u32,
    source: CandidateSource,
}

/// The pose of a rig problem; with `all`, every distinct minimum, best first.
pub(crate) fn solve(
    opts: &RigOptions,
    input: &RigInput<'_>,
    all: Option<&mut Solutions>,
) -> Result<Solution, PnpError> {
    check_loss(opts)?;
    let rays = rays::rays(input)?;
    let cost = working_cost(&rays).ok_or(PnpError::NoSolution)?;
    let minima = search(opts, &rays, &cost);
    if minima.is_empty() {
        return Err(PnpError::NoSolution);
    }
    let count = if all.is_some() {
        minima.len().min(MAX_CANDIDATES)
    } else if opts.refinement == Refinement::Algebraic {
        1
    } else {
        let first = &minima[0];
        let n = rays.rays.len();
        let rival = |m: &Minimum| {
            (2 * m.in_front > n) == (2 * first.in_front > n) && m.f <= PIXEL_RIVAL * first.f
        };
        1 + minima[1..]
            .iter()
            .take(PIXEL_STARTS - 1)
            .take_while(|m| rival(m))
            .count()
    };
    // A vertical the images contradict (at the best minimum) is reported as such.
    let mut checks: ArrayVec<(Solution, Option<VerticalCheck>), MAX_CANDIDATES> = ArrayVec::new();
    for m in minima.iter().take(count) {
        let (r, t) = to_original(&rays, &cost, &m.r);
        checks.push(finish(opts, &rays, input, &cost, m, &r, &t));
    }
    // Best first (most points in front, then the lowest cost), sorted in place: an
    // `ArrayVec` of `MAX_CANDIDATES` solutions is tens of kilobytes, never moved or collected.
    checks.sort_by(|a, b| order(&a.0, &b.0));
    vertical::verdict(checks[0].1)?;
    if let Some(all) = all {
        for (s, _) in &checks {
            let duplicate = all.iter().any(|o: &Solution| {
                (o.rotation - s.rotation).norm() <= 1e-6
                    && (o.translation - s.translation).norm() <= 1e-6 * (1.0 + s.translation.norm())
            });
            if !duplicate && !all.is_full() {
                all.push(*s);
            }
        }
    }
    Ok(checks[0].0)
}

/// The maximum-likelihood pose of the basin of `initial` (`x_rig = R X + t`): the pixel
/// refinement from it, without the search.
pub(crate) fn refine_from(
    opts: &RigOptions,
    input: &RigInput<'_>,
    initial: (&Matrix3<f64>, &Vector3<f64>),
) -> Result<Solution, PnpError> {
    check_loss(opts)?;
    let rays = rays::rays(input)?;
    let cost = working_cost(&rays).ok_or(PnpError::NoSolution)?;
    let rw = *initial.0;
    let m = Minimum {
        r: rw,
        f: cost.value(&rw),
        in_front: 0,
        iterations: 0,
        source: CandidateSource::Initial,
    };
    let mut opts = *opts;
    opts.refinement = Refinement::Reprojection;
    let (sol, check) = finish(&opts, &rays, input, &cost, &m, initial.0, initial.1);
    vertical::verdict(check)?;
    Ok(sol)
}

fn check_loss(opts: &RigOptions) -> Result<(), PnpError> {
    if opts.loss.is_valid() {
        Ok(())
    } else {
        Err(PnpError::InvalidOption { option: "loss" })
    }
}

/// The working frame's point of ray `k`: world point, centre, direction, weight.
fn working(rays: &Rays, k: usize) -> (Vector3<f64>, Vector3<f64>, Vector3<f64>, f64) {
    let r = &rays.rays[k];
    (
        (rays.obs.world[k].coords - rays.x_mean) / rays.scale,
        rays.working_centres[r.camera],
        r.direction,
        r.weight,
    )
}

fn working_cost(rays: &Rays) -> Option<Cost> {
    Cost::new(rays.rays.len(), |k| working(rays, k))
}

/// The pose in the caller's frame of the working frame's rotation `r` (the translation the
/// cost's minimiser gives): `R X + t - c = scale (R X' + t' - c')`, so
/// `t = scale t' - R x_mean + c_mean`.
fn to_original(rays: &Rays, cost: &Cost, r: &Matrix3<f64>) -> (Matrix3<f64>, Vector3<f64>) {
    let tw = cost.translation(r);
    (*r, tw * rays.scale - r * rays.x_mean + rays.c_mean)
}

/// Points in front of their ray's centre at the working-frame rotation `r`.
fn in_front(rays: &Rays, cost: &Cost, r: &Matrix3<f64>) -> usize {
    let t = cost.translation(r);
    (0..rays.rays.len())
        .filter(|&k| {
            let (x, c, v, _) = working(rays, k);
            (r * x + t - c).dot(&v) > 0.0
        })
        .count()
}

/// The search: every start refined by Newton (but starts within [`IN_BASIN`] of a refined
/// minimum, unless exhaustive), distinct minima sorted with the most points in front first,
/// then by cost.
fn search(opts: &RigOptions, rays: &Rays, cost: &Cost) -> Vec<Minimum> {
    let starts = starts(rays, cost, opts.exhaustive);
    let mut minima: Vec<Minimum> = Vec::new();
    let tol = opts.newton_step_tolerance.max(1e-12);
    for (r0, source) in starts {
        if !opts.exhaustive && minima.iter().any(|m| (m.r - r0).norm() <= IN_BASIN) {
            continue;
        }
        let (r, f, iterations) = cost.newton(&r0, opts.newton_iterations, tol);
        if !r.iter().all(|x| x.is_finite()) {
            continue;
        }
        if minima.iter().any(|m| (m.r - r).norm() <= SAME_MINIMUM) {
            continue;
        }
        minima.push(Minimum {
            r,
            f,
            in_front: 0,
            iterations,
            source,
        });
    }
    // The points in front rank several minima (one needs no count: its refinement counts them).
    if minima.len() > 1 {
        for m in &mut minima {
            m.in_front = in_front(rays, cost, &m.r);
        }
    }
    let n = rays.rays.len();
    minima.sort_by(|a, b| {
        let front = |m: &Minimum| 2 * m.in_front > n;
        front(b).cmp(&front(a)).then(a.f.total_cmp(&b.f))
    });
    minima
}

/// The starting rotations: the null vector of the homogenised cost `[[M, g], [g^T, k]]` (the
/// exact rotation for noise-free data), the quadratic part's null vector (the sign of positive
/// determinant), and the
/// gP3P poses of a few spread triples of rays (at most [`GP3P_MAX_RAYS`] rays, or exhaustive).
fn starts(rays: &Rays, cost: &Cost, exhaustive: bool) -> Vec<(Matrix3<f64>, CandidateSource)> {
    let mut out = Vec::new();
    let mut hom = SMatrix::<f64, 10, 10>::zeros();
    hom.fixed_view_mut::<9, 9>(0, 0).copy_from(&cost.m);
    hom.fixed_view_mut::<9, 1>(0, 9).copy_from(&cost.g);
    hom.fixed_view_mut::<1, 9>(9, 0)
        .copy_from(&cost.g.transpose());
    hom[(9, 9)] = cost.k;
    // The smallest eigenvectors by inverse iteration (as the central `nullspace`'s fast path),
    // the full decomposition if the shifted factorisation fails.
    let z = smallest_eigenvector(&hom, cost.scale + cost.k).or_else(|| {
        let eig = hom.symmetric_eigen();
        let i = eig.eigenvalues.imin();
        Some(eig.eigenvectors.column(i).into_owned())
    });
    if let Some(z) = z {
        if z[9].abs() > 1e-9 * z.norm() {
            let r = V9::from_fn(|k, _| z[k] / z[9]);
            if let Some(rot) = nearest_rotation_polar(&Matrix3::from_fn(|a, b| r[3 * a + b])) {
                out.push((rot, CandidateSource::Generalized));
            }
        }
    }
    let e = smallest_eigenvector(&cost.m, cost.scale).or_else(|| {
        let eig = cost.m.symmetric_eigen();
        let i = eig.eigenvalues.imin();
        Some(eig.eigenvectors.column(i).into_owned())
    });
    if let Some(e) = e {
        // The sign with a positive determinant (`vec(R)` has det 1), as `nullspace`'s case 1.
        let v: [f64; 9] = std::array::from_fn(|i| e[i]);
        if let Some(rot) = candidate_to_rotation(&v) {
            out.push((rot, CandidateSource::Case1));
        }
    }
    if rays.rays.len() > GP3P_MAX_RAYS && !exhaustive {
        return out;
    }
    for triple in spread_triples(rays) {
        let world: [Point3<f64>; 3] = triple.map(|k| rays.obs.world[k]);
        let centres = triple.map(|k| Point3::from(rays.rays[k].centre));
        let dirs = triple.map(|k| rays.rays[k].direction);
        for pose in gp3p(&world, &centres, &dirs) {
            out.push((pose.rotation, CandidateSource::Gp3p));
        }
    }
    out
}

/// Up to [`GP3P_TRIPLES`] triples of rays, spread over the cameras and the points: every
/// triple for at most six rays, otherwise triples of rays a third of the list apart, from
/// different cameras where the order allows.
fn spread_triples(rays: &Rays) -> Vec<[usize; 3]> {
    let n = rays.rays.len();
    if n <= 6 {
        let mut out = Vec::new();
        for a in 0..n {
            for b in a + 1..n {
                for c in b + 1..n {
                    out.push([a, b, c]);
                }
            }
        }
        return out;
    }
    (0..GP3P_TRIPLES)
        .map(|k| {
            let a = k * n / (3 * GP3P_TRIPLES);
            [a, a + n / 3, a + 2 * n / 3]
        })
        .collect()
}

/// A minimum finished: refined in pixels (the default mode; with a known vertical, on to the
/// maximum a posteriori pose), its costs, diagnostics and covariance; and the vertical's test.
#[allow(clippy::too_many_arguments)]
fn finish(
    opts: &RigOptions,
    rays: &Rays,
    input: &RigInput<'_>,
    cost: &Cost,
    m: &Minimum,
    r: &Matrix3<f64>,
    t: &Vector3<f64>,
) -> (Solution, Option<VerticalCheck>) {
    let fmax = input
        .rig
        .cameras()
        .iter()
        .map(|c| {
            let (fx, fy) = c.focal_lengths();
            fx.max(fy)
        })
        .fold(0.0, f64::max);
    let algebraic = m.f / cost.scale;
    // The algebraic mode evaluates the pixel cost at the object-space minimum (no iteration).
    let algebraic_only = opts.refinement == Refinement::Algebraic;
    let iterations = if algebraic_only {
        0
    } else {
        opts.reprojection_iterations
    };
    let e = refine::refine(
        rays,
        input.rig,
        opts.loss,
        (r, t),
        iterations,
        m.f <= EXACT_FIT * cost.scale,
        opts.vertical.map(|v| v.with_points(rays.rays.len())),
    );
    let (r, t, cost_px, squared, weight_sum, front) =
        (e.r, e.t, e.cost, e.squared, e.weight_sum, e.in_front);
    let (iterations, converged) = if algebraic_only {
        (0, true)
    } else {
        (e.iterations, e.converged)
    };
    let n = rays.rays.len();
    let covariance = opts
        .covariance
        .and_then(|noise| refine::covariance(rays, input.rig, &r, &t, noise));
    let mut sol = Solution::from_parts(r, t);
    sol.cost = cost_px.min(f64::MAX);
    sol.algebraic_cost = algebraic;
    sol.reprojection_rmse = (squared / weight_sum).sqrt() / fmax;
    sol.cheirality_ok = 2 * front > n;
    sol.degenerate = false;
    sol.planar = rays.planarity < 1e-3;
    sol.source = m.source;
    sol.newton_iterations = m.iterations;
    sol.reprojection_iterations = iterations;
    sol.converged = converged;
    sol.used = n;
    sol.skipped = rays.skipped;
    sol.covariance = covariance;
    (sol, e.vertical)
}

/// Best first: most points in front, then the lowest cost.
fn order(a: &Solution, b: &Solution) -> core::cmp::Ordering {
    (!a.cheirality_ok)
        .cmp(&!b.cheirality_ok)
        .then(a.cost.total_cmp(&b.cost))
}
