//! A known vertical: the direction of gravity measured in the camera's frame (an IMU) and known
//! in the world's ([`Gravity`], given to a solve by [`crate::Problem::gravity`]).

use nalgebra::Vector3;

use crate::error::PnpError;

/// The direction of gravity (or any direction known in both frames) measured in the camera's
/// frame and known in the world's, with the measurement's uncertainty. For a rig problem
/// ([`crate::Problem::rig`]) the camera's frame is the rig's.
///
/// With it, a solve returns the maximum a posteriori pose: the reprojection error plus the
/// vertical as a prior, `|R g_world - g_camera|^2 / sigma^2` in units of the image noise's
/// variance (estimated from the residuals of the unconstrained maximum-likelihood pose), and
/// RANSAC ([`crate::ransac::Ransac::estimate`]) draws samples of two points solved by the
/// upright two-point pose. When the images and the measured vertical disagree by more than
/// their combined uncertainties allow, the solve is [`PnpError::GravityMismatch`] rather than a
/// pose bent towards a wrong vertical (docs/algorithm.md, `vertical`).
///
/// ```
/// use eopnp::{Gravity, Problem, Solver};
/// use nalgebra::{Point2, Point3, Rotation3, Vector3};
///
/// let r = Rotation3::from_euler_angles(0.1, -0.2, 0.3);
/// let t = Vector3::new(0.1, -0.2, 6.0);
/// let world = [
///     Point3::new(-1.0, -1.0, 0.5), Point3::new(1.0, -1.0, -0.5), Point3::new(1.0, 1.0, 0.2),
///     Point3::new(-1.0, 1.0, -0.1), Point3::new(0.3, 0.2, 1.0), Point3::new(-0.4, 0.6, -0.8),
/// ];
/// let image: Vec<Point2<f64>> = world
///     .iter()
///     .map(|x| { let p = r * x + t; Point2::new(p.x / p.z, p.y / p.z) })
///     .collect();
/// // The world's z axis points up; an IMU measures gravity in the camera's frame.
/// let down_world = Vector3::new(0.0, 0.0, -1.0);
/// let down_camera = r * down_world;
/// let gravity = Gravity::new(down_camera, down_world, 0.1)?;
/// let sol = Solver::default().solve(&Problem::normalised(&world, &image).gravity(gravity))?;
/// assert!((sol.translation - t).norm() < 1e-9);
/// # Ok::<(), eopnp::PnpError>(())
/// ```
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gravity {
    in_camera: Vector3<f64>,
    in_world: Vector3<f64>,
    sigma_deg: f64,
}

impl Gravity {
    /// The direction `in_camera` measured in the camera's (rig's) frame, the same direction
    /// `in_world` in the world's frame (any non-zero lengths: both are normalised; "down" in
    /// both, or "up" in both), and `sigma_deg`, the standard deviation in degrees of the
    /// measured direction's angle about each of the two axes across it (an IMU's tilt
    /// accuracy, e.g. 0.1 to 1 degree).
    ///
    /// # Errors
    /// [`PnpError::InvalidOption`] (`"gravity"`) if a direction is zero or not finite, or
    /// `sigma_deg` is not finite and positive.
    pub fn new(
        in_camera: Vector3<f64>,
        in_world: Vector3<f64>,
        sigma_deg: f64,
    ) -> Result<Self, PnpError> {
        // A direction of length 1 to rounding is kept as it is (so that the unit vectors of a
        // `Gravity` give the same `Gravity` again), any other is divided by its length.
        let unit = |v: Vector3<f64>| {
            let n = v.norm();
            (n > 0.0 && n.is_finite()).then(|| {
                if (n - 1.0).abs() <= 4.0 * f64::EPSILON {
                    v
                } else {
                    v / n
                }
            })
        };
        let invalid = PnpError::InvalidOption { option: "gravity" };
        if !(sigma_deg > 0.0 && sigma_deg.is_finite()) {
            return Err(invalid);
        }
        match (unit(in_camera), unit(in_world)) {
            (Some(in_camera), Some(in_world)) => Ok(Gravity {
                in_camera,
                in_world,
                sigma_deg,
            }),
            _ => Err(invalid),
        }
    }

    /// The measured direction in the camera's (rig's) frame, unit length.
    #[must_use]
    pub fn in_camera(&self) -> Vector3<f64> {
        self.in_camera
    }

    /// The direction in the world's frame, unit length.
    #[must_use]
    pub fn in_world(&self) -> Vector3<f64> {
        self.in_world
    }

    /// The measurement's standard deviation, in degrees.
    #[must_use]
    pub fn sigma_deg(&self) -> f64 {
        self.sigma_deg
    }

    /// The same direction in the frame of a rig's camera whose rotation in the rig is `rk`:
    /// `g_cam = R_k g_rig`.
    pub(crate) fn rotated(&self, rk: &nalgebra::Matrix3<f64>) -> Gravity {
        Gravity {
            in_camera: (rk * self.in_camera).normalize(),
            ..*self
        }
    }
}
