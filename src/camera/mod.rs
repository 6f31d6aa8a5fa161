//! COLMAP camera models: projection of normalised image points to pixels and iterative
//! undistortion of pixels back to normalised image points.
//!
//! ```
//! use eopnp::camera::Camera;
//! use nalgebra::Point2;
//!
//! // The bundled model's camera: SIMPLE_RADIAL f, cx, cy, k.
//! let cam = Camera::from_colmap("SIMPLE_RADIAL", 1200, 1600, vec![1245.65, 600.0, 800.0, 0.0577])?;
//! let n = Point2::new(0.2, -0.3);
//! let px = cam.project(n);
//! assert!((cam.undistort(px)? - n).norm() < 1e-12);
//! # Ok::<(), eopnp::camera::CameraError>(())
//! ```
//!
//! The models, their parameter orders and their distortion formulas are COLMAP's
//! (`src/colmap/sensor/models.h`), so a camera read from a COLMAP reconstruction
//! ([`crate::colmap`]) maps points exactly as COLMAP does:
//!
//! | model                   | parameters                                       |
//! |-------------------------|--------------------------------------------------|
//! | `SIMPLE_PINHOLE`        | `f, cx, cy`                                      |
//! | `PINHOLE`               | `fx, fy, cx, cy`                                 |
//! | `SIMPLE_RADIAL`         | `f, cx, cy, k`                                   |
//! | `RADIAL`                | `f, cx, cy, k1, k2`                              |
//! | `OPENCV`                | `fx, fy, cx, cy, k1, k2, p1, p2`                 |
//! | `OPENCV_FISHEYE`        | `fx, fy, cx, cy, k1, k2, k3, k4`                 |
//! | `FULL_OPENCV`           | `fx, fy, cx, cy, k1, k2, p1, p2, k3, k4, k5, k6` |
//! | `SIMPLE_RADIAL_FISHEYE` | `f, cx, cy, k`                                   |
//! | `RADIAL_FISHEYE`        | `f, cx, cy, k1, k2`                              |
//!
//! and one model that is not COLMAP's, OpenCV's full perspective model
//! ([`CameraModel::OpenCvThinPrismTilted`], `OPENCV_THIN_PRISM_TILTED`: `fx, fy, cx, cy, k1,
//! k2, p1, p2, k3, k4, k5, k6, s1, s2, s3, s4, tau_x, tau_y`; no COLMAP id, never read from or
//! written to a COLMAP model).
//!
//! OpenCV interop: [`Camera::from_opencv`] takes the camera matrix and distortion vector of
//! `cv2.projectPoints` / `cv2.solvePnP` (0, 4, 5, 8, 12 or 14 coefficients),
//! [`Camera::from_opencv_fisheye`] those of `cv2.fisheye`; [`Camera::to_opencv`] and
//! [`Camera::to_opencv_fisheye`] give them back for the models that have an exact OpenCV form.
//! Such a camera reproduces OpenCV's mapping as is, with no half-pixel shift: its pixels are
//! in OpenCV's convention (the centre of the upper-left pixel is `(0, 0)`); add 0.5 to `cx` and
//! `cy` for pixels in COLMAP's convention below.
//!
//! Pixel convention (COLMAP's): the upper-left corner of the image is `(0, 0)`, so the centre
//! of the upper-left pixel is `(0.5, 0.5)`. The camera model is a plain mapping between
//! normalised coordinates `(x/z, y/z)` and pixels; no half-pixel shift is applied anywhere.
//!
//! For a perspective model, a normalised point `(u, v)` is distorted to
//! `(u, v) + D(u, v)` and then mapped to pixels by the focal lengths and principal point.
//! Fisheye models first map `(u, v)` to `theta / r (u, v)` (`r = |(u, v)|`, `theta = atan r`,
//! the equidistant projection) and distort that. `OPENCV_THIN_PRISM_TILTED` adds the
//! thin-prism terms to `D` and then applies OpenCV's projective tilt. [`Camera::undistort`]
//! inverts the distortion (and the tilt) by Newton's method with an analytic Jacobian, a trust
//! region (as COLMAP) and at most [`UNDISTORT_MAX_ITERATIONS`] iterations; a pixel whose
//! undistortion does not converge is an error, never a silently wrong point.

