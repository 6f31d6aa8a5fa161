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
//! the equidistant projection; `atan` is `numeric::trig::atan_nonneg`, within a few ulp of
//! `f64::atan` and free of calls, so that the per-point loops stay packed) and distort that.
//! `OPENCV_THIN_PRISM_TILTED` adds the thin-prism terms to `D` and then applies OpenCV's
//! projective tilt. [`Camera::undistort`] inverts the distortion (and the tilt) by Newton's
//! method with an analytic Jacobian, a trust region (as COLMAP) and at most
//! 100 iterations; a pixel whose
//! undistortion does not converge is an error, never a silently wrong point. For the radial
//! models the pixel path of the solver runs the same iteration along each pixel's ray, sixteen
//! pixels at a time (`distortion::radial_undistortion`, docs/algorithm.md, `refine`).

use nalgebra::Point2;

mod distortion;
mod model;
mod opencv;
mod projector;

use distortion::{
    tilt_matrix, Distortion, Fisheye, FullOpenCv, NoDistortion, OpenCv, Radial, SimpleRadial,
    ThinPrismTilted,
};
pub use model::{CameraError, CameraModel, SUPPORTED_MODELS};
pub(crate) use projector::{Project, ProjectionJob, Projector};

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
            params: c.params().to_vec(),
        }
    }
}

/// The most parameters of a supported model (`OPENCV_THIN_PRISM_TILTED`'s 18).
pub(crate) const MAX_PARAMS: usize = 18;

/// A camera: model, image size and parameters (validated on construction; with feature
/// `serde`, deserialization validates the same way). The parameters are stored inline, so a
/// camera is `Copy` (a [`crate::Solution`] carries an estimated one).
#[derive(Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(try_from = "CameraFields", into = "CameraFields")
)]
pub struct Camera {
    model: CameraModel,
    width: u64,
    height: u64,
    /// The model's parameters first, zeros after them.
    params: [f64; MAX_PARAMS],
}

