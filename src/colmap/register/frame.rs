//! Registration of a frame: the pose of a rig re-estimated from the 2D-3D correspondences of all
//! the frame's images at once ([`Problem::rig`]), compared with the model's `rig_from_world`.

use std::ops::Range;
use std::time::Instant;

use nalgebra::{Isometry3, Matrix3, Vector3};

use super::{emptied_with_room, pixel_squares, Registrar};
use crate::camera::Camera;
use crate::colmap::model::{Image, Model, RegisterError};
use crate::colmap::rigs::{Frame, SensorId};
use crate::ransac::{Ransac, RansacStats};
use crate::{Problem, Rig, Solution, Solver};

/// The result of [`register_frame`]: a frame's rig pose, as [`super::Registration`] is an
/// image's camera pose.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Clone, Debug)]
#[non_exhaustive]
pub struct FrameRegistration {
    /// Frame id.
    pub frame_id: u32,
    /// The frame's rig.
    pub rig_id: u32,
    /// The frame's images, in the order of its data ids: camera `k` of the problem's rig is
    /// image `image_ids[k]`'s camera.
    pub image_ids: Vec<u32>,
    /// Number of 2D-3D correspondences of the frame's images (observations with a 3D point).
    pub n: usize,
    /// Correspondences the pose was fitted to: all that could be undistorted, or RANSAC's
    /// inliers.
    pub inliers: usize,
    /// Observations skipped because their pixel could not be undistorted.
    pub skipped: usize,
    /// The estimated pose of the rig, `x_rig = R X + t` (`rig_from_world`); image `k`'s camera
    /// pose is its `sensor_from_rig` composed with it.
    pub solution: Solution,
    /// RANSAC's statistics, when registered with RANSAC.
    pub ransac: Option<RansacStats>,
    /// Rotation difference to the model's `rig_from_world`, degrees (as
    /// [`super::Registration::rotation_error_deg`]).
    pub rotation_error_deg: f64,
    /// Translation difference to the model's `rig_from_world`, percent of its `|t|`.
    pub translation_error_pct: f64,
    /// RMS reprojection error of the estimated pose in pixels, each correspondence through its
    /// own camera (full camera model, the camera's pose in the rig composed with the rig's),
    /// over the correspondences it was fitted to.
    pub rmse_px: f64,
    /// RMS reprojection error of the model's frame pose in pixels over the same
    /// correspondences, for comparison.
    pub model_rmse_px: f64,
    /// Wall time of undistortion plus solve (or RANSAC), microseconds.
    pub micros: f64,
}

/// A frame's images, each with its camera and the camera's pose in the rig.
struct FrameImages<'m> {
    images: Vec<&'m Image>,
    cameras: Vec<(Camera, Isometry3<f64>)>,
}

/// The images of `frame`, their cameras and the cameras' poses in the frame's rig.
fn frame_images<'m>(model: &'m Model, frame: &Frame) -> Result<FrameImages<'m>, RegisterError> {
    let rig = model
        .rigs
        .get(&frame.rig_id)
        .ok_or(RegisterError::UnknownRig(frame.rig_id))?;
    let mut out = FrameImages {
        images: Vec::new(),
        cameras: Vec::new(),
    };
    for id in frame.image_ids() {
        let (img, cam) = model.image_and_camera(id)?;
        let pose = rig.sensor_from_rig(SensorId::camera(img.camera_id)).ok_or(
            RegisterError::NoSensorPose {
                rig_id: rig.id,
                camera_id: img.camera_id,
            },
        )?;
        out.images.push(img);
        out.cameras.push((*cam, pose.isometry()));
    }
    if out.images.is_empty() {
        return Err(RegisterError::EmptyFrame(frame.id));
    }
    Ok(out)
}

impl Registrar<'_> {
    /// Re-estimates the pose of frame `frame_id`'s rig and compares it with the model's: as
    /// [`register_frame`].
    ///
    /// # Errors
    /// As [`register_frame`].
    pub fn register_frame(
        &mut self,
        frame_id: u32,
        solver: &Solver,
        ransac: Option<&Ransac>,
    ) -> Result<FrameRegistration, RegisterError> {
        let model = self.model;
        let frame = model
            .frames
            .get(&frame_id)
            .ok_or(RegisterError::UnknownFrame(frame_id))?;
        let FrameImages { images, cameras } = frame_images(model, frame)?;
        let rig = Rig::new(cameras)?;

        // The correspondences image by image, each with its camera's index in the rig.
        let total: usize = images.iter().map(|img| img.points2d.len()).sum();
        emptied_with_room(&mut self.world, total);
        emptied_with_room(&mut self.pixels, total);
        emptied_with_room(&mut self.which, total);
        let mut ranges: Vec<Range<usize>> = Vec::with_capacity(images.len());
        for (k, img) in images.iter().enumerate() {
            let start = self.world.len();
            self.points.gather(img, &mut self.world, &mut self.pixels);
            let end = self.world.len();
            self.which.resize(end, k as u32);
            ranges.push(start..end);
        }
        let (world, pixels, which) = (&self.world[..], &self.pixels[..], &self.which[..]);

        let start = Instant::now();
        let problem = Problem::rig(world, pixels, which, &rig);
        let (solution, mask, stats) = match ransac {
            None => (solver.solve(&problem)?, None, None),
            Some(r) => {
                let s = r.estimate(solver, &problem)?;
                (s.solution, Some(s.inliers), Some(s.stats))
            }
        };
        let micros = start.elapsed().as_secs_f64() * 1e6;

        let rmse = |r: &Matrix3<f64>, t: &Vector3<f64>| {
            let (mut sum, mut count) = (0.0, 0usize);
            for (k, range) in ranges.iter().enumerate() {
                let (rk, tk) = rig.pose(k);
                let keep = mask.as_deref().map(|m| &m[range.clone()]);
                let (s, c) = pixel_squares(
                    &rig.cameras()[k],
                    &world[range.clone()],
                    &pixels[range.clone()],
                    keep,
                    &(rk * r),
                    &(rk * t + tk),
                );
                sum += s;
                count += c;
            }
            if count == 0 {
                f64::NAN
            } else {
                (sum / count as f64).sqrt()
            }
        };
        let reference = &frame.rig_from_world;
        let (r_ref, t_ref) = (reference.rotation(), reference.t);
        let (r, t) = (solution.rotation, solution.translation);
        Ok(FrameRegistration {
            frame_id,
            rig_id: frame.rig_id,
            image_ids: images.iter().map(|img| img.id).collect(),
            n: world.len(),
            inliers: mask
                .as_ref()
                .map_or(solution.used, |m| m.iter().filter(|x| **x).count()),
            skipped: solution.skipped,
            ransac: stats,
            rotation_error_deg: crate::numeric::rotation::rotation_error_deg(&r, &r_ref),
            translation_error_pct: crate::numeric::rotation::translation_error_pct(&t, &t_ref),
            rmse_px: rmse(&r, &t),
            model_rmse_px: rmse(&r_ref, &t_ref),
            solution,
            micros,
        })
    }
}

