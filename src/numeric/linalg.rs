//! Small fixed-size linear algebra for the fast path: Cholesky factorisation (also the
//! positive-definiteness test of the certificates and of `M - tau I`), the smallest
//! eigenvector of the 9x9 positive semidefinite `M` by inverse iteration, the number of
//! eigenvalues below a threshold (LDL^T inertia with diagonal pivoting, Sturm count as the
//! fallback), and `refine`'s damped 6 x 6 solve (`L D L^T`, no square root). No allocation; every
//! loop has a fixed bound.

use nalgebra::{SMatrix, SVector};

/// A Cholesky factor `L`: its rows (`rows[i][j]`, zero above the diagonal) and the
/// reciprocals of its diagonal, which the factorisation forms anyway and the substitutions
/// multiply by (a division on every step would lengthen their dependency chains).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Factor<const D: usize> {
    rows: [[f64; D]; D],
    inv_diag: [f64; D],
}

/// Cholesky factor `L` (lower) of a symmetric positive definite matrix, or `None` (also for a
/// NaN entry).
pub(crate) fn cholesky<const D: usize>(a: &SMatrix<f64, D, D>) -> Option<SMatrix<f64, D, D>> {
    let f = cholesky_rows::<D>(|i, j| a[(i, j)]).ok()?;
    Some(SMatrix::from_fn(|i, j| f.rows[i][j]))
}

/// Whether the symmetric matrix with lower-triangle entries `a(i, j)`, `j <= i`, is positive
/// definite: its Cholesky factorisation exists (`false` also for a NaN entry). With the
/// factorisation unrolled, `a` is evaluated at constant indices: a matrix formed from others
/// entry by entry is never stored.
#[inline(always)]
pub(crate) fn positive_definite<const D: usize>(a: impl Fn(usize, usize) -> f64) -> bool {
    cholesky_rows::<D>(a).is_ok()
}

/// The Cholesky factor of `m - shift I`, or the index `j` of the first pivot that is not
/// positive: the leading `j x j` block was factored, so it is positive definite (up to the
/// factorisation's backward error), and by Cauchy's interlacing theorem `m - shift I` has at
/// most `D - j` eigenvalues `<= 0`.
pub(crate) fn cholesky_shifted_or_pivot<const D: usize>(
    m: &SMatrix<f64, D, D>,
    shift: f64,
) -> Result<Factor<D>, usize> {
    cholesky_rows::<D>(|i, j| if i == j { m[(i, i)] - shift } else { m[(i, j)] })
}

/// Runs `$body` once for each index of the list, with `$j` a constant (`const $j: usize`):
/// the loops of the body then have constant trip counts and unroll into straight-line code
/// (the factorisations and substitutions below, for every dimension up to 12).
macro_rules! for_each_const {
    ($j:ident in [$($k:literal),*] $body:block) => {
        $({
            const $j: usize = $k;
            $body
        })*
    };
}

/// The rows of the Cholesky factor `L` of the symmetric matrix with lower-triangle entries
/// `a(i, j)`, `j <= i`, or the index of the first pivot that is not positive (also for a NaN
/// entry). The textbook column-by-column order of operations; `L` is row-major, so that every
/// inner product runs over two contiguous slices.
#[inline(always)]
fn cholesky_rows<const D: usize>(a: impl Fn(usize, usize) -> f64) -> Result<Factor<D>, usize> {
    const { assert!(D <= 12) };
    let mut f = Factor {
        rows: [[0.0f64; D]; D],
        inv_diag: [0.0f64; D],
    };
    for_each_const!(J in [0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11] {
        if J < D {
            cholesky_column::<D, J>(&mut f, &a)?;
        }
    });
    Ok(f)
}

/// Column `J` of [`cholesky_rows`]: the pivot, then the entries below it.
#[inline(always)]
fn cholesky_column<const D: usize, const J: usize>(
    f: &mut Factor<D>,
    a: &impl Fn(usize, usize) -> f64,
) -> Result<(), usize> {
    let (head, below) = f.rows.split_at_mut(J + 1);
    let rj = &mut head[J];
    let d = dot_down(a(J, J), &rj[..J], &rj[..J]);
    if !(d > 0.0) {
        return Err(J);
    }
    let djj = d.sqrt();
    rj[J] = djj;
    let rj = &rj[..J];
    // One division per column: the entries below the pivot are independent products.
    let inv = 1.0 / djj;
    f.inv_diag[J] = inv;
    for (i, ri) in (J + 1..D).zip(below.iter_mut()) {
        ri[J] = dot_down(a(i, J), &ri[..J], rj) * inv;
    }
    Ok(())
}

