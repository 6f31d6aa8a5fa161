//! The input of every solve: [`Problem`], world points and their observations.

use nalgebra::{Point2, Point3};

use crate::camera::Camera;
use crate::gravity::Gravity;
use crate::rig::Rig;

/// One pose problem: world points and their observations (normalised image points, observed
/// pixels through a camera, or pixels through the cameras of a [`Rig`]), with optional
/// per-point weights. Every entry point that
/// solves takes one: [`Solver::solve`](crate::Solver::solve),
/// [`Solver::solve_all`](crate::Solver::solve_all), [`Solver::refine`](crate::Solver::refine),
/// [`Ransac::estimate`](crate::ransac::Ransac::estimate) and the batch forms.
///
/// ```
/// use eopnp::camera::Camera;
/// use eopnp::{Problem, Solver};
/// use nalgebra::{Point2, Point3, Vector3};
///
/// let t = Vector3::new(0.1, -0.2, 6.0);
/// let world = [
///     Point3::new(-1.0, -1.0, 0.5), Point3::new(1.0, -1.0, -0.5), Point3::new(1.0, 1.0, 0.2),
///     Point3::new(-1.0, 1.0, -0.1), Point3::new(0.3, 0.2, 1.0), Point3::new(-0.4, 0.6, -0.8),
/// ];
/// let image: Vec<Point2<f64>> = world
///     .iter()
///     .map(|x| { let p = x.coords + t; Point2::new(p.x / p.z, p.y / p.z) })
///     .collect();
///
/// // Normalised image points (x/z, y/z).
/// let sol = Solver::default().solve(&Problem::normalised(&world, &image))?;
/// assert!((sol.translation - t).norm() < 1e-9);
///
/// // Observed pixels through a camera, with a weight per point.
/// let cam = Camera::pinhole(800.0, 800.0, 320.0, 240.0)?;
/// let pixels: Vec<Point2<f64>> = image.iter().map(|m| cam.project(*m)).collect();
/// let weights = [1.0, 1.0, 2.0, 1.0, 1.0, 0.5];
/// let sol = Solver::default().solve(&Problem::pixels(&world, &pixels, &cam).weights(&weights))?;
/// assert!((sol.translation - t).norm() < 1e-9);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Copy, Debug)]
pub struct Problem<'a> {
    pub(crate) world: &'a [Point3<f64>],
    pub(crate) observations: Observations<'a>,
    pub(crate) weights: Option<&'a [f64]>,
    pub(crate) gravity: Option<Gravity>,
    pub(crate) unknown_focal: Option<FocalRange>,
    pub(crate) refine_principal_point: bool,
    pub(crate) refine_distortion: bool,
}

/// Where an unknown focal length is sought ([`Problem::unknown_focal`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum FocalRange {
    /// Between these multiples of the camera's focal length.
    Relative(f64, f64),
    /// Between these focal lengths, pixels.
    Pixels(f64, f64),
}

impl FocalRange {
    /// The range as multiples of a camera whose (first) focal length is `f`, or
    /// `InvalidOption("unknown_focal")` unless `0 < lo < hi` are finite.
    pub(crate) fn scales(self, f: f64) -> Result<(f64, f64), crate::PnpError> {
        let (lo, hi) = match self {
            FocalRange::Relative(lo, hi) => (lo, hi),
            FocalRange::Pixels(lo, hi) => (lo / f, hi / f),
        };
        if lo > 0.0 && hi > lo && hi.is_finite() {
            Ok((lo, hi))
        } else {
            Err(crate::PnpError::InvalidOption {
                option: "unknown_focal",
            })
        }
    }
}

/// The observations of a [`Problem`].
#[derive(Clone, Copy, Debug)]
pub(crate) enum Observations<'a> {
    /// Normalised image points `(x/z, y/z)`, with the focal lengths `(fx, fy)` in pixels that
    /// make RANSAC's threshold a pixel distance (plain solves ignore them).
    Normalised {
        points: &'a [Point2<f64>],
        focal: (f64, f64),
    },
    /// Observed pixels and the camera that took them.
    Pixels {
        points: &'a [Point2<f64>],
        camera: &'a Camera,
    },
    /// Observed pixels, each in one camera of a rig.
    Rig {
        points: &'a [Point2<f64>],
        cameras: &'a [u32],
        rig: &'a Rig,
    },
}

impl<'a> Problem<'a> {
    /// World points and their normalised image points `(x/z, y/z)`: the camera's projection
    /// already undone. Residuals, costs and a robust loss's scale are then in normalised units
    /// (multiply by the focal length for pixels).
    #[must_use]
    pub fn normalised(world: &'a [Point3<f64>], image: &'a [Point2<f64>]) -> Self {
        Problem {
            world,
            observations: Observations::Normalised {
                points: image,
                focal: (1.0, 1.0),
            },
            weights: None,
            gravity: None,
            unknown_focal: None,
            refine_principal_point: false,
            refine_distortion: false,
        }
    }

