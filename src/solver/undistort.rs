//! The one undistortion path of pixel input: the correspondences checked, their pixels
//! undistorted in bulk, those that cannot be undistorted left out (the pixel-input path of
//! [`Solver`] and of [`crate::ransac::Ransac`]).

use std::borrow::Cow;

use nalgebra::{Point2, Point3};

use super::Solver;
use crate::camera::Camera;
use crate::error::{InputKind, PnpError};
use crate::pipeline::Refinement;

impl Solver {
    /// The pixel-input path of a solve and a refinement of pixels: the loss checked, then the
    /// correspondences undistorted ([`undistort_all`]), with the first-order weights
    /// ([`Undistorted::weights`]) unless `refine_pixels` ends the solve (the default mode, through
    /// a camera with distortion or with a robust loss): `refine_pixels` minimises the pixel error
    /// itself, and the solve on the undistorted points before it only gives its start, from the
    /// caller's weights alone (none: the unweighted passes). Measured on the bundled COLMAP model:
    /// the same `refine_pixels` passes, a solve of pixels 0.898M -> 0.771M instructions per image
    /// (with the weights no longer formed by the undistortion).
    pub(super) fn undistort<'a>(
        &self,
        world: &'a [Point3<f64>],
        pixels: &'a [Point2<f64>],
        camera: &Camera,
        user_weights: Option<&'a [f64]>,
    ) -> Result<Undistorted<'a>, PnpError> {
        self.check_loss()?;
        let first_order =
            !(self.opts.refinement == Refinement::Reprojection && self.refine_pixels_runs(camera));
        undistort_all(world, pixels, camera, user_weights, first_order)
    }
}

/// Pixel correspondences made ready for the solvers by [`undistort_all`]. When every pixel
/// could be undistorted (the usual case) the world points, pixels and caller's weights are the
/// caller's slices, borrowed; otherwise copies of the kept ones.
pub(crate) struct Undistorted<'a> {
    /// The world points of the correspondences whose pixel could be undistorted.
    pub world: Cow<'a, [Point3<f64>]>,
    /// Their normalised image points.
    pub image: Vec<Point2<f64>>,
    /// Their first-order weights (formed only when asked for): `|det J_i| / (fx fy)` times
    /// the caller's weight; `None` when not formed or all exactly 1 (a camera without
    /// distortion and no weights from the caller), so that the solve takes its unweighted
    /// path.
    pub weights: Option<Vec<f64>>,
    /// Their indices in the caller's slices, or `None` when every correspondence is kept.
    pub used: Option<Vec<usize>>,
    /// Their pixels.
    pub pixels: Cow<'a, [Point2<f64>]>,
    /// Their weights given by the caller (`None`: all 1).
    pub user_weights: Option<Cow<'a, [f64]>>,
    /// The residual row weights `(fx^2, fy^2) / max(fx, fy)^2`.
    pub rows: (f64, f64),
    /// The camera's focal lengths `(fx, fy)`, pixels.
    pub focal: (f64, f64),
}

impl Undistorted<'_> {
    /// The weights of the solve on the undistorted points: the first-order weights if formed,
    /// else the caller's.
    pub fn solve_weights(&self) -> Option<&[f64]> {
        self.weights.as_deref().or(self.user_weights.as_deref())
    }

    /// The index in the caller's slices of kept correspondence `k`.
    pub fn index(&self, k: usize) -> usize {
        self.used.as_ref().map_or(k, |u| u[k])
    }
}

