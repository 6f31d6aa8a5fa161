//! A camera's projection with its parameters unpacked once ([`Projector`]): the per-point
//! projection (with its Jacobian) that the pixel-space refinement is generic over, and the
//! undistortion of pixels one at a time and in bulk.

use nalgebra::Point2;

use super::distortion::{
    iterative_undistortion, radial_chunk, with_lens, Distortion, Lens, NoDistortion, RADIAL_CHUNK,
};
use super::CameraError;
use crate::numeric::trig::{atan_nonneg, tan_quadrant};

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
/// ([`Camera::projector`](super::Camera::projector)): what the per-point loops of the
/// pixel-space refinement call.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Projector {
    pub(super) focal: (f64, f64),
    pub(super) centre: (f64, f64),
    pub(super) fisheye: bool,
    pub(super) distortion: Distortion,
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

    /// [`Camera::undistort`](super::Camera::undistort): the normalised point of a pixel, and
    /// `det J / (fx fy)`, `J` the Jacobian of [`Projector::project`] at that point (1 without
    /// distortion).
    #[inline]
    pub(crate) fn undistort(&self, pixel: Point2<f64>) -> Result<(Point2<f64>, f64), CameraError> {
        with_lens!(self.distortion, l => self.undistort_with(l, pixel))
    }

    /// [`Camera::undistort_weighted`](super::Camera::undistort_weighted).
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
    /// [`Camera::undistort_weighted`](super::Camera::undistort_weighted) from the Jacobian of the
    /// distortion at the last Newton iterate (the point the convergence check evaluated it at)
    /// and, for the fisheye models, the determinant of the equidistant map in closed form,
    /// `theta / (r (1 + r^2))`, `r = tan theta`.
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

/// The result of [`Camera::undistort_weighted`](super::Camera::undistort_weighted) from that of
/// [`Camera::undistort`](super::Camera::undistort): the weight `|det J|`, or
/// [`CameraError::OutOfRange`] if it is not finite.
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