    /// World points and the pixels where `camera` observed them (any supported model, lens
    /// distortion included). In the default mode the pose minimises the pixel error through
    /// the camera model; costs and a robust loss's scale are in pixels.
    #[must_use]
    pub fn pixels(world: &'a [Point3<f64>], pixels: &'a [Point2<f64>], camera: &'a Camera) -> Self {
        Problem {
            world,
            observations: Observations::Pixels {
                points: pixels,
                camera,
            },
            weights: None,
            gravity: None,
            unknown_focal: None,
            refine_principal_point: false,
            refine_distortion: false,
        }
    }

    /// World points and the pixels where the cameras of a multi-camera rig observed them:
    /// correspondence `i` was seen by camera `cameras[i]` of `rig`. The pose solved for is the
    /// rig's, `x_rig = R X + t` (see [`Rig`] for the cameras' poses in it); in the default mode
    /// it minimises the pixel error through each observation's camera model. A rig of one
    /// camera, or observations from one camera only, is the central problem of that camera.
    ///
    /// ```
    /// use eopnp::camera::Camera;
    /// use eopnp::{Problem, Rig, Solver};
    /// use nalgebra::{Isometry3, Point2, Point3, Translation3, UnitQuaternion, Vector3};
    ///
    /// // Two cameras looking left and right, 0.5 units apart.
    /// let cam = Camera::pinhole(600.0, 600.0, 320.0, 240.0)?;
    /// let left = Isometry3::from_parts(
    ///     Translation3::new(0.25, 0.0, 0.0),
    ///     UnitQuaternion::from_euler_angles(0.0, 0.6, 0.0),
    /// );
    /// let right = Isometry3::from_parts(
    ///     Translation3::new(-0.25, 0.0, 0.0),
    ///     UnitQuaternion::from_euler_angles(0.0, -0.6, 0.0),
    /// );
    /// let rig = Rig::new(vec![(cam.clone(), left), (cam, right)])?;
    /// // The rig's pose in the world, and points in front of each camera.
    /// let rig_from_world = Isometry3::from_parts(
    ///     Translation3::new(0.1, -0.2, 0.3),
    ///     UnitQuaternion::from_euler_angles(0.05, 0.1, -0.02),
    /// );
    /// let (mut world, mut pixels, mut which) = (Vec::new(), Vec::new(), Vec::new());
    /// for i in 0..12 {
    ///     let k = i % 2;
    ///     let p_cam = Point3::new((i % 3) as f64 - 1.0, (i % 4) as f64 * 0.4 - 0.6, 4.0 + (i % 5) as f64);
    ///     let cam_from_rig = rig.cam_from_rig()[k];
    ///     world.push(rig_from_world.inverse() * (cam_from_rig.inverse() * p_cam));
    ///     pixels.push(rig.cameras()[k].project(Point2::new(p_cam.x / p_cam.z, p_cam.y / p_cam.z)));
    ///     which.push(k as u32);
    /// }
    /// let sol = Solver::default().solve(&Problem::rig(&world, &pixels, &which, &rig))?;
    /// assert!((sol.translation - rig_from_world.translation.vector).norm() < 1e-9);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    #[must_use]
    pub fn rig(
        world: &'a [Point3<f64>],
        pixels: &'a [Point2<f64>],
        cameras: &'a [u32],
        rig: &'a Rig,
    ) -> Self {
        Problem {
            world,
            observations: Observations::Rig {
                points: pixels,
                cameras,
                rig,
            },
            weights: None,
            gravity: None,
            unknown_focal: None,
            refine_principal_point: false,
            refine_distortion: false,
        }
    }

    /// One non-negative weight per correspondence, scaling its squared residuals (a point of
    /// weight 0 is ignored: the result is exactly that of dropping it). Default: all 1.
    #[must_use]
    pub fn weights(mut self, weights: &'a [f64]) -> Self {
        self.weights = Some(weights);
        self
    }

    /// A known vertical (the direction of gravity measured by an IMU, [`Gravity`]): the solve
    /// returns the maximum a posteriori pose with it as a prior, RANSAC samples two points, and
    /// a vertical that the images contradict is [`crate::PnpError::GravityMismatch`].
    /// Default: none.
    #[must_use]
    pub fn gravity(mut self, gravity: Gravity) -> Self {
        self.gravity = Some(gravity);
        self
    }