use nalgebra::{Matrix3, Point2};

mod distortion;
mod model;

use distortion::{iterative_undistortion, tilt_matrix, Distortion};
pub use model::{CameraError, CameraModel, SUPPORTED_MODELS};

/// The serialized form of a [`Camera`]: its fields, checked by [`Camera::new`] on the way in.
#[cfg(feature = "serde")]
#[derive(serde::Serialize, serde::Deserialize)]
struct CameraFields {
    model: CameraModel,
    width: u64,
    height: u64,
    params: Vec<f64>,
}

#[cfg(feature = "serde")]
impl TryFrom<CameraFields> for Camera {
    type Error = CameraError;
    fn try_from(c: CameraFields) -> Result<Self, CameraError> {
        Camera::new(c.model, c.width, c.height, c.params)
    }
}

#[cfg(feature = "serde")]
impl From<Camera> for CameraFields {
    fn from(c: Camera) -> Self {
        CameraFields {
            model: c.model,
            width: c.width,
            height: c.height,
            params: c.params,
        }
    }
}

/// Hard bound on the Newton iterations of [`Camera::undistort`].
pub const UNDISTORT_MAX_ITERATIONS: u32 = crate::numeric::bounds::UNDISTORT_MAX_ITERATIONS;
/// A camera: model, image size and parameters (validated on construction; with feature
/// `serde`, deserialization validates the same way).
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(try_from = "CameraFields", into = "CameraFields")
)]
pub struct Camera {
    model: CameraModel,
    width: u64,
    height: u64,
    params: Vec<f64>,
}

impl Camera {
    /// A camera of `model` with COLMAP's parameter order (see the module documentation).
    ///
    /// # Errors
    /// [`CameraError::ParamCount`] for the wrong number of parameters,
    /// [`CameraError::InvalidParams`] for non-finite parameters, non-positive focal lengths or
    /// (`OPENCV_THIN_PRISM_TILTED`) a tilt angle of `pi/2` or more.
    pub fn new(
        model: CameraModel,
        width: u64,
        height: u64,
        params: Vec<f64>,
    ) -> Result<Self, CameraError> {
        if params.len() != model.num_params() {
            return Err(CameraError::ParamCount {
                model,
                expected: model.num_params(),
                got: params.len(),
            });
        }
        if let Some(i) = params.iter().position(|p| !p.is_finite()) {
            return Err(CameraError::InvalidParams(format!(
                "parameter {} of {model} ({}) is not finite",
                i + 1,
                model.params_info()
            )));
        }
        let cam = Camera {
            model,
            width,
            height,
            params,
        };
        let (fx, fy) = cam.intrinsics_scale();
        if !(fx > 0.0 && fy > 0.0) {
            return Err(CameraError::InvalidParams(format!(
                "focal length must be positive (got {fx}, {fy})"
            )));
        }
        if cam.model == CameraModel::OpenCvThinPrismTilted {
            let (tx, ty) = (cam.params[16], cam.params[17]);
            if !(tx.abs() < core::f64::consts::FRAC_PI_2 && ty.abs() < core::f64::consts::FRAC_PI_2)
            {
                return Err(CameraError::InvalidParams(format!(
                    "tilt angles tau_x = {tx}, tau_y = {ty} (radians) must be below pi/2 in \
                     magnitude"
                )));
            }
        }
        Ok(cam)
    }

    /// A camera from a COLMAP model name and parameters, e.g.
    /// `Camera::from_colmap("SIMPLE_RADIAL", 1200, 1600, vec![1245.65, 600.0, 800.0, 0.0577])`.
    ///
    /// # Errors
    /// [`CameraError::UnsupportedModel`] naming an unsupported model, and as [`Camera::new`].
    pub fn from_colmap(
        model_name: &str,
        width: u64,
        height: u64,
        params: Vec<f64>,
    ) -> Result<Self, CameraError> {
        Camera::new(CameraModel::from_name(model_name)?, width, height, params)
    }

