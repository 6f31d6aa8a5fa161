//! RANSAC on a multi-camera rig: samples of three rays spread over the rig's cameras, solved by
//! the generalized three-point pose (gP3P), MSAC scoring of the pixel error of every
//! observation through its own camera, local optimisation and the final fit by the pixel
//! refinement of generalized EOPnP on the inliers, and the same a contrario consensus as for
//! one camera. Observations in one camera only are that camera's central problem.

use std::time::Instant;

use nalgebra::{Matrix3, Point3, Vector3};
use rand_core::SeedableRng;
use rand_pcg::Pcg64;

use super::chance;
use super::score::{msac, sample2, sample3};
use super::upright::Upright;
use super::{needed_iterations, Ransac, RansacSolution, RansacStats, FINAL_STEPS, LO_STEPS};
use crate::error::PnpError;
use crate::generalized::{self, pixel_error2, refine_pixels, Rays, RigInput};
use crate::numeric::gp3p::{gp3p, Gp3pSolutions};
use crate::solver::central_problem;
use crate::Solver;

/// Attempts to draw a sample whose rays are not all in one camera (when the rays span two or
/// more cameras) before taking the last drawn.
const SPREAD_ATTEMPTS: usize = 16;
/// Inliers an EOPnP fit needs (as for one camera).
const MIN_FIT_POINTS: usize = 6;

/// The best hypothesis so far.
#[derive(Clone, Copy)]
struct Scored {
    r: Matrix3<f64>,
    t: Vector3<f64>,
    cost: f64,
    inliers: usize,
}