/// `s - x_0 y_0 - x_1 y_1 - ...`, subtracted in order.
#[inline(always)]
fn dot_down(s: f64, x: &[f64], y: &[f64]) -> f64 {
    x.iter().zip(y).fold(s, |s, (a, b)| s - a * b)
}

/// Solves `L L^T x = b` in place: two substitutions, each step ending in a multiplication by
/// the reciprocal of the pivot.
#[inline(always)]
fn cholesky_solve<const D: usize>(f: &Factor<D>, x: &mut [f64; D]) {
    let (rows, inv_diag) = (&f.rows, &f.inv_diag);
    const { assert!(D <= 12) };
    for_each_const!(I in [0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11] {
        if I < D {
            let (done, rest) = x.split_at_mut(I);
            rest[0] = dot_down(rest[0], &rows[I][..I], done) * inv_diag[I];
        }
    });
    for_each_const!(I in [11, 10, 9, 8, 7, 6, 5, 4, 3, 2, 1, 0] {
        if I < D {
            let (head, done) = x.split_at_mut(I + 1);
            let s = done
                .iter()
                .zip(&rows[I + 1..])
                .fold(head[I], |s, (xk, rk)| s - rk[I] * xk);
            head[I] = s * inv_diag[I];
        }
    });
}

/// Inverse-iteration steps, at most: each multiplies the error by `(l1 - sigma) / (l2 - sigma)`.
/// The vector only seeds a Newton refinement (`newton`), so a few steps suffice.
const INVERSE_ITERATIONS: usize = 4;
/// Inverse iteration stops early once a step changes the unit vector by at most this: the
/// error left is then about this times `(l1 - sigma) / (l2 - sigma)`, below the distance at
/// which the nearest rotation to the vector starts Newton anyway (measured on the comparison
/// program's rows against always 4 steps: the same failures and errors, no row slower; with
/// 1e-3 the general rows were 2-4 % slower than with 1e-2).
const INVERSE_TOL: f64 = 1e-2;

/// The shift of [`cholesky_shifted_up`], relative to `scale`.
const EIGENVECTOR_SHIFT: f64 = 1e-12;

/// The Cholesky factor of `m + delta I`, `delta = EIGENVECTOR_SHIFT scale`, and `-delta`: for
/// the symmetric positive semidefinite `m` a shift below its smallest eigenvalue, which the
/// factorisation proves (the factor for [`inverse_iteration`]). `None` if the factorisation
/// fails or the input is not finite.
pub(crate) fn cholesky_shifted_up<const D: usize>(
    m: &SMatrix<f64, D, D>,
    scale: f64,
) -> Option<(Factor<D>, f64)> {
    let delta = EIGENVECTOR_SHIFT * scale;
    Some((cholesky_shifted_or_pivot(m, -delta).ok()?, -delta))
}

/// Unit eigenvector of the smallest eigenvalue of the symmetric positive semidefinite `m`
/// (approximately: [`inverse_iteration`] with [`cholesky_shifted_up`]'s factor), or `None` if
/// the factorisation fails or the input is not finite.
pub(crate) fn smallest_eigenvector<const D: usize>(
    m: &SMatrix<f64, D, D>,
    scale: f64,
) -> Option<SVector<f64, D>> {
    inverse_iteration(m, &cholesky_shifted_up(m, scale)?.0)
}