    /// A pinhole camera without distortion (COLMAP's `PINHOLE`; image size 0, i.e. unknown):
    /// `px = fx x + cx`, `py = fy y + cy` for normalised `(x, y)`.
    ///
    /// ```
    /// use eopnp::camera::Camera;
    /// use nalgebra::Point2;
    ///
    /// let cam = Camera::pinhole(800.0, 800.0, 320.0, 240.0)?;
    /// assert_eq!(cam.project(Point2::new(0.1, -0.05)), Point2::new(400.0, 200.0));
    /// # Ok::<(), eopnp::camera::CameraError>(())
    /// ```
    ///
    /// # Errors
    /// [`CameraError::InvalidParams`] for non-finite parameters or non-positive focal lengths.
    pub fn pinhole(fx: f64, fy: f64, cx: f64, cy: f64) -> Result<Self, CameraError> {
        Camera::new(CameraModel::Pinhole, 0, 0, vec![fx, fy, cx, cy])
    }

    /// A camera from OpenCV's camera matrix `K` and distortion vector, as passed to
    /// `cv2.projectPoints`, `cv2.solvePnP` or `cv2.undistortPoints`: [`Camera::project`] then
    /// equals `cv2.projectPoints` of the point `(x, y, 1)` with `rvec = tvec = 0`.
    ///
    /// `dist` is in OpenCV's order `(k1, k2, p1, p2[, k3[, k4, k5, k6[, s1, s2, s3, s4[, tauX,
    /// tauY]]]])` (tilt angles in radians), and the model follows from its length alone:
    ///
    /// | coefficients | model                                                      |
    /// |--------------|------------------------------------------------------------|
    /// | 0            | `PINHOLE`                                                  |
    /// | 4            | `OPENCV`                                                   |
    /// | 5, 8         | `FULL_OPENCV` (missing coefficients 0)                     |
    /// | 12, 14       | `OPENCV_THIN_PRISM_TILTED` (missing tilt 0; not COLMAP's) |
    ///
    /// `K` must be `[[fx, 0, cx], [0, fy, cy], [0, 0, 1]]` with `fx, fy > 0`. OpenCV's image
    /// size is not part of these parameters: the camera's [`Camera::width`] and
    /// [`Camera::height`] are 0 (no computation of this crate uses them; build the camera with
    /// [`Camera::new`]`(cam.model(), width, height, cam.params().to_vec())` to record them).
    /// Pixels are in OpenCV's convention (see the module documentation).
    ///
    /// ```
    /// use eopnp::camera::{Camera, CameraModel};
    /// use nalgebra::{Matrix3, Point2};
    ///
    /// let k = Matrix3::new(800.0, 0.0, 320.0, 0.0, 810.0, 240.0, 0.0, 0.0, 1.0);
    /// let cam = Camera::from_opencv(&k, &[-0.2, 0.05, 1e-3, -5e-4, 0.01])?;
    /// assert_eq!(cam.model(), CameraModel::FullOpenCv);
    /// let n = Point2::new(0.3, -0.2);
    /// let px = cam.project(n); // cv2.projectPoints([(0.3, -0.2, 1)], 0, 0, K, dist)
    /// assert!((cam.undistort(px)? - n).norm() < 1e-12);
    /// # Ok::<(), eopnp::camera::CameraError>(())
    /// ```
    ///
    /// # Errors
    /// [`CameraError::InvalidParams`] for a distortion vector of another length, a non-finite
    /// entry, a `K` not of the form above, in particular a non-zero skew `K[0][1]` (which these
    /// models cannot represent, and which `cv2.projectPoints` ignores), non-positive focal
    /// lengths or a tilt angle of `pi/2` or more.
    pub fn from_opencv(k: &Matrix3<f64>, dist: &[f64]) -> Result<Self, CameraError> {
        const NAMES: [&str; 14] = [
            "k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6", "s1", "s2", "s3", "s4", "tauX", "tauY",
        ];
        let mut params = opencv_intrinsics(k)?.to_vec();
        let n = dist.len();
        if !matches!(n, 0 | 4 | 5 | 8 | 12 | 14) {
            return Err(CameraError::InvalidParams(format!(
                "an OpenCV distortion vector has 0, 4, 5, 8, 12 or 14 coefficients, got {n}"
            )));
        }
        if let Some(i) = dist.iter().position(|c| !c.is_finite()) {
            return Err(CameraError::InvalidParams(format!(
                "distortion coefficient {} ({}) is not finite",
                i, NAMES[i]
            )));
        }
        let (model, len) = match n {
            0 => (CameraModel::Pinhole, 0),
            4 => (CameraModel::OpenCv, 4),
            5 | 8 => (CameraModel::FullOpenCv, 8),
            _ => (CameraModel::OpenCvThinPrismTilted, 14),
        };
        params.extend_from_slice(dist);
        params.resize(4 + len, 0.0);
        Camera::new(model, 0, 0, params)
    }

