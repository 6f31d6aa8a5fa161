//! Solves with free intrinsics: an unknown focal length ([`crate::Problem::unknown_focal`]),
//! a refined principal point or distortion ([`crate::Problem::refine_principal_point`],
//! [`crate::Problem::refine_distortion`]): the intrinsics and the pose that minimise the pixel
//! error together.
//!
//! With an unknown focal length, the search (docs/algorithm.md, `refine_intrinsics`): P4Pf
//! ([`crate::numeric::p4pf`]) on [`SUBSETS`] four-point subsets spread over the
//! correspondences gives candidate focal lengths, each scored by its hypothesis' pixel cost on
//! every correspondence; the best [`STARTS`] - 1 of them within the range, and the camera's own
//! focal length, each start a full solve at that focal length (EOPnP and the maximum-likelihood
//! refinement: the global pose for it), and `refine_intrinsics` runs from each to a minimum
//! over pose and intrinsics together. The lowest wins. With a known focal length, the one start
//! is the solve through the given camera.

use nalgebra::{Isometry3, Matrix3, Point2, Point3, Vector3};

use super::Solver;
use crate::camera::Camera;
use crate::covariance::{from_rotation_vector, NoiseModel};
use crate::error::PnpError;
use crate::numeric::p4pf::p4pf;
use crate::pipeline::refine_intrinsics::{
    covariance, refine_intrinsics, squared_cost, Free, IntrinsicsInputs, IntrinsicsOutcome,
    MAX_ITERATIONS,
};
use crate::pipeline::Loss;
use crate::pipeline::Solution;
use crate::problem::{FocalRange, Problem};

/// Four-point subsets tried by P4Pf.
const SUBSETS: usize = 12;
/// Starts refined over pose and focal length: the camera's focal length and the best of the
/// other candidates.
const STARTS: usize = 4;
/// A geometric grid of focal scales within the range, each a candidate scored by the cost of
/// the solve at it: P4Pf's hypotheses from four noisy points can all miss, as with a narrow
/// field of view, where the perspective that fixes the focal length is faint.
const GRID: usize = 7;

/// The free intrinsics of a solve: which, and the focal length's range (its scale over the
/// camera's; `(1, 1)` when it is known).
#[derive(Clone, Copy)]
pub(crate) struct FreeIntrinsics {
    pub free: Free,
    pub range: Option<FocalRange>,
}

impl FreeIntrinsics {
    /// The focal scale's range, checked, for a camera of first focal length `f0`.
    fn scales(self, f0: f64) -> Result<(f64, f64), PnpError> {
        self.range.map_or(Ok((1.0, 1.0)), |r| r.scales(f0))
    }
}

/// `TooFewPoints` unless the correspondences of weight > 0 determine the pose and the free
/// intrinsics (two equations each).
fn check_count(
    world: &[Point3<f64>],
    weights: Option<&[f64]>,
    camera: &Camera,
    free: Free,
) -> Result<(), PnpError> {
    let (centre, dist) = camera.intrinsic_groups();
    let params = 6
        + usize::from(free.focal)
        + if free.principal_point {
            centre.len()
        } else {
            0
        }
        + if free.distortion { dist.len() } else { 0 };
    let got = weights.map_or(world.len(), |w| w.iter().filter(|x| **x > 0.0).count());
    let need = params.div_ceil(2);
    if got < need {
        return Err(PnpError::TooFewPoints { got, need });
    }
    Ok(())
}

/// The plain problem of `pixels` through `camera` with the caller's weights.
fn pixel_problem<'a>(
    world: &'a [Point3<f64>],
    pixels: &'a [Point2<f64>],
    camera: &'a Camera,
    weights: Option<&'a [f64]>,
) -> Problem<'a> {
    let p = Problem::pixels(world, pixels, camera);
    match weights {
        Some(w) => p.weights(w),
        None => p,
    }
}

impl Solver {
    /// The solve of pixels through `camera` with the intrinsics `free` estimated.
    pub(super) fn pixels_intrinsics(
        &self,
        world: &[Point3<f64>],
        pixels: &[Point2<f64>],
        camera: &Camera,
        weights: Option<&[f64]>,
        free: FreeIntrinsics,
    ) -> Result<Solution, PnpError> {
        let range = free.scales(camera.focal_lengths().0)?;
        // The inputs checked (and the solve at the camera's focal length, one of the starts).
        let first = self.solve(&pixel_problem(world, pixels, camera, weights))?;
        check_count(world, weights, camera, free.free)?;
        let search = free.free.focal;
        self.finish_intrinsics(
            world, pixels, camera, weights, free.free, range, first, search,
        )
    }