/// Inverse iteration with the Cholesky factor `l` of `m - sigma I` (any shift `sigma` below
/// the smallest eigenvalue), at most [`INVERSE_ITERATIONS`] steps, until a step moves the unit
/// vector by at most [`INVERSE_TOL`] (from the second step on): the unit eigenvector of the
/// smallest eigenvalue of `m`, approximately, or `None` for non-finite iterates.
pub(crate) fn inverse_iteration<const D: usize>(
    m: &SMatrix<f64, D, D>,
    l: &Factor<D>,
) -> Option<SVector<f64, D>> {
    // Start from the coordinate axis with the smallest diagonal entry (the direction along
    // which M is smallest among the axes), plus a small all-ones component so no eigenvector is
    // exactly missed.
    let kmin = (0..D)
        .min_by(|&i, &j| m[(i, i)].total_cmp(&m[(j, j)]))
        .unwrap_or(0);
    let mut x = SVector::<f64, D>::from_element(1e-3);
    x[kmin] = 1.0;
    for k in 0..INVERSE_ITERATIONS {
        let prev = x;
        cholesky_solve(l, &mut x.data.0[0]);
        let n = x.norm();
        if !(n > 0.0 && n.is_finite()) {
            return None;
        }
        x /= n;
        if k > 0 && (x - prev).norm() <= INVERSE_TOL {
            break;
        }
    }
    Some(x)
}

/// Householder reduction of the symmetric 9x9 `m` to tridiagonal form `Q^T m Q = T` (Q not
/// formed): the diagonal and the off-diagonal of `T`. Seven reflections; no allocation.
#[allow(clippy::needless_range_loop)]
fn tridiagonal9(m: &SMatrix<f64, 9, 9>) -> ([f64; 9], [f64; 8]) {
    const N: usize = 9;
    let mut a = [[0.0f64; N]; N];
    for i in 0..N {
        for j in 0..N {
            a[i][j] = 0.5 * (m[(i, j)] + m[(j, i)]);
        }
    }
    let mut off = [0.0f64; N - 1];
    for k in 0..N - 2 {
        // Reflection v (entries k+1..N) mapping a[k+1..N][k] onto a multiple of e_{k+1}.
        let mut scale = 0.0f64;
        for i in k + 1..N {
            scale = scale.max(a[i][k].abs());
        }
        if scale == 0.0 {
            off[k] = 0.0;
            continue;
        }
        let mut v = [0.0f64; N];
        let mut norm2 = 0.0;
        for i in k + 1..N {
            v[i] = a[i][k] / scale;
            norm2 += v[i] * v[i];
        }
        let alpha = -norm2.sqrt().copysign(v[k + 1]);
        off[k] = alpha * scale;
        v[k + 1] -= alpha;
        let vnorm2: f64 = (k + 1..N).map(|i| v[i] * v[i]).sum();
        if !(vnorm2 > 0.0) {
            continue;
        }
        let beta = 2.0 / vnorm2;
        // Trailing block update: A <- H A H, H = I - beta v v^T (rows/cols k+1..N).
        let mut p = [0.0f64; N];
        for i in k + 1..N {
            let mut s = 0.0;
            for j in k + 1..N {
                s += a[i][j] * v[j];
            }
            p[i] = beta * s;
        }
        let mut vp = 0.0;
        for i in k + 1..N {
            vp += v[i] * p[i];
        }
        let kk = 0.5 * beta * vp;
        for i in k + 1..N {
            p[i] -= kk * v[i];
        }
        for i in k + 1..N {
            for j in k + 1..N {
                a[i][j] -= v[i] * p[j] + p[i] * v[j];
            }
        }
    }
    off[N - 2] = a[N - 1][N - 2];
    let mut diag = [0.0f64; N];
    for i in 0..N {
        diag[i] = a[i][i];
    }
    (diag, off)
}

/// Number of eigenvalues of the symmetric `m` strictly below `tau`, by Sylvester's law of
/// inertia: the number of negative pivots of an LDL^T factorisation of `m - tau I`.
///
/// First [`inertia_ldlt`] (symmetric elimination with diagonal pivoting, about a fifth of the
/// work), accepted only when its multipliers and element growth are bounded, so that its
/// backward error is a small multiple of `eps max|m - tau I|`, as for the tridiagonal method.
/// For `m` positive semidefinite and `tau` small (the solver's use) that is the common case.
/// Otherwise Householder tridiagonalisation (a fixed number of reflections) and the Sturm count
/// of `T - tau I` (the tridiagonal recurrence is backward stable).
pub(crate) fn count_eigenvalues_below(m: &SMatrix<f64, 9, 9>, tau: f64) -> usize {
    inertia_ldlt(m, tau).unwrap_or_else(|| sturm_count_below(m, tau))
}

/// Largest multiplier accepted by [`inertia_ldlt`].
const LDLT_MAX_MULTIPLIER: f64 = 2.0;
/// Largest element growth accepted by [`inertia_ldlt`] (relative to `max |m - tau I|`).
const LDLT_MAX_GROWTH: f64 = 4.0;

