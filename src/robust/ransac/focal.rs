//! RANSAC with an unknown focal length ([`crate::Problem::unknown_focal`]): samples of four
//! correspondences solved by P4Pf ([`crate::numeric::p4pf`]; poses with their focal lengths,
//! those outside the range dropped), MSAC scoring of the pixel error through the camera at each
//! hypothesis' focal length, local optimisation and the final fit by `refine_intrinsics` (pose and
//! focal length together) on the inliers, the final solution the unknown-focal refinement of
//! the final inliers ([`crate::Solver::refine`]), and the same a contrario consensus as with a
//! known focal length.

use std::time::Instant;

use nalgebra::{Isometry3, Matrix3, Point2, Point3, UnitQuaternion, Vector3};
use rand_core::SeedableRng;
use rand_pcg::Pcg64;

use super::chance;
use super::score::{index, msac};
use super::{needed_iterations, Ransac, RansacSolution, RansacStats, FINAL_STEPS, LO_STEPS};
use crate::camera::Camera;
use crate::error::{InputKind, PnpError};
use crate::numeric::p4pf::p4pf;
use crate::pipeline::refine_intrinsics::{refine_intrinsics, Free, IntrinsicsInputs};
use crate::problem::{FocalRange, Problem};
use crate::Solver;

/// Inliers a fit needs (as with a known focal length).
const MIN_FIT_POINTS: usize = 6;
/// Levenberg-Marquardt iterations of a local or final fit (their results are re-scored and
/// re-classified; the returned solution is refined to convergence).
const FIT_ITERATIONS: u32 = 8;

/// A hypothesis: pose, focal scale (over the camera's), MSAC cost and inliers.
#[derive(Clone, Copy)]
struct Scored {
    r: Matrix3<f64>,
    t: Vector3<f64>,
    scale: f64,
    cost: f64,
    inliers: usize,
}

/// Four distinct indices in `0..n`, or `None` (n < 4, or the bounded attempts ran out).
fn sample4(rng: &mut Pcg64, n: usize) -> Option<[usize; 4]> {
    if n < 4 {
        return None;
    }
    let mut s = [0usize; 4];
    let mut k = 0;
    for _ in 0..256 {
        let c = index(rng, n);
        if !s[..k].contains(&c) {
            s[k] = c;
            k += 1;
            if k == 4 {
                return Some(s);
            }
        }
    }
    None
}

