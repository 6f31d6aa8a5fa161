//! The `nullspace` cases 2, 3 and 4: their inputs, gradient cubics and matrices, written out
//! from docs/algorithm.md.

use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

use super::cost::upper_pairs;
use super::determinants::poly_eval;

// ----------------------------------------------------------------------------------------------
// `nullspace` case 2

/// Case 2 inputs from `A` (6 x 3) and `b` (6): `Q = A^T A` as `[Q00, Q01, Q02, Q11, Q12, Q22]`,
/// `p = A^T b`.
#[must_use]
pub fn case2_inputs(a: &SMatrix<f64, 6, 3>, b: &SVector<f64, 6>) -> ([f64; 6], [f64; 3]) {
    let q = a.transpose() * a;
    let p = a.transpose() * b;
    (
        [
            q[(0, 0)],
            q[(0, 1)],
            q[(0, 2)],
            q[(1, 1)],
            q[(1, 2)],
            q[(2, 2)],
        ],
        [p[0], p[1], p[2]],
    )
}

/// The gradient cubics of `C2` at `y`, written out from docs/algorithm.md, `nullspace` case 2:
///
/// `g1 = 4 Q00 x^3 + 6 Q01 y x^2 + (2 (Q11 + 2 Q02) y^2 - 4 p0) x + (2 Q12 y^3 - 2 p1 y)`,
/// `g2 = 2 Q01 x^3 + 2 (Q11 + 2 Q02) y x^2 + (6 Q12 y^2 - 2 p1) x + (4 Q22 y^3 - 4 p2 y)`.
///
/// Returns the ascending coefficients of `g1` and `g2` and their absolute-value scales.
#[must_use]
pub fn case2_cubics(
    q: &[f64; 6],
    p: &[f64; 3],
    y: f64,
) -> ([f64; 4], [f64; 4], [f64; 4], [f64; 4]) {
    let [q00, q01, q02, q11, q12, q22] = *q;
    let [p0, p1, p2] = *p;
    let (y2, y3) = (y * y, y * y * y);
    let g1 = [
        2.0 * q12 * y3 - 2.0 * p1 * y,
        2.0 * (q11 + 2.0 * q02) * y2 - 4.0 * p0,
        6.0 * q01 * y,
        4.0 * q00,
    ];
    let g2 = [
        4.0 * q22 * y3 - 4.0 * p2 * y,
        6.0 * q12 * y2 - 2.0 * p1,
        2.0 * (q11 + 2.0 * q02) * y,
        2.0 * q01,
    ];
    let (ya, y2a, y3a) = (y.abs(), y2, y3.abs());
    let g1a = [
        2.0 * q12.abs() * y3a + 2.0 * p1.abs() * ya,
        2.0 * (q11.abs() + 2.0 * q02.abs()) * y2a + 4.0 * p0.abs(),
        6.0 * q01.abs() * ya,
        4.0 * q00.abs(),
    ];
    let g2a = [
        4.0 * q22.abs() * y3a + 4.0 * p2.abs() * ya,
        6.0 * q12.abs() * y2a + 2.0 * p1.abs(),
        2.0 * (q11.abs() + 2.0 * q02.abs()) * ya,
        2.0 * q01.abs(),
    ];
    (g1, g2, g1a, g2a)
}

// ----------------------------------------------------------------------------------------------
// `nullspace` case 3

/// My own enumeration of the case-3 monomials `k1^i k2^j` (G5: (4,0), (3,1), ..., (0,0)).
#[must_use]
pub fn case3_monomials() -> Vec<[u8; 2]> {
    let mut out = Vec::new();
    for d in (0..=4u8).rev() {
        for i in (0..=d).rev() {
            out.push([i, d - i]);
        }
    }
    out
}

/// `k = [k1^2, k2^2, k1 k2, k1, k2, 1]` (`nullspace` case 3).
#[must_use]
pub fn case3_k(k1: f64, k2: f64) -> SVector<f64, 6> {
    SVector::<f64, 6>::from_column_slice(&[k1 * k1, k2 * k2, k1 * k2, k1, k2, 1.0])
}

/// The 21 upper-triangle entries of the symmetric 6 x 6 `H`, row by row.
#[must_use]
pub fn h_upper21(h: &SMatrix<f64, 6, 6>) -> [f64; 21] {
    let pairs = upper_pairs(&[0, 1, 2, 3, 4, 5]);
    std::array::from_fn(|k| h[pairs[k]])
}

/// Coefficient `c_ij` of a case-3 coefficient array in my own monomial order (4 x 4+ table
/// indexed `[i][j]`, zero where `i + j > 4`).
#[must_use]
pub fn case3_table(c: &[f64; 15]) -> [[f64; 5]; 5] {
    let mut t = [[0.0; 5]; 5];
    for (ci, e) in c.iter().zip(case3_monomials()) {
        t[e[0] as usize][e[1] as usize] = *ci;
    }
    t
}