/// The number of negative pivots of `m - tau I = P L D L^T P^T` (pivot: the largest remaining
/// diagonal entry in magnitude), or `None` when a pivot is zero, a multiplier exceeds
/// [`LDLT_MAX_MULTIPLIER`], a pivot exceeds [`LDLT_MAX_GROWTH`] times the largest entry of
/// `m - tau I`, or the input is not finite. With those bounds every entry of `|L||D||L^T|` is
/// at most `9 * 2 * 4 * 2` times that largest entry, so the factorisation is exact for a matrix
/// within about `150 gamma_9 max|m - tau I|` (about `3e-13 max|m - tau I|`) of `m - tau I`
/// (Higham, Accuracy and Stability, Thm. 9.3 applied to LDL^T), and its inertia is that of
/// `m - tau I` up to eigenvalues that close to 0.
#[allow(clippy::needless_range_loop)]
fn inertia_ldlt(m: &SMatrix<f64, 9, 9>, tau: f64) -> Option<usize> {
    const N: usize = 9;
    let mut a = [[0.0f64; N]; N];
    let mut amax = 0.0f64;
    // 0 * x is NaN exactly when x is NaN or infinite.
    let mut nonfinite = 0.0f64;
    for i in 0..N {
        for j in 0..i {
            let v = 0.5 * (m[(i, j)] + m[(j, i)]);
            a[i][j] = v;
            a[j][i] = v;
            nonfinite += 0.0 * v;
            if v.abs() > amax {
                amax = v.abs();
            }
        }
        let v = m[(i, i)] - tau;
        a[i][i] = v;
        nonfinite += 0.0 * v;
        if v.abs() > amax {
            amax = v.abs();
        }
    }
    if nonfinite != 0.0 || !amax.is_finite() {
        return None;
    }
    let limit = LDLT_MAX_GROWTH * amax;
    // Eliminated rows are marked instead of moved; the remaining rows are updated across all
    // nine columns (a fixed width the compiler unrolls and vectorises; the entries of eliminated
    // columns are never read again).
    let mut done = [false; N];
    let mut negative = 0;
    for _ in 0..N {
        let mut p = N;
        let mut best = -1.0f64;
        for q in 0..N {
            if !done[q] && a[q][q].abs() > best {
                best = a[q][q].abs();
                p = q;
            }
        }
        if p == N {
            return None; // a NaN appeared
        }
        let d = a[p][p];
        if !(d != 0.0 && d.abs() <= limit) {
            return None;
        }
        negative += usize::from(d < 0.0);
        done[p] = true;
        let pivot_row = a[p];
        for i in 0..N {
            if done[i] {
                continue;
            }
            let li = a[i][p] / d;
            if !(li.abs() <= LDLT_MAX_MULTIPLIER) {
                return None;
            }
            for j in 0..N {
                a[i][j] -= li * pivot_row[j];
            }
        }
    }
    Some(negative)
}

/// [`count_eigenvalues_below`] by Householder tridiagonalisation and a Sturm count.
fn sturm_count_below(m: &SMatrix<f64, 9, 9>, tau: f64) -> usize {
    let (diag, off) = tridiagonal9(m);
    let mut count = 0;
    let mut q = 1.0f64;
    for i in 0..9 {
        let e2 = if i == 0 { 0.0 } else { off[i - 1] * off[i - 1] };
        q = (diag[i] - tau) - if i == 0 { 0.0 } else { e2 / q };
        if q == 0.0 {
            // Exactly zero pivot: perturb by the smallest relative amount (standard practice).
            q = -f64::EPSILON * (diag[i].abs() + tau.abs()).max(f64::MIN_POSITIVE);
        }
        if q < 0.0 {
            count += 1;
        }
    }
    count
}