    /// A camera from the camera matrix `K` and the distortion `(k1, k2, k3, k4)` of OpenCV's
    /// fisheye model (`cv2.fisheye.projectPoints`, `cv2.fisheye.undistortPoints`): an
    /// `OPENCV_FISHEYE` camera, whose [`Camera::project`] equals `cv2.fisheye.projectPoints` of
    /// the point `(x, y, 1)` with `rvec = tvec = 0`.
    ///
    /// `K` and the image size are as in [`Camera::from_opencv`]; the skew `alpha` of
    /// `cv2.fisheye` must be 0 (`K[0][1] = 0`).
    ///
    /// ```
    /// use eopnp::camera::{Camera, CameraModel};
    /// use nalgebra::{Matrix3, Point2};
    ///
    /// let k = Matrix3::new(400.0, 0.0, 640.0, 0.0, 401.0, 480.0, 0.0, 0.0, 1.0);
    /// let cam = Camera::from_opencv_fisheye(&k, &[0.02, -0.01, 0.003, -0.001])?;
    /// assert_eq!(cam.model(), CameraModel::OpenCvFisheye);
    /// let n = Point2::new(1.5, -0.7); // about 59 degrees off axis
    /// assert!((cam.undistort(cam.project(n))? - n).norm() < 1e-12);
    /// # Ok::<(), eopnp::camera::CameraError>(())
    /// ```
    ///
    /// # Errors
    /// [`CameraError::InvalidParams`] as [`Camera::from_opencv`].
    pub fn from_opencv_fisheye(k: &Matrix3<f64>, dist: &[f64; 4]) -> Result<Self, CameraError> {
        let mut params = opencv_intrinsics(k)?.to_vec();
        if let Some(i) = dist.iter().position(|c| !c.is_finite()) {
            return Err(CameraError::InvalidParams(format!(
                "fisheye distortion coefficient k{} is not finite",
                i + 1
            )));
        }
        params.extend_from_slice(dist);
        Camera::new(CameraModel::OpenCvFisheye, 0, 0, params)
    }

    /// OpenCV's camera matrix and distortion vector of this camera, for `cv2.projectPoints`,
    /// `cv2.solvePnP` or `cv2.undistortPoints`, if its model has an exact OpenCV form: every
    /// perspective model (`PINHOLE` and `SIMPLE_PINHOLE` give an empty vector,
    /// `SIMPLE_RADIAL`, `RADIAL` and `OPENCV` 4 coefficients, `FULL_OPENCV` 8,
    /// `OPENCV_THIN_PRISM_TILTED` 14). `None` for the fisheye models (see
    /// [`Camera::to_opencv_fisheye`]).
    ///
    /// ```
    /// use eopnp::camera::{Camera, CameraModel};
    /// use nalgebra::Point2;
    ///
    /// let params = vec![1245.6, 600.0, 800.0, 0.06];
    /// let cam = Camera::from_colmap("SIMPLE_RADIAL", 1200, 1600, params)?;
    /// let (k, dist) = cam.to_opencv().unwrap();
    /// assert_eq!((k[(0, 0)], k[(1, 1)], k[(0, 2)], k[(1, 2)]), (1245.6, 1245.6, 600.0, 800.0));
    /// assert_eq!(dist, [0.06, 0.0, 0.0, 0.0]);
    /// // Back: the same mapping, as an OPENCV camera.
    /// let back = Camera::from_opencv(&k, &dist)?;
    /// assert_eq!(back.model(), CameraModel::OpenCv);
    /// let n = Point2::new(0.3, -0.2);
    /// assert!((back.project(n) - cam.project(n)).norm() < 1e-9);
    /// # Ok::<(), eopnp::camera::CameraError>(())
    /// ```
    #[must_use]
    pub fn to_opencv(&self) -> Option<(Matrix3<f64>, Vec<f64>)> {
        let p = &self.params;
        let dist = match self.model {
            CameraModel::SimplePinhole | CameraModel::Pinhole => vec![],
            CameraModel::SimpleRadial => vec![p[3], 0.0, 0.0, 0.0],
            CameraModel::Radial => vec![p[3], p[4], 0.0, 0.0],
            CameraModel::OpenCv | CameraModel::FullOpenCv | CameraModel::OpenCvThinPrismTilted => {
                p[4..].to_vec()
            }
            CameraModel::OpenCvFisheye
            | CameraModel::SimpleRadialFisheye
            | CameraModel::RadialFisheye => return None,
        };
        Some((self.opencv_matrix(), dist))
    }

