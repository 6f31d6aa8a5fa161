//! Registration: an image's pose re-estimated from its 2D-3D correspondences alone, plain or
//! robust, and compared with the model's.

use std::time::Instant;

use nalgebra::{Matrix3, Point2, Point3, Vector3};

use super::model::{Model, RegisterError};
use crate::camera::{Camera, Project, ProjectionJob};
use crate::ransac::{Ransac, RansacStats};
use crate::{Solution, Solver};

/// The result of [`register_image`].
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Clone, Debug)]
#[non_exhaustive]
pub struct Registration {
    /// Image id.
    pub image_id: u32,
    /// Image name.
    pub name: String,
    /// Number of 2D-3D correspondences of the image (observations with a 3D point).
    pub n: usize,
    /// Correspondences the pose was fitted to: all that could be undistorted, or RANSAC's
    /// inliers.
    pub inliers: usize,
    /// Observations skipped because their pixel could not be undistorted.
    pub skipped: usize,
    /// The estimated pose.
    pub solution: Solution,
    /// RANSAC's statistics, when registered with RANSAC.
    pub ransac: Option<RansacStats>,
    /// Rotation difference to the model's pose, degrees (largest angle between corresponding
    /// columns, [`crate::metrics::rotation_error_deg`]).
    pub rotation_error_deg: f64,
    /// Translation difference to the model's pose, percent of the model's `|t|`
    /// ([`crate::metrics::translation_error_pct`]).
    pub translation_error_pct: f64,
    /// RMS reprojection error of the estimated pose in pixels, through the full camera model,
    /// over the correspondences it was fitted to.
    pub rmse_px: f64,
    /// RMS reprojection error of the model's own pose in pixels over the same correspondences,
    /// for comparison.
    pub model_rmse_px: f64,
    /// Wall time of undistortion plus solve (or RANSAC), microseconds.
    pub micros: f64,
}

/// RMS pixel reprojection error of pose `(r, t)` through the full camera model over the
/// correspondences selected by `keep` (all if `None`).
pub(crate) fn pixel_rmse(
    cam: &Camera,
    world: &[Point3<f64>],
    pixels: &[Point2<f64>],
    keep: Option<&[bool]>,
    r: &Matrix3<f64>,
    t: &Vector3<f64>,
) -> f64 {
    // The camera unpacked and its model dispatched once, not per point.
    cam.projector().with_projection(Rmse {
        world,
        pixels,
        keep,
        r,
        t,
    })
}

/// [`pixel_rmse`]'s loop, for one lens model.
struct Rmse<'a> {
    world: &'a [Point3<f64>],
    pixels: &'a [Point2<f64>],
    keep: Option<&'a [bool]>,
    r: &'a Matrix3<f64>,
    t: &'a Vector3<f64>,
}

impl ProjectionJob for Rmse<'_> {
    type Output = f64;

    fn run<P: Project + Copy>(self, projection: P) -> f64 {
        let (mut s, mut k) = (0.0, 0usize);
        for (i, (x, px)) in self.world.iter().zip(self.pixels).enumerate() {
            if self.keep.is_some_and(|m| !m[i]) {
                continue;
            }
            let p = self.r * x.coords + self.t;
            let (qx, qy) = projection.project(p.x / p.z, p.y / p.z);
            s += (Point2::new(qx, qy) - px).norm_squared();
            k += 1;
        }
        if k == 0 {
            f64::NAN
        } else {
            (s / k as f64).sqrt()
        }
    }
}

/// Re-estimates the pose of image `image_id` from its 2D-3D correspondences and compares it
/// with the model's pose: with `ransac = None` by `solver` on all correspondences
/// ([`Solver::solve_pixels`]: the pixels are undistorted with the image's camera, so the
/// minimised error is, to first order, the pixel reprojection error that COLMAP's bundle
/// adjustment minimises), or robustly by [`Ransac::estimate_pixels`] with `solver` for the
/// local optimisation and the final fit. The time reported includes the undistortion.
///
/// See the [module documentation](super) for a runnable example.
///
/// # Errors
/// [`RegisterError`] for an unknown image or camera and for solver failures (e.g. fewer than
/// four correspondences, or no consensus).
pub fn register_image(
    model: &Model,
    image_id: u32,
    solver: &Solver,
    ransac: Option<&Ransac>,
) -> Result<Registration, RegisterError> {
    let (img, cam) = model.image_and_camera(image_id)?;
    let (world, pixels) = model.correspondences(image_id);

    let start = Instant::now();
    let (solution, mask, stats) = match ransac {
        None => (solver.solve_pixels(&world, &pixels, cam)?, None, None),
        Some(r) => {
            let s = r.estimate_pixels(solver, cam, &world, &pixels)?;
            (s.solution, Some(s.inliers), Some(s.stats))
        }
    };
    let micros = start.elapsed().as_secs_f64() * 1e6;

    let (r_ref, t_ref) = img.pose();
    let r = solution.rotation;
    let t = solution.pose.translation.vector;
    let keep = mask.as_deref();
    Ok(Registration {
        image_id,
        name: img.name.clone(),
        n: world.len(),
        inliers: mask
            .as_ref()
            .map_or(solution.used, |m| m.iter().filter(|x| **x).count()),
        skipped: solution.skipped,
        ransac: stats,
        rotation_error_deg: crate::metrics::rotation_error_deg(&r, &r_ref),
        translation_error_pct: crate::metrics::translation_error_pct(&t, &t_ref),
        rmse_px: pixel_rmse(cam, &world, &pixels, keep, &r, &t),
        model_rmse_px: pixel_rmse(cam, &world, &pixels, keep, &r_ref, &t_ref),
        solution,
        micros,
    })
}
