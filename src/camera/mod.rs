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

use crate::numeric::trig::{atan_nonneg, tan_quadrant};

mod distortion;
mod model;
mod opencv;

use distortion::{
    iterative_undistortion, radial_chunk, tilt_matrix, with_lens, Distortion, Fisheye, FullOpenCv,
    Lens, NoDistortion, OpenCv, Radial, SimpleRadial, ThinPrismTilted, RADIAL_CHUNK,
};
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
        &self.params
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

/// A projection from normalised points to pixels with its Jacobian: what the per-point loop of
/// the pixel-space refinement (`refine_pixels`) is generic over.
pub(crate) trait Project {
    /// The pixel of the normalised point `(x, y)`.
    fn project(&self, x: f64, y: f64) -> (f64, f64);
    /// The pixel of the normalised point `(x, y)` and the Jacobian `d pixel / d (x, y)`,
    /// row-major.
    fn project_with_jacobian(&self, x: f64, y: f64) -> ((f64, f64), [f64; 4]);
}

/// Code generic over the projection ([`Projector::with_projection`]).
pub(crate) trait ProjectionJob {
    type Output;
    fn run<P: Project + Copy>(self, projection: P) -> Self::Output;
}

/// A projection with one lens model: the per-point code of [`Projector`] without the dispatch.
/// `FISHEYE`: the equidistant map comes first (a compile-time choice, so that the per-point
/// code has no branch on the model).
#[derive(Clone, Copy)]
pub(crate) struct LensProjection<L, const FISHEYE: bool> {
    focal: (f64, f64),
    centre: (f64, f64),
    lens: L,
}

/// The pixel of the normalised point `(x, y)` through `p` (no Jacobian).
#[inline(always)]
fn project_one<L: Lens, const FISHEYE: bool>(
    p: &LensProjection<L, FISHEYE>,
    x: f64,
    y: f64,
) -> (f64, f64) {
    let (mut u, mut v) = (x, y);
    if FISHEYE {
        let r = (x * x + y * y).sqrt();
        if r > f64::EPSILON {
            let s = atan_nonneg(r) / r;
            u *= s;
            v *= s;
        }
    }
    let ([xd, yd], _, _) = p.lens.apply(u, v);
    (p.focal.0 * xd + p.centre.0, p.focal.1 * yd + p.centre.1)
}

/// `body` with `$p` bound to the [`LensProjection`] of the projector `$proj`: the model (lens
/// and fisheye map) dispatched once.
macro_rules! with_lens_projection {
    ($proj:expr, $p:ident => $body:expr) => {{
        let pr = &$proj;
        let (focal, centre) = (pr.focal, pr.centre);
        if pr.fisheye {
            with_lens!(pr.distortion, lens => {
                let $p = LensProjection::<_, true> { focal, centre, lens };
                $body
            })
        } else {
            with_lens!(pr.distortion, lens => {
                let $p = LensProjection::<_, false> { focal, centre, lens };
                $body
            })
        }
    }};
}

impl<L: Lens, const FISHEYE: bool> Project for LensProjection<L, FISHEYE> {
    #[inline(always)]
    fn project(&self, x: f64, y: f64) -> (f64, f64) {
        project_one(self, x, y)
    }

    #[inline(always)]
    fn project_with_jacobian(&self, x: f64, y: f64) -> ((f64, f64), [f64; 4]) {
        let (fx, fy) = self.focal;
        // Fisheye models: chain rule through (u, v) = s(r) (x, y), s = atan(r) / r.
        let (u, v, jf) = if FISHEYE {
            let r2 = x * x + y * y;
            let r = r2.sqrt();
            if r > 1e-8 {
                let at = atan_nonneg(r);
                let s = at / r;
                // ds/dr = (r / (1 + r^2) - atan r) / r^2; d(s x)/dx = s + x^2 s'(r) / r.
                let q = (r / (1.0 + r2) - at) / (r2 * r);
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
        let ([xd, yd], jd, _) = self.lens.apply(u, v);
        let m = [
            jd[0] * jf[0] + jd[1] * jf[2],
            jd[0] * jf[1] + jd[1] * jf[3],
            jd[2] * jf[0] + jd[3] * jf[2],
            jd[2] * jf[1] + jd[3] * jf[3],
        ];
        (
            (fx * xd + self.centre.0, fy * yd + self.centre.1),
            [fx * m[0], fx * m[1], fy * m[2], fy * m[3]],
        )
    }
}

/// A camera's projection, normalised point to pixel, with the parameters unpacked once
/// ([`Camera::projector`]): what the per-point loops of the pixel-space refinement call.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Projector {
    focal: (f64, f64),
    centre: (f64, f64),
    fisheye: bool,
    distortion: Distortion,
}

impl Projector {
    /// The identity: a pinhole camera with unit focal lengths at the origin (normalised
    /// coordinates are its pixels).
    pub(crate) fn identity() -> Projector {
        Projector {
            focal: (1.0, 1.0),
            centre: (0.0, 0.0),
            fisheye: false,
            distortion: Distortion::None(NoDistortion),
        }
    }

