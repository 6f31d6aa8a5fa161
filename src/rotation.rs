//! Rotation utilities: CGR (Cayley-Gibbs-Rodrigues) maps, the exponential map, the nearest
//! rotation (ALGORITHM.md S5), an accurate 3 x 3 SVD, the error metrics of ALGORITHM.md
//! section 1, and a closed-form rotation -> quaternion conversion (T11).
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

/// CGR vector of a rotation: `s = [R32 - R23, R13 - R31, R21 - R12] / (1 + trace R)`.
///
/// Singular at 180 degrees (`1 + trace R = 0`: the result is infinite or NaN) and
/// ill-conditioned near it (trap T1); the refinement never uses it for that reason.
#[cfg(test)]
pub(crate) fn rotation_to_cgr(r: &Matrix3<f64>) -> Vector3<f64> {
    Vector3::new(
        r[(2, 1)] - r[(1, 2)],
        r[(0, 2)] - r[(2, 0)],
        r[(1, 0)] - r[(0, 1)],
    ) / (1.0 + r.trace())
}

/// Exponential map of so(3) (Rodrigues): the rotation by angle `|w|` about `w / |w|`.
///
/// Evaluated through the unit quaternion `(cos(t/2), sin(t/2) w / t)`, `t = |w|`, with a
/// Taylor branch for `sin(t/2) / t` below `t = 1e-4` (truncation error < 1e-27).
pub(crate) fn exp_so3(w: &Vector3<f64>) -> Matrix3<f64> {
    // Euler-Rodrigues form: q = (cos(t/2), sin(t/2) w / t), R = (q0^2 - v'v) I + 2 v v' + 2 q0 [v]x.
    // This is orthonormal to rounding even at large angles (the I + a K + b K^2 form loses
    // ~1e-15 at t = 3).
    let t2 = w.norm_squared();
    let t = t2.sqrt();
    let h = 0.5 * t;
    // sin(h) / t = 0.5 sin(h) / h.
    let k = if t < 1e-4 {
        let h2 = h * h;
        0.5 * (1.0 - h2 / 6.0 + h2 * h2 / 120.0)
    } else {
        0.5 * h.sin() / h
    };
    let q0 = h.cos();
    let v = w * k;
    Matrix3::identity() * (q0 * q0 - v.norm_squared())
        + v * v.transpose() * 2.0
        + skew(&v) * (2.0 * q0)
}

/// Thin result of [`svd3`]: `A = u * diag(s) * v^T`, `s` descending and >= 0, `u` and `v`
/// orthogonal (`det u = +-1`, `det v = +-1`).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Svd3 {
    /// Left singular vectors (columns).
    pub u: Matrix3<f64>,
    /// Singular values, descending.
    pub s: Vector3<f64>,
    /// Right singular vectors (columns).
    pub v: Matrix3<f64>,
}

/// Hard bound on the Jacobi sweeps of [`svd3`] (a 3 x 3 matrix converges in about 4-6).
pub(crate) const SVD_MAX_SWEEPS: usize = 40;

/// Singular value decomposition of a 3 x 3 matrix by one-sided (Hestenes) Jacobi rotations.
///
/// The matrix is first divided by a power of two near its largest absolute entry (exact), so
/// no intermediate overflows or underflows for any finite input. Every singular value is
/// accurate to about `eps * s[0]`. `u`'s third column is `+-(u0 x u1)` (sign chosen to match
/// the data), so `u` is orthogonal even when singular values are zero. Returns `None` if an
/// entry is not finite. The zero matrix gives `s = 0`, `u = v = I`.
pub(crate) fn svd3(a: &Matrix3<f64>) -> Option<Svd3> {
    let (cols, vcols, nrm, scale) = jacobi3::<true>(a)?;
    let Some(scale) = scale else {
        return Some(Svd3 {
            u: Matrix3::identity(),
            s: Vector3::zeros(),
            v: Matrix3::identity(),
        });
    };
    Some(finish_svd3(&cols, &vcols, &nrm, scale))
}