impl Ransac {
    /// [`Ransac::estimate`] of a rig problem.
    pub(super) fn estimate_rig(
        &self,
        solver: &Solver,
        input: &RigInput<'_>,
    ) -> Result<RansacSolution, PnpError> {
        let start = Instant::now();
        self.check()?;
        solver.check_loss()?;
        let one = generalized::one_camera(input)?;
        if let Some(k) = one {
            let mut sol = self.estimate(solver, &central_problem(input, k))?;
            sol.solution = crate::solver::in_rig(&sol.solution, input.rig, k);
            return Ok(sol);
        }
        let rays = generalized::rays(input)?;
        let n = input.world.len();
        let m = rays.rays.len();
        let th2 = self.threshold_px * self.threshold_px;
        let mut stats = RansacStats::default();
        let mut rng = Pcg64::seed_from_u64(self.seed);
        let cameras_used = {
            let mut c: Vec<usize> = rays.rays.iter().map(|r| r.camera).collect();
            c.sort_unstable();
            c.dedup();
            c.len()
        };
        let score = |r: &Matrix3<f64>, t: &Vector3<f64>, bound: f64| -> Option<Scored> {
            let errors = (0..m).map(|k| pixel_error2(&rays, input.rig, k, r, t));
            let (cost, inliers) = msac(errors, th2, bound)?;
            Some(Scored {
                r: *r,
                t: *t,
                cost,
                inliers,
            })
        };
        let mut best: Option<Scored> = None;
        let mut needed = f64::INFINITY;
        // With a known vertical: samples of two rays, solved by up2p.
        let upright = input.gravity.as_ref().map(Upright::new);
        let size = if upright.is_some() { 2 } else { 3 };
        while stats.iterations < self.max_iterations
            && (stats.iterations < self.min_iterations || f64::from(stats.iterations) < needed)
        {
            stats.iterations += 1;
            let mut sample = None;
            for _ in 0..SPREAD_ATTEMPTS {
                // A sample of two is `[a, b, b]` (its third ray the second's).
                let drawn = if upright.is_some() {
                    sample2(&mut rng, m).map(|[a, b]| [a, b, b])
                } else {
                    sample3(&mut rng, m)
                };
                let Some(s) = drawn else {
                    break;
                };
                let cam = |i: usize| rays.rays[s[i]].camera;
                sample = Some(s);
                if cameras_used < 2 || !(cam(0) == cam(1) && cam(1) == cam(2)) {
                    break;
                }
            }
            let Some(s) = sample else {
                continue;
            };
            let world: [Point3<f64>; 3] = s.map(|k| rays.obs.world[k]);
            let centres = s.map(|k| Point3::from(rays.rays[k].centre));
            let dirs = s.map(|k| rays.rays[k].direction);
            let poses = if let Some(up) = &upright {
                let mut poses = Gp3pSolutions::new();
                poses.extend(up.poses(
                    [&world[0], &world[1]],
                    [&centres[0], &centres[1]],
                    [&dirs[0], &dirs[1]],
                ));
                poses
            } else {
                gp3p(&world, &centres, &dirs)
            };
            for pose in poses {
                stats.hypotheses += 1;
                let bound = best.map_or(f64::INFINITY, |b| b.cost);
                let Some(mut cand) = score(&pose.rotation, &pose.translation, bound) else {
                    continue;
                };
                if self.local_optimisation {
                    for _ in 0..LO_STEPS {
                        stats.local_fits += 1;
                        let Some((r, t)) = fit(solver, &rays, input, &cand.r, &cand.t, th2) else {
                            break;
                        };
                        match score(&r, &t, cand.cost) {
                            Some(better) if better.cost < cand.cost => cand = better,
                            _ => break,
                        }
                    }
                }
                best = Some(cand);
                needed = needed_iterations(self.confidence, cand.inliers as f64 / m as f64, size);
            }
        }
        let no_consensus = PnpError::NoConsensus {
            iterations: stats.iterations,
            inliers: best.map_or(0, |b| b.inliers),
            needed: MIN_FIT_POINTS.min(n),
        };
        let best = best.ok_or(no_consensus.clone())?;

        // Final fit: refit and re-classify with the final threshold until the set is stable.
        let thf = self.threshold_px * self.final_threshold_factor;
        let thf2 = thf * thf;
        let (mut r, mut t) = (best.r, best.t);
        let mut prev: Vec<bool> = Vec::new();
        for _ in 0..FINAL_STEPS {
            stats.final_fits += 1;
            let mask = inlier_mask(&rays, input, &r, &t, thf2);
            if mask == prev {
                break;
            }
            let Some((rn, tn)) = fit(solver, &rays, input, &r, &t, thf2) else {
                break;
            };
            (r, t) = (rn, tn);
            prev = mask;
        }
        // The returned solution: generalized EOPnP's refinement on the final inliers (the
        // others weight 0), with the solver's options (covariance included).
        let mask_rays = inlier_mask(&rays, input, &r, &t, thf2);
        let mut weights = vec![0.0; n];
        let mut mask = vec![false; n];
        for (k, ry) in rays.rays.iter().enumerate() {
            if mask_rays[k] {
                weights[ry.index] = input.weights.map_or(1.0, |w| w[ry.index]);
                mask[ry.index] = true;
            }
        }
        let num_inliers = mask.iter().filter(|x| **x).count();
        // A consensus no larger than wrong poses reach by chance is none (chance.rs): the
        // chance rate of each camera from its observations' spread, weighted by their number.
        let mut rate = 0.0;
        for c in 0..input.rig.cameras().len() {
            let px: Vec<nalgebra::Point2<f64>> = rays
                .rays
                .iter()
                .zip(&rays.obs.pixels)
                .filter(|(r, _)| r.camera == c)
                .map(|(_, p)| *p)
                .collect();
            if !px.is_empty() {
                rate += chance::chance_inlier_rate(&px, (1.0, 1.0), thf) * px.len() as f64;
            }
        }
        let rate = rate / m as f64;
        let needed = chance::least_consensus(n, rate).max(MIN_FIT_POINTS.min(n));
        if num_inliers < needed {
            return Err(PnpError::NoConsensus {
                iterations: stats.iterations,
                inliers: num_inliers,
                needed,
            });
        }
        let masked = RigInput {
            weights: Some(&weights),
            ..*input
        };
        // With a known vertical, on to the maximum a posteriori pose (the `vertical` stage).
        let opts = solver.with_gravity(input.gravity).rig_options();
        let mut solution = generalized::refine_from(&opts, &masked, (&r, &t))?;
        // The mask of the returned pose.
        let final_rays = inlier_mask(
            &rays,
            input,
            &solution.rotation,
            &solution.translation,
            thf2,
        );
        mask.iter_mut().for_each(|x| *x = false);
        for (k, ry) in rays.rays.iter().enumerate() {
            mask[ry.index] = final_rays[k];
        }
        let num_inliers = mask.iter().filter(|x| **x).count();
        solution.skipped = rays.skipped;
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
}

/// The rays within the threshold (squared, pixels) of the pose.
fn inlier_mask(
    rays: &Rays,
    input: &RigInput<'_>,
    r: &Matrix3<f64>,
    t: &Vector3<f64>,
    th2: f64,
) -> Vec<bool> {
    (0..rays.rays.len())
        .map(|k| pixel_error2(rays, input.rig, k, r, t) < th2)
        .collect()
}

/// The pixel refinement of generalized EOPnP from `(r, t)` on the rays within the threshold,
/// or `None` with fewer than [`MIN_FIT_POINTS`] of them (all of them for smaller problems).
fn fit(
    solver: &Solver,
    rays: &Rays,
    input: &RigInput<'_>,
    r: &Matrix3<f64>,
    t: &Vector3<f64>,
    th2: f64,
) -> Option<(Matrix3<f64>, Vector3<f64>)> {
    let mask = inlier_mask(rays, input, r, t, th2);
    let count = mask.iter().filter(|x| **x).count();
    if count < MIN_FIT_POINTS.min(rays.rays.len()) {
        return None;
    }
    let sub = rays.subset(input.rig, &mask);
    let opts = solver.rig_options();
    let e = refine_pixels(
        &sub,
        input.rig,
        opts.loss,
        (r, t),
        super::FINAL_STEPS.max(20),
        false,
        None,
    );
    (e.cost.is_finite() && e.r.iter().all(|x| x.is_finite())).then_some((e.r, e.t))
}
