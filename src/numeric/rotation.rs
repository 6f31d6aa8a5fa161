//! Rotation utilities: CGR (Cayley-Gibbs-Rodrigues) maps, the exponential map, the nearest rotation
//! (docs/algorithm.md, `nullspace`, candidate to rotation), an accurate 3 x 3 SVD, the error
//! metrics of docs/algorithm.md section 1, and a closed-form rotation -> quaternion conversion
//! (T11).
//!
//! | symbol | meaning |
//! |---|---|
//! | `s` | CGR vector, `s = tan(theta / 2) * axis` |
//! | `R(s)` | `((1 - s's) I + 2 [s]x + 2 s s') / (1 + s's)` |
//! | `r` | `vec(R)`, row-major `[R11 R12 R13 R21 R22 R23 R31 R32 R33]` |
//!
//! Why a hand-written SVD: nalgebra 0.35 computes the SVD of a `Matrix3` through the symmetric
//! eigen-decomposition of `A^T A` (`linalg/svd3.rs`), which squares the singular values (trap T9):
//! for singular values (1, 1e-8, 3e-9) it returns the second one 5-25 % off. [`svd3`] is a
//! one-sided Jacobi SVD with a hard sweep bound, accurate to about `eps * sigma_max` in every
//! singular value.

use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};

use crate::numeric::mat3::{pow2_scale, svd3};
use crate::numeric::trig;

/// `[a]x`, the cross-product matrix of `a`.
#[rustfmt::skip]
pub(crate) fn skew(a: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(
        0.0, -a.z, a.y,
        a.z, 0.0, -a.x,
        -a.y, a.x, 0.0,
    )
}

/// Rotation of the CGR vector `s`: `R(s) = ((1 - s's) I + 2 [s]x + 2 s s') / (1 + s's)`.
///
/// Accurate for every finite `s` (for `|s| > 1` numerator and denominator are divided by
/// `|s|^2` first, so huge `s`, i.e. angles near 180 degrees, neither overflow nor lose the
/// orthonormality). A non-finite `s` gives a non-finite matrix.
pub(crate) fn cgr_to_rotation(s: &Vector3<f64>) -> Matrix3<f64> {
    let k = s.amax();
    if k <= 1.0 {
        let ss = s.norm_squared();
        let inv = 1.0 / (1.0 + ss);
        (Matrix3::identity() * (1.0 - ss) + skew(s) * 2.0 + s * s.transpose() * 2.0) * inv
    } else {
        // s = k n with |n|_inf = 1: R = ((1/k^2 - n'n) I + (2/k) [n]x + 2 n n') / (1/k^2 + n'n).
        let n = s / k;
        let a = 1.0 / (k * k);
        let nn = n.norm_squared();
        let inv = 1.0 / (a + nn);
        (Matrix3::identity() * (a - nn) + skew(&n) * (2.0 / k) + n * n.transpose() * 2.0) * inv
    }
}

/// Exponential map of so(3) (Rodrigues): the rotation by angle `|w|` about `w / |w|`.
///
/// Evaluated through the unit quaternion `(cos(t/2), sin(t/2) w / t)`, `t = |w|`; below
/// `t/2 = 1/4` (every step of the refinements but the first from a poor start) `sin(t/2) /
/// (t/2)` and `cos(t/2)` come from their Taylor series in `(t/2)^2 = |w|^2 / 4`
/// ([`trig::sinc_cos_small`], within 1 ulp; no square root on the refinement's chain of
/// dependent operations), above from libm.
pub(crate) fn exp_so3(w: &Vector3<f64>) -> Matrix3<f64> {
    // Euler-Rodrigues form: q = (cos(t/2), sin(t/2) w / t), R = (q0^2 - v'v) I + 2 v v' + 2 q0 [v]x.
    // This is orthonormal to rounding even at large angles (the I + a K + b K^2 form loses
    // ~1e-15 at t = 3).
    let t2 = w.norm_squared();
    // (t/2)^2.
    let h2 = 0.25 * t2;
    // sin(h) / t = 0.5 sin(h) / h.
    let (k, q0) = if h2 <= trig::SMALL_ANGLE * trig::SMALL_ANGLE {
        let (sinc, cos) = trig::sinc_cos_small(h2);
        (0.5 * sinc, cos)
    } else {
        let h = 0.5 * t2.sqrt();
        (0.5 * h.sin() / h, h.cos())
    };
    let v = w * k;
    Matrix3::identity() * (q0 * q0 - v.norm_squared())
        + v * v.transpose() * 2.0
        + skew(&v) * (2.0 * q0)
}

/// Nearest rotation to `a` in the Frobenius norm (docs/algorithm.md, `nullspace`, candidate to
/// rotation):
/// `U diag(1, 1, sgn det(U V^T)) V^T` from the SVD `a = U S V^T` (sgn 0 taken as +1).
///
/// Returns `None` if an entry is not finite or `a` is zero.
pub(crate) fn nearest_rotation(a: &Matrix3<f64>) -> Option<Matrix3<f64>> {
    let svd = svd3(a)?;
    if svd.s[0] == 0.0 {
        return None;
    }
    let uvt = svd.u * svd.v.transpose();
    if uvt.determinant() >= 0.0 {
        Some(uvt)
    } else {
        let mut u = svd.u;
        u.column_mut(2).neg_mut();
        Some(u * svd.v.transpose())
    }
}

/// Non-planar candidate `r` (null-space vector, any scale and sign) to a rotation
/// (docs/algorithm.md, `nullspace`, candidate to rotation): reshape row-major, negate if the
/// determinant is negative, project with [`nearest_rotation`]. Returns `None` for non-finite or
/// zero `r`.
pub(crate) fn candidate_to_rotation(r: &[f64; 9]) -> Option<Matrix3<f64>> {
    let a = pow2_scaled(&Matrix3::from_row_slice(r))?;
    let a = if a.determinant() < 0.0 { -a } else { a };
    polar_rotation(&a).or_else(|| nearest_rotation(&a))
}

