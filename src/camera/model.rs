//! The supported COLMAP camera models (names, ids, parameter counts) and the errors of
//! building a camera and of undistorting a pixel.

use core::fmt;

/// A camera model: COLMAP's models, and OpenCV's full perspective model
/// ([`CameraModel::OpenCvThinPrismTilted`], not a COLMAP model).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(into = "&'static str", try_from = "String")
)]
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
    /// `fx, fy, cx, cy, k1, k2, p1, p2, k3, k4, k5, k6, s1, s2, s3, s4, tau_x, tau_y`:
    /// OpenCV's full perspective model (`cv2.projectPoints` with 14 distortion coefficients:
    /// rational radial, tangential, thin-prism and tilted-sensor terms; the tilt angles in
    /// radians, `|tau| < pi/2`).
    ///
    /// **Not a COLMAP model**: it has no COLMAP id ([`CameraModel::colmap_id`] is `None`),
    /// COLMAP's readers never produce it, [`CameraModel::from_name`] does not accept its name
    /// `"OPENCV_THIN_PRISM_TILTED"` (parsing with [`str::parse`] does), and
    /// [`crate::colmap::write_model`] refuses it. Built by
    /// [`crate::camera::Camera::from_opencv`] for 12 and 14 coefficients.
    ///
    /// The map is OpenCV's: the distortion `(u, v) + D(u, v)` of the rational model plus
    /// `(s1 r^2 + s2 r^4, s3 r^2 + s4 r^4)`, then the projective tilt `(a, b) -> (X/W, Y/W)`,
    /// `(X, Y, W) = T (a, b, 1)` with OpenCV's `computeTiltProjectionMatrix(tau_x, tau_y)`.
    OpenCvThinPrismTilted,
}

/// Every supported COLMAP model, in COLMAP id order (all models except
/// [`CameraModel::OpenCvThinPrismTilted`], which is not a COLMAP model).
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
    /// COLMAP's name of the model, e.g. `"SIMPLE_RADIAL"` (for
    /// [`CameraModel::OpenCvThinPrismTilted`], this crate's name `"OPENCV_THIN_PRISM_TILTED"`).
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
            CameraModel::OpenCvThinPrismTilted => "OPENCV_THIN_PRISM_TILTED",
        }
    }

    /// COLMAP's numeric model id (used by the binary model format); `None` for
    /// [`CameraModel::OpenCvThinPrismTilted`], which is not a COLMAP model.
    ///
    /// ```
    /// use eopnp::camera::CameraModel;
    /// assert_eq!(CameraModel::FullOpenCv.colmap_id(), Some(6));
    /// assert_eq!(CameraModel::OpenCvThinPrismTilted.colmap_id(), None);
    /// ```
    #[must_use]
    pub fn colmap_id(self) -> Option<i32> {
        match self {
            CameraModel::SimplePinhole => Some(0),
            CameraModel::Pinhole => Some(1),
            CameraModel::SimpleRadial => Some(2),
            CameraModel::Radial => Some(3),
            CameraModel::OpenCv => Some(4),
            CameraModel::OpenCvFisheye => Some(5),
            CameraModel::FullOpenCv => Some(6),
            CameraModel::SimpleRadialFisheye => Some(8),
            CameraModel::RadialFisheye => Some(9),
            CameraModel::OpenCvThinPrismTilted => None,
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
            CameraModel::OpenCvThinPrismTilted => 18,
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
            CameraModel::OpenCvThinPrismTilted => {
                "fx, fy, cx, cy, k1, k2, p1, p2, k3, k4, k5, k6, s1, s2, s3, s4, tau_x, tau_y"
            }
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
            .find(|m| m.colmap_id() == Some(id))
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

    pub(super) fn is_fisheye(self) -> bool {
        matches!(
            self,
            CameraModel::OpenCvFisheye
                | CameraModel::SimpleRadialFisheye
                | CameraModel::RadialFisheye
        )
    }

    /// Whether the model has a single focal length `f`.
    pub(super) fn single_focal(self) -> bool {
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

/// Parses [`CameraModel::name`]: COLMAP's names (as [`CameraModel::from_name`]) and
/// `"OPENCV_THIN_PRISM_TILTED"`, so that `model.to_string().parse()` gives `model` back.
impl core::str::FromStr for CameraModel {
    type Err = CameraError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        if s == CameraModel::OpenCvThinPrismTilted.name() {
            return Ok(CameraModel::OpenCvThinPrismTilted);
        }
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
    /// 100 Newton iterations, or converged to a point where the
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
                // The name as read, with control and other invisible characters escaped.
                write!(
                    f,
                    "unsupported camera model \"{}\" (supported: {})",
                    name.escape_debug(),
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

/// The model's name (serialized form).
impl From<CameraModel> for &'static str {
    fn from(m: CameraModel) -> Self {
        m.name()
    }
}

/// A model from its name, as [`core::str::FromStr`] parses it (serialized form).
impl TryFrom<String> for CameraModel {
    type Error = CameraError;
    fn try_from(s: String) -> Result<Self, CameraError> {
        s.parse()
    }
}
