//! COLMAP camera models: projection of normalised image points to pixels and iterative
//! undistortion of pixels back to normalised image points.
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
//! Pixel convention (COLMAP's): the upper-left corner of the image is `(0, 0)`, so the centre
//! of the upper-left pixel is `(0.5, 0.5)`. The camera model is a plain mapping between
//! normalised coordinates `(x/z, y/z)` and pixels; no half-pixel shift is applied anywhere.
//!
//! For a perspective model, a normalised point `(u, v)` is distorted to
//! `(u, v) + D(u, v)` and then mapped to pixels by the focal lengths and principal point.
//! Fisheye models first map `(u, v)` to `theta / r (u, v)` (`r = |(u, v)|`, `theta = atan r`,
//! the equidistant projection) and distort that. [`Camera::undistort`] inverts the distortion
//! by Newton's method with an analytic Jacobian, a trust region (as COLMAP) and at most
//! [`UNDISTORT_MAX_ITERATIONS`] iterations; a pixel whose undistortion does not converge is
//! an error, never a silently wrong point.

use core::fmt;
use nalgebra::Point2;

use crate::numeric::bounds::{Bound, Budget};

/// Hard bound on the Newton iterations of [`Camera::undistort`].
pub const UNDISTORT_MAX_ITERATIONS: u32 = crate::numeric::bounds::UNDISTORT_MAX_ITERATIONS;
/// Newton stops when the step is below this (relative to `max(1, |x|)`).
const STEP_TOL: f64 = 1e-14;
/// Convergence check: the distortion equation must hold to this (relative to `max(1, |x0|)`),
/// a few ulps above the rounding of its evaluation.
const RESIDUAL_TOL: f64 = 1e-13;

/// A COLMAP camera model.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[non_exhaustive]
pub enum CameraModel {
    /// `f, cx, cy`: pinhole, one focal length, no distortion (COLMAP id 0).
    SimplePinhole,
    /// `fx, fy, cx, cy`: pinhole, no distortion (COLMAP id 1).
    Pinhole,
    /// `f, cx, cy, k`: one radial distortion term `k r^2` (COLMAP id 2).
    SimpleRadial,
    /// `f, cx, cy, k1, k2`: radial distortion `k1 r^2 + k2 r^4` (COLMAP id 3).
    Radial,
    /// `fx, fy, cx, cy, k1, k2, p1, p2`: OpenCV's radial and tangential distortion
    /// (COLMAP id 4).
    OpenCv,
    /// `fx, fy, cx, cy, k1, k2, k3, k4`: OpenCV's fisheye model (COLMAP id 5).
    OpenCvFisheye,
    /// `fx, fy, cx, cy, k1, k2, p1, p2, k3, k4, k5, k6`: OpenCV's rational model
    /// (COLMAP id 6).
    FullOpenCv,
    /// `f, cx, cy, k`: equidistant fisheye with one radial term (COLMAP id 8).
    SimpleRadialFisheye,
    /// `f, cx, cy, k1, k2`: equidistant fisheye with two radial terms (COLMAP id 9).
    RadialFisheye,
}

/// Every supported model, in COLMAP id order.
pub const SUPPORTED_MODELS: [CameraModel; 9] = [
    CameraModel::SimplePinhole,
    CameraModel::Pinhole,
    CameraModel::SimpleRadial,
    CameraModel::Radial,
    CameraModel::OpenCv,
    CameraModel::OpenCvFisheye,
    CameraModel::FullOpenCv,
    CameraModel::SimpleRadialFisheye,
    CameraModel::RadialFisheye,
];

/// COLMAP's names of its models this crate does not support (for a clearer error message).
const KNOWN_UNSUPPORTED: [(i32, &str); 9] = [
    (7, "FOV"),
    (10, "THIN_PRISM_FISHEYE"),
    (11, "RAD_TAN_THIN_PRISM_FISHEYE"),
    (12, "SIMPLE_DIVISION"),
    (13, "DIVISION"),
    (14, "SIMPLE_FISHEYE"),
    (15, "FISHEYE"),
    (16, "EUCM"),
    (17, "EQUIRECTANGULAR"),
];

