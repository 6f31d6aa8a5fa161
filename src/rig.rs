//! Multi-camera rigs: cameras fixed to one body, each with its pose in the rig.

use nalgebra::{Isometry3, Matrix3, Point3, Vector3};

use crate::camera::{Camera, Projector};
use crate::error::PnpError;

/// A rig of calibrated cameras fixed relative to each other (a car's or a headset's cameras, a
/// stereo pair): each camera with its pose in the rig, `cam_from_rig` (`x_cam = R_k x_rig +
/// t_k`, the convention of COLMAP's rigs and pycolmap's `cams_from_rig`). A problem on a rig
/// ([`crate::Problem::rig`]) has each observation in one of the rig's cameras, and its
/// [`crate::Solution`] is the rig's pose in the world, `x_rig = R X + t`; camera `k`'s pose is
/// then `x_cam = R_k (R X + t) + t_k`.
///
/// ```
/// use eopnp::camera::Camera;
/// use eopnp::Rig;
/// use nalgebra::{Isometry3, Translation3, UnitQuaternion};
///
/// // A stereo pair: the left camera is the rig's frame, the right one 0.12 units to its right
/// // (so a point of the rig at x = 0.12 is at x = 0 in the right camera).
/// let cam = Camera::pinhole(800.0, 800.0, 320.0, 240.0)?;
/// let left = Isometry3::identity();
/// let right = Isometry3::from_parts(Translation3::new(-0.12, 0.0, 0.0), UnitQuaternion::identity());
/// let rig = Rig::new(vec![(cam.clone(), left), (cam, right)])?;
/// assert_eq!(rig.cameras().len(), 2);
/// assert!((rig.centre(1) - nalgebra::Point3::new(0.12, 0.0, 0.0)).norm() < 1e-15);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug)]
pub struct Rig {
    cameras: Vec<Camera>,
    cam_from_rig: Vec<Isometry3<f64>>,
    /// Each camera's rotation `R_k` as a matrix.
    rotations: Vec<Matrix3<f64>>,
    /// Each camera's projection, formed once (every solve reads it).
    projectors: Vec<Projector>,
}

/// Two rigs are equal when their cameras and poses are (the rest is formed from them).
impl PartialEq for Rig {
    fn eq(&self, other: &Rig) -> bool {
        self.cameras == other.cameras && self.cam_from_rig == other.cam_from_rig
    }
}

impl Rig {
    /// A rig of cameras, each with its pose in the rig (`x_cam = R_k x_rig + t_k`).
    ///
    /// # Errors
    /// [`PnpError::InvalidOption`] (`"rig"`) for a rig without cameras, (`"cam_from_rig"`) for
    /// a pose that is not finite.
    pub fn new(cameras: Vec<(Camera, Isometry3<f64>)>) -> Result<Rig, PnpError> {
        if cameras.is_empty() {
            return Err(PnpError::InvalidOption { option: "rig" });
        }
        let finite = |p: &Isometry3<f64>| {
            p.translation.vector.iter().all(|v| v.is_finite())
                && p.rotation.coords.iter().all(|v| v.is_finite())
        };
        if !cameras.iter().all(|(_, p)| finite(p)) {
            return Err(PnpError::InvalidOption {
                option: "cam_from_rig",
            });
        }
        let rotations = cameras
            .iter()
            .map(|(_, p)| p.rotation.to_rotation_matrix().into_inner())
            .collect();
        let (cameras, cam_from_rig): (Vec<Camera>, _) = cameras.into_iter().unzip();
        let projectors = cameras.iter().map(Camera::projector).collect();
        Ok(Rig {
            cameras,
            cam_from_rig,
            rotations,
            projectors,
        })
    }

    /// The cameras, in index order.
    #[must_use]
    pub fn cameras(&self) -> &[Camera] {
        &self.cameras
    }

    /// Each camera's pose in the rig, `x_cam = R_k x_rig + t_k`, in index order.
    #[must_use]
    pub fn cam_from_rig(&self) -> &[Isometry3<f64>] {
        &self.cam_from_rig
    }

    /// The centre of camera `k` in the rig frame, `-R_k^T t_k`.
    ///
    /// # Panics
    /// If `k` is not a camera of the rig.
    #[must_use]
    pub fn centre(&self, k: usize) -> Point3<f64> {
        Point3::from(-(self.rotations[k].transpose() * self.cam_from_rig[k].translation.vector))
    }

    /// Camera `k`'s projection.
    pub(crate) fn projector(&self, k: usize) -> &Projector {
        &self.projectors[k]
    }

    /// Camera `k`'s rotation `R_k` and translation `t_k`.
    pub(crate) fn pose(&self, k: usize) -> (&Matrix3<f64>, &Vector3<f64>) {
        (&self.rotations[k], &self.cam_from_rig[k].translation.vector)
    }
}
