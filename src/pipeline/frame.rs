//! The `frame` stage of docs/algorithm.md: input validation and the normalised working frame.
//!
//! | symbol | meaning |
//! |---|---|
//! | `X_i`, `m_i`, `w_i` | world point, image point (normalised), weight (1 without weights) |
//! | `c` | weighted centroid `sum w_i X_i / sum w_i` |
//! | `Pc_i` | `X_i - c` |
//! | `Rw` | right singular vectors (rows) of the matrix with rows `sqrt(w_i) Pc_i^T` |
//! | `d` | weighted RMS distance `sqrt(sum w_i |Pc_i|^2 / sum w_i)` |
//! | `P_i` | working-frame point `Rw Pc_i / d` (centred, principal axes, unit RMS) |
//! | `ratio` | `sv2 / sv0` (planarity; plane normal = working-frame z) |
//!
//! Cost: two O(N) passes, no allocation. Pass 1 validates the input and forms the raw weighted sums
//! of the centroid and the ranges; pass 2 ([`crate::pipeline::moments::accumulate_centred`]) forms,
//! in the centred but unrotated points `Y = X - c`, every `moments` sum (their `sum w Y Y^T` is the
//! scatter matrix) and the image spread. `Rw` is then the eigenvector matrix of the scatter
//! ([`sym_eigen3_closed`], closed form; the third pass below uses [`sym_eigen3`], cyclic Jacobi
//! with a sweep bound, for its relative accuracy), and the sums are carried to the working frame
//! exactly (they are linear and quadratic in `P = Rw Y / d`): the `moments` sums come out of
//! `frame` ([`WorkingFrame::sums`]).
//!
//! Trap T9: the scatter's eigenvalues are the squared singular values, so it resolves
//! `sv1 / sv0` and `sv2 / sv0` only down to about `sqrt(eps)`; and in a nearly planar (or
//! collinear) cloud the rotated sums of the small coordinates would carry absolute errors
//! `eps |S|` instead of errors relative to themselves. So the fast path is taken only when
//! `sv2 / sv0 >= 1e-2` by the scatter (`lambda2 >= 1e-4 lambda0`, far from every threshold:
//! collinear 1e-8, planar 1e-6 and 1e-3). Otherwise a third pass accumulates the sums of the
//! points rotated by the scatter's axes (`P' = Rw0 Y / d`), in which each small coordinate is
//! computed directly, with an error relative to the point (as the streamed QR did): the
//! scatter `S'` of that pass is diagonal up to `eps |S|` off-diagonal entries, its Jacobi
//! eigen-decomposition `S' = Q L Q^T` is accurate relative to each eigenvalue (a scaled
//! diagonally dominant matrix), so `sv_k = sqrt(L_k)` resolves the collinearity threshold
//! like an SVD of the points, and `Rw = Q^T Rw0` with the sums carried by `Q^T`, a rotation
//! within the blocks of comparable axes, keeps that accuracy. (The previous three-pass
//! implementation with a streamed Givens QR is kept as the tests' reference,
//! `working_frame_qr`.)
//!
//! Range safety: world coordinates, image coordinates and weights are divided by exact powers
//! of two near their largest magnitudes before any square is formed, so inputs from ~1e-300 to
//! ~1e300 give the same frame (up to the exact power-of-two factors) and nothing overflows.
//! Inputs whose normalisation would overflow (|X| above about 4e307) or whose spread is below
//! the normal `f64` range are rejected with [`DegenerateKind::ScaleOutOfRange`].
//!
//! Weights: a point with `w_i = 0` is skipped by every pass (it is still checked for
//! finiteness), so it gives results bit-identical to removing it.

use nalgebra::{Matrix3, Point2, Point3, Vector2, Vector3};

use super::moments::{accumulate_centred, Accumulator, CentredMap};
use crate::error::{DegenerateKind, InputKind, PnpError};
use crate::numeric::mat3::{pow2_scale, sym_eigen3, sym_eigen3_closed};