impl CameraModel {
    /// COLMAP's name of the model, e.g. `"SIMPLE_RADIAL"`.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            CameraModel::SimplePinhole => "SIMPLE_PINHOLE",
            CameraModel::Pinhole => "PINHOLE",
            CameraModel::SimpleRadial => "SIMPLE_RADIAL",
            CameraModel::Radial => "RADIAL",
            CameraModel::OpenCv => "OPENCV",
            CameraModel::OpenCvFisheye => "OPENCV_FISHEYE",
            CameraModel::FullOpenCv => "FULL_OPENCV",
            CameraModel::SimpleRadialFisheye => "SIMPLE_RADIAL_FISHEYE",
            CameraModel::RadialFisheye => "RADIAL_FISHEYE",
        }
    }

    /// COLMAP's numeric model id (used by the binary model format).
    #[must_use]
    pub fn colmap_id(self) -> i32 {
        match self {
            CameraModel::SimplePinhole => 0,
            CameraModel::Pinhole => 1,
            CameraModel::SimpleRadial => 2,
            CameraModel::Radial => 3,
            CameraModel::OpenCv => 4,
            CameraModel::OpenCvFisheye => 5,
            CameraModel::FullOpenCv => 6,
            CameraModel::SimpleRadialFisheye => 8,
            CameraModel::RadialFisheye => 9,
        }
    }

    /// Number of parameters of the model.
    #[must_use]
    pub fn num_params(self) -> usize {
        match self {
            CameraModel::SimplePinhole => 3,
            CameraModel::Pinhole => 4,
            CameraModel::SimpleRadial | CameraModel::SimpleRadialFisheye => 4,
            CameraModel::Radial | CameraModel::RadialFisheye => 5,
            CameraModel::OpenCv | CameraModel::OpenCvFisheye => 8,
            CameraModel::FullOpenCv => 12,
        }
    }

    /// The parameter names in order, e.g. `"f, cx, cy, k"`.
    #[must_use]
    pub fn params_info(self) -> &'static str {
        match self {
            CameraModel::SimplePinhole => "f, cx, cy",
            CameraModel::Pinhole => "fx, fy, cx, cy",
            CameraModel::SimpleRadial | CameraModel::SimpleRadialFisheye => "f, cx, cy, k",
            CameraModel::Radial | CameraModel::RadialFisheye => "f, cx, cy, k1, k2",
            CameraModel::OpenCv => "fx, fy, cx, cy, k1, k2, p1, p2",
            CameraModel::OpenCvFisheye => "fx, fy, cx, cy, k1, k2, k3, k4",
            CameraModel::FullOpenCv => "fx, fy, cx, cy, k1, k2, p1, p2, k3, k4, k5, k6",
        }
    }

    /// The model of a COLMAP name (exact, upper case as COLMAP writes it).
    ///
    /// # Errors
    /// [`CameraError::UnsupportedModel`] naming the model if it is not one of
    /// [`SUPPORTED_MODELS`].
    pub fn from_name(name: &str) -> Result<Self, CameraError> {
        SUPPORTED_MODELS
            .iter()
            .copied()
            .find(|m| m.name() == name)
            .ok_or_else(|| CameraError::UnsupportedModel(name.to_string()))
    }

    /// The model of a COLMAP numeric model id.
    ///
    /// # Errors
    /// [`CameraError::UnsupportedModel`] naming the model (or the id, if COLMAP has no such
    /// model) if it is not supported.
    pub fn from_colmap_id(id: i32) -> Result<Self, CameraError> {
        if let Some(m) = SUPPORTED_MODELS
            .iter()
            .copied()
            .find(|m| m.colmap_id() == id)
        {
            return Ok(m);
        }
        let name = KNOWN_UNSUPPORTED
            .iter()
            .find(|(i, _)| *i == id)
            .map_or_else(
                || format!("unknown model id {id}"),
                |(_, n)| format!("{n} (model id {id})"),
            );
        Err(CameraError::UnsupportedModel(name))
    }

    fn is_fisheye(self) -> bool {
        matches!(
            self,
            CameraModel::OpenCvFisheye
                | CameraModel::SimpleRadialFisheye
                | CameraModel::RadialFisheye
        )
    }

    /// Whether the model has a single focal length `f`.
    fn single_focal(self) -> bool {
        matches!(
            self,
            CameraModel::SimplePinhole
                | CameraModel::SimpleRadial
                | CameraModel::Radial
                | CameraModel::SimpleRadialFisheye
                | CameraModel::RadialFisheye
        )
    }
}

impl fmt::Display for CameraModel {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl core::str::FromStr for CameraModel {
    type Err = CameraError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        CameraModel::from_name(s)
    }
}