    /// [`Solver::refine`] of pixels through `camera` with the intrinsics `free` estimated: the
    /// pose refined from `initial` through the given camera, then over pose and intrinsics.
    pub(super) fn refine_pixels_intrinsics(
        &self,
        world: &[Point3<f64>],
        pixels: &[Point2<f64>],
        camera: &Camera,
        weights: Option<&[f64]>,
        free: FreeIntrinsics,
        initial: &Isometry3<f64>,
    ) -> Result<Solution, PnpError> {
        let range = free.scales(camera.focal_lengths().0)?;
        let first = self.refine(&pixel_problem(world, pixels, camera, weights), initial)?;
        check_count(world, weights, camera, free.free)?;
        self.finish_intrinsics(
            world, pixels, camera, weights, free.free, range, first, false,
        )
    }

    /// From `first`, the solution through the given camera: with `search`, the other focal
    /// lengths' starts (module docs); `refine_intrinsics` from each, the lowest with its focal
    /// scale within `(lo, hi)` as the solution.
    #[allow(clippy::too_many_arguments)]
    fn finish_intrinsics(
        &self,
        world: &[Point3<f64>],
        pixels: &[Point2<f64>],
        camera: &Camera,
        weights: Option<&[f64]>,
        free: Free,
        (lo, hi): (f64, f64),
        first: Solution,
        search: bool,
    ) -> Result<Solution, PnpError> {
        let plain = |scale: f64| -> Result<Solution, PnpError> {
            let cam = camera.with_focal_scale(scale);
            self.solve(&pixel_problem(world, pixels, &cam, weights))
        };
        // The candidates: P4Pf's best few, and the grid, each scored by the solve at it.
        let mut scored: Vec<(f64, f64, Solution)> = Vec::new();
        if search {
            let mut scales: Vec<f64> = candidates(world, pixels, camera, weights, (lo, hi))
                .into_iter()
                .take(STARTS)
                .collect();
            let (llo, lhi) = (lo.ln(), hi.ln());
            scales.extend(
                (0..GRID).map(|k| (llo + (lhi - llo) * (k as f64 + 0.5) / GRID as f64).exp()),
            );
            for s in scales {
                if (s - 1.0).abs() <= 1e-3 || scored.iter().any(|o| (s / o.0 - 1.0).abs() <= 1e-3) {
                    continue;
                }
                if let Ok(sol) = plain(s) {
                    scored.push((s, sol.cost, sol));
                }
            }
            scored.sort_by(|a, b| a.1.total_cmp(&b.1));
            scored.truncate(STARTS - 1);
        }
        let (f0, _) = camera.focal_lengths();
        let inputs = IntrinsicsInputs {
            world,
            pixels,
            weights,
            free,
            focal_range: (lo * f0, hi * f0),
            loss: self.opts.loss,
        };
        let within = |o: &IntrinsicsOutcome| o.cost.is_finite();
        let mut best: Option<(IntrinsicsOutcome, Solution)> = None;
        let mut consider = |sol: Solution, scale: f64| {
            let start = camera.with_focal_scale(scale);
            let out = refine_intrinsics(
                &inputs,
                &sol.rotation,
                &sol.translation,
                &start,
                MAX_ITERATIONS,
            );
            if let Some(o) = out.filter(within) {
                if best.as_ref().is_none_or(|(b, _)| o.cost < b.cost) {
                    best = Some((o, sol));
                }
            }
        };
        // Should no refinement end within the range: the lowest solve at a focal length within
        // it (the camera's, or a candidate's).
        let fallback = core::iter::once((1.0, first.cost, first))
            .chain(scored.iter().copied())
            .filter(|(s, _, _)| *s >= lo && *s <= hi)
            .min_by(|a, b| a.1.total_cmp(&b.1));
        consider(first, 1.0);
        for (s, _, sol) in scored {
            consider(sol, s);
        }
        let Some((o, mut sol)) = best else {
            let (s, _, mut sol) = fallback.ok_or(PnpError::NoSolution)?;
            sol.camera = Some(camera.with_focal_scale(s));
            return Ok(sol);
        };
        sol.rotation = o.r;
        sol.translation = o.t;
        sol.cost = o.cost;
        let wsum = weights.map_or(sol.used as f64, |w| w.iter().filter(|x| **x > 0.0).sum());
        let (fx, fy) = o.camera.focal_lengths();
        // The RMS residual without the loss.
        let sq = if inputs.loss == Loss::Squared {
            o.cost
        } else {
            squared_cost(&inputs, &o).unwrap_or(f64::INFINITY)
        };
        sol.reprojection_rmse = if wsum > 0.0 {
            (sq / wsum).sqrt() / fx.max(fy)
        } else {
            f64::INFINITY
        };
        sol.reprojection_iterations += o.iterations;
        sol.converged = o.converged;
        sol.camera = Some(o.camera);
        // The marginal covariance of the pose with the intrinsics free, and the focal length's
        // standard deviation.
        sol.covariance = self.covariance.and_then(|noise| {
            let sigma = match noise {
                NoiseModel::Sigma(s) => Some(s),
                NoiseModel::Estimated => None,
            };
            let (pose, focal_sigma, sigma) = covariance(&inputs, &o, sigma)?;
            from_rotation_vector(&pose, sigma, focal_sigma)
        });
        Ok(sol)
    }
}

