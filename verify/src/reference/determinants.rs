//! Determinants and resultants: Hadamard's bound, nalgebra's LU determinant with an
//! a-posteriori error bound, the permanent, the Sylvester and Bezout matrices of two cubics,
//! and polynomial evaluation with its absolute-value scale.

use nalgebra::{DMatrix, Matrix3};

use super::gamma;

/// Hadamard's bound `prod_i |row_i|_2` (>= |det A|, and >= every term of the Leibniz expansion).
#[must_use]
pub fn hadamard(a: &DMatrix<f64>) -> f64 {
    (0..a.nrows()).map(|i| a.row(i).norm()).product()
}

/// `det A` by nalgebra's LU with partial pivoting, after scaling each row by a power of two
/// (exact) so that its largest entry lies in [1, 2); returns the determinant and the
/// first-order a-posteriori bound on its rounding error:
///
/// LU with partial pivoting returns `L U = P (A_s + dA)`, `|dA| <= gamma_n |L| |U|`
/// (Higham Thm 9.3), and the product of the `n` pivots adds `gamma_n |det|`. To first order
/// `|det(A_s + dA) - det A_s| <= sum_ij |cof_ij(A_s)| |dA_ij|`, and Hadamard's inequality on the
/// minor gives `|cof_ij| <= H(A_s) / |row_i(A_s)|_2`. The bound is scaled back to `A`.
#[must_use]
pub fn det_with_bound(a: &DMatrix<f64>) -> (f64, f64) {
    let n = a.nrows();
    let mut scaled = a.clone();
    let mut log2 = 0i32;
    for i in 0..n {
        let mx = scaled.row(i).amax();
        if mx > 0.0 {
            let e = mx.log2().floor() as i32;
            let f = 2f64.powi(-e);
            for j in 0..n {
                scaled[(i, j)] *= f;
            }
            log2 += e;
        }
    }
    let lu = scaled.clone().lu();
    let det_s = lu.determinant();
    let l = lu.l();
    let uu = lu.u();
    let lu_abs = l.abs() * uu.abs(); // rows in the permuted order P A_s
                                     // Permute the row norms in the same way as the LU: apply P to the scaled matrix.
    let mut pa = scaled.clone();
    lu.p().permute_rows(&mut pa);
    let h = hadamard(&pa);
    let mut bound = 0.0;
    for i in 0..n {
        let rn = pa.row(i).norm();
        if rn > 0.0 {
            let row_sum: f64 = lu_abs.row(i).iter().sum();
            bound += gamma(n) * row_sum * h / rn;
        }
    }
    bound += gamma(n) * det_s.abs();
    let back = 2f64.powi(log2);
    (det_s * back, bound * back)
}

/// Permanent of a small non-negative matrix (Ryser's formula); bounds the sum of the absolute
/// values of all terms of the Leibniz expansion of the determinant.
#[must_use]
pub fn permanent(a: &DMatrix<f64>) -> f64 {
    let n = a.nrows();
    let mut total = 0.0;
    for mask in 1u32..(1 << n) {
        let mut prod = 1.0;
        for i in 0..n {
            let mut s = 0.0;
            for j in 0..n {
                if mask & (1 << j) != 0 {
                    s += a[(i, j)];
                }
            }
            prod *= s;
        }
        let sign = if (n as u32 - mask.count_ones()).is_multiple_of(2) {
            1.0
        } else {
            -1.0
        };
        total += sign * prod;
    }
    total
}

/// The 6 x 6 Sylvester matrix (eq. 22) of two cubics given by ascending coefficients
/// `p = [p0, p1, p2, p3]`, `q = [q0, ...]`: rows `p x^2, p x, p, q x^2, q x, q`, columns in
/// descending powers `x^5 .. x^0`.
#[must_use]
pub fn sylvester(p: &[f64; 4], q: &[f64; 4]) -> DMatrix<f64> {
    let mut s = DMatrix::zeros(6, 6);
    for (block, poly) in [p, q].iter().enumerate() {
        for shift in 0..3 {
            let row = 3 * block + shift;
            // x^(n + 2 - shift) sits in column 5 - (n + 2 - shift)
            for n in 0..4 {
                s[(row, 3 - n + shift)] = poly[n];
            }
        }
    }
    s
}

/// 3 x 3 Bezout matrix of two cubics (docs/algorithm.md G7), `br(i, j) = p_i q_j - p_j q_i`.
#[must_use]
pub fn bezout(p: &[f64; 4], q: &[f64; 4]) -> Matrix3<f64> {
    let br = |i: usize, j: usize| p[i] * q[j] - p[j] * q[i];
    Matrix3::new(
        br(1, 0),
        br(2, 0),
        br(3, 0),
        br(2, 0),
        br(2, 1) + br(3, 0),
        br(3, 1),
        br(3, 0),
        br(3, 1),
        br(3, 2),
    )
}

/// Absolute-value scale of the Bezout route to the resultant: `per(|Bez|)` with every
/// `br(i, j)` replaced by `|p_i| |q_j| + |p_j| |q_i|` (inputs `pa`, `qa` already absolute-value
/// scales of the coefficients).
#[must_use]
pub fn bezout_abs_permanent(pa: &[f64; 4], qa: &[f64; 4]) -> f64 {
    let br = |i: usize, j: usize| pa[i] * qa[j] + pa[j] * qa[i];
    let b = DMatrix::from_row_slice(
        3,
        3,
        &[
            br(1, 0),
            br(2, 0),
            br(3, 0),
            br(2, 0),
            br(2, 1) + br(3, 0),
            br(3, 1),
            br(3, 0),
            br(3, 1),
            br(3, 2),
        ],
    );
    permanent(&b)
}

/// `sum_n a[n] x^n` and `sum_n |a[n]| |x|^n`.
#[must_use]
pub fn poly_eval(a: &[f64], x: f64) -> (f64, f64) {
    let (mut v, mut s, mut p) = (0.0, 0.0, 1.0);
    for &an in a {
        v += an * p;
        s += (an * p).abs();
        p *= x;
    }
    (v, s)
}