/// Errors of camera construction and undistortion.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum CameraError {
    /// The camera model is not supported (the string names it).
    UnsupportedModel(String),
    /// Wrong number of parameters for the model.
    ParamCount {
        /// The model.
        model: CameraModel,
        /// Parameters the model needs.
        expected: usize,
        /// Parameters given.
        got: usize,
    },
    /// A parameter is not finite, or a focal length is not positive.
    InvalidParams(String),
    /// The pixel (or the normalised point) is NaN or infinite.
    NonFinite,
    /// The undistortion of the pixel did not converge within
    /// [`UNDISTORT_MAX_ITERATIONS`] Newton iterations, or converged to a point where the
    /// distortion map folds over (the pixel is outside the region where the model is
    /// invertible).
    NoConvergence {
        /// The pixel.
        pixel: (f64, f64),
    },
    /// The pixel lies at or beyond 90 degrees from the optical axis of a fisheye camera: it has
    /// no normalised coordinates `(x/z, y/z)` with `z > 0`.
    BeyondHemisphere {
        /// The pixel.
        pixel: (f64, f64),
    },
    /// The pixel is so far outside the image that its normalised coordinates, or the lens
    /// model's local scale there, overflow `f64`.
    OutOfRange {
        /// The pixel.
        pixel: (f64, f64),
    },
}

impl fmt::Display for CameraError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CameraError::UnsupportedModel(name) => {
                let list: Vec<&str> = SUPPORTED_MODELS.iter().map(|m| m.name()).collect();
                write!(
                    f,
                    "unsupported camera model \"{name}\" (supported: {})",
                    list.join(", ")
                )
            }
            CameraError::ParamCount {
                model,
                expected,
                got,
            } => write!(
                f,
                "camera model {model} takes {expected} parameters ({}), got {got}",
                model.params_info()
            ),
            CameraError::InvalidParams(why) => write!(f, "invalid camera parameters: {why}"),
            CameraError::NonFinite => f.write_str("point coordinate is NaN or infinite"),
            CameraError::NoConvergence { pixel } => write!(
                f,
                "undistortion of pixel ({:?}, {:?}) did not converge (outside the region where \
                 the distortion model is invertible?)",
                pixel.0, pixel.1
            ),
            CameraError::BeyondHemisphere { pixel } => write!(
                f,
                "pixel ({:?}, {:?}) is 90 degrees or more off the optical axis of this fisheye \
                 camera: it has no normalised image coordinates",
                pixel.0, pixel.1
            ),
            CameraError::OutOfRange { pixel } => write!(
                f,
                "pixel ({:?}, {:?}) is too far outside the image for this camera model (its \
                 normalised coordinates or the lens model's scale there overflow); check the \
                 pixel coordinates and the camera parameters",
                pixel.0, pixel.1
            ),
        }
    }
}

impl std::error::Error for CameraError {}

/// Pinhole intrinsics: `px = fx x + skew y + cx`, `py = fy y + cy` for normalised `(x, y)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Intrinsics {
    /// Focal length in x, pixels.
    pub fx: f64,
    /// Focal length in y, pixels.
    pub fy: f64,
    /// Principal point x, pixels.
    pub cx: f64,
    /// Principal point y, pixels.
    pub cy: f64,
    /// Skew, pixels (0 for almost every camera).
    pub skew: f64,
}

impl Intrinsics {
    /// Normalised image coordinates of a pixel.
    #[must_use]
    pub fn normalize(&self, px: &Point2<f64>) -> Point2<f64> {
        let y = (px.y - self.cy) / self.fy;
        let x = (px.x - self.cx - self.skew * y) / self.fx;
        Point2::new(x, y)
    }

    /// Pixel of a normalised image point.
    #[must_use]
    pub fn project(&self, p: &Point2<f64>) -> Point2<f64> {
        Point2::new(
            self.fx * p.x + self.skew * p.y + self.cx,
            self.fy * p.y + self.cy,
        )
    }
}

/// A camera: model, image size and parameters (validated on construction).
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    model: CameraModel,
    width: u64,
    height: u64,
    params: Vec<f64>,
}

/// The distortion coefficients of a model in a uniform layout:
/// `D(u, v) = (u g(r2) + 2 p1 u v + p2 (r2 + 2 u^2), v g(r2) + 2 p2 u v + p1 (r2 + 2 v^2))`
/// with `g = k1 r2 + k2 r2^2 + k3 r2^3 + k4 r2^4` (polynomial models) or
/// `g = (1 + k1 r2 + k2 r4 + k3 r6) / (1 + k4 r2 + k5 r4 + k6 r6) - 1` (FULL_OPENCV).
#[derive(Clone, Copy, Debug, Default)]
struct Distortion {
    k: [f64; 4],
    p: [f64; 2],
    rational: Option<[f64; 6]>,
}