/// Re-estimates the pose of frame `frame_id`'s rig from the 2D-3D correspondences of all its
/// images and compares it with the model's `rig_from_world`: the frame's images become the
/// cameras of a [`Rig`] (each camera with its `sensor_from_rig` pose from the model's rig, the
/// reference camera at the identity), and every image's correspondences observations of its
/// camera ([`Problem::rig`]); with `ransac = None` solved by `solver` on all correspondences
/// (in the default mode the pose minimises the pixel reprojection error of every observation
/// through its own camera, distortion included), or robustly by [`Ransac::estimate`]. The
/// time reported includes the undistortion. For several frames of one model, a [`Registrar`]
/// builds the table of the model's 3D points once.
///
/// ```
/// use eopnp::camera::Camera;
/// use eopnp::colmap::{
///     register_frame, DataId, Frame, Image, Model, Point3D, Pose, SensorId, SensorRig,
/// };
/// use eopnp::Solver;
/// use nalgebra::{Isometry3, Point2, Point3, Translation3, UnitQuaternion};
///
/// // A stereo rig: camera 1 is the reference (the rig's frame), camera 2 sits 0.2 units to
/// // its right; one frame, whose two images see twelve 3D points.
/// let right = Isometry3::from_parts(
///     Translation3::new(-0.2, 0.0, 0.0),
///     UnitQuaternion::identity(),
/// );
/// let rig_from_world = Isometry3::from_parts(
///     Translation3::new(0.1, -0.2, 6.0),
///     UnitQuaternion::from_euler_angles(0.1, -0.2, 0.3),
/// );
/// let mut model = Model::default();
/// let points: Vec<Point3<f64>> = (0..12u32)
///     .map(|i| {
///         let i = f64::from(i);
///         Point3::new(i % 3.0 - 1.0, (i % 4.0) * 0.5 - 0.7, (i % 5.0) * 0.3)
///     })
///     .collect();
/// for (k, xyz) in points.iter().enumerate() {
///     let id = k as u64 + 1;
///     model.points.insert(id, Point3D { id, xyz: *xyz, rgb: [0; 3], error: 0.0, track: vec![] });
/// }
/// for (id, cam_from_rig) in [(1, Isometry3::identity()), (2, right)] {
///     model.cameras.insert(id, Camera::pinhole(800.0, 800.0, 320.0, 240.0)?);
///     let pose = cam_from_rig * rig_from_world;
///     let points2d = points
///         .iter()
///         .enumerate()
///         .map(|(k, x)| {
///             let p = pose * x;
///             let pixel = Point2::new(800.0 * p.x / p.z + 320.0, 800.0 * p.y / p.z + 240.0);
///             (pixel, Some(k as u64 + 1))
///         })
///         .collect();
///     let Pose { q, t } = Pose::from_isometry(&pose);
///     let name = format!("cam{id}.png");
///     model.images.insert(id, Image { id, q, t, camera_id: id, name, points2d });
/// }
/// let (cam1, cam2) = (SensorId::camera(1), SensorId::camera(2));
/// model.rigs.insert(1, SensorRig {
///     id: 1,
///     ref_sensor: Some(cam1),
///     sensors: vec![(cam2, Some(Pose::from_isometry(&right)))],
/// });
/// model.frames.insert(1, Frame {
///     id: 1,
///     rig_id: 1,
///     rig_from_world: Pose::from_isometry(&rig_from_world),
///     data_ids: vec![DataId { sensor: cam1, id: 1 }, DataId { sensor: cam2, id: 2 }],
/// });
///
/// let reg = register_frame(&model, 1, &Solver::default(), None)?;
/// assert_eq!((reg.image_ids.as_slice(), reg.n), (&[1, 2][..], 24));
/// assert!(reg.rotation_error_deg < 1e-9 && reg.rmse_px < 1e-6);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// [`RegisterError`] for an unknown frame, rig, image or camera, a camera without a known
/// pose in the rig, a frame without images, and for solver failures (e.g. too few
/// correspondences, or no consensus).
pub fn register_frame(
    model: &Model,
    frame_id: u32,
    solver: &Solver,
    ransac: Option<&Ransac>,
) -> Result<FrameRegistration, RegisterError> {
    Registrar::with_table(model, false).register_frame(frame_id, solver, ransac)
}