/// `a` divided by a power of two near its largest entry (exact), so that its determinant
/// cannot overflow or underflow; `None` for non-finite or zero `a`.
fn pow2_scaled(a: &Matrix3<f64>) -> Option<Matrix3<f64>> {
    if !a.iter().all(|x| x.is_finite()) {
        return None;
    }
    let amax = a.amax();
    if amax == 0.0 {
        return None;
    }
    Some(a / pow2_scale(amax))
}

/// [`nearest_rotation`] of `a` as it is (no sign taken away, unlike [`candidate_to_rotation`]):
/// by [`polar_rotation`] when `det a > 0` (the orthogonal polar factor is then the nearest
/// rotation), by the SVD otherwise. Returns `None` for non-finite or zero `a`.
pub(crate) fn nearest_rotation_polar(a: &Matrix3<f64>) -> Option<Matrix3<f64>> {
    let a = pow2_scaled(a)?;
    polar_rotation(&a).or_else(|| nearest_rotation(&a))
}

/// Scaled Newton steps of [`polar_rotation`], at most.
const POLAR_ITERATIONS: usize = 8;
/// [`polar_rotation`] stops after a step that changes the matrix by at most this (Frobenius
/// norm): the iteration converges quadratically, so the result is then orthogonal to rounding.
const POLAR_TOL: f64 = 1e-8;
/// [`polar_rotation`] leaves to the SVD a matrix with `det X <= POLAR_MIN_DET |X|_F^3`
/// (nearly singular: the inverse in the iteration would be inaccurate).
const POLAR_MIN_DET: f64 = 1e-8;

/// The orthogonal polar factor of `a` (det > 0), which is its nearest rotation, by Newton's
/// iteration with Higham's Frobenius-norm scaling: `X <- (g X + X^-T / g) / 2` with
/// `g = sqrt(|X^-1|_F / |X|_F)`, `X^-T` the cofactor matrix (rows `x1 x x2`, `x2 x x0`,
/// `x0 x x1`) over the determinant. The case-1 start settles in 2 steps on noise-free input
/// and 3-4 at sigma = 2 px (N = 10 and 100, 200 problems each); `candidate_to_rotation` then
/// takes about 940 instructions per call at N = 10 against about 1,580 with
/// [`nearest_rotation`]'s SVD (callgrind).
/// `None` (the caller uses the SVD) when an iterate is nearly singular or `POLAR_ITERATIONS`
/// steps do not settle it.
fn polar_rotation(a: &Matrix3<f64>) -> Option<Matrix3<f64>> {
    let mut x = *a;
    for _ in 0..POLAR_ITERATIONS {
        let (x0, x1, x2) = (
            x.row(0).transpose(),
            x.row(1).transpose(),
            x.row(2).transpose(),
        );
        let (c0, c1, c2) = (x1.cross(&x2), x2.cross(&x0), x0.cross(&x1));
        let det = x0.dot(&c0);
        let nx2 = x.norm_squared();
        if !(det > POLAR_MIN_DET * nx2 * nx2.sqrt()) {
            return None;
        }
        let inv_t = Matrix3::from_rows(&[c0.transpose(), c1.transpose(), c2.transpose()]) / det;
        let g = (inv_t.norm() / nx2.sqrt()).sqrt();
        let next = (x * g + inv_t / g) * 0.5;
        let step = (next - x).norm();
        x = next;
        if step <= POLAR_TOL {
            return Some(x);
        }
    }
    None
}

/// Angle between two vectors in radians, `atan2(|a x b|, a . b)` (accurate at small angles,
/// unlike `acos`).
fn angle_between(a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    a.cross(b).norm().atan2(a.dot(b))
}

/// Rotation error in degrees (the paper's metric, docs/algorithm.md section 1): the largest angle
/// between corresponding columns of `a` and `b`, each computed as `atan2(|a x b|, a . b)`.
///
/// Resolves errors down to about 1e-14 degrees and is well defined at 180 degrees (unlike
/// `Rotation3::angle` of `a^T b` composed with `axis()`). Both arguments should be rotations.
pub fn rotation_error_deg(a: &Matrix3<f64>, b: &Matrix3<f64>) -> f64 {
    let mut worst = 0.0f64;
    for k in 0..3 {
        let e = angle_between(&a.column(k).into_owned(), &b.column(k).into_owned());
        worst = worst.max(e);
    }
    worst.to_degrees()
}

/// Translation error in percent: `100 |t - t_true| / |t_true|` (docs/algorithm.md section 1).
///
/// Infinite or NaN when `t_true` is zero.
pub fn translation_error_pct(t: &Vector3<f64>, t_true: &Vector3<f64>) -> f64 {
    100.0 * (t - t_true).norm() / t_true.norm()
}

/// Unit quaternion of a rotation matrix, in closed form (no iteration; trap T11).
///
/// Uses nalgebra 0.35 `UnitQuaternion::from_rotation_matrix`, which is closed form (it
/// branches on `trace > 0`, else on the largest diagonal entry, so the divisor is always at
/// least 1: Shepperd's method). The result is renormalised. Exact at 180 degrees. `r` must be
/// orthonormal (project with [`nearest_rotation`] first if it may not be).
pub(crate) fn to_unit_quaternion(r: &Matrix3<f64>) -> UnitQuaternion<f64> {
    let q = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(*r));
    UnitQuaternion::new_normalize(q.into_inner())
}

#[cfg(test)]
#[path = "../../tests/unit/numeric/rotation.rs"]
mod tests;