/// Fast path of `frame`: the frame comes from the scatter when `lambda2 >= SCATTER_MIN * lambda0`
/// (`sv2 / sv0 >= 1e-2`; see the module documentation, trap T9).
const SCATTER_MIN: f64 = 1e-4;
/// Raw (unscaled) pass-1 sums are used only when the world and image ranges are at most
/// `2^RAW_RANGE` and the largest weight within `2^-RAW_RANGE ..= 2^RAW_RANGE`: then no term or
/// partial sum over- or underflows for any N < 2^60, and the sums equal the power-of-two scaled
/// ones times the exact unit (identical frames under power-of-two scaling). Else a rescan in
/// scaled units.
const RAW_RANGE: i32 = 480;
/// Smallest power-of-two unit (2^-1000): its reciprocal is finite.
pub(crate) const MIN_UNIT: f64 = 9.332636185032189e-302;

/// Minimum number of correspondences (with a weight > 0).
pub(crate) const MIN_POINTS: usize = 4;
/// A weight at or below `NEGLIGIBLE_WEIGHT` times the largest weight cannot change any
/// weighted sum at f64 precision (2^-52), so such a point does not count towards
/// [`MIN_POINTS`] (it is still used).
pub(crate) const NEGLIGIBLE_WEIGHT: f64 = f64::EPSILON;
/// `frame` collinearity test: collinear if `sv1 <= COLLINEAR_TOL * sv0`.
pub(crate) const COLLINEAR_TOL: f64 = 1e-8;
/// `frame` image-spread test: coincident unless `spread > IMAGE_SPREAD_TOL * max(1, max |m|)`.
pub(crate) const IMAGE_SPREAD_TOL: f64 = 1e-12;
/// `frame` small-image test: the pose is flagged degenerate when
/// `spread <= SMALL_IMAGE_TOL * max(1, max |m|)`. The perspective effects that fix the
/// rotation (beyond the weak-perspective reflection ambiguity) are of relative size `spread`
/// in the image, and the rounding of the image coordinates is `eps max |m| / spread` relative
/// to it; below this bound their ratio, `spread^2 / (eps max |m|)`, is under about 4,500,
/// where noise-free patterns shrunk towards one point start to give wrong poses at ratios of
/// about 15 (`tests/tiny_image.rs`).
pub(crate) const SMALL_IMAGE_TOL: f64 = 1e-6;

/// The normalised working frame of `frame`: `P = Rw (X - c) / d`.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct WorkingFrame {
    /// Weighted centroid of the world points.
    pub c: Vector3<f64>,
    /// Weighted RMS distance of the world points to `c` (> 0, a normal f64).
    pub d: f64,
    /// Principal axes as rows (singular values descending, det +1); identity if not aligned.
    pub rw: Matrix3<f64>,
    /// Planarity `sv2 / sv0` (computed even when not aligned).
    pub ratio: f64,
    /// The image spread is below [`SMALL_IMAGE_TOL`]: too small, at f64 resolution, to fix
    /// the pose (flagged as degenerate).
    pub small_image: bool,
    /// Number of correspondences with a weight > 0 (N without weights).
    pub n_active: usize,
    /// The weight unit: a power of two near the largest weight (1 without weights). Later
    /// stages use `w_i / weight_unit` (an exact scaling, largest value in `[1, 2)`), so that
    /// no weighted sum over- or underflows and a common scale of the weights changes nothing
    /// but the reported cost.
    pub weight_unit: f64,
    /// `sum w_i / weight_unit` over the active points.
    pub weight_sum: f64,
    /// The `moments` sums of the same input in this frame (`P = Rw (X - c) / d`, weights
    /// `w / weight_unit`): equal, up to rounding, to [`crate::pipeline::moments::accumulate`]
    /// with this frame, divided by `weight_unit`.
    pub sums: Accumulator,
}

