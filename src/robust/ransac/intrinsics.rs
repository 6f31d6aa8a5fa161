//! RANSAC with a refined principal point or distortion ([`crate::Problem::refine_principal_point`],
//! [`crate::Problem::refine_distortion`]): the consensus is found through the given camera (with
//! its focal length when it is unknown, [`super::focal`]); then the inliers are refined with the
//! free intrinsics, re-classified through the refined camera at the final threshold and refitted
//! until the inlier set stops changing, so that the returned inliers are those of the returned
//! camera (a guess without distortion misses the inliers at the image's edges).

use nalgebra::{Point2, Point3};

use super::{Ransac, RansacSolution, FINAL_STEPS};
use crate::camera::Camera;
use crate::error::PnpError;
use crate::problem::Problem;
use crate::solver::FreeIntrinsics;
use crate::Solver;

/// World points, their pixels and the caller's weights.
type Correspondences<'a> = (&'a [Point3<f64>], &'a [Point2<f64>], Option<&'a [f64]>);

impl Ransac {
    /// `out`, found through `camera`, refitted with the free intrinsics `free` (module docs).
    pub(super) fn refit_intrinsics(
        &self,
        solver: &Solver,
        (world, pixels, weights): Correspondences<'_>,
        camera: &Camera,
        free: FreeIntrinsics,
        mut out: RansacSolution,
    ) -> Result<RansacSolution, PnpError> {
        let start = std::time::Instant::now();
        let thf = self.threshold_px * self.final_threshold_factor;
        let (f0, _) = camera.focal_lengths();
        let range = free.range.map(|r| r.scales(f0)).transpose()?;
        let mut cam = out.solution.camera.unwrap_or(*camera);
        let mut fw = vec![0.0; world.len()];
        for _ in 0..FINAL_STEPS {
            for (i, w) in fw.iter_mut().enumerate() {
                *w = if out.inliers[i] {
                    weights.map_or(1.0, |w| w[i])
                } else {
                    0.0
                };
            }
            let mut fit = Problem::pixels(world, pixels, &cam).weights(&fw);
            if let Some((lo, hi)) = range {
                fit = fit.unknown_focal_within(lo * f0, hi * f0);
            }
            (fit.refine_principal_point, fit.refine_distortion) =
                (free.free.principal_point, free.free.distortion);
            let sol = solver.refine(&fit, &out.solution.pose())?;
            cam = sol.camera.unwrap_or(cam);
            out.solution = sol;
            // The inliers through the refined camera.
            let (r, t) = (sol.rotation, sol.translation);
            let inliers: Vec<bool> = (0..world.len())
                .map(|i| {
                    let p = r * world[i].coords + t;
                    weights.is_none_or(|w| w[i] > 0.0)
                        && p.z > 0.0
                        && (cam.project(Point2::new(p.x / p.z, p.y / p.z)) - pixels[i]).norm() < thf
                })
                .collect();
            if inliers == out.inliers {
                break;
            }
            out.num_inliers = inliers.iter().filter(|x| **x).count();
            out.inliers = inliers;
        }
        out.stats.inliers = out.num_inliers;
        out.stats.inlier_ratio = out.num_inliers as f64 / world.len() as f64;
        out.stats.micros += start.elapsed().as_secs_f64() * 1e6;
        Ok(out)
    }
}