    /// The camera's focal length is unknown (pixels through a camera only, [`Problem::pixels`]):
    /// it is estimated with the pose, between a tenth and ten times the camera's, which is the
    /// starting guess (square pixels: a camera's two focal lengths scaled alike; the principal
    /// point and the distortion as given, unless [`Problem::refine_principal_point`] or
    /// [`Problem::refine_distortion`]). The solution carries the estimated camera in
    /// [`Solution::camera`](crate::Solution::camera); the pose and focal length minimise the
    /// pixel error together (docs/algorithm.md, `refine_intrinsics`). Normalised or rig input,
    /// or a known vertical, with it is [`crate::PnpError::InvalidOption`] (`"unknown_focal"`).
    ///
    /// ```
    /// use eopnp::camera::Camera;
    /// use eopnp::{Problem, Solver};
    /// use nalgebra::{Point2, Point3, Vector3};
    ///
    /// let t = Vector3::new(0.1, -0.2, 6.0);
    /// let world: Vec<Point3<f64>> = (0..12)
    ///     .map(|i| Point3::new((i % 4) as f64 - 1.5, (i % 3) as f64 - 1.0, (i % 5) as f64 * 0.5 - 1.0))
    ///     .collect();
    /// let truth = Camera::pinhole(1200.0, 1200.0, 320.0, 240.0)?;
    /// let pixels: Vec<Point2<f64>> = world
    ///     .iter()
    ///     .map(|x| { let p = x.coords + t; truth.project(Point2::new(p.x / p.z, p.y / p.z)) })
    ///     .collect();
    /// // The camera as far as known: the focal length a guess, 800 px.
    /// let guess = Camera::pinhole(800.0, 800.0, 320.0, 240.0)?;
    /// let sol = Solver::default().solve(&Problem::pixels(&world, &pixels, &guess).unknown_focal())?;
    /// let (fx, _) = sol.camera.unwrap().focal_lengths();
    /// assert!((fx - 1200.0).abs() < 1e-6);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    #[must_use]
    pub fn unknown_focal(mut self) -> Self {
        self.unknown_focal = Some(FocalRange::Relative(0.1, 10.0));
        self
    }

    /// As [`Problem::unknown_focal`], the focal length sought between `min_px` and `max_px`
    /// (the camera's first focal length's range, which need not hold the guess: the solution
    /// is the least pixel error within it, on its bound if the minimum is outside; finite,
    /// `0 < min_px < max_px`, else
    /// [`crate::PnpError::InvalidOption`] (`"unknown_focal"`) at solve time).
    #[must_use]
    pub fn unknown_focal_within(mut self, min_px: f64, max_px: f64) -> Self {
        self.unknown_focal = Some(FocalRange::Pixels(min_px, max_px));
        self
    }

    /// The principal point is refined with the pose (and the focal length when unknown), the
    /// camera's the starting guess: pixels through a camera only (COLMAP's
    /// `refine_principal_point`). The estimate is well determined only by many points over a
    /// wide field of view; the solution carries it in
    /// [`Solution::camera`](crate::Solution::camera). Normalised or rig input, or a known
    /// vertical, with it is [`crate::PnpError::InvalidOption`] (`"refine_principal_point"`);
    /// fewer correspondences than the free parameters' half is
    /// [`crate::PnpError::TooFewPoints`].
    #[must_use]
    pub fn refine_principal_point(mut self) -> Self {
        self.refine_principal_point = true;
        self
    }

    /// The camera's distortion parameters (those after the principal point in
    /// [`Camera::params`](crate::camera::Camera::params); none for the pinhole models) are
    /// refined with the pose (and the focal length when unknown), the camera's the starting
    /// guess: pixels through a camera only (COLMAP's `refine_extra_params`). The solution
    /// carries them in [`Solution::camera`](crate::Solution::camera). Normalised or rig input,
    /// or a known vertical, with it is [`crate::PnpError::InvalidOption`]
    /// (`"refine_distortion"`); fewer correspondences than the free parameters' half is
    /// [`crate::PnpError::TooFewPoints`].
    #[must_use]
    pub fn refine_distortion(mut self) -> Self {
        self.refine_distortion = true;
        self
    }

    /// For normalised image points: the camera's focal lengths `(fx, fy)` in pixels, so that
    /// RANSAC's inlier threshold ([`Ransac::threshold_px`](crate::ransac::Ransac::threshold_px))
    /// is a pixel distance. Default `(1, 1)`: the threshold in normalised units. Plain solves do
    /// not use it; a pixel problem has its camera's and ignores this.
    #[must_use]
    pub fn focal(mut self, fx: f64, fy: f64) -> Self {
        if let Observations::Normalised { points, .. } = self.observations {
            self.observations = Observations::Normalised {
                points,
                focal: (fx, fy),
            };
        }
        self
    }
}