impl Distortion {
    /// `g(r2)` and `g'(r2)`.
    fn radial(&self, r2: f64) -> (f64, f64) {
        if let Some([k1, k2, k3, k4, k5, k6]) = self.rational {
            let n = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
            let dn = k1 + r2 * (2.0 * k2 + 3.0 * r2 * k3);
            let d = 1.0 + r2 * (k4 + r2 * (k5 + r2 * k6));
            let dd = k4 + r2 * (2.0 * k5 + 3.0 * r2 * k6);
            (n / d - 1.0, (dn * d - n * dd) / (d * d))
        } else {
            let [k1, k2, k3, k4] = self.k;
            let g = r2 * (k1 + r2 * (k2 + r2 * (k3 + r2 * k4)));
            let dg = k1 + r2 * (2.0 * k2 + r2 * (3.0 * k3 + 4.0 * r2 * k4));
            (g, dg)
        }
    }

    /// `(u, v) + D(u, v)` and its Jacobian `[[a, b], [c, d]]`.
    fn apply(&self, u: f64, v: f64) -> ((f64, f64), [f64; 4]) {
        let (u2, v2, uv) = (u * u, v * v, u * v);
        let r2 = u2 + v2;
        let (g, dg) = self.radial(r2);
        let [p1, p2] = self.p;
        let du = u * g + 2.0 * p1 * uv + p2 * (r2 + 2.0 * u2);
        let dv = v * g + 2.0 * p2 * uv + p1 * (r2 + 2.0 * v2);
        let j = [
            1.0 + g + 2.0 * u2 * dg + 2.0 * p1 * v + 6.0 * p2 * u,
            2.0 * uv * dg + 2.0 * p1 * u + 2.0 * p2 * v,
            2.0 * uv * dg + 2.0 * p2 * v + 2.0 * p1 * u,
            1.0 + g + 2.0 * v2 * dg + 2.0 * p2 * u + 6.0 * p1 * v,
        ];
        ((u + du, v + dv), j)
    }
}

impl Camera {
    /// A camera of `model` with COLMAP's parameter order (see the module documentation).
    ///
    /// # Errors
    /// [`CameraError::ParamCount`] for the wrong number of parameters,
    /// [`CameraError::InvalidParams`] for non-finite parameters or non-positive focal lengths.
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

    /// The pinhole part of the camera (focal lengths and principal point, no distortion).
    #[must_use]
    pub fn intrinsics(&self) -> Intrinsics {
        let (fx, fy) = self.intrinsics_scale();
        let (cx, cy) = self.principal_point();
        Intrinsics {
            fx,
            fy,
            cx,
            cy,
            skew: 0.0,
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

    /// [`Camera::undistort`] and the weight of the point in [`solve_pixels`]:
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

/// Solves `x + D(x) = x0` for `x` (COLMAP's `IterativeUndistortion`, with a tighter stopping
/// rule and an explicit convergence check). `None` if it does not converge.
fn iterative_undistortion(d: &Distortion, x0: (f64, f64)) -> Option<(f64, f64)> {
    // COLMAP's trust region: |step| <= max(0.1 |x|, 0.1).
    const REL_RADIUS: f64 = 0.1;
    const RADIUS: f64 = 0.1;
    let scale0 = 1f64.max(x0.0.hypot(x0.1));
    let (mut u, mut v) = x0;
    let mut steps = Budget::new(Bound::Undistort);
    while steps.next() {
        let ((xu, xv), j) = d.apply(u, v);
        let (fu, fv) = (xu - x0.0, xv - x0.1);
        let det = j[0] * j[3] - j[1] * j[2];
        if !(det.is_finite() && det != 0.0 && fu.is_finite() && fv.is_finite()) {
            return None;
        }
        let mut su = (j[3] * fu - j[1] * fv) / det;
        let mut sv = (j[0] * fv - j[2] * fu) / det;
        let radius = (REL_RADIUS * u.hypot(v)).max(RADIUS);
        let sn = su.hypot(sv);
        if sn > radius {
            su *= radius / sn;
            sv *= radius / sn;
        }
        u -= su;
        v -= sv;
        if su.hypot(sv) <= STEP_TOL * 1f64.max(u.hypot(v)) {
            break;
        }
    }
    // Convergence check: the equation holds and the map is locally invertible (det J > 0,
    // as at the image centre) at the solution.
    let ((xu, xv), j) = d.apply(u, v);
    let res = (xu - x0.0).hypot(xv - x0.1);
    let det = j[0] * j[3] - j[1] * j[2];
    // (Running out of iterations is accepted only if this residual test passes anyway.)
    let ok = u.is_finite() && v.is_finite() && res <= RESIDUAL_TOL * scale0 && det > 0.0;
    ok.then_some((u, v))
}

#[cfg(test)]
mod tests;