/// Candidate focal scales from P4Pf on spread four-point subsets, best first (by the pixel cost
/// of each hypothesis on every correspondence), within `(lo, hi)`.
fn candidates(
    world: &[Point3<f64>],
    pixels: &[Point2<f64>],
    camera: &Camera,
    weights: Option<&[f64]>,
    (lo, hi): (f64, f64),
) -> Vec<f64> {
    let (f0, _) = camera.focal_lengths();
    // The correspondences that undistort at the camera's focal length, as pixels relative to
    // the principal point of the equivalent pinhole camera.
    let mut idx: Vec<usize> = Vec::new();
    let mut centred: Vec<Point2<f64>> = Vec::new();
    for (i, px) in pixels.iter().enumerate() {
        if weights.is_some_and(|w| !(w[i] > 0.0)) {
            continue;
        }
        if let Ok(n) = camera.undistort(*px) {
            idx.push(i);
            centred.push(Point2::new(n.x * f0, n.y * f0));
        }
    }
    let n = idx.len();
    if n < 4 {
        return Vec::new();
    }
    let mut scored: Vec<(f64, f64)> = Vec::new();
    let mut state = 0x9e37_79b9_7f4a_7c15_u64 ^ n as u64;
    let mut next = |m: usize| {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        ((state >> 33) as usize) % m
    };
    for _ in 0..SUBSETS {
        let mut s = [0usize; 4];
        let mut k = 0;
        let mut attempts = 0;
        while k < 4 && attempts < 64 {
            attempts += 1;
            let c = next(n);
            if !s[..k].contains(&c) {
                s[k] = c;
                k += 1;
            }
        }
        if k < 4 {
            continue;
        }
        let w4 = s.map(|j| world[idx[j]]);
        let m4 = s.map(|j| centred[j]);
        for sol in p4pf(&w4, &m4) {
            let scale = sol.focal / f0;
            if !(scale >= lo && scale <= hi) {
                continue;
            }
            let cost = hypothesis_cost(
                world,
                &idx,
                &centred,
                &sol.rotation,
                &sol.translation,
                sol.focal,
            );
            scored.push((cost, scale));
        }
    }
    scored.sort_by(|a, b| a.0.total_cmp(&b.0));
    scored.into_iter().map(|(_, s)| s).collect()
}

/// The pinhole pixel cost of a hypothesis on the correspondences `idx` (each term capped at
/// `(0.1 f)^2`, so that a few points far off do not decide it).
fn hypothesis_cost(
    world: &[Point3<f64>],
    idx: &[usize],
    centred: &[Point2<f64>],
    r: &Matrix3<f64>,
    t: &Vector3<f64>,
    f: f64,
) -> f64 {
    let cap = (0.1 * f) * (0.1 * f);
    idx.iter()
        .zip(centred)
        .map(|(&i, m)| {
            let p = r * world[i].coords + t;
            if !(p.z > 0.0) {
                return cap;
            }
            let (du, dv) = (f * p.x / p.z - m.x, f * p.y / p.z - m.y);
            (du * du + dv * dv).min(cap)
        })
        .sum()
}