    /// The pixel of the normalised point `(x, y)`.
    #[inline]
    pub(crate) fn project(&self, x: f64, y: f64) -> (f64, f64) {
        with_lens_projection!(self, p => project_one(&p, x, y))
    }

    /// The pixel of the normalised point `(x, y)` and the Jacobian `d pixel / d (x, y)`,
    /// row-major.
    #[inline]
    pub(crate) fn project_with_jacobian(&self, x: f64, y: f64) -> ((f64, f64), [f64; 4]) {
        with_lens_projection!(self, p => p.project_with_jacobian(x, y))
    }

    /// Runs `job` with this projection's lens model fixed at compile time (the model
    /// dispatched once, not per point).
    pub(crate) fn with_projection<J: ProjectionJob>(&self, job: J) -> J::Output {
        with_lens_projection!(self, p => job.run(p))
    }

    /// [`Camera::undistort`]: the normalised point of a pixel, and `det J / (fx fy)`, `J` the
    /// Jacobian of [`Projector::project`] at that point (1 without distortion).
    #[inline]
    pub(crate) fn undistort(&self, pixel: Point2<f64>) -> Result<(Point2<f64>, f64), CameraError> {
        with_lens!(self.distortion, l => self.undistort_with(l, pixel))
    }

    /// [`Camera::undistort_weighted`].
    #[cfg(test)]
    #[inline]
    pub(crate) fn undistort_weighted(
        &self,
        pixel: Point2<f64>,
    ) -> Result<(Point2<f64>, f64), CameraError> {
        with_lens!(self.distortion, l => self.undistort_weighted_with(l, pixel))
    }

    /// Every pixel through [`Projector::undistort_weighted`] with the model dispatched once,
    /// in bulk: entry `i` of `out` (and of `weights`, when given) becomes pixel `i`'s point
    /// (and weight); `failed(i)` is called, in order, for each pixel that has none (any error
    /// of `undistort_weighted`), whose entries are then unspecified. `out` and `weights` are
    /// as long as `pixels`.
    pub(crate) fn undistort_into(
        &self,
        pixels: &[Point2<f64>],
        out: &mut [Point2<f64>],
        weights: Option<&mut [f64]>,
        failed: impl FnMut(usize),
    ) {
        debug_assert_eq!(out.len(), pixels.len());
        match weights {
            Some(w) => {
                debug_assert_eq!(w.len(), pixels.len());
                with_lens!(self.distortion, l => self.undistort_into_with(l, pixels, out, w, failed));
            }
            None => with_lens!(self.distortion, l => {
                self.undistort_into_with(l, pixels, out, Discard, failed)
            }),
        }
    }

    /// [`Projector::undistort_into`] for one lens. A radial lens ([`Lens::RADIAL`])
    /// undistorts its pixels sixteen at a time along their rays (`radial_chunk`: the same
    /// iterates in exact arithmetic), and a pixel whose iteration it leaves undecided goes
    /// through [`Projector::undistort_weighted_with`].
    #[inline(always)]
    fn undistort_into_with<L: Lens, W: WeightSink>(
        &self,
        lens: L,
        pixels: &[Point2<f64>],
        out: &mut [Point2<f64>],
        mut weights: W,
        mut failed: impl FnMut(usize),
    ) {
        let n = pixels.len().min(out.len());
        let (pixels, out) = (&pixels[..n], &mut out[..n]);
        if L::IDENTITY && !self.fisheye {
            // No distortion: the affine map alone, with undistort_with's outcome (a pixel or
            // a result that is not finite gives none; the weight is 1).
            let ((fx, fy), (cx, cy)) = (self.focal, self.centre);
            for (i, (px, o)) in pixels.iter().zip(out.iter_mut()).enumerate() {
                let (u, v) = ((px.x - cx) / fx, (px.y - cy) / fy);
                if u.is_finite() && v.is_finite() {
                    *o = Point2::new(u, v);
                    weights.set(i, 1.0);
                } else {
                    failed(i);
                }
            }
            return;
        }
        // One pixel through the one-pixel path.
        let one = |i: usize,
                   px: Point2<f64>,
                   o: &mut Point2<f64>,
                   weights: &mut W,
                   failed: &mut dyn FnMut(usize)| {
            match self.undistort_weighted_with(lens, px) {
                Ok((m, w)) => {
                    *o = m;
                    weights.set(i, w);
                }
                Err(_) => failed(i),
            }
        };
        if !L::RADIAL {
            for (i, (px, o)) in pixels.iter().zip(out.iter_mut()).enumerate() {
                one(i, *px, o, &mut weights, &mut failed);
            }
            return;
        }
        let mut dets = [0.0; RADIAL_CHUNK];
        for (c, (chunk, outs)) in pixels
            .chunks(RADIAL_CHUNK)
            .zip(out.chunks_mut(RADIAL_CHUNK))
            .enumerate()
        {
            let mut undecided = if self.fisheye {
                radial_chunk::<L, true>(&lens, self.focal, self.centre, chunk, outs, &mut dets)
            } else {
                radial_chunk::<L, false>(&lens, self.focal, self.centre, chunk, outs, &mut dets)
            };
            let i0 = c * RADIAL_CHUNK;
            // weight_of's outcome: the weight |det J| (finite where the lane decided).
            for (j, d) in dets.iter().take(chunk.len()).enumerate() {
                weights.set(i0 + j, d.abs());
            }
            while undecided != 0 {
                let j = undecided.trailing_zeros() as usize;
                undecided &= undecided - 1;
                one(i0 + j, chunk[j], &mut outs[j], &mut weights, &mut failed);
            }
        }
    }