    /// OpenCV's fisheye camera matrix and distortion `(k1, k2, k3, k4)` of this camera, for
    /// `cv2.fisheye.projectPoints` or `cv2.fisheye.undistortPoints`, if it is a fisheye
    /// camera (`OPENCV_FISHEYE`, `SIMPLE_RADIAL_FISHEYE`, `RADIAL_FISHEYE`, missing
    /// coefficients 0); `None` for the perspective models (see [`Camera::to_opencv`]).
    ///
    /// ```
    /// use eopnp::camera::Camera;
    ///
    /// let params = vec![700.0, 600.0, 800.0, 0.03, -0.004];
    /// let cam = Camera::from_colmap("RADIAL_FISHEYE", 1200, 1600, params)?;
    /// let (k, dist) = cam.to_opencv_fisheye().unwrap();
    /// assert_eq!(dist, [0.03, -0.004, 0.0, 0.0]);
    /// assert!(cam.to_opencv().is_none());
    /// # Ok::<(), eopnp::camera::CameraError>(())
    /// ```
    #[must_use]
    pub fn to_opencv_fisheye(&self) -> Option<(Matrix3<f64>, [f64; 4])> {
        let p = &self.params;
        let dist = match self.model {
            CameraModel::OpenCvFisheye => [p[4], p[5], p[6], p[7]],
            CameraModel::SimpleRadialFisheye => [p[3], 0.0, 0.0, 0.0],
            CameraModel::RadialFisheye => [p[3], p[4], 0.0, 0.0],
            CameraModel::SimplePinhole
            | CameraModel::Pinhole
            | CameraModel::SimpleRadial
            | CameraModel::Radial
            | CameraModel::OpenCv
            | CameraModel::FullOpenCv
            | CameraModel::OpenCvThinPrismTilted => return None,
        };
        Some((self.opencv_matrix(), dist))
    }

    /// `[[fx, 0, cx], [0, fy, cy], [0, 0, 1]]`.
    fn opencv_matrix(&self) -> Matrix3<f64> {
        let (fx, fy) = self.intrinsics_scale();
        let (cx, cy) = self.principal_point();
        Matrix3::new(fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0)
    }

    /// The camera model.
    #[must_use]
    pub fn model(&self) -> CameraModel {
        self.model
    }

    /// Image width in pixels.
    #[must_use]
    pub fn width(&self) -> u64 {
        self.width
    }

    /// Image height in pixels.
    #[must_use]
    pub fn height(&self) -> u64 {
        self.height
    }

    /// The parameters in COLMAP's order.
    #[must_use]
    pub fn params(&self) -> &[f64] {
        &self.params
    }

    /// Focal lengths `(fx, fy)` in pixels (`(f, f)` for single-focal models): the scale from
    /// normalised to pixel residuals, for weighting.
    #[must_use]
    pub fn intrinsics_scale(&self) -> (f64, f64) {
        let p = &self.params;
        if self.model.single_focal() {
            (p[0], p[0])
        } else {
            (p[0], p[1])
        }
    }

    /// Principal point `(cx, cy)` in pixels.
    #[must_use]
    pub fn principal_point(&self) -> (f64, f64) {
        let p = &self.params;
        if self.model.single_focal() {
            (p[1], p[2])
        } else {
            (p[2], p[3])
        }
    }

    /// Whether the model has lens distortion terms (all models except the pinhole ones).
    #[must_use]
    pub fn has_distortion(&self) -> bool {
        !matches!(
            self.model,
            CameraModel::SimplePinhole | CameraModel::Pinhole
        )
    }

