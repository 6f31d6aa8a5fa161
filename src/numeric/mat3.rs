//! Small dense linear algebra on 3 x 3 matrices, each routine with a hard iteration bound and
//! exact power-of-two scaling where a square could over- or underflow: the one-sided Jacobi SVD
//! ([`svd3`] and its parts), the cyclic Jacobi symmetric eigen-decomposition ([`sym_eigen3`]),
//! the smallest eigenvalue of a symmetric matrix ([`min_eigenvalue_sym3`]), a Cholesky
//! factorisation and solve ([`cholesky3`]), the reciprocal condition number ([`rcond3`]) and
//! the null vector of a rank-2 matrix ([`null_vector3`]).
//!
//! Why a hand-written SVD: nalgebra 0.35 computes the SVD of a `Matrix3` through the symmetric
//! eigen-decomposition of `A^T A`, which squares the singular values: for singular values
//! (1, 1e-8, 3e-9) it returns the second one 5-25 % off. [`svd3`] is a one-sided Jacobi SVD
//! with a hard sweep bound, accurate to about `eps * sigma_max` in every singular value.

use nalgebra::{Matrix3, Vector3};

use crate::numeric::bounds::{Bound, Budget};

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

/// Singular value decomposition of a 3 x 3 matrix by one-sided (Hestenes) Jacobi rotations.
///
/// The matrix is first divided by a power of two near its largest absolute entry (exact), so
/// no intermediate overflows or underflows for any finite input. Every singular value is
/// accurate to about `eps * s[0]`. `u`'s third column is `+-(u0 x u1)` (sign chosen to match
/// the data), so `u` is orthogonal even when singular values are zero. Returns `None` if an
/// entry is not finite. The zero matrix gives `s = 0`, `u = v = I`.
#[inline]
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
    // ordinary matrix that used all its sweeps).
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
    let mut sweeps = Budget::new(Bound::Svd3Sweeps);
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

/// Eigen-decomposition of a symmetric 3 x 3 matrix by cyclic Jacobi rotations: eigenvalues
/// descending and the eigenvectors as the columns of an orthogonal matrix.
///
/// The matrix is first divided by a power of two near its largest absolute entry (exact). A
/// rotation is skipped when `|a_pq| <= eps sqrt(|a_pp a_qq|)` (the relative criterion of
/// Demmel and Veselic: for a positive definite matrix that is diagonal up to a small relative
/// coupling, every eigenvalue comes out with a small *relative* error, not only `eps |A|`), and
/// the sweeps stop when a sweep rotates nothing or after `bounds::SYM_EIGEN3_MAX_SWEEPS`. Returns `None`
/// for non-finite input. Only the upper triangle is read.
pub(crate) fn sym_eigen3(a: &Matrix3<f64>) -> Option<(Vector3<f64>, Matrix3<f64>)> {
    let (mut b, scale) = scaled_symmetric(a)?;
    let mut v = Matrix3::<f64>::identity();
    let mut sweeps = Budget::new(Bound::FrameEigenSweeps);
    while sweeps.next() {
        let mut rotated = false;
        for &(p, q, r) in &[(0usize, 1usize, 2usize), (0, 2, 1), (1, 2, 0)] {
            let apq = b[(p, q)];
            if apq == 0.0 || apq.abs() <= f64::EPSILON * (b[(p, p)] * b[(q, q)]).abs().sqrt() {
                continue;
            }
            rotated = true;
            // Rutishauser's formulas: t = tan(phi) of the smaller rotation that zeroes a_pq.
            let zeta = (b[(q, q)] - b[(p, p)]) / (2.0 * apq);
            let t = if zeta.abs() > 1e150 {
                0.5 / zeta
            } else {
                let t = 1.0 / (zeta.abs() + (1.0 + zeta * zeta).sqrt());
                if zeta < 0.0 {
                    -t
                } else {
                    t
                }
            };
            let c = 1.0 / (1.0 + t * t).sqrt();
            let s = c * t;
            let app = b[(p, p)] - t * apq;
            let aqq = b[(q, q)] + t * apq;
            let arp = b[(r, p)];
            let arq = b[(r, q)];
            let nrp = c * arp - s * arq;
            let nrq = s * arp + c * arq;
            b[(p, p)] = app;
            b[(q, q)] = aqq;
            b[(p, q)] = 0.0;
            b[(q, p)] = 0.0;
            b[(r, p)] = nrp;
            b[(p, r)] = nrp;
            b[(r, q)] = nrq;
            b[(q, r)] = nrq;
            for i in 0..3 {
                let vp = v[(i, p)];
                let vq = v[(i, q)];
                v[(i, p)] = c * vp - s * vq;
                v[(i, q)] = s * vp + c * vq;
            }
        }
        if !rotated {
            break;
        }
    }
    Some(sorted_eigen(
        [b[(0, 0)], b[(1, 1)], b[(2, 2)]],
        [0, 1, 2].map(|k| v.column(k).into_owned()),
        scale,
    ))
}