    /// [`Projector::undistort_weighted`] for one lens: the weight `|det J| / (fx fy)` of
    /// [`Camera::undistort_weighted`] from the Jacobian of the distortion at the last Newton
    /// iterate (the point the convergence check evaluated it at) and, for the fisheye models,
    /// the determinant of the equidistant map in closed form, `theta / (r (1 + r^2))`,
    /// `r = tan theta`.
    #[inline(always)]
    fn undistort_weighted_with<L: Lens>(
        &self,
        lens: L,
        pixel: Point2<f64>,
    ) -> Result<(Point2<f64>, f64), CameraError> {
        let (n, det) = self.undistort_with(lens, pixel)?;
        weight_of(pixel, n, det)
    }

    /// [`Projector::undistort`] for one lens; the second value is `det J / (fx fy)`, `J` the
    /// Jacobian of the projection at the normalised point.
    #[inline(always)]
    fn undistort_with<L: Lens>(
        &self,
        lens: L,
        pixel: Point2<f64>,
    ) -> Result<(Point2<f64>, f64), CameraError> {
        if !(pixel.x.is_finite() && pixel.y.is_finite()) {
            return Err(CameraError::NonFinite);
        }
        let (fx, fy) = self.focal;
        let (cx, cy) = self.centre;
        let x0 = ((pixel.x - cx) / fx, (pixel.y - cy) / fy);
        let (uv, det) = if L::IDENTITY {
            (x0, 1.0)
        } else {
            iterative_undistortion(&lens, x0).ok_or(CameraError::NoConvergence {
                pixel: (pixel.x, pixel.y),
            })?
        };
        let (u, v) = uv;
        if !(u.is_finite() && v.is_finite()) {
            return Err(CameraError::OutOfRange {
                pixel: (pixel.x, pixel.y),
            });
        }
        if !self.fisheye {
            return Ok((Point2::new(u, v), det));
        }
        // Equidistant fisheye: theta = |(u, v)|, normalised radius r = tan(theta); the map
        // (x, y) -> theta / r (x, y) has determinant theta / (r (1 + r^2)).
        let theta = (u * u + v * v).sqrt();
        if theta >= core::f64::consts::FRAC_PI_2 {
            return Err(CameraError::BeyondHemisphere {
                pixel: (pixel.x, pixel.y),
            });
        }
        if theta > f64::EPSILON {
            let r = tan_quadrant(theta);
            let s = r / theta;
            Ok((Point2::new(u * s, v * s), det / (s * (1.0 + r * r))))
        } else {
            Ok((Point2::new(u, v), det))
        }
    }
}

/// Where [`Projector::undistort_into`] puts the weights: a slice, or nowhere.
trait WeightSink {
    fn set(&mut self, i: usize, w: f64);
}

/// No weights asked for.
struct Discard;

impl WeightSink for Discard {
    #[inline(always)]
    fn set(&mut self, _: usize, _: f64) {}
}

impl WeightSink for &mut [f64] {
    #[inline(always)]
    fn set(&mut self, i: usize, w: f64) {
        self[i] = w;
    }
}

/// The result of [`Camera::undistort_weighted`] from that of [`Camera::undistort`]: the
/// weight `|det J|`, or [`CameraError::OutOfRange`] if it is not finite.
#[inline(always)]
fn weight_of(
    pixel: Point2<f64>,
    n: Point2<f64>,
    det: f64,
) -> Result<(Point2<f64>, f64), CameraError> {
    let w = det.abs();
    if w.is_finite() {
        Ok((n, w))
    } else {
        Err(CameraError::OutOfRange {
            pixel: (pixel.x, pixel.y),
        })
    }
}

#[cfg(test)]
#[path = "../../tests/unit/camera.rs"]
mod tests;
