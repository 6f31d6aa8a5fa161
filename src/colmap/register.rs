//! Registration: an image's pose re-estimated from its 2D-3D correspondences alone, plain or
//! robust, and compared with the model's; a frame's rig pose in `register/frame.rs`.

use core::ops::ControlFlow;
use std::time::Instant;

use nalgebra::{Matrix3, Point2, Point3, Vector3};

use super::model::{Image, Model, PointLookup, RegisterError};
use crate::camera::{Camera, Project, ProjectionJob};
use crate::numeric::lanes::{dispatched, lane_sum, unweighted_blocks, Block, LANES};
use crate::ransac::{Ransac, RansacStats};
use crate::{Problem, Refinement, Solution, Solver};

mod frame;

pub use frame::{register_frame, FrameRegistration};

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
    /// columns, each as `atan2(|a x b|, a . b)`: the paper's metric).
    pub rotation_error_deg: f64,
    /// Translation difference to the model's pose, percent of the model's `|t|`
    /// (`100 |t - t_model| / |t_model|`).
    pub translation_error_pct: f64,
    /// RMS reprojection error of the estimated pose in pixels, through the full camera model
    /// (the estimated camera with free intrinsics), over the correspondences it was fitted to.
    pub rmse_px: f64,
    /// RMS reprojection error of the model's own pose in pixels over the same correspondences,
    /// for comparison.
    pub model_rmse_px: f64,
    /// With free intrinsics (an unknown focal length through [`Registrar::register_with`]):
    /// the estimated focal length's error against the model camera's, percent (the larger of
    /// the two axes' `100 |f - f_model| / f_model`); `None` through the model's camera.
    pub focal_error_pct: Option<f64>,
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
    let (sum, count) = pixel_squares(cam, world, pixels, keep, r, t);
    if count == 0 {
        f64::NAN
    } else {
        (sum / count as f64).sqrt()
    }
}

/// [`pixel_rmse`]'s sum of squared pixel residuals and their number.
fn pixel_squares(
    cam: &Camera,
    world: &[Point3<f64>],
    pixels: &[Point2<f64>],
    keep: Option<&[bool]>,
    r: &Matrix3<f64>,
    t: &Vector3<f64>,
) -> (f64, usize) {
    // The camera unpacked and its model dispatched once, not per point.
    cam.projector().with_projection(Rmse {
        world,
        pixels,
        keep,
        r,
        t,
    })
}

/// [`pixel_rmse`]'s pass, for one lens model: the sum of the squared pixel residuals and their
/// number.
struct Rmse<'a> {
    world: &'a [Point3<f64>],
    pixels: &'a [Point2<f64>],
    keep: Option<&'a [bool]>,
    r: &'a Matrix3<f64>,
    t: &'a Vector3<f64>,
}

impl ProjectionJob for Rmse<'_> {
    type Output = (f64, usize);

    fn run<P: Project + Copy>(self, projection: P) -> (f64, usize) {
        let pose = ((*self.r).into(), (*self.t).into());
        match self.keep {
            None => squared_residuals::<P, false>(&projection, &pose, self.world, self.pixels, &[]),
            Some(k) => squared_residuals::<P, true>(&projection, &pose, self.world, self.pixels, k),
        }
    }
}

dispatched! {
    /// The sum of the squared pixel residuals of the correspondences (those with `keep[i]`
    /// when `KEEP`) under the pose `(r, t)` (`r` column-major: `r[j]` is column `j`), and their
    /// number. Lane `l` sums the points `l, l + LANES, ...`. Built for the processor
    /// ([`crate::numeric::lanes::dispatched`]).
    fn squared_residuals[P: Project, const KEEP: bool][P, KEEP](
        projection: &P,
        pose: &([[f64; 3]; 3], [f64; 3]),
        world: &[Point3<f64>],
        pixels: &[Point2<f64>],
        keep: &[bool],
    ) -> (f64, usize) = squared_residuals_body;
}