/// The gradient cubics of `C3 = sum c_ij x^i y^j` at `y` (docs/algorithm.md, `nullspace` case 3, by
/// the power rule on the table): `dC3/dx = sum_ij i c_ij x^(i-1) y^j`,
/// `dC3/dy = sum_ij j c_ij x^i y^(j-1)`. Returns ascending coefficients in `x` of both cubics and
/// their absolute-value scales.
#[must_use]
#[allow(clippy::needless_range_loop)] // i, j are the exponents
pub fn case3_cubics(c: &[f64; 15], y: f64) -> ([f64; 4], [f64; 4], [f64; 4], [f64; 4]) {
    let t = case3_table(c);
    let (mut gx, mut gy, mut gxa, mut gya) = ([0.0; 4], [0.0; 4], [0.0; 4], [0.0; 4]);
    for i in 0..5 {
        for j in 0..5 - i {
            if i >= 1 {
                let v = i as f64 * t[i][j] * y.powi(j as i32);
                gx[i - 1] += v;
                gxa[i - 1] += v.abs();
            }
            if j >= 1 {
                let v = j as f64 * t[i][j] * y.powi(j as i32 - 1);
                gy[i] += v;
                gya[i] += v.abs();
            }
        }
    }
    (gx, gy, gxa, gya)
}

// ----------------------------------------------------------------------------------------------
// `nullspace` case 4

/// My own enumeration of the case-4 input layout `[i, j, n]` (`n <= 1` for `j < 2`, `n <= 2`
/// for `j = 2`), compared with `CASE4_T_LAYOUT` in a test.
#[must_use]
pub fn case4_layout() -> Vec<[u8; 3]> {
    let mut out = Vec::new();
    for i in 0..3u8 {
        for j in 0..3u8 {
            for n in 0..=(if j == 2 { 2u8 } else { 1 }) {
                out.push([i, j, n]);
            }
        }
    }
    out
}

/// `T_ij(k1)` and `|T|_ij(|k1|)` (absolute-value scale) from the 21 inputs.
#[must_use]
pub fn case4_t_at(t: &[f64; 21], k1: f64) -> (Matrix3<f64>, Matrix3<f64>) {
    let mut tv = Matrix3::zeros();
    let mut ta = Matrix3::zeros();
    for (x, e) in t.iter().zip(case4_layout()) {
        let (i, j, n) = (e[0] as usize, e[1] as usize, e[2] as i32);
        tv[(i, j)] += x * k1.powi(n);
        ta[(i, j)] += x.abs() * k1.abs().powi(n);
    }
    (tv, ta)
}

/// `M(k1)` from docs/algorithm.md, `nullspace` case 4 with numeric `T = T(k1)` (rows `T_i`):
///
/// `row_i   = (T00 - T21) T2 + T01 T1 - T20 T0 + [-T22, T02, 0]`,
/// `row_ii  = (T20 - T11) T2 + T21 T1 - T10 T0 + [-T12, T22, 0]`,
/// `row_iii = P00 T0 + P11 T1 + 2 P01 T2 + [2 P02, 2 P12, P22]`,
/// `P_ab = T2a T2b - (T0a T1b + T1a T0b) / 2`.
///
/// Called with `sign = -1` and `|T|` it returns the absolute-value scale (every minus turned
/// into a plus).
#[must_use]
pub fn case4_m_from_t(t: &Matrix3<f64>, abs: bool) -> Matrix3<f64> {
    let sg = if abs { 1.0 } else { -1.0 };
    let row = |i: usize| t.row(i).transpose();
    let (t0, t1, t2) = (row(0), row(1), row(2));
    let r1 = (t[(0, 0)] + sg * t[(2, 1)]) * t2
        + t[(0, 1)] * t1
        + sg * t[(2, 0)] * t0
        + Vector3::new(sg * t[(2, 2)], t[(0, 2)], 0.0);
    let r2 = (t[(2, 0)] + sg * t[(1, 1)]) * t2
        + t[(2, 1)] * t1
        + sg * t[(1, 0)] * t0
        + Vector3::new(sg * t[(1, 2)], t[(2, 2)], 0.0);
    let p = |a: usize, b: usize| {
        t[(2, a)] * t[(2, b)] + sg * (t[(0, a)] * t[(1, b)] + t[(1, a)] * t[(0, b)]) / 2.0
    };
    let pm = |a: usize, b: usize| if abs { p(a, b).abs() } else { p(a, b) };
    let r3 = pm(0, 0) * t0
        + pm(1, 1) * t1
        + 2.0 * pm(0, 1) * t2
        + Vector3::new(2.0 * pm(0, 2), 2.0 * pm(1, 2), pm(2, 2));
    Matrix3::from_rows(&[r1.transpose(), r2.transpose(), r3.transpose()])
}

/// The kernel's 45-number layout of `M(k1)` evaluated at `k1`: entry `(i, j)` is
/// `sum_n out[(3 i + j) * 5 + n] k1^n`.
#[must_use]
pub fn case4_layout_at(out: &[f64; 45], k1: f64) -> Matrix3<f64> {
    Matrix3::from_fn(|i, j| poly_eval(&out[(3 * i + j) * 5..(3 * i + j) * 5 + 5], k1).0)
}