    fn distortion(&self) -> Distortion {
        let p = &self.params;
        let mut d = Distortion::default();
        match self.model {
            CameraModel::SimplePinhole | CameraModel::Pinhole => {}
            CameraModel::SimpleRadial | CameraModel::SimpleRadialFisheye => d.k[0] = p[3],
            CameraModel::Radial | CameraModel::RadialFisheye => {
                d.k[0] = p[3];
                d.k[1] = p[4];
            }
            CameraModel::OpenCv => {
                d.k[0] = p[4];
                d.k[1] = p[5];
                d.p = [p[6], p[7]];
            }
            CameraModel::OpenCvFisheye => d.k = [p[4], p[5], p[6], p[7]],
            CameraModel::FullOpenCv => {
                d.p = [p[6], p[7]];
                d.rational = Some([p[4], p[5], p[8], p[9], p[10], p[11]]);
            }
            CameraModel::OpenCvThinPrismTilted => {
                d.p = [p[6], p[7]];
                d.rational = Some([p[4], p[5], p[8], p[9], p[10], p[11]]);
                d.prism = [p[12], p[13], p[14], p[15]];
                if p[16] != 0.0 || p[17] != 0.0 {
                    d.tilt = Some(tilt_matrix(p[16], p[17]));
                }
            }
        }
        d
    }

    /// The pixel of a normalised image point `(x/z, y/z)` (COLMAP's `ImgFromCam` with
    /// `w = 1`). Non-finite input gives non-finite output.
    #[must_use]
    pub fn project(&self, normalised: Point2<f64>) -> Point2<f64> {
        let (mut u, mut v) = (normalised.x, normalised.y);
        if self.model.is_fisheye() {
            let r = u.hypot(v);
            if r > f64::EPSILON {
                let s = r.atan() / r;
                u *= s;
                v *= s;
            }
        }
        let ((xd, yd), _) = self.distortion().apply(u, v);
        let (fx, fy) = self.intrinsics_scale();
        let (cx, cy) = self.principal_point();
        Point2::new(fx * xd + cx, fy * yd + cy)
    }

    /// The Jacobian `d pixel / d normalised` of [`Camera::project`] at a normalised point,
    /// row-major `[[dpx/dx, dpx/dy], [dpy/dx, dpy/dy]]`, for weighting residuals in pixels.
    #[must_use]
    pub fn project_jacobian(&self, normalised: Point2<f64>) -> [f64; 4] {
        let (fx, fy) = self.intrinsics_scale();
        let (x, y) = (normalised.x, normalised.y);
        // Fisheye models: chain rule through (u, v) = s(r) (x, y), s = atan(r) / r.
        let (u, v, jf) = if self.model.is_fisheye() {
            let r2 = x * x + y * y;
            let r = r2.sqrt();
            if r > 1e-8 {
                let s = r.atan() / r;
                // ds/dr = (r / (1 + r^2) - atan r) / r^2; d(s x)/dx = s + x^2 s'(r) / r.
                let ds = (r / (1.0 + r2) - r.atan()) / r2;
                let q = ds / r;
                (
                    s * x,
                    s * y,
                    [s + q * x * x, q * x * y, q * x * y, s + q * y * y],
                )
            } else {
                (x, y, [1.0, 0.0, 0.0, 1.0])
            }
        } else {
            (x, y, [1.0, 0.0, 0.0, 1.0])
        };
        let (_, jd) = self.distortion().apply(u, v);
        let m = [
            jd[0] * jf[0] + jd[1] * jf[2],
            jd[0] * jf[1] + jd[1] * jf[3],
            jd[2] * jf[0] + jd[3] * jf[2],
            jd[2] * jf[1] + jd[3] * jf[3],
        ];
        [fx * m[0], fx * m[1], fy * m[2], fy * m[3]]
    }