/// Solves `(H + lam I) delta = -g` by a 6 x 6 `L D L^T` factorisation ([`ldl_rows`]); `None`
/// if `H + lam I` is not (numerically) positive definite, including NaN entries.
///
/// `L D L^T`, not Cholesky: the factorisation has no square root. At N = 4 and 5 a `refine`
/// iteration is one chain of dependent operations (this solve, the step's rotation, the
/// pass over the points, the normal equations, the next solve), and the Cholesky factor's six
/// square roots, each followed by the division by it, were the longest links of the chain:
/// with `L D L^T` (the same instruction count) a general N = 4 solve took about 6 % less time
/// (docs/speed-log.md).
// Not inlined: compiled once, its loops unroll the same whatever the caller (inlined into
// `refine`'s loop, the Cholesky version measured 300 to 620 instructions per call from build to
// build).
#[inline(never)]
pub(crate) fn solve_damped6(h: &[[f64; 6]; 6], lam: f64, g: &[f64; 6]) -> Option<[f64; 6]> {
    let f = ldl_rows::<6>(|i, j| if i == j { h[i][i] + lam } else { h[i][j] }).ok()?;
    let mut delta = g.map(|x| -x);
    ldl_solve(&f, &mut delta);
    Some(delta)
}

/// An `L D L^T` factor: the rows of the unit lower triangular `L` below the diagonal
/// (`rows[i][j]`, `j < i`; the rest zero) and the reciprocals of the pivots `D`.
struct Ldl<const D: usize> {
    rows: [[f64; D]; D],
    inv_pivot: [f64; D],
}

/// The `L D L^T` factor of the symmetric matrix with lower-triangle entries `a(i, j)`,
/// `j <= i`, or the index of the first pivot that is not positive (also for a NaN entry):
/// the pivots are the squares of the Cholesky factor's diagonal, so the test is that of
/// [`cholesky_rows`]. Column by column, as [`cholesky_rows`].
#[inline(always)]
fn ldl_rows<const D: usize>(a: impl Fn(usize, usize) -> f64) -> Result<Ldl<D>, usize> {
    const { assert!(D <= 12) };
    let mut f = Ldl {
        rows: [[0.0f64; D]; D],
        inv_pivot: [0.0f64; D],
    };
    let mut pivot = [0.0f64; D];
    for_each_const!(J in [0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11] {
        if J < D {
            ldl_column::<D, J>(&mut f, &mut pivot, &a)?;
        }
    });
    Ok(f)
}

/// Column `J` of [`ldl_rows`]: with `v_k = L_Jk d_k`, the pivot `d_J = a_JJ - sum_k L_Jk v_k`,
/// then the entries below it, `L_iJ = (a_iJ - sum_k L_ik v_k) / d_J`.
#[inline(always)]
fn ldl_column<const D: usize, const J: usize>(
    f: &mut Ldl<D>,
    pivot: &mut [f64; D],
    a: &impl Fn(usize, usize) -> f64,
) -> Result<(), usize> {
    let (head, below) = f.rows.split_at_mut(J + 1);
    let rj = &head[J][..J];
    let v: [f64; D] = core::array::from_fn(|k| if k < J { rj[k] * pivot[k] } else { 0.0 });
    let d = dot_down(a(J, J), rj, &v[..J]);
    if !(d > 0.0) {
        return Err(J);
    }
    pivot[J] = d;
    // One division per column: the entries below the pivot are independent products.
    let inv = 1.0 / d;
    f.inv_pivot[J] = inv;
    for (i, ri) in (J + 1..D).zip(below.iter_mut()) {
        ri[J] = dot_down(a(i, J), &ri[..J], &v[..J]) * inv;
    }
    Ok(())
}

/// Solves `L D L^T x = b` in place: the substitution with `L`, the multiplication by
/// `D^-1`, the substitution with `L^T`.
#[inline(always)]
fn ldl_solve<const D: usize>(f: &Ldl<D>, x: &mut [f64; D]) {
    let rows = &f.rows;
    const { assert!(D <= 12) };
    for_each_const!(I in [0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11] {
        if I < D {
            let (done, rest) = x.split_at_mut(I);
            rest[0] = dot_down(rest[0], &rows[I][..I], done);
        }
    });
    for (xi, inv) in x.iter_mut().zip(&f.inv_pivot) {
        *xi *= inv;
    }
    for_each_const!(I in [11, 10, 9, 8, 7, 6, 5, 4, 3, 2, 1, 0] {
        if I < D {
            let (head, done) = x.split_at_mut(I + 1);
            head[I] = done
                .iter()
                .zip(&rows[I + 1..])
                .fold(head[I], |s, (xk, rk)| s - rk[I] * xk);
        }
    });
}

#[cfg(test)]
#[path = "../../tests/unit/numeric/linalg.rs"]
mod tests;