/// Eigen-decomposition of a symmetric 3 x 3 matrix in closed form (as [`sym_eigen3`]:
/// eigenvalues descending, eigenvectors as the columns of an orthogonal matrix; only the
/// upper triangle is read; `None` for non-finite input) with a shorter dependency chain than
/// the Jacobi iteration's square roots and divisions: in the frame at N = 10 that iteration
/// cost 0.32 us per call and this form saves 0.13 us per solve (interleaved medians).
///
/// The eigenvalues first by the trigonometric formula, which is only accurate to about
/// `sqrt(eps) |A|` where two of them nearly coincide; they serve to pick the eigenvalue that is
/// the farthest from the other two and its eigenvector, the largest cross product of two rows
/// of `A - lambda I` (accurate to `eps |A| / gap` with a gap of at least a third of the
/// spread). The other two eigenvectors come from one Jacobi rotation of `A` restricted to the
/// orthogonal complement, and every eigenvalue from the vectors (the Rayleigh quotient and the
/// rotated 2 x 2 diagonal): accurate to about `eps |A|` each (Eberly's construction, "A robust
/// eigensolver for 3 x 3 symmetric matrices", 2014). Eigenvectors of nearly equal eigenvalues
/// are any orthonormal basis of their plane, as with any method. The frame's fast path uses
/// it where `lambda2 >= 1e-4 lambda0` and every threshold is far away; nearly planar and
/// collinear clouds go on to [`sym_eigen3`]'s relative accuracy (trap T9, `pipeline::frame`).
pub(crate) fn sym_eigen3_closed(a: &Matrix3<f64>) -> Option<(Vector3<f64>, Matrix3<f64>)> {
    let (m, scale) = scaled_symmetric(a)?;
    let (a00, a01, a02) = (m[(0, 0)], m[(0, 1)], m[(0, 2)]);
    let (a11, a12, a22) = (m[(1, 1)], m[(1, 2)], m[(2, 2)]);
    // (The zero matrix is diagonal.)
    let off = a01 * a01 + a02 * a02 + a12 * a12;
    if off == 0.0 {
        // Diagonal: exact.
        return Some(sorted_eigen(
            [a00, a11, a22],
            [Vector3::x(), Vector3::y(), Vector3::z()],
            scale,
        ));
    }
    // Trigonometric eigenvalues of the deviatoric part (approximate, see above).
    let q = (a00 + a11 + a22) / 3.0;
    let (d0, d1, d2) = (a00 - q, a11 - q, a22 - q);
    let p = ((d0 * d0 + d1 * d1 + d2 * d2 + 2.0 * off) / 6.0).sqrt();
    let det =
        d0 * (d1 * d2 - a12 * a12) - a01 * (a01 * d2 - a12 * a02) + a02 * (a01 * a12 - d1 * a02);
    let r = (det / (2.0 * p * p * p)).clamp(-1.0, 1.0);
    let phi = r.acos() / 3.0;
    let l0 = q + 2.0 * p * phi.cos();
    let l2 = q + 2.0 * p * (phi + 2.0 * core::f64::consts::FRAC_PI_3).cos();
    let l1 = 3.0 * q - l0 - l2;
    // The eigenvector of the eigenvalue farthest from the other two.
    let first = if l0 - l1 >= l1 - l2 { l0 } else { l2 };
    let rows = [
        Vector3::new(a00 - first, a01, a02),
        Vector3::new(a01, a11 - first, a12),
        Vector3::new(a02, a12, a22 - first),
    ];
    let cross = [
        rows[0].cross(&rows[1]),
        rows[0].cross(&rows[2]),
        rows[1].cross(&rows[2]),
    ];
    let norms = cross.map(|c| c.norm_squared());
    let k = if norms[0] >= norms[1] && norms[0] >= norms[2] {
        0
    } else if norms[1] >= norms[2] {
        1
    } else {
        2
    };
    if !(norms[k] > 0.0) {
        return None;
    }
    let v = cross[k] / norms[k].sqrt();
    // An orthonormal basis (u, w) of the plane orthogonal to v.
    let u = any_orthogonal(&v);
    let w = v.cross(&u);
    // A restricted to the plane, diagonalised by one Jacobi rotation.
    let (mu, mw) = (m * u, m * w);
    let (b00, b01, b11) = (u.dot(&mu), u.dot(&mw), w.dot(&mw));
    let (c, s, e0, e1) = if b01 == 0.0 {
        (1.0, 0.0, b00, b11)
    } else {
        let zeta = (b11 - b00) / (2.0 * b01);
        let t = zeta.signum() / (zeta.abs() + (1.0 + zeta * zeta).sqrt());
        let c = 1.0 / (1.0 + t * t).sqrt();
        (c, c * t, b00 - t * b01, b11 + t * b01)
    };
    let (x0, x1) = (u * c - w * s, u * s + w * c);
    let lv = v.dot(&(m * v));
    Some(sorted_eigen([lv, e0, e1], [v, x0, x1], scale))
}