impl WorkingFrame {
    /// World point to the working frame: `Rw (x - c) / d`.
    #[inline]
    pub(crate) fn to_working(&self, x: &Point3<f64>) -> Vector3<f64> {
        (self.rw * (x.coords - self.c)) * (1.0 / self.d)
    }

    /// `select`'s depth rule: `count` points in front are more than half of the active points.
    #[inline]
    pub(crate) fn most_in_front(&self, count: usize) -> bool {
        2 * count > self.n_active
    }

    /// Working-frame pose to the world pose (`output`): `(R Rw, d t - R Rw c)`.
    ///
    /// Both poses give the same projection of every point. The result can overflow only if
    /// the world coordinates themselves are near the f64 limit; callers check finiteness.
    pub(crate) fn to_world(
        &self,
        r_work: &Matrix3<f64>,
        t_work: &Vector3<f64>,
    ) -> (Matrix3<f64>, Vector3<f64>) {
        let r = r_work * self.rw;
        let t = t_work * self.d - r * self.c;
        (r, t)
    }
}

/// Weight of point `i` (1 without weights).
#[inline]
fn weight(weights: Option<&[f64]>, i: usize) -> f64 {
    match weights {
        Some(w) => w[i],
        None => 1.0,
    }
}

/// `max(a, b)` for non-NaN inputs (compiles to a plain max instruction).
#[inline(always)]
fn fmax(a: f64, b: f64) -> f64 {
    if a > b {
        a
    } else {
        b
    }
}

/// Result of the fused validation / centroid pass.
struct Scan {
    /// Number of points with `w > 0`.
    n_active: usize,
    /// Largest `|X_k|`, `|m_k|`, `w` over the active points.
    xmax: f64,
    mmax: f64,
    wmax: f64,
    /// Smallest weight > 0 (`wmax` without weights).
    wmin: f64,
    /// Raw sums `sum w`, `sum w X`, `sum w m` (all points; `w = 0` adds exact zeros).
    wsum: f64,
    xsum: Vector3<f64>,
    msum: Vector2<f64>,
    /// Some weight is negative.
    negative: bool,
}

/// Pass 1 (`W`: weights present): ranges over the active points and the raw weighted sums.
/// Any non-finite input makes a sum non-finite (`0 * inf` and `inf - inf` are NaN), so
/// finiteness is checked on the sums, and the exact index scan runs only then.
#[inline(always)]
fn scan<const W: bool>(world: &[Point3<f64>], image: &[Point2<f64>], weights: &[f64]) -> Scan {
    let n = world.len().min(image.len());
    let mut out = Scan {
        n_active: 0,
        xmax: 0.0,
        mmax: 0.0,
        wmax: 0.0,
        wmin: 0.0,
        wsum: 0.0,
        xsum: Vector3::zeros(),
        msum: Vector2::zeros(),
        negative: false,
    };
    let (mut sx, mut sy, mut sz, mut su, mut sv, mut sw) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    let (mut xmax, mut mmax, mut wmax) = (0.0f64, 0.0f64, 0.0f64);
    let mut wmin = f64::INFINITY;
    let mut n_active = 0usize;
    let mut negative = false;
    for i in 0..n {
        let x = &world[i];
        let m = &image[i];
        let ax = fmax(fmax(x.x.abs(), x.y.abs()), x.z.abs());
        let am = fmax(m.x.abs(), m.y.abs());
        if W {
            let w = weights[i];
            negative |= w < 0.0;
            if w > 0.0 {
                n_active += 1;
                xmax = fmax(xmax, ax);
                mmax = fmax(mmax, am);
                wmax = fmax(wmax, w);
                wmin = wmin.min(w);
            }
            sw += w;
            sx += w * x.x;
            sy += w * x.y;
            sz += w * x.z;
            su += w * m.x;
            sv += w * m.y;
        } else {
            xmax = fmax(xmax, ax);
            mmax = fmax(mmax, am);
            sx += x.x;
            sy += x.y;
            sz += x.z;
            su += m.x;
            sv += m.y;
        }
    }
    if !W {
        n_active = n;
        wmax = 1.0;
        wmin = 1.0;
        sw = n as f64;
    }
    out.n_active = n_active;
    out.xmax = xmax;
    out.mmax = mmax;
    out.wmax = wmax;
    out.wmin = wmin;
    out.wsum = sw;
    out.xsum = Vector3::new(sx, sy, sz);
    out.msum = Vector2::new(su, sv);
    out.negative = negative;
    out
}