    /// The normalised image point `(x/z, y/z)` of a pixel: inverts [`Camera::project`].
    ///
    /// The distortion is inverted by Newton's method (analytic Jacobian, COLMAP's trust region)
    /// with at most [`UNDISTORT_MAX_ITERATIONS`] iterations, followed by a check that the
    /// distortion equation holds to about 1e-13 and that the distortion map is locally
    /// invertible at the solution.
    ///
    /// # Errors
    /// [`CameraError::NonFinite`] for a NaN or infinite pixel, [`CameraError::NoConvergence`]
    /// if the iteration does not converge, [`CameraError::BeyondHemisphere`] for a fisheye
    /// pixel 90 degrees or more off axis.
    pub fn undistort(&self, pixel: Point2<f64>) -> Result<Point2<f64>, CameraError> {
        if !(pixel.x.is_finite() && pixel.y.is_finite()) {
            return Err(CameraError::NonFinite);
        }
        let (fx, fy) = self.intrinsics_scale();
        let (cx, cy) = self.principal_point();
        let x0 = ((pixel.x - cx) / fx, (pixel.y - cy) / fy);
        let fail = CameraError::NoConvergence {
            pixel: (pixel.x, pixel.y),
        };
        let (u, v) = if self.has_distortion() {
            iterative_undistortion(&self.distortion(), x0).ok_or(fail)?
        } else {
            x0
        };
        if !(u.is_finite() && v.is_finite()) {
            return Err(CameraError::OutOfRange {
                pixel: (pixel.x, pixel.y),
            });
        }
        if !self.model.is_fisheye() {
            return Ok(Point2::new(u, v));
        }
        // Equidistant fisheye: theta = |(u, v)|, normalised radius tan(theta).
        let theta = u.hypot(v);
        if theta >= core::f64::consts::FRAC_PI_2 {
            return Err(CameraError::BeyondHemisphere {
                pixel: (pixel.x, pixel.y),
            });
        }
        if theta > f64::EPSILON {
            let s = theta.tan() / theta;
            Ok(Point2::new(u * s, v * s))
        } else {
            Ok(Point2::new(u, v))
        }
    }

    /// [`Camera::undistort`] and the weight of the point in [`crate::Solver::solve_pixels`]:
    /// `|det J| / (fx fy)`, `J` the Jacobian of [`Camera::project`] at the normalised point (to
    /// first order, the squared scale of a pixel error in normalised units relative to the
    /// undistorted pinhole camera).
    ///
    /// # Errors
    /// As [`Camera::undistort`], and [`CameraError::OutOfRange`] if the weight overflows.
    pub fn undistort_weighted(
        &self,
        pixel: Point2<f64>,
    ) -> Result<(Point2<f64>, f64), CameraError> {
        let n = self.undistort(pixel)?;
        let (fx, fy) = self.intrinsics_scale();
        let j = self.project_jacobian(n);
        let w = ((j[0] * j[3] - j[1] * j[2]) / (fx * fy)).abs();
        if w.is_finite() {
            Ok((n, w))
        } else {
            Err(CameraError::OutOfRange {
                pixel: (pixel.x, pixel.y),
            })
        }
    }
}

/// `[fx, fy, cx, cy]` of OpenCV's camera matrix, which must be
/// `[[fx, 0, cx], [0, fy, cy], [0, 0, 1]]` with finite entries (`fx, fy > 0` is checked by
/// [`Camera::new`]).
fn opencv_intrinsics(k: &Matrix3<f64>) -> Result<[f64; 4], CameraError> {
    let bad = |why: String| Err(CameraError::InvalidParams(why));
    if k.iter().any(|v| !v.is_finite()) {
        return bad("camera matrix K has a non-finite entry".to_string());
    }
    let row2 = [k[(2, 0)], k[(2, 1)], k[(2, 2)]];
    if row2 != [0.0, 0.0, 1.0] {
        return bad(format!(
            "camera matrix K must have last row [0, 0, 1], got {row2:?}"
        ));
    }
    if k[(1, 0)] != 0.0 {
        return bad(format!(
            "camera matrix K must have K[1][0] = 0, got {}",
            k[(1, 0)]
        ));
    }
    if k[(0, 1)] != 0.0 {
        return bad(format!(
            "camera matrix K has skew K[0][1] = {}: not representable by these camera models \
             (cv2.projectPoints ignores it too)",
            k[(0, 1)]
        ));
    }
    Ok([k[(0, 0)], k[(1, 1)], k[(0, 2)], k[(1, 2)]])
}

#[cfg(test)]
#[path = "../../tests/unit/camera.rs"]
mod tests;