/// The symmetric matrix of `a`'s upper triangle divided by an exact power of two near its
/// largest entry (1 for the zero matrix), and that power; `None` if an entry is not finite.
fn scaled_symmetric(a: &Matrix3<f64>) -> Option<(Matrix3<f64>, f64)> {
    let b = Matrix3::new(
        a[(0, 0)],
        a[(0, 1)],
        a[(0, 2)],
        a[(0, 1)],
        a[(1, 1)],
        a[(1, 2)],
        a[(0, 2)],
        a[(1, 2)],
        a[(2, 2)],
    );
    if !b.iter().all(|x| x.is_finite()) {
        return None;
    }
    let amax = b.amax();
    let scale = if amax == 0.0 { 1.0 } else { pow2_scale(amax) };
    Some((b / scale, scale))
}

/// Eigenpairs sorted by decreasing eigenvalue (a fixed sorting network), the eigenvalues
/// times `scale`, the vectors as columns.
fn sorted_eigen(
    vals: [f64; 3],
    vecs: [Vector3<f64>; 3],
    scale: f64,
) -> (Vector3<f64>, Matrix3<f64>) {
    let mut idx = [0usize, 1, 2];
    for &(i, j) in &[(0usize, 1usize), (1, 2), (0, 1)] {
        if vals[idx[i]] < vals[idx[j]] {
            idx.swap(i, j);
        }
    }
    (
        Vector3::new(vals[idx[0]], vals[idx[1]], vals[idx[2]]) * scale,
        Matrix3::from_columns(&[vecs[idx[0]], vecs[idx[1]], vecs[idx[2]]]),
    )
}

/// Smallest eigenvalue of a symmetric 3 x 3 matrix by cyclic Jacobi rotations (at most
/// `bounds::MIN_EIGEN3_MAX_SWEEPS` sweeps), computed in units of the largest entry. Absolute error about
/// `eps * |H|` (Weyl's bound: rotations stop once every off-diagonal entry is below
/// `eps / 8 * |H|_F`). The trigonometric closed form is not used: it loses accuracy to
/// `~sqrt(eps) |H|` when two eigenvalues nearly coincide (acos near +-1), which would leave
/// `H + shift I` indefinite. NaN for non-finite input.
#[inline]
pub(crate) fn min_eigenvalue_sym3(h: &Matrix3<f64>) -> f64 {
    let scale = h.amax();
    if scale == 0.0 || !scale.is_finite() {
        return if scale == 0.0 { 0.0 } else { f64::NAN };
    }
    let mut a = (h + h.transpose()) * (0.5 / scale);
    let thresh = 0.125 * f64::EPSILON * a.norm();
    let mut sweeps = Budget::new(Bound::HessianEigenSweeps);
    while sweeps.next() {
        let mut rotated = false;
        for &(p, q) in &[(0usize, 1usize), (0, 2), (1, 2)] {
            let apq = a[(p, q)];
            if apq.abs() <= thresh {
                continue;
            }
            rotated = true;
            let theta = (a[(q, q)] - a[(p, p)]) / (2.0 * apq);
            let t = if theta.abs() > 1e150 {
                0.5 / theta
            } else {
                theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt())
            };
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            a[(p, p)] -= t * apq;
            a[(q, q)] += t * apq;
            a[(p, q)] = 0.0;
            a[(q, p)] = 0.0;
            let r = 3 - p - q;
            let (arp, arq) = (a[(r, p)], a[(r, q)]);
            a[(r, p)] = c * arp - s * arq;
            a[(p, r)] = a[(r, p)];
            a[(r, q)] = s * arp + c * arq;
            a[(q, r)] = a[(r, q)];
        }
        if !rotated {
            break;
        }
    }
    a[(0, 0)].min(a[(1, 1)]).min(a[(2, 2)]) * scale
}

/// The `L D L^T` factor of a symmetric 3 x 3 matrix ([`ldl3`]): `L`'s entries below the
/// diagonal and the reciprocals of the pivots.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Ldl3 {
    l10: f64,
    l20: f64,
    l21: f64,
    inv_d: [f64; 3],
}