#[inline(always)]
fn squared_residuals_body<P: Project, const KEEP: bool>(
    projection: &P,
    pose: &([[f64; 3]; 3], [f64; 3]),
    world: &[Point3<f64>],
    pixels: &[Point2<f64>],
    keep: &[bool],
) -> (f64, usize) {
    let (r, t) = pose;
    let (mut sum, mut count) = ([0.0; LANES], [0usize; LANES]);
    // Lane l of a block that starts at point `start`, gathered by `unweighted_blocks` (the
    // points transposed, so that the lanes run as one packed computation).
    let mut lane = |blk: &Block, start: usize, l: usize| {
        let x = [blk.x[0][l], blk.x[1][l], blk.x[2][l]];
        let p = |j: usize| r[0][j] * x[0] + r[1][j] * x[1] + r[2][j] * x[2] + t[j];
        let (px, py, pz) = (p(0), p(1), p(2));
        let (u, v) = projection.project(px / pz, py / pz);
        let (ex, ey) = (u - blk.m[0][l], v - blk.m[1][l]);
        let e = ex * ex + ey * ey;
        // A select, so that a point at depth 0 outside the selection cannot poison the sum.
        let kept = !KEEP || keep.get(start + l).copied().unwrap_or(false);
        sum[l] += if kept { e } else { 0.0 };
        count[l] += usize::from(kept);
    };
    let mut start = 0;
    let rest = unweighted_blocks(world, pixels, |blk| {
        for l in 0..LANES {
            lane(blk, start, l);
        }
        start += LANES;
        ControlFlow::<()>::Continue(())
    });
    if let ControlFlow::Continue((blk, filled)) = rest {
        for l in 0..filled {
            lane(&blk, start, l);
        }
    }
    (lane_sum(&sum), count.iter().sum())
}

/// Registers images of one model ([`Registrar::register`]), or frames of a model with rigs
/// ([`Registrar::register_frame`]): the model's 3D points are looked up in a table indexed by
/// id, built once, and each image's correspondences are gathered into buffers that keep
/// their capacity from image to image. [`register_image`] and [`register_frame`] are one
/// image or frame with a registrar of its own.
///
/// See the [module documentation](super) for a runnable example.
#[derive(Debug)]
pub struct Registrar<'m> {
    model: &'m Model,
    points: PointLookup<'m>,
    world: Vec<Point3<f64>>,
    pixels: Vec<Point2<f64>>,
    /// Each correspondence's camera in a frame's rig ([`Registrar::register_frame`]).
    which: Vec<u32>,
}

impl<'m> Registrar<'m> {
    /// A registrar for `model`: one walk of its 3D points into a table of their coordinates
    /// indexed by id (when the largest id is at most four times their number, as in COLMAP's
    /// numbering from 1; otherwise the points are looked up in [`Model::points`]).
    #[must_use]
    pub fn new(model: &'m Model) -> Self {
        Self::with_table(model, true)
    }

    /// A registrar whose table serves many images (`many`: coordinates) or one (references,
    /// see [`PointLookup`]).
    fn with_table(model: &'m Model, many: bool) -> Self {
        Registrar {
            model,
            points: PointLookup::new(model, 4 * model.points.len(), many),
            world: Vec::new(),
            pixels: Vec::new(),
            which: Vec::new(),
        }
    }

    /// The correspondences of `img` into the buffers: their capacity, kept from image to image,
    /// made room for every observation (the pages of what is not written are not touched), so
    /// that they do not grow point by point.
    fn gather(&mut self, img: &Image) {
        emptied_with_room(&mut self.world, img.points2d.len());
        emptied_with_room(&mut self.pixels, img.points2d.len());
        self.points.gather(img, &mut self.world, &mut self.pixels);
    }

    /// Re-estimates the pose of image `image_id` and compares it with the model's: as
    /// [`register_image`].
    ///
    /// # Errors
    /// As [`register_image`].
    pub fn register(
        &mut self,
        image_id: u32,
        solver: &Solver,
        ransac: Option<&Ransac>,
    ) -> Result<Registration, RegisterError> {
        self.register_with(image_id, solver, ransac, |p| p)
    }