/// Undistorts pixel correspondences (the pixel-input path of [`Solver`] and of
/// [`crate::ransac::Ransac`]): checks the lengths and the caller's weights (their errors carry
/// the correspondence's index), then keeps every correspondence whose pixel can be
/// undistorted, with its first-order weight if `first_order`. Buffers are sized once; the
/// world points, pixels and caller's weights are copied only from the first pixel that cannot
/// be undistorted on.
pub(crate) fn undistort_all<'a>(
    world: &'a [Point3<f64>],
    pixels: &'a [Point2<f64>],
    camera: &Camera,
    user_weights: Option<&'a [f64]>,
    first_order: bool,
) -> Result<Undistorted<'a>, PnpError> {
    if world.len() != pixels.len() {
        return Err(PnpError::LengthMismatch {
            world: world.len(),
            image: pixels.len(),
        });
    }
    if let Some(uw) = user_weights {
        if uw.len() != world.len() {
            return Err(PnpError::WeightsLength {
                weights: uw.len(),
                points: world.len(),
            });
        }
        for (index, w) in uw.iter().enumerate() {
            if !w.is_finite() {
                return Err(PnpError::NonFinite {
                    index,
                    input: InputKind::Weight,
                });
            }
            if *w < 0.0 {
                return Err(PnpError::InvalidWeight { index });
            }
        }
    }
    let n = world.len();
    let focal = camera.focal_lengths();
    let (fx, fy) = focal;
    let fmax = fx.max(fy);
    let rows = ((fx / fmax).powi(2), (fy / fmax).powi(2));
    // Every pixel undistorted in bulk into buffers of size `n` (with `|det J| / (fx fy)` into
    // `weights` when the first-order weights are formed); the indices of the pixels left out,
    // in order (no allocation when there is none, the usual case).
    let mut image = vec![Point2::origin(); n];
    let mut weights =
        (first_order && (camera.has_distortion() || user_weights.is_some())).then(|| vec![0.0; n]);
    let mut failed: Vec<usize> = Vec::new();
    camera
        .projector()
        .undistort_into(pixels, &mut image, weights.as_deref_mut(), |i| {
            failed.push(i)
        });
    // The first-order weights times the caller's, checked in order.
    if let Some(w) = weights.as_mut() {
        let mut bad = None;
        for_kept(n, &failed, |i| {
            let weight = user_weights.map_or(w[i], |uw| uw[i] * w[i]);
            w[i] = weight;
            if bad.is_none() && !weight.is_finite() {
                bad = Some(i);
            }
        });
        if let Some(index) = bad {
            return Err(PnpError::NonFinite {
                index,
                input: InputKind::Weight,
            });
        }
    }
    if failed.is_empty() {
        return Ok(Undistorted {
            world: Cow::Borrowed(world),
            image,
            weights,
            used: None,
            pixels: Cow::Borrowed(pixels),
            user_weights: user_weights.map(Cow::Borrowed),
            rows,
            focal,
        });
    }
    // Some pixels left out: the kept correspondences copied, the buffers compacted.
    let m = n - failed.len();
    let mut used = Vec::with_capacity(m);
    for_kept(n, &failed, |i| used.push(i));
    fn pick<T: Copy>(s: &[T], used: &[usize]) -> Vec<T> {
        used.iter().map(|&i| s[i]).collect()
    }
    let kept_world = pick(world, &used);
    let kept_pixels = pick(pixels, &used);
    let kept_user = user_weights.map(|uw| pick(uw, &used));
    for (k, &i) in used.iter().enumerate() {
        image[k] = image[i];
        if let Some(w) = weights.as_mut() {
            w[k] = w[i];
        }
    }
    image.truncate(m);
    if let Some(w) = weights.as_mut() {
        w.truncate(m);
    }
    Ok(Undistorted {
        world: Cow::Owned(kept_world),
        image,
        weights,
        used: Some(used),
        pixels: Cow::Owned(kept_pixels),
        user_weights: kept_user.map(Cow::Owned),
        rows,
        focal,
    })
}

/// `each(i)` for every index `i` in `0..n` that is not in `skip` (ascending), in order.
fn for_kept(n: usize, skip: &[usize], mut each: impl FnMut(usize)) {
    let mut skip = skip.iter().copied().peekable();
    for i in 0..n {
        if skip.next_if_eq(&i).is_none() {
            each(i);
        }
    }
}