/// The `L D L^T` factor of the symmetric 3 x 3 `a` (its lower triangle read); `None` unless
/// positive definite (every pivot > 0 and finite: Cholesky's test). No square root, and a
/// reciprocal per pivot that the solve multiplies by: `newton`'s damped Newton step is one chain of
/// dependent operations (the factorisation, the solve, the trial rotation, its cost), which
/// the Cholesky factor lengthened by three square roots and nine divisions.
#[inline]
pub(crate) fn ldl3(a: &Matrix3<f64>) -> Option<Ldl3> {
    let pivot_ok = |d: f64| d > 0.0 && d.is_finite();
    let d0 = a[(0, 0)];
    if !pivot_ok(d0) {
        return None;
    }
    let i0 = 1.0 / d0;
    let (v10, v20) = (a[(1, 0)], a[(2, 0)]);
    let (l10, l20) = (v10 * i0, v20 * i0);
    let d1 = a[(1, 1)] - l10 * v10;
    if !pivot_ok(d1) {
        return None;
    }
    let i1 = 1.0 / d1;
    let v21 = a[(2, 1)] - l20 * v10;
    let l21 = v21 * i1;
    let d2 = a[(2, 2)] - l20 * v20 - l21 * v21;
    if !pivot_ok(d2) {
        return None;
    }
    Some(Ldl3 {
        l10,
        l20,
        l21,
        inv_d: [i0, i1, 1.0 / d2],
    })
}

/// Solves `L D L^T x = b` with [`ldl3`]'s factor.
#[inline]
pub(crate) fn ldl3_solve(f: &Ldl3, b: &Vector3<f64>) -> Vector3<f64> {
    let y0 = b[0];
    let y1 = b[1] - f.l10 * y0;
    let y2 = b[2] - f.l20 * y0 - f.l21 * y1;
    let x2 = y2 * f.inv_d[2];
    let x1 = y1 * f.inv_d[1] - f.l21 * x2;
    let x0 = y0 * f.inv_d[0] - f.l10 * x1 - f.l20 * x2;
    Vector3::new(x0, x1, x2)
}

/// Reciprocal condition number of a 3x3 matrix (smallest / largest singular value; 0 for a
/// zero or non-finite matrix). Uses `svd3`'s singular values: nalgebra's 3x3 SVD squares the singular values.
#[inline]
pub(crate) fn rcond3(m: &Matrix3<f64>) -> f64 {
    match singular_values3(m) {
        Some(s) if s[0] > 0.0 => s[2] / s[0],
        _ => 0.0,
    }
}

/// The right singular vector of the smallest singular value of `m` (any scale and sign), for
/// an `m` that is singular up to rounding (case 4 at a root of det M(k1)).
///
/// For rank 2, the cross product `c` of two rows is that vector; the pair with the largest
/// `|c|` is used. It is accepted only when a residual bound certifies it: with `y = c / |c|`,
/// `|M y|^2 >= s2^2 sin^2(angle(y, v3))` and `s2 >= |c| / s1 >= |c| / |M|_F` give
/// `sin(angle) <= |M c| |M|_F / |c|^2` (plus the rounding of `M c`, `4 eps |M|_F |c|`), which
/// must be below `NULL_VECTOR_TOL`, i.e. the cross product agrees with the singular vector to
/// rounding level. Otherwise (rank below 2, or `s3` not negligible against `s2`) the SVD
/// decides ([`smallest_right_singular_vector`]). `None` if an entry is not finite.
#[inline]
pub(crate) fn null_vector3(m: &Matrix3<f64>) -> Option<Vector3<f64>> {
    const NULL_VECTOR_TOL: f64 = 1e-13;
    let r: [Vector3<f64>; 3] = std::array::from_fn(|i| m.row(i).transpose());
    let cs = [r[0].cross(&r[1]), r[0].cross(&r[2]), r[1].cross(&r[2])];
    let mut best = 0;
    let mut best_n2 = cs[0].norm_squared();
    for (i, c) in cs.iter().enumerate().skip(1) {
        let n2 = c.norm_squared();
        if n2 > best_n2 {
            best = i;
            best_n2 = n2;
        }
    }
    let c = cs[best];
    let fro = m.norm();
    let lhs = ((m * c).norm() + 4.0 * f64::EPSILON * fro * best_n2.sqrt()) * fro;
    let rhs = NULL_VECTOR_TOL * best_n2;
    if best_n2 > 0.0 && lhs.is_finite() && rhs.is_finite() && lhs <= rhs {
        return Some(c);
    }
    smallest_right_singular_vector(m)
}

/// Two unit vectors orthogonal to the unit `v` and to each other.
pub(crate) fn orthogonal_pair(v: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    // The axis least aligned with `v`, made orthogonal to it.
    let (ax, ay, az) = (v.x.abs(), v.y.abs(), v.z.abs());
    let e = if ax <= ay && ax <= az {
        Vector3::x()
    } else if ay <= az {
        Vector3::y()
    } else {
        Vector3::z()
    };
    let a = v.cross(&e).normalize();
    (a, v.cross(&a))
}