    /// Re-estimates the pose of image `image_id` as [`Registrar::register`] does, on the
    /// problem that `problem` makes of the image's ([`Problem::pixels`] through its camera)
    /// with any option a [`Problem`] takes. `|p| p.unknown_focal()` re-estimates the image's
    /// focal length with its pose (the model's camera the starting guess, as in COLMAP;
    /// [`Registration::focal_error_pct`] its error against the model's); others are
    /// [`Problem::refine_distortion`], a known vertical ([`Problem::gravity`]) or weights (one
    /// per correspondence, in the order of the image's 2D points that have a 3D point).
    ///
    /// ```
    /// use eopnp::colmap::{read_model, ReadOptions, Registrar};
    /// use eopnp::Solver;
    ///
    /// # let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("data/colmap-boxes");
    /// let model = read_model(&dir, &ReadOptions::default())?;
    /// let mut registrar = Registrar::new(&model);
    /// for id in model.images.keys() {
    ///     let reg = registrar.register_with(*id, &Solver::default(), None, |p| p.unknown_focal())?;
    ///     assert!(reg.focal_error_pct.unwrap() < 0.01 && reg.rotation_error_deg < 0.01);
    /// }
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    ///
    /// # Errors
    /// As [`register_image`], and the solver's errors for the options (e.g.
    /// [`crate::PnpError::InvalidOption`]).
    pub fn register_with(
        &mut self,
        image_id: u32,
        solver: &Solver,
        ransac: Option<&Ransac>,
        problem: impl for<'p> FnOnce(Problem<'p>) -> Problem<'p>,
    ) -> Result<Registration, RegisterError> {
        let (img, cam) = self.model.image_and_camera(image_id)?;
        self.gather(img);
        let (world, pixels) = (&self.world[..], &self.pixels[..]);

        let start = Instant::now();
        let problem = problem(Problem::pixels(world, pixels, cam));
        let (solution, mask, stats) = match ransac {
            None => (solver.solve(&problem)?, None, None),
            Some(r) => {
                let s = r.estimate(solver, &problem)?;
                (s.solution, Some(s.inliers), Some(s.stats))
            }
        };
        let micros = start.elapsed().as_secs_f64() * 1e6;

        let (r_ref, t_ref) = img.pose();
        let r = solution.rotation;
        let t = solution.translation;
        let keep = mask.as_deref();
        // The estimate's RMS pixel error: in the default mode, on every correspondence, the
        // solution reports it (`refine`'s or `refine_pixels`' last pass, through the camera:
        // `reprojection_rmse` is it divided by `max(fx, fy)`); otherwise (RANSAC's inliers, pixels
        // left out, the algebraic mode's first-order error) one pass of its own.
        // The camera the pose was estimated through: the model's, or with free intrinsics the
        // estimate.
        let estimated = solution.camera.as_ref().unwrap_or(cam);
        let (fx, fy) = estimated.focal_lengths();
        let rmse_px = if ransac.is_none()
            && solution.skipped == 0
            && solver.minimises() == Refinement::Reprojection
        {
            solution.reprojection_rmse * fx.max(fy)
        } else {
            pixel_rmse(estimated, world, pixels, keep, &r, &t)
        };
        let focal_error_pct = solution.camera.map(|c| focal_error_pct(&c, cam));
        Ok(Registration {
            image_id,
            name: img.name.clone(),
            n: world.len(),
            inliers: mask
                .as_ref()
                .map_or(solution.used, |m| m.iter().filter(|x| **x).count()),
            skipped: solution.skipped,
            ransac: stats,
            rotation_error_deg: crate::numeric::rotation::rotation_error_deg(&r, &r_ref),
            translation_error_pct: crate::numeric::rotation::translation_error_pct(&t, &t_ref),
            rmse_px,
            model_rmse_px: pixel_rmse(cam, world, pixels, keep, &r_ref, &t_ref),
            focal_error_pct,
            solution,
            micros,
        })
    }
}

/// The larger of the two axes' relative focal length errors of `estimated` against `model`,
/// percent.
pub(crate) fn focal_error_pct(estimated: &Camera, model: &Camera) -> f64 {
    let ((ex, ey), (mx, my)) = (estimated.focal_lengths(), model.focal_lengths());
    let error = |e: f64, m: f64| 100.0 * (e - m).abs() / m;
    error(ex, mx).max(error(ey, my))
}

/// `buffer` emptied, with room for `n` elements: a larger one allocated afresh when needed
/// (`reserve` on the emptied vector would copy its old contents over).
fn emptied_with_room<T>(buffer: &mut Vec<T>, n: usize) {
    buffer.clear();
    if buffer.capacity() < n {
        *buffer = Vec::with_capacity(n);
    }
}

/// Re-estimates the pose of image `image_id` from its 2D-3D correspondences and compares it
/// with the model's pose: with `ransac = None` by `solver` on all correspondences
/// ([`Solver::solve`] of [`Problem::pixels`]: in the default mode the pose minimises the pixel
/// reprojection error through the image's camera, distortion included, the error that
/// COLMAP's bundle adjustment minimises), or robustly by [`Ransac::estimate`] with `solver`
/// for the local optimisation and the final fit. The time reported includes the undistortion. For
/// several images of one model, a [`Registrar`] builds the table of the model's 3D points once
/// instead of once per call.
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
    Registrar::with_table(model, false).register(image_id, solver, ransac)
}

/// [`register_image`] of the problem that `problem` makes of the image's, as
/// [`Registrar::register_with`] (for one image): `|p| p.unknown_focal()` re-estimates the
/// focal length with the pose.
///
/// # Errors
/// As [`Registrar::register_with`].
pub fn register_image_with(
    model: &Model,
    image_id: u32,
    solver: &Solver,
    ransac: Option<&Ransac>,
    problem: impl for<'p> FnOnce(Problem<'p>) -> Problem<'p>,
) -> Result<Registration, RegisterError> {
    Registrar::with_table(model, false).register_with(image_id, solver, ransac, problem)
}