/// The first invalid input in the documented order: non-finite coordinates or weights (index
/// by index, world before image before weight), then the first negative weight.
fn first_invalid(
    world: &[Point3<f64>],
    image: &[Point2<f64>],
    weights: Option<&[f64]>,
) -> Option<PnpError> {
    let mut first_negative: Option<usize> = None;
    for i in 0..world.len().min(image.len()) {
        let x = &world[i];
        if !(x.x.is_finite() && x.y.is_finite() && x.z.is_finite()) {
            return Some(PnpError::NonFinite {
                index: i,
                input: InputKind::World,
            });
        }
        let m = &image[i];
        if !(m.x.is_finite() && m.y.is_finite()) {
            return Some(PnpError::NonFinite {
                index: i,
                input: InputKind::Image,
            });
        }
        let w = weight(weights, i);
        if !w.is_finite() {
            return Some(PnpError::NonFinite {
                index: i,
                input: InputKind::Weight,
            });
        }
        if w < 0.0 && first_negative.is_none() {
            first_negative = Some(i);
        }
    }
    first_negative.map(|index| PnpError::InvalidWeight { index })
}

/// `frame`: validate the input and compute the working frame, with the `moments` sums in it.
///
/// Checks, in this order (the first failing one is reported): lengths of world and image
/// ([`PnpError::LengthMismatch`]); length of the weights ([`PnpError::WeightsLength`]);
/// N >= 4 ([`PnpError::TooFewPoints`] with `got = N`); every coordinate and weight finite,
/// scanning index by index, world before image before weight ([`PnpError::NonFinite`]); no
/// negative weight ([`PnpError::InvalidWeight`]); at least 4 points with a weight > 0, then
/// at least 4 with a weight above [`NEGLIGIBLE_WEIGHT`] times the largest
/// ([`PnpError::TooFewPoints`] with `got` = that count); world range
/// ([`DegenerateKind::ScaleOutOfRange`] if a coordinate exceeds `f64::MAX / 4`); coincident
/// world points; collinear world points (`sv1 <= 1e-8 sv0`); world spread below the normal
/// range ([`DegenerateKind::ScaleOutOfRange`]); coincident image points (weighted RMS spread
/// `<= 1e-12 max(1, max |m|)`). All range quantities are taken over points with weight > 0.
///
/// `align = false` keeps the user's axes (`rw = I`; a test option, valid for non-planar
/// input only); every check still runs and `ratio` is still computed.
///
/// Inlined (with [`frame_impl`]) into its caller, the solve's `frame` + `moments`, so that the
/// frame is built where the solve keeps it: returned by value it was copied (560 bytes) three to
/// four times per solve; with [`Accumulator::system`] inlined too, 22.05k -> 21.30k instructions
/// per solve at N = 10 (callgrind).
#[inline(always)]
pub(crate) fn working_frame(
    world: &[Point3<f64>],
    image: &[Point2<f64>],
    weights: Option<&[f64]>,
    align: bool,
) -> Result<WorkingFrame, PnpError> {
    frame_impl(world, image, weights, align, false)
}