/// The singular values of `a` (descending), bit for bit those of [`svd3`] (the same column
/// rotations, without accumulating `v` or forming `u`). `None` if an entry is not finite.
pub(crate) fn singular_values3(a: &Matrix3<f64>) -> Option<Vector3<f64>> {
    let (_, _, nrm, scale) = jacobi3::<false>(a)?;
    let Some(scale) = scale else {
        return Some(Vector3::zeros());
    };
    let norms = nrm.map(f64::sqrt);
    let idx = sort_desc(&norms);
    Some(Vector3::new(norms[idx[0]], norms[idx[1]], norms[idx[2]]) * scale)
}

/// The right singular vector of the smallest singular value of `a`, bit for bit `svd3(a)`'s
/// `v.column(2)` (without forming `u`). `None` if an entry is not finite.
pub(crate) fn smallest_right_singular_vector(a: &Matrix3<f64>) -> Option<Vector3<f64>> {
    let (_, v, nrm, scale) = jacobi3::<true>(a)?;
    if scale.is_none() {
        return Some(Vector3::z());
    }
    let idx = sort_desc(&nrm.map(f64::sqrt));
    Some(Vector3::from(v[idx[2]]))
}

/// `a . b` for 3-vectors, summed left to right (as nalgebra's `dot` of a `Vector3`).
#[inline(always)]
fn dot3(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Indices of `norms` in descending order (a fixed 3-element sorting network).
#[inline(always)]
fn sort_desc(norms: &[f64; 3]) -> [usize; 3] {
    let mut idx = [0usize, 1, 2];
    for &(i, j) in &[(0usize, 1usize), (1, 2), (0, 1)] {
        if norms[idx[i]] < norms[idx[j]] {
            idx.swap(i, j);
        }
    }
    idx
}

/// One Jacobi rotation of the column pair (p, q) of `b` (and of `v` if `WANT_V`), if their inner
/// product exceeds its rounding error. `nrm` holds the squared column norms of `b` and is kept
/// current. Returns whether a rotation was applied.
#[inline(always)]
fn jacobi_pair<const WANT_V: bool>(
    b: &mut [[f64; 3]; 3],
    v: &mut [[f64; 3]; 3],
    nrm: &mut [f64; 3],
    p: usize,
    q: usize,
) -> bool {
    let alpha = nrm[p];
    let beta = nrm[q];
    let gamma = dot3(&b[p], &b[q]);
    // Rotate only when the columns' inner product exceeds its own rounding error
    // (a length-3 dot product: about 3 eps |b_p| |b_q|); with a threshold of 1 eps, a
    // pair whose computed gamma is rounding noise can be rotated forever (found: an
    // ordinary matrix that used all SVD_MAX_SWEEPS sweeps).
    if gamma == 0.0 || gamma.abs() <= 4.0 * f64::EPSILON * alpha.sqrt() * beta.sqrt() {
        return false;
    }
    let zeta = (beta - alpha) / (2.0 * gamma);
    let t = if zeta.abs() > 1e150 {
        0.5 / zeta
    } else {
        zeta.signum() / (zeta.abs() + (1.0 + zeta * zeta).sqrt())
    };
    let c = 1.0 / (1.0 + t * t).sqrt();
    let s = c * t;
    let (bp, bq) = (b[p], b[q]);
    for i in 0..3 {
        b[p][i] = c * bp[i] - s * bq[i];
        b[q][i] = s * bp[i] + c * bq[i];
    }
    if WANT_V {
        let (vp, vq) = (v[p], v[q]);
        for i in 0..3 {
            v[p][i] = c * vp[i] - s * vq[i];
            v[q][i] = s * vp[i] + c * vq[i];
        }
    }
    nrm[p] = dot3(&b[p], &b[p]);
    nrm[q] = dot3(&b[q], &b[q]);
    true
}

/// Column arrays of `b` (the scaled input after the rotations) and of `v` (identity if not
/// `WANT_V`), the squared column norms of `b`, and the power-of-two scale (`None` for the zero
/// matrix). `None` if an entry is not finite.
///
/// The sweeps: see [`svd3`]. Squared column norms are cached and recomputed only for rotated
/// columns (the same expression, so the same values as recomputing them at every pair).
#[inline(always)]
#[allow(clippy::type_complexity)]
fn jacobi3<const WANT_V: bool>(
    a: &Matrix3<f64>,
) -> Option<([[f64; 3]; 3], [[f64; 3]; 3], [f64; 3], Option<f64>)> {
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let mut amax: f64 = 0.0;
    for x in a.iter() {
        if !x.is_finite() {
            return None;
        }
        amax = amax.max(x.abs());
    }
    if amax == 0.0 {
        return Some(([[0.0; 3]; 3], v, [0.0; 3], None));
    }
    let scale = pow2_scale(amax);
    let mut b: [[f64; 3]; 3] = std::array::from_fn(|j| std::array::from_fn(|i| a[(i, j)] / scale));
    let mut nrm = [dot3(&b[0], &b[0]), dot3(&b[1], &b[1]), dot3(&b[2], &b[2])];
    let mut sweeps = crate::bounds::Budget::new(crate::bounds::Bound::Svd3Sweeps);
    while sweeps.next() {
        let r01 = jacobi_pair::<WANT_V>(&mut b, &mut v, &mut nrm, 0, 1);
        let r02 = jacobi_pair::<WANT_V>(&mut b, &mut v, &mut nrm, 0, 2);
        let r12 = jacobi_pair::<WANT_V>(&mut b, &mut v, &mut nrm, 1, 2);
        if !(r01 || r02 || r12) {
            break;
        }
    }
    Some((b, v, nrm, Some(scale)))
}

/// `u`, sorted `s` and `v` from the converged columns (see [`svd3`]).
#[inline(always)]
fn finish_svd3(b: &[[f64; 3]; 3], v: &[[f64; 3]; 3], nrm: &[f64; 3], scale: f64) -> Svd3 {
    // Sort the columns by norm, descending.
    let norms = nrm.map(f64::sqrt);
    let idx = sort_desc(&norms);
    let s = Vector3::new(norms[idx[0]], norms[idx[1]], norms[idx[2]]);
    let vs = Matrix3::from_columns(&[
        Vector3::from(v[idx[0]]),
        Vector3::from(v[idx[1]]),
        Vector3::from(v[idx[2]]),
    ]);
    let b0 = Vector3::from(b[idx[0]]);
    let b1 = Vector3::from(b[idx[1]]);
    let b2 = Vector3::from(b[idx[2]]);
    // s[0] > 0 because amax > 0 and the rotations preserve the Frobenius norm.
    let u0 = b0 / s[0];
    let u1 = {
        let g = b1 - u0 * u0.dot(&b1);
        let gn = g.norm();
        if s[1] > f64::EPSILON * s[0] && gn > 0.0 {
            g / gn
        } else {
            any_orthogonal(&u0)
        }
    };
    let c = u0.cross(&u1);
    let u2 = if c.dot(&b2) < 0.0 { -c } else { c };
    Svd3 {
        u: Matrix3::from_columns(&[u0, u1, u2]),
        s: s * scale,
        v: vs,
    }
}

/// A unit vector orthogonal to the unit vector `u`.
fn any_orthogonal(u: &Vector3<f64>) -> Vector3<f64> {
    // Cross with the coordinate axis least aligned with u.
    let e = if u.x.abs() <= u.y.abs() && u.x.abs() <= u.z.abs() {
        Vector3::x()
    } else if u.y.abs() <= u.z.abs() {
        Vector3::y()
    } else {
        Vector3::z()
    };
    u.cross(&e).normalize()
}

/// The power of two `2^k <= x < 2^(k+1)` for finite `x > 0` (exact scaling factor).
pub(crate) fn pow2_scale(x: f64) -> f64 {
    debug_assert!(x > 0.0 && x.is_finite());
    let bits = x.to_bits();
    if x >= f64::MIN_POSITIVE {
        // Normal: keep the exponent, clear the mantissa.
        f64::from_bits(bits & 0x7ff0_0000_0000_0000)
    } else {
        // Subnormal: x = m 2^-1074; keep the highest set bit of m.
        f64::from_bits(1u64 << (63 - (bits & 0x000f_ffff_ffff_ffff).leading_zeros()))
    }
}

/// Nearest rotation to `a` in the Frobenius norm (ALGORITHM.md S5):
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
/// (ALGORITHM.md S5): reshape row-major, negate if the determinant is negative, project with
/// [`nearest_rotation`]. Returns `None` for non-finite or zero `r`.
pub(crate) fn candidate_to_rotation(r: &[f64; 9]) -> Option<Matrix3<f64>> {
    let a = Matrix3::from_row_slice(r);
    if !a.iter().all(|x| x.is_finite()) {
        return None;
    }
    let amax = a.amax();
    if amax == 0.0 {
        return None;
    }
    // Exact power-of-two scaling so the determinant cannot overflow or underflow.
    let a = a / pow2_scale(amax);
    let a = if a.determinant() < 0.0 { -a } else { a };
    nearest_rotation(&a)
}

/// Angle between two vectors in radians, `atan2(|a x b|, a . b)` (accurate at small angles,
/// unlike `acos`).
fn angle_between(a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    a.cross(b).norm().atan2(a.dot(b))
}

/// Rotation error in degrees (the paper's metric, ALGORITHM.md section 1): the largest angle
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

/// Translation error in percent: `100 |t - t_true| / |t_true|` (ALGORITHM.md section 1).
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
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_pcg::Pcg64;

    fn rand_rot(rng: &mut Pcg64) -> Matrix3<f64> {
        // Haar-uniform via a random unit quaternion.
        let mut q = [0.0f64; 4];
        loop {
            for x in q.iter_mut() {
                *x = rng.random_range(-1.0..1.0);
            }
            let n = q.iter().map(|x| x * x).sum::<f64>();
            if n > 1e-3 && n <= 1.0 {
                break;
            }
        }
        let q = UnitQuaternion::new_normalize(nalgebra::Quaternion::new(q[0], q[1], q[2], q[3]));
        q.to_rotation_matrix().into_inner()
    }

    /// Orthonormality tolerance for products of computed orthogonal factors: each factor is
    /// orthogonal to ~10 Jacobi rotations' rounding and the product adds 3-term dot products;
    /// measured max 1.8e-15 (8 eps) over 2000 random inputs, allow 4e-15.
    const ORTH_TOL: f64 = 4e-15;

    fn orth_err(r: &Matrix3<f64>) -> f64 {
        (r.transpose() * r - Matrix3::identity()).amax()
    }

    #[test]
    fn cgr_roundtrip_and_orthonormal() {
        let mut rng = Pcg64::seed_from_u64(1);
        for _ in 0..200 {
            let r = rand_rot(&mut rng);
            let s = rotation_to_cgr(&r);
            let r2 = cgr_to_rotation(&s);
            // Round trip through the CGR map: error grows like |s| ~ 1/(1 + tr R); random
            // rotations keep 1 + tr R well away from 0 except rarely, allow 1e-12.
            if 1.0 + r.trace() > 1e-2 {
                assert!((r - r2).amax() < 1e-12, "{}", (r - r2).amax());
            }
            // Rounding only: a few ulps.
            assert!(orth_err(&r2) < 1e-15);
            assert!((r2.determinant() - 1.0).abs() < 1e-15);
        }
        // Huge s (angle within 1e-12 rad of 180 deg) stays finite and orthonormal.
        let s = Vector3::new(1.0, -2.0, 0.5) * 1e200;
        let r = cgr_to_rotation(&s);
        assert!(orth_err(&r) < 1e-15);
        let n = Vector3::new(1.0, -2.0, 0.5).normalize();
        let expected = n * n.transpose() * 2.0 - Matrix3::identity();
        assert!((r - expected).amax() < 1e-15);
    }

    #[test]
    fn cgr_matches_formula() {
        // Against the literal formula Rbar(s) / (1 + s's) from ALGORITHM.md section 1.
        let s = Vector3::new(0.3, -0.7, 1.9);
        let (s1, s2, s3) = (s.x, s.y, s.z);
        #[rustfmt::skip]
        let rbar = Matrix3::new(
            1.0 + s1 * s1 - s2 * s2 - s3 * s3, 2.0 * (s1 * s2 - s3), 2.0 * (s1 * s3 + s2),
            2.0 * (s1 * s2 + s3), 1.0 - s1 * s1 + s2 * s2 - s3 * s3, 2.0 * (s2 * s3 - s1),
            2.0 * (s1 * s3 - s2), 2.0 * (s1 + s2 * s3), 1.0 - s1 * s1 - s2 * s2 + s3 * s3,
        );
        let r = rbar / (1.0 + s.norm_squared());
        // Same formula, different grouping: a few ulps.
        assert!((cgr_to_rotation(&s) - r).amax() < 1e-15);
    }

    #[test]
    fn exp_matches_nalgebra() {
        let mut rng = Pcg64::seed_from_u64(2);
        for k in 0..300 {
            let mag = 10f64.powi(-(k % 12)) * 3.0;
            let w = Vector3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            )
            .normalize()
                * mag;
            let r = exp_so3(&w);
            let rn = Rotation3::from_scaled_axis(w).into_inner();
            // Both are accurate to a few ulps of O(1) entries (measured max 8.9e-16 = 4 eps).
            assert!(
                (r - rn).amax() < 2e-15,
                "{} at |w| = {mag}",
                (r - rn).amax()
            );
            assert!(orth_err(&r) < 2e-15);
        }
        assert_eq!(exp_so3(&Vector3::zeros()), Matrix3::identity());
    }

    #[test]
    fn svd3_converges_well_within_its_sweep_bound() {
        // An ordinary matrix (a candidate of the case-1 start) on which a 1-eps rotation
        // threshold kept rotating a pair whose inner product is rounding noise: all 40 sweeps.
        let a = Matrix3::from_column_slice(&[
            0.03165774668062224,
            0.06537362588744486,
            -0.0041840607448066815,
            0.023226095764420775,
            0.1598864994284672,
            -0.027021008617450003,
            -0.02359280146445423,
            -0.1725975064488418,
            0.05489997101597928,
        ]);
        use crate::bounds::{tests::with_limit, Bound};
        let (out, hit) = with_limit(Bound::Svd3Sweeps, 8, || svd3(&a));
        assert_eq!(hit, 0, "more than 8 sweeps");
        let svd = out.unwrap();
        let rec = svd.u * Matrix3::from_diagonal(&svd.s) * svd.v.transpose();
        assert!(
            (rec - a).amax() < 4.0 * f64::EPSILON * svd.s[0],
            "{:e}",
            (rec - a).amax()
        );
        assert!((svd.u.transpose() * svd.u - Matrix3::identity()).amax() < 1e-15);
        assert!((svd.v.transpose() * svd.v - Matrix3::identity()).amax() < 1e-15);
    }

    #[test]
    fn svd3_accuracy() {
        let mut rng = Pcg64::seed_from_u64(3);
        for k in 0..200 {
            let u = rand_rot(&mut rng);
            let v = rand_rot(&mut rng);
            let sv = match k % 4 {
                0 => Vector3::new(1.0, 1e-8, 3e-9),
                1 => Vector3::new(2.0, 1.0, 0.0),
                2 => Vector3::new(1.0, 1.0, 1.0),
                _ => Vector3::new(5.0, 1e-12, 1e-20),
            };
            let a = u * Matrix3::from_diagonal(&sv) * v.transpose();
            let d = svd3(&a).unwrap();
            // Backward error: a few eps * |A|.
            let rec = d.u * Matrix3::from_diagonal(&d.s) * d.v.transpose();
            assert!((rec - a).amax() < 1e-14 * sv[0]);
            // Singular values: absolute error a few eps * s0 (1e-15 * s0 allows ~5 ulps).
            for i in 0..3 {
                assert!(
                    (d.s[i] - sv[i]).abs() < 1e-15 * sv[0],
                    "{k} {i} {:e}",
                    d.s[i]
                );
            }
            assert!(orth_err(&d.u) < ORTH_TOL && orth_err(&d.v) < ORTH_TOL);
        }
        // Graded test of T9: relative accuracy of sv1 at 1e-8 must be far better than the
        // 5-25 % of the eigen-decomposition route.
        let u = Rotation3::from_scaled_axis(Vector3::new(0.3, 0.1, -0.2)).into_inner();
        let v = Rotation3::from_scaled_axis(Vector3::new(0.7, -0.4, 0.4)).into_inner();
        let a = u * Matrix3::from_diagonal(&Vector3::new(1.0, 1e-8, 3e-9)) * v.transpose();
        let d = svd3(&a).unwrap();
        // eps / 1e-8 relative: allow 1e-7.
        assert!((d.s[1] / 1e-8 - 1.0).abs() < 1e-7);
        // Extreme magnitudes, including subnormal entries: scaled internally.
        for scale in [1e300, 1e-300, 1e-310] {
            let d = svd3(&(a * scale)).unwrap();
            assert!((d.s[0] / scale - 1.0).abs() < 1e-14, "{scale}");
        }
        assert!(svd3(&Matrix3::from_element(f64::NAN)).is_none());
    }

    #[test]
    fn singular_values3_and_null_vector_match_svd3_bitwise() {
        let mut rng = Pcg64::seed_from_u64(6);
        for k in 0..300 {
            let mut a = Matrix3::from_fn(|_, _| rng.random_range(-1.0..1.0));
            if k % 3 == 1 {
                // rank 2
                let c = a.column(0) * 0.3 - a.column(1) * 1.7;
                a.set_column(2, &c);
            }
            if k % 3 == 2 {
                a *= 1e-310;
            }
            let s = singular_values3(&a).unwrap();
            let d = svd3(&a).unwrap();
            let y = smallest_right_singular_vector(&a).unwrap();
            for i in 0..3 {
                assert_eq!(y[i].to_bits(), d.v[(i, 2)].to_bits(), "{k} {i}");
            }
            for i in 0..3 {
                assert_eq!(s[i].to_bits(), d.s[i].to_bits(), "{k} {i}");
            }
        }
        assert_eq!(
            singular_values3(&Matrix3::zeros()).unwrap(),
            Vector3::zeros()
        );
        assert!(singular_values3(&Matrix3::from_element(f64::NAN)).is_none());
        assert_eq!(
            smallest_right_singular_vector(&Matrix3::zeros()).unwrap(),
            svd3(&Matrix3::zeros()).unwrap().v.column(2)
        );
        assert!(smallest_right_singular_vector(&Matrix3::from_element(f64::NAN)).is_none());
    }

    #[test]
    fn pow2_scale_brackets() {
        for x in [
            1.0,
            1.5,
            2.0,
            3.999,
            1e-300,
            5e-324,
            1e-310,
            3e-320,
            f64::MAX,
            f64::MIN_POSITIVE,
        ] {
            let p = pow2_scale(x);
            assert!(p <= x && x < 2.0 * p, "{x} {p}");
            // A power of two: no mantissa bits (normal) or a single bit (subnormal).
            if p >= f64::MIN_POSITIVE {
                assert_eq!(p.to_bits() & 0x000f_ffff_ffff_ffff, 0, "{x}");
            } else {
                assert_eq!(p.to_bits().count_ones(), 1, "{x}");
            }
        }
    }

    #[test]
    fn nearest_rotation_properties() {
        let mut rng = Pcg64::seed_from_u64(4);
        for _ in 0..200 {
            let r = rand_rot(&mut rng);
            // Projection of a rotation is itself (to the orthonormality rounding).
            let p = nearest_rotation(&r).unwrap();
            assert!((p - r).amax() < ORTH_TOL);
            // Scale invariant, and a reflection maps to a rotation (det +1).
            let p = nearest_rotation(&(r * 3.7)).unwrap();
            assert!((p - r).amax() < ORTH_TOL);
            let refl = r * Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, -1.0));
            let p = nearest_rotation(&refl).unwrap();
            assert!((p.determinant() - 1.0).abs() < ORTH_TOL && orth_err(&p) < ORTH_TOL);
            // Perturbed rotation: result is a rotation close to r.
            let noise = Matrix3::from_fn(|_, _| rng.random_range(-1e-3..1e-3));
            let p = nearest_rotation(&(r + noise)).unwrap();
            assert!(orth_err(&p) < ORTH_TOL && (p.determinant() - 1.0).abs() < ORTH_TOL);
            assert!(rotation_error_deg(&p, &r) < 0.5);
        }
        // Rank deficient input still gives a rotation.
        let p = nearest_rotation(&Matrix3::from_diagonal(&Vector3::new(1.0, 0.0, 0.0))).unwrap();
        assert!(orth_err(&p) < ORTH_TOL && (p.determinant() - 1.0).abs() < ORTH_TOL);
        assert!(nearest_rotation(&Matrix3::zeros()).is_none());
        assert!(nearest_rotation(&Matrix3::from_element(f64::INFINITY)).is_none());
    }

    #[test]
    fn candidate_to_rotation_sign_and_skip() {
        let r = Rotation3::from_scaled_axis(Vector3::new(0.2, -1.0, 2.0)).into_inner();
        let mut v = [0.0; 9];
        for i in 0..3 {
            for j in 0..3 {
                v[3 * i + j] = -2.5e-200 * r[(i, j)]; // row-major, negative scale
            }
        }
        let p = candidate_to_rotation(&v).unwrap();
        // Orthonormality-level rounding (see ORTH_TOL).
        assert!((p - r).amax() < ORTH_TOL);
        assert!(candidate_to_rotation(&[0.0; 9]).is_none());
        let mut bad = v;
        bad[4] = f64::NAN;
        assert!(candidate_to_rotation(&bad).is_none());
    }

    #[test]
    fn rotation_error_metric() {
        let r = Rotation3::from_scaled_axis(Vector3::new(0.0, 0.0, 1e-12)).into_inner();
        let e = rotation_error_deg(&r, &Matrix3::identity());
        // atan2 resolves 1e-12 rad to relative rounding.
        assert!((e - 1e-12f64.to_degrees()).abs() < 1e-24);
        let flip = Matrix3::from_diagonal(&Vector3::new(1.0, -1.0, -1.0));
        assert!((rotation_error_deg(&flip, &Matrix3::identity()) - 180.0).abs() < 1e-12);
        let t = translation_error_pct(&Vector3::new(1.0, 0.0, 0.01), &Vector3::new(1.0, 0.0, 0.0));
        assert!((t - 1.0).abs() < 1e-12);
    }

    #[test]
    fn quaternion_at_180_degrees() {
        let axes = [
            Vector3::x(),
            Vector3::y(),
            Vector3::z(),
            Vector3::new(1.0, 1.0, 0.0),
            Vector3::new(1.0, -1.0, 1.0),
            Vector3::new(0.0, 0.3, -2.0),
            Vector3::new(-0.4, 0.1, 0.2),
        ];
        for a in &axes {
            let n = a.normalize();
            // Exactly 180 degrees: R = 2 n n' - I.
            let r = n * n.transpose() * 2.0 - Matrix3::identity();
            let q = to_unit_quaternion(&r);
            let back = q.to_rotation_matrix().into_inner();
            // Closed form: entries to a few ulps.
            assert!((back - r).amax() < 1e-15, "{a:?}: {}", (back - r).amax());
            assert!(q.w.abs() < 1e-15);
            assert!((q.angle() - std::f64::consts::PI).abs() < 1e-7);
            assert!(rotation_error_deg(&back, &r) < 1e-12);
        }
        // Random rotations and near-180 ones.
        let mut rng = Pcg64::seed_from_u64(5);
        for k in 0..300 {
            let r = if k % 2 == 0 {
                rand_rot(&mut rng)
            } else {
                let n = Vector3::new(
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                )
                .normalize();
                exp_so3(&(n * (std::f64::consts::PI - 1e-9 * rng.random::<f64>())))
            };
            let back = to_unit_quaternion(&r).to_rotation_matrix().into_inner();
            assert!((back - r).amax() < 2e-15);
        }
    }
}