impl Ransac {
    /// [`Ransac::estimate`] of pixels through `camera` with its focal length unknown.
    pub(super) fn estimate_focal(
        &self,
        solver: &Solver,
        camera: &Camera,
        world: &[Point3<f64>],
        pixels: &[Point2<f64>],
        weights: Option<&[f64]>,
        range: FocalRange,
    ) -> Result<RansacSolution, PnpError> {
        let start = Instant::now();
        self.check()?;
        solver.check_loss()?;
        let n = world.len();
        crate::pipeline::check_lengths(n, pixels.len(), weights)?;
        for (i, (x, p)) in world.iter().zip(pixels).enumerate() {
            let input = if !x.coords.iter().all(|v| v.is_finite()) {
                InputKind::World
            } else if !(p.x.is_finite() && p.y.is_finite()) {
                InputKind::Image
            } else if weights.is_some_and(|w| !w[i].is_finite()) {
                InputKind::Weight
            } else {
                if weights.is_some_and(|w| w[i] < 0.0) {
                    return Err(PnpError::InvalidWeight { index: i });
                }
                continue;
            };
            return Err(PnpError::NonFinite { index: i, input });
        }
        let (f0, _) = camera.focal_lengths();
        let (lo, hi) = range.scales(f0)?;
        let (cx, cy) = camera.principal_point();
        let proj = camera.projector();
        // The correspondences that undistort at the camera's focal length (the samples' pixels
        // relative to the principal point of the equivalent pinhole camera), the others only
        // scored.
        let centred: Vec<Option<Point2<f64>>> = pixels
            .iter()
            .map(|p| {
                camera
                    .undistort(*p)
                    .ok()
                    .map(|m| Point2::new(m.x * f0, m.y * f0))
            })
            .collect();
        let usable: Vec<usize> = (0..n)
            .filter(|&i| centred[i].is_some() && weights.is_none_or(|w| w[i] > 0.0))
            .collect();
        let th2 = self.threshold_px * self.threshold_px;
        // The squared pixel error of point `i` under a hypothesis (`th2` when behind).
        let sq_err = |r: &Matrix3<f64>, t: &Vector3<f64>, scale: f64, i: usize, cap: f64| {
            let p = r * world[i].coords + t;
            if !(p.z > 0.0) {
                return cap;
            }
            let (px, py) = proj.project(p.x / p.z, p.y / p.z);
            let (du, dv) = (
                cx + scale * (px - cx) - pixels[i].x,
                cy + scale * (py - cy) - pixels[i].y,
            );
            let e2 = du * du + dv * dv;
            if e2.is_finite() {
                e2
            } else {
                cap
            }
        };
        let score = |r: &Matrix3<f64>, t: &Vector3<f64>, scale: f64, bound: f64| {
            let errors = usable.iter().map(|&i| sq_err(r, t, scale, i, th2));
            let (cost, inliers) = msac(errors, th2, bound)?;
            Some(Scored {
                r: *r,
                t: *t,
                scale,
                cost,
                inliers,
            })
        };
        let mut mask = vec![0.0; n];
        // `refine_intrinsics` (the focal length free) on the points within `thr2` of `(r, t, scale)` (the caller's weights).
        let mut fit = |r: &Matrix3<f64>, t: &Vector3<f64>, scale: f64, thr2: f64| {
            let mut count = 0;
            for (i, m) in mask.iter_mut().enumerate() {
                let inside = centred[i].is_some()
                    && weights.is_none_or(|w| w[i] > 0.0)
                    && sq_err(r, t, scale, i, f64::INFINITY) < thr2;
                *m = if inside {
                    weights.map_or(1.0, |w| w[i])
                } else {
                    0.0
                };
                count += usize::from(inside);
            }
            if count < MIN_FIT_POINTS.min(usable.len()) {
                return None;
            }
            let inp = IntrinsicsInputs {
                world,
                pixels,
                weights: Some(&mask),
                free: Free {
                    focal: true,
                    ..Free::default()
                },
                focal_range: (lo * f0, hi * f0),
                // The fits are least squares on the points within the threshold; the final
                // solution has the solver's loss.
                loss: crate::pipeline::Loss::Squared,
            };
            let start = camera.with_focal_scale(scale);
            refine_intrinsics(&inp, r, t, &start, FIT_ITERATIONS)
                .filter(|o| o.cost.is_finite())
                .map(|o| (o.r, o.t, o.camera.focal_lengths().0 / f0))
        };

        let mut stats = RansacStats::default();
        let mut rng = Pcg64::seed_from_u64(self.seed);
        let mut best: Option<Scored> = None;
        let mut needed = f64::INFINITY;
        let m = usable.len();
        while stats.iterations < self.max_iterations
            && (stats.iterations < self.min_iterations || f64::from(stats.iterations) < needed)
        {
            stats.iterations += 1;
            let Some(s) = sample4(&mut rng, m) else {
                continue;
            };
            let idx = s.map(|k| usable[k]);
            let w4 = idx.map(|i| world[i]);
            let m4 = idx.map(|i| centred[i].expect("usable"));
            for h in p4pf(&w4, &m4) {
                let scale = h.focal / f0;
                if !(scale >= lo && scale <= hi) {
                    continue;
                }
                stats.hypotheses += 1;
                let bound = best.map_or(f64::INFINITY, |b| b.cost);
                let Some(mut cand) = score(&h.rotation, &h.translation, scale, bound) else {
                    continue;
                };
                if self.local_optimisation {
                    for _ in 0..LO_STEPS {
                        stats.local_fits += 1;
                        let Some((r, t, sc)) = fit(&cand.r, &cand.t, cand.scale, th2) else {
                            break;
                        };
                        match score(&r, &t, sc, cand.cost) {
                            Some(better) if better.cost < cand.cost => cand = better,
                            _ => break,
                        }
                    }
                }
                best = Some(cand);
                needed = needed_iterations(self.confidence, cand.inliers as f64 / m as f64, 4);
            }
        }
        let no_consensus = PnpError::NoConsensus {
            iterations: stats.iterations,
            inliers: best.map_or(0, |b| b.inliers),
            needed: MIN_FIT_POINTS.min(n),
        };
        let best = best.ok_or(no_consensus.clone())?;

        // Final fit with the final threshold, until the inlier set is stable.
        let thf = self.threshold_px * self.final_threshold_factor;
        let thf2 = thf * thf;
        let (mut r, mut t, mut scale) = (best.r, best.t, best.scale);
        let inside = |r: &Matrix3<f64>, t: &Vector3<f64>, scale: f64| -> Vec<bool> {
            (0..n)
                .map(|i| {
                    centred[i].is_some()
                        && weights.is_none_or(|w| w[i] > 0.0)
                        && sq_err(r, t, scale, i, f64::INFINITY) < thf2
                })
                .collect()
        };
        let mut prev: Vec<bool> = Vec::new();
        for _ in 0..FINAL_STEPS {
            stats.final_fits += 1;
            let now = inside(&r, &t, scale);
            if now == prev {
                break;
            }
            let Some((rn, tn, sn)) = fit(&r, &t, scale, thf2) else {
                break;
            };
            (r, t, scale) = (rn, tn, sn);
            prev = now;
        }
        let inliers = inside(&r, &t, scale);
        let num_inliers = inliers.iter().filter(|x| **x).count();
        let rate = chance::chance_inlier_rate(pixels, (1.0, 1.0), thf);
        let least = chance::least_consensus(n, rate).max(MIN_FIT_POINTS.min(n));
        if num_inliers < least {
            return Err(PnpError::NoConsensus {
                iterations: stats.iterations,
                inliers: num_inliers,
                needed: least,
            });
        }
        // The solution: the unknown-focal refinement of the inliers (the others weight 0) from
        // the fit, the camera at the fit's focal length as the guess.
        let fw: Vec<f64> = (0..n)
            .map(|i| {
                if inliers[i] {
                    weights.map_or(1.0, |w| w[i])
                } else {
                    0.0
                }
            })
            .collect();
        let cam = camera.with_focal_scale(scale);
        let (f_lo, f_hi) = (lo * f0, hi * f0);
        let problem = Problem::pixels(world, pixels, &cam)
            .weights(&fw)
            .unknown_focal_within(f_lo, f_hi);
        let pose = Isometry3::from_parts(t.into(), UnitQuaternion::from_matrix(&r));
        let solution = solver.refine(&problem, &pose)?;
        stats.inliers = num_inliers;
        stats.inlier_ratio = num_inliers as f64 / n as f64;
        stats.micros = start.elapsed().as_secs_f64() * 1e6;
        Ok(RansacSolution {
            solution,
            inliers,
            num_inliers,
            stats,
        })
    }
}
