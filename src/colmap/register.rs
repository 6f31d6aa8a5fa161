//! Registration: an image's pose re-estimated from its 2D-3D correspondences alone, compared
//! with the model's.

use std::time::Instant;

use nalgebra::{Matrix3, Point2, Point3, Vector3};

use super::model::{Model, RegisterError};
use crate::camera::Camera;
use crate::{Solution, Solver};

/// The result of [`register_image`].
#[derive(Clone, Debug)]
#[non_exhaustive]
pub struct Registration {
    /// Image id.
    pub image_id: u32,
    /// Image name.
    pub name: String,
    /// Number of 2D-3D correspondences used.
    pub n: usize,
    /// Correspondences counted as inliers (all of them in this non-robust mode).
    pub inliers: usize,
    /// Observations skipped because their pixel could not be undistorted.
    pub skipped: usize,
    /// The estimated pose.
    pub solution: Solution,
    /// Rotation difference to the model's pose, degrees (largest angle between corresponding
    /// columns, [`crate::metrics::rotation_error_deg`]).
    pub rotation_error_deg: f64,
    /// Translation difference to the model's pose, percent of the model's `|t|`
    /// ([`crate::metrics::translation_error_pct`]).
    pub translation_error_pct: f64,
    /// RMS reprojection error of the estimated pose in pixels, through the full camera model.
    pub rmse_px: f64,
    /// RMS reprojection error of the model's own pose in pixels, for comparison.
    pub model_rmse_px: f64,
    /// Wall time of undistortion plus solve, microseconds.
    pub micros: f64,
}

/// RMS pixel reprojection error of pose `(r, t)` through the full camera model.
fn pixel_rmse(
    cam: &Camera,
    world: &[Point3<f64>],
    pixels: &[Point2<f64>],
    r: &Matrix3<f64>,
    t: &Vector3<f64>,
) -> f64 {
    if world.is_empty() {
        return f64::NAN;
    }
    let mut s = 0.0;
    for (x, px) in world.iter().zip(pixels) {
        let p = r * x.coords + t;
        let q = cam.project(Point2::new(p.x / p.z, p.y / p.z));
        s += (q - px).norm_squared();
    }
    (s / world.len() as f64).sqrt()
}

/// Re-estimates the pose of image `image_id` from all its 2D-3D correspondences with `solver`
/// and compares it with the model's pose.
///
/// Solved with [`crate::camera::solve_pixels`]: the observed pixels are undistorted with the
/// image's camera and solved in normalised coordinates with per-point pixel-scale weights, so
/// the minimised error is, to first order, the pixel reprojection error that COLMAP's bundle
/// adjustment minimises. The time reported includes the undistortion.
///
/// # Errors
/// [`RegisterError`] for an unknown image or camera and for solver failures (e.g. fewer than
/// four correspondences).
pub fn register_image(
    model: &Model,
    image_id: u32,
    solver: &Solver,
) -> Result<Registration, RegisterError> {
    let (img, cam) = model.image_and_camera(image_id)?;
    let (world, pixels) = model.correspondences(image_id);

    let start = Instant::now();
    let sol = solver.solve_camera(cam, &world, &pixels)?;
    let micros = start.elapsed().as_secs_f64() * 1e6;
    let solution = sol.solution;

    let (r_ref, t_ref) = img.pose();
    let r = solution.rotation;
    let t = solution.pose.translation.vector;
    Ok(Registration {
        image_id,
        name: img.name.clone(),
        n: sol.used,
        inliers: sol.used,
        skipped: sol.skipped,
        rotation_error_deg: crate::metrics::rotation_error_deg(&r, &r_ref),
        translation_error_pct: crate::metrics::translation_error_pct(&t, &t_ref),
        rmse_px: pixel_rmse(cam, &world, &pixels, &r, &t),
        model_rmse_px: pixel_rmse(cam, &world, &pixels, &r_ref, &t_ref),
        solution,
        micros,
    })
}