impl core::fmt::Debug for Camera {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Camera")
            .field("model", &self.model)
            .field("width", &self.width)
            .field("height", &self.height)
            .field("params", &self.params())
            .finish()
    }
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
        let mut stored = [0.0; MAX_PARAMS];
        stored[..params.len()].copy_from_slice(&params);
        Camera {
            model,
            width,
            height,
            params: stored,
        }
        .validated()
    }

    /// `self` if its focal lengths are positive and its tilt (`OPENCV_THIN_PRISM_TILTED`)
    /// below `pi/2` (finiteness is the caller's check).
    fn validated(self) -> Result<Self, CameraError> {
        let cam = self;
        let (fx, fy) = cam.focal_lengths();
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
        &self.params[..self.model.num_params()]
    }

    /// Focal lengths `(fx, fy)` in pixels (`(f, f)` for single-focal models): the scale from
    /// normalised to pixel residuals, for weighting.
    #[must_use]
    pub fn focal_lengths(&self) -> (f64, f64) {
        let p = &self.params;
        if self.model.single_focal() {
            (p[0], p[0])
        } else {
            (p[0], p[1])
        }
    }

    /// The indices in [`Camera::params`] of the principal point `(cx, cy)` and of the
    /// distortion parameters (all those after the principal point).
    pub(crate) fn intrinsic_groups(&self) -> ([usize; 2], core::ops::Range<usize>) {
        let first = if self.model.single_focal() { 1 } else { 2 };
        ([first, first + 1], first + 2..self.model.num_params())
    }

    /// This camera with the parameters `changed` (of [`Camera::params`]' length), or `None`
    /// if they are not a valid camera ([`Camera::new`]'s checks).
    pub(crate) fn with_params(&self, changed: &[f64]) -> Option<Camera> {
        if changed.len() != self.model.num_params() || changed.iter().any(|p| !p.is_finite()) {
            return None;
        }
        let mut c = *self;
        c.params[..changed.len()].copy_from_slice(changed);
        c.validated().ok()
    }

    /// This camera with its focal length(s) multiplied by `scale` (finite and positive: the
    /// caller's promise), everything else equal.
    pub(crate) fn with_focal_scale(&self, scale: f64) -> Camera {
        let mut c = *self;
        c.params[0] *= scale;
        if !self.model.single_focal() {
            c.params[1] *= scale;
        }
        c
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

    /// The model's distortion, its coefficients copied out of the parameters once.
    fn distortion(&self) -> Distortion {
        let p = &self.params;
        match self.model {
            CameraModel::SimplePinhole | CameraModel::Pinhole => Distortion::None(NoDistortion),
            CameraModel::SimpleRadial | CameraModel::SimpleRadialFisheye => {
                Distortion::SimpleRadial(SimpleRadial([p[3]]))
            }
            CameraModel::Radial | CameraModel::RadialFisheye => {
                Distortion::Radial(Radial([p[3], p[4]]))
            }
            CameraModel::OpenCv => Distortion::OpenCv(OpenCv([p[4], p[5], p[6], p[7]])),
            CameraModel::OpenCvFisheye => Distortion::Fisheye(Fisheye([p[4], p[5], p[6], p[7]])),
            CameraModel::FullOpenCv => {
                let mut k = [0.0; 8];
                k.copy_from_slice(&p[4..12]);
                Distortion::FullOpenCv(FullOpenCv(k))
            }
            CameraModel::OpenCvThinPrismTilted => {
                let mut k = [0.0; 12];
                k.copy_from_slice(&p[4..16]);
                let tilt = (p[16] != 0.0 || p[17] != 0.0).then(|| tilt_matrix(p[16], p[17]));
                Distortion::ThinPrismTilted(ThinPrismTilted { k, tilt })
            }
        }
    }

    /// The camera's projection with its parameters unpacked once, for per-point loops.
    pub(crate) fn projector(&self) -> Projector {
        Projector {
            focal: self.focal_lengths(),
            centre: self.principal_point(),
            fisheye: self.model.is_fisheye(),
            distortion: self.distortion(),
        }
    }

    /// The pixel of a normalised image point `(x/z, y/z)` (COLMAP's `ImgFromCam` with
    /// `w = 1`). Non-finite input gives non-finite output.
    #[must_use]
    pub fn project(&self, normalised: Point2<f64>) -> Point2<f64> {
        let (px, py) = self.projector().project(normalised.x, normalised.y);
        Point2::new(px, py)
    }

    /// The Jacobian `d pixel / d normalised` of [`Camera::project`] at a normalised point,
    /// row-major `[[dpx/dx, dpx/dy], [dpy/dx, dpy/dy]]`, for weighting residuals in pixels.
    #[must_use]
    pub fn project_jacobian(&self, normalised: Point2<f64>) -> [f64; 4] {
        self.projector()
            .project_with_jacobian(normalised.x, normalised.y)
            .1
    }

    /// The normalised image point `(x/z, y/z)` of a pixel: inverts [`Camera::project`].
    ///
    /// The distortion is inverted by Newton's method (analytic Jacobian, COLMAP's trust region)
    /// with at most 100 iterations, followed by a check that the
    /// distortion equation holds to about 1e-13, that the distortion map is locally
    /// invertible at the solution, and that the solution is on the pixel's side of the
    /// principal point (with extreme coefficients a pixel can also have a preimage mirrored
    /// through it; that one is refused).
    ///
    /// # Errors
    /// [`CameraError::NonFinite`] for a NaN or infinite pixel, [`CameraError::NoConvergence`]
    /// if the iteration does not converge, [`CameraError::BeyondHemisphere`] for a fisheye
    /// pixel 90 degrees or more off axis.
    pub fn undistort(&self, pixel: Point2<f64>) -> Result<Point2<f64>, CameraError> {
        self.projector().undistort(pixel).map(|(n, _)| n)
    }

    /// [`Camera::undistort`] and the point's first-order weight in a solve of pixels:
    /// `|det J| / (fx fy)`, `J` the Jacobian of [`Camera::project`] at the normalised point (to
    /// first order, the squared scale of a pixel error in normalised units relative to the
    /// undistorted pinhole camera).
    ///
    /// # Errors
    /// As [`Camera::undistort`], and [`CameraError::OutOfRange`] if the weight overflows.
    #[cfg(test)]
    pub(crate) fn undistort_weighted(
        &self,
        pixel: Point2<f64>,
    ) -> Result<(Point2<f64>, f64), CameraError> {
        self.projector().undistort_weighted(pixel)
    }
}

#[cfg(test)]
#[path = "../../tests/unit/camera.rs"]
mod tests;