/// The first input checks, in the documented order: equal slice lengths, one weight per point,
/// at least [`MIN_POINTS`] points.
pub(crate) fn check_lengths(
    n: usize,
    image_len: usize,
    weights: Option<&[f64]>,
) -> Result<(), PnpError> {
    if image_len != n {
        return Err(PnpError::LengthMismatch {
            world: n,
            image: image_len,
        });
    }
    if let Some(w) = weights {
        if w.len() != n {
            return Err(PnpError::WeightsLength {
                weights: w.len(),
                points: n,
            });
        }
    }
    if n < MIN_POINTS {
        return Err(PnpError::TooFewPoints {
            got: n,
            need: MIN_POINTS,
        });
    }
    Ok(())
}

/// [`working_frame`]; `force_pass3` takes the rotated third pass even when the scatter alone
/// would do (tests compare both paths).
#[inline(always)]
fn frame_impl(
    world: &[Point3<f64>],
    image: &[Point2<f64>],
    weights: Option<&[f64]>,
    align: bool,
    force_pass3: bool,
) -> Result<WorkingFrame, PnpError> {
    check_lengths(world.len(), image.len(), weights)?;
    let n = world.len();

    // Pass 1: validation, ranges, raw weighted sums.
    let sc = match weights {
        None => scan::<false>(world, image, &[]),
        Some(w) => scan::<true>(world, image, w),
    };
    let sums_finite = sc.wsum.is_finite()
        && sc.xsum.iter().all(|x| x.is_finite())
        && sc.msum.iter().all(|x| x.is_finite());
    if !sums_finite || sc.negative {
        if let Some(e) = first_invalid(world, image, weights) {
            return Err(e);
        }
        // (All finite: a raw sum overflowed; the scaled rescan below handles it.)
    }
    let (n_active, xmax, mmax, wmax) = (sc.n_active, sc.xmax, sc.mmax, sc.wmax);
    if n_active < MIN_POINTS {
        return Err(PnpError::TooFewPoints {
            got: n_active,
            need: MIN_POINTS,
        });
    }
    if let Some(w) = weights.filter(|_| sc.wmin <= NEGLIGIBLE_WEIGHT * wmax) {
        // Some weights are negligible next to the largest: count the others (a rare pass).
        let floor = NEGLIGIBLE_WEIGHT * wmax;
        let counted = w.iter().filter(|&&wi| wi > floor).count();
        if counted < MIN_POINTS {
            return Err(PnpError::TooFewPoints {
                got: counted,
                need: MIN_POINTS,
            });
        }
    }
    if xmax > f64::MAX / 4.0 {
        return Err(PnpError::Degenerate(DegenerateKind::ScaleOutOfRange));
    }
    if xmax == 0.0 {
        return Err(PnpError::Degenerate(DegenerateKind::CoincidentWorldPoints));
    }
    // Exact power-of-two units: scaled world coordinates in [-2, 2], the largest weight in
    // [1, 2), scaled image coordinates in [-2, 2]. (Units are at least 2^-1000, so that their
    // reciprocals are finite: a world, weight or image entirely below that is only scaled up
    // to 2^1000.)
    let unit = |x: f64| pow2_scale(x).max(MIN_UNIT);
    let sx = unit(xmax);
    let sw = unit(wmax);
    let sm = if mmax > 0.0 { unit(mmax) } else { 1.0 };
    let (isx, isw, ism) = (1.0 / sx, 1.0 / sw, 1.0 / sm);

    // Weighted means (scaled units).
    let big = 2f64.powi(RAW_RANGE);
    let raw_ok = sums_finite
        && xmax <= big
        && mmax <= big
        && (weights.is_none() || (wmax <= big && wmax >= 1.0 / big));
    let (wsum, xsum, msum) = if raw_ok {
        // Exact rescaling of the raw sums (see RAW_RANGE).
        (sc.wsum * isw, sc.xsum * (isx * isw), sc.msum * (ism * isw))
    } else {
        let mut wsum = 0.0f64;
        let mut xsum = Vector3::<f64>::zeros();
        let mut msum = Vector2::<f64>::zeros();
        for i in 0..n {
            let w = weight(weights, i);
            if w <= 0.0 {
                continue;
            }
            let w = w * isw;
            wsum += w;
            xsum += (world[i].coords * isx) * w;
            msum += (image[i].coords * ism) * w;
        }
        (wsum, xsum, msum)
    };
    let cs = xsum / wsum;
    let ms = msum / wsum;

    // Pass 2: every `moments` sum of Y = X / sx - cs (weights w / sw) and the image spread.
    let map = CentredMap {
        inv_unit: isx,
        centre: cs,
        inv_weight: isw,
        inv_image: ism,
        image_mean: ms,
    };
    let pass = accumulate_centred(world, image, weights, &map, None);
    let scatter = pass.acc.s;
    let trace = scatter.trace();
    if trace == 0.0 {
        return Err(PnpError::Degenerate(DegenerateKind::CoincidentWorldPoints));
    }
    // d in units of sx (a normal number: trace > 0 and wsum in (0, 2^60)).
    let dd = (trace / pass.acc.sw).sqrt();
    let (vals, vecs) = sym_eigen3_closed(&scatter).ok_or(PnpError::NoSolution)?;
    let rows = |v: &Matrix3<f64>| {
        let mut r = v.transpose();
        if r.determinant() < 0.0 {
            r.row_mut(2).neg_mut();
        }
        r
    };
    let (lambda, rw, sums) = if vals[2] >= SCATTER_MIN * vals[0] && !force_pass3 {
        // Fast path: every threshold is far away (module documentation).
        let rw = if align {
            rows(&vecs)
        } else {
            Matrix3::identity()
        };
        let sums = pass.acc.transformed(&(rw / dd));
        (vals, rw, sums)
    } else {
        // Pass 3: the sums of the points rotated by the scatter's axes, then the exact frame
        // from their scatter (trap T9; module documentation).
        let rw0 = rows(&vecs);
        let a0 = rw0 / dd;
        let rot = accumulate_centred(world, image, weights, &map, Some(&a0)).acc;
        let (vals1, q) = sym_eigen3(&rot.s).ok_or(PnpError::NoSolution)?;
        if align {
            let qt = rows(&q);
            (vals1, qt * rw0, rot.transformed(&qt))
        } else {
            (
                vals1,
                Matrix3::identity(),
                pass.acc.transformed(&(Matrix3::identity() / dd)),
            )
        }
    };
    // Singular values of the rows sqrt(w) Y (in the unit of the pass: a common factor).
    let sv = lambda.map(|l| l.max(0.0).sqrt());
    if sv[0] == 0.0 {
        return Err(PnpError::Degenerate(DegenerateKind::CoincidentWorldPoints));
    }
    if sv[1] <= COLLINEAR_TOL * sv[0] {
        return Err(PnpError::Degenerate(DegenerateKind::CollinearWorldPoints));
    }
    let d = dd * sx;
    if !(d.is_finite() && d >= f64::MIN_POSITIVE) {
        return Err(PnpError::Degenerate(DegenerateKind::ScaleOutOfRange));
    }
    let spread = (pass.spread / pass.acc.sw).sqrt();
    // (`spread` is finite here; written so that a NaN would also be rejected.)
    if spread.is_nan() || spread <= IMAGE_SPREAD_TOL * mmax.max(1.0) / sm {
        return Err(PnpError::Degenerate(DegenerateKind::CoincidentImagePoints));
    }
    let small_image = spread <= SMALL_IMAGE_TOL * mmax.max(1.0) / sm;
    Ok(WorkingFrame {
        small_image,
        c: cs * sx,
        d,
        rw,
        ratio: sv[2] / sv[0],
        n_active,
        weight_unit: sw,
        weight_sum: pass.acc.sw,
        sums,
    })
}

#[cfg(test)]
#[path = "../../tests/unit/pipeline/frame.rs"]
mod tests;
