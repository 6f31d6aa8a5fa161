//! Direct numeric definitions (docs/algorithm.md sections 1, 3 and 4), written from the formulas
//! with nalgebra and never from `eopnp-codegen`.
//!
//! Symbols: `s = (s1, s2, s3)` the CGR parameters, `Rbar(s) = (1 - s^T s) I + 2 [s]x + 2 s s^T`,
//! `rbar = vec(Rbar)` row-major, `J = d rbar / d s` (9 x 3), `HR_a = d^2 rbar_a / ds ds` (3 x 3),
//! `M` the symmetric 9 x 9 cost matrix, `C(s) = rbar^T M rbar`.
//!
//! Every value comes with an *absolute-value scale*: the same expression evaluated with every
//! input and every coefficient replaced by its absolute value (the "running error" scale of a
//! straight-line evaluation). A straight-line evaluation of depth `d` has forward error at most
//! `gamma_d = d u / (1 - d u)` times that scale (Higham, *Accuracy and Stability of Numerical
//! Algorithms*, 2nd ed., section 3.1), whatever cancellation the value itself suffers. The
//! verification norms divide by these scales.
//!
//! Generic functions take `T: ComplexField<RealField = f64>` so that the same definition runs in
//! `f64` and in `Complex<f64>` (complex-step derivatives).

use nalgebra::{ComplexField, DMatrix, Matrix3, SMatrix, SVector, Vector3};

/// 9 x 9 real matrix (the cost matrix `M`).
pub type M9 = SMatrix<f64, 9, 9>;
/// 9-vector (`rbar`, `vec(R)`).
pub type V9 = SVector<f64, 9>;
/// 9 x 3 matrix (the Jacobian `J`).
pub type J93 = SMatrix<f64, 9, 3>;

/// Unit roundoff of f64, `2^-53`.
pub const U: f64 = f64::EPSILON / 2.0;

/// `gamma_n = n u / (1 - n u)` (Higham, Lemma 3.1).
#[must_use]
pub fn gamma(n: usize) -> f64 {
    let nu = n as f64 * U;
    nu / (1.0 - nu)
}

fn c<T: ComplexField<RealField = f64>>(x: f64) -> T {
    T::from_real(x)
}

/// `[a]x` (docs/algorithm.md section 1).
#[must_use]
pub fn skew<T: ComplexField<RealField = f64> + Copy>(a: &[T; 3]) -> [[T; 3]; 3] {
    let z = c::<T>(0.0);
    [[z, -a[2], a[1]], [a[2], z, -a[0]], [-a[1], a[0], z]]
}

/// `rbar(s) = vec((1 - s^T s) I + 2 [s]x + 2 s s^T)`, row-major (eq. 1).
#[must_use]
pub fn rbar_g<T: ComplexField<RealField = f64> + Copy>(s: &[T; 3]) -> [T; 9] {
    let sts = s[0] * s[0] + s[1] * s[1] + s[2] * s[2];
    let sk = skew(s);
    let two = c::<T>(2.0);
    let mut out = [c::<T>(0.0); 9];
    for i in 0..3 {
        for j in 0..3 {
            let mut v = two * s[i] * s[j] + two * sk[i][j];
            if i == j {
                v += c::<T>(1.0) - sts;
            }
            out[3 * i + j] = v;
        }
    }
    out
}

/// `J(s) = d rbar / d s` (9 x 3), from differentiating the Cayley formula:
/// `d Rbar / d s_k = -2 s_k I + 2 [e_k]x + 2 (e_k s^T + s e_k^T)`.
#[must_use]
pub fn jac_g<T: ComplexField<RealField = f64> + Copy>(s: &[T; 3]) -> [[T; 3]; 9] {
    let two = c::<T>(2.0);
    let z = c::<T>(0.0);
    let mut out = [[z; 3]; 9];
    for k in 0..3 {
        let mut e = [z; 3];
        e[k] = c::<T>(1.0);
        let ek = skew(&e);
        for i in 0..3 {
            for j in 0..3 {
                let mut v = two * ek[i][j];
                if i == j {
                    v -= two * s[k];
                }
                if i == k {
                    v += two * s[j];
                }
                if j == k {
                    v += two * s[i];
                }
                out[3 * i + j][k] = v;
            }
        }
    }
    out
}

/// `HR_a[k][l] = d^2 Rbar_ij / ds_k ds_l = -2 delta_kl delta_ij + 2 (delta_ik delta_jl +
/// delta_il delta_jk)`, `a = 3 i + j` (constant in `s`).
#[must_use]
pub fn hr() -> [Matrix3<f64>; 9] {
    let mut out = [Matrix3::zeros(); 9];
    for i in 0..3 {
        for j in 0..3 {
            let h = &mut out[3 * i + j];
            for k in 0..3 {
                for l in 0..3 {
                    let mut v = 0.0;
                    if k == l && i == j {
                        v -= 2.0;
                    }
                    if i == k && j == l {
                        v += 2.0;
                    }
                    if i == l && j == k {
                        v += 2.0;
                    }
                    h[(k, l)] = v;
                }
            }
        }
    }
    out
}

/// `rbar(s)` as an nalgebra vector.
#[must_use]
pub fn rbar(s: &[f64; 3]) -> V9 {
    V9::from_column_slice(&rbar_g(s))
}

/// `J(s)` as an nalgebra matrix.
#[must_use]
pub fn jac(s: &[f64; 3]) -> J93 {
    let j = jac_g(s);
    J93::from_fn(|a, k| j[a][k])
}

/// Absolute-value scale of `rbar(s)`: every entry of `Rbar` is, after cancellation, a sum of
/// monomials with coefficients +-1 or +-2: diagonal `1 + s_i^2 - s_j^2 - s_k^2` -> `1 + |s|^2`,
/// off-diagonal `(i, j)` `2 s_i s_j +- 2 s_k` -> `2 |s_i s_j| + 2 |s_k|` (`k` the third index).
#[must_use]
pub fn rbar_abs(s: &[f64; 3]) -> V9 {
    let n2 = s[0] * s[0] + s[1] * s[1] + s[2] * s[2];
    V9::from_fn(|a, _| {
        let (i, j) = (a / 3, a % 3);
        if i == j {
            1.0 + n2
        } else {
            let k = 3 - i - j;
            2.0 * (s[i] * s[j]).abs() + 2.0 * s[k].abs()
        }
    })
}

/// `C(s) = rbar(s)^T M rbar(s)` (eq. 14), generic.
#[must_use]
pub fn cost_g<T: ComplexField<RealField = f64> + Copy>(m: &M9, s: &[T; 3]) -> T {
    let r = rbar_g(s);
    let mut acc = c::<T>(0.0);
    for a in 0..9 {
        let mut row = c::<T>(0.0);
        for b in 0..9 {
            row += c::<T>(m[(a, b)]) * r[b];
        }
        acc += r[a] * row;
    }
    acc
}

/// `grad C(s) = 2 J(s)^T M rbar(s)` (docs/algorithm.md, G2), generic.
#[must_use]
pub fn grad_g<T: ComplexField<RealField = f64> + Copy>(m: &M9, s: &[T; 3]) -> [T; 3] {
    let r = rbar_g(s);
    let j = jac_g(s);
    let mut mr = [c::<T>(0.0); 9];
    for a in 0..9 {
        for b in 0..9 {
            mr[a] += c::<T>(m[(a, b)]) * r[b];
        }
    }
    let mut g = [c::<T>(0.0); 3];
    for k in 0..3 {
        for a in 0..9 {
            g[k] += c::<T>(2.0) * j[a][k] * mr[a];
        }
    }
    g
}

/// `C(s)` in f64.
#[must_use]
pub fn cost(m: &M9, s: &[f64; 3]) -> f64 {
    let r = rbar(s);
    r.dot(&(m * r))
}

/// `grad C(s) = 2 J^T M rbar` in f64.
#[must_use]
pub fn grad(m: &M9, s: &[f64; 3]) -> Vector3<f64> {
    2.0 * jac(s).transpose() * (m * rbar(s))
}

/// `hess C(s) = 2 J^T M J + 2 sum_a (M rbar)_a HR_a` (docs/algorithm.md, `newton` and G2).
#[must_use]
pub fn hess(m: &M9, s: &[f64; 3]) -> Matrix3<f64> {
    let j = jac(s);
    let mr = m * rbar(s);
    let hrs = hr();
    let mut h = 2.0 * j.transpose() * m * j;
    for a in 0..9 {
        h += 2.0 * mr[a] * hrs[a];
    }
    h
}

/// Absolute-value scales of `C`, `grad C`, `hess C` at `s` (see the module doc): with
/// `|r| = rbar_abs(s)`, `|J|` (every entry of `J` is a single monomial, so `|J|` is its own
/// absolute-value scale) and `|HR_a|`:
/// `S_C = |r|^T |M| |r|`, `S_g = 2 |J|^T |M| |r|`, `S_H = 2 |J|^T |M| |J| + 2 sum_a (|M| |r|)_a |HR_a|`.
#[must_use]
pub fn cost_scales(m: &M9, s: &[f64; 3]) -> (f64, Vector3<f64>, Matrix3<f64>) {
    let ma = m.abs();
    let ra = rbar_abs(s);
    let ja = jac(s).abs();
    let mra = ma * ra;
    let hrs = hr();
    let mut sh = 2.0 * ja.transpose() * ma * ja;
    for a in 0..9 {
        sh += 2.0 * mra[a] * hrs[a].abs();
    }
    (ra.dot(&mra), 2.0 * ja.transpose() * mra, sh)
}

/// My own enumeration of the 35 cost monomials (docs/algorithm.md G1: degree 4, 3, 2, 1, 0; within a
/// degree by decreasing power of `s1`, then of `s2`). Compared with `COST_MONOMIALS` in a test.
#[must_use]
pub fn cost_monomials() -> Vec<[u8; 3]> {
    let mut out = Vec::new();
    for d in (0..=4u8).rev() {
        for a in (0..=d).rev() {
            for b in (0..=d - a).rev() {
                out.push([a, b, d - a - b]);
            }
        }
    }
    out
}

/// `sum_i c[i] s^e_i` and `sum_i |c[i]| |s^e_i|` with my own monomial enumeration.
#[must_use]
pub fn eval_monomials(coef: &[f64; 35], s: &[f64; 3]) -> (f64, f64) {
    let mons = cost_monomials();
    let (mut v, mut a) = (0.0, 0.0);
    for (ci, e) in coef.iter().zip(&mons) {
        let m = s[0].powi(e[0] as i32) * s[1].powi(e[1] as i32) * s[2].powi(e[2] as i32);
        v += ci * m;
        a += (ci * m).abs();
    }
    (v, a)
}

/// My own enumeration of the upper triangle of a symmetric matrix over the given indices, row by
/// row: (i, j) with i <= j (compared with `COST_M_UPPER` / `PLANAR_M_UPPER` in a test).
#[must_use]
pub fn upper_pairs(idx: &[usize]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    for (p, &i) in idx.iter().enumerate() {
        for &j in &idx[p..] {
            out.push((i, j));
        }
    }
    out
}

/// The 45 upper-triangle entries of `M` (kernel input layout).
#[must_use]
pub fn m_upper45(m: &M9) -> [f64; 45] {
    let pairs = upper_pairs(&[0, 1, 2, 3, 4, 5, 6, 7, 8]);
    std::array::from_fn(|k| m[pairs[k]])
}

/// `PLANAR` (docs/algorithm.md, constants and tolerances): the entries of `r` in the first two
/// columns of `R`.
pub const PLANAR: [usize; 6] = [0, 1, 3, 4, 6, 7];

/// The 21 planar upper-triangle entries of `M` (planar kernel input layout).
#[must_use]
pub fn m_upper21(m: &M9) -> [f64; 21] {
    let pairs = upper_pairs(&PLANAR);
    std::array::from_fn(|k| m[pairs[k]])
}

/// `M` with rows and columns 2, 5, 8 set to zero (the planar cost matrix).
#[must_use]
pub fn planar_restrict(m: &M9) -> M9 {
    M9::from_fn(|i, j| {
        if PLANAR.contains(&i) && PLANAR.contains(&j) {
            m[(i, j)]
        } else {
            0.0
        }
    })
}

// ----------------------------------------------------------------------------------------------
// `newton`: the local model on SO(3)

/// `D = blockdiag(R^T, R^T, R^T)` (docs/algorithm.md, `newton`), so that `vec(A R) = D vec(A)`.
#[must_use]
pub fn blockdiag_rt(r: &Matrix3<f64>) -> M9 {
    let mut d = M9::zeros();
    for b in 0..3 {
        d.fixed_view_mut::<3, 3>(3 * b, 3 * b)
            .copy_from(&r.transpose());
    }
    d
}

/// Row-major `vec(R)`.
#[must_use]
pub fn vec_r(r: &Matrix3<f64>) -> V9 {
    V9::from_fn(|a, _| r[(a / 3, a % 3)])
}

/// The explicit `newton` model at `R`: `M_k = D^T M D`, `f = e^T M_k e`, `g = 2 J0^T M_k e`,
/// `H_C = 2 J0^T M_k J0 + 2 sum_j (M_k e)_j HR_j`, with their absolute-value scales
/// (`|D|`, `|J0|`, `|HR_j|` in place of `D`, `J0`, `HR_j`; `D e = vec(R)`).
#[must_use]
pub fn local_model(m: &M9, r: &Matrix3<f64>) -> LocalModel {
    let d = blockdiag_rt(r);
    let mk = d.transpose() * m * d;
    let e = vec_r(&Matrix3::identity());
    let j0 = jac(&[0.0; 3]);
    let mke = mk * e;
    let hrs = hr();
    let mut hc = 2.0 * j0.transpose() * mk * j0;
    for a in 0..9 {
        hc += 2.0 * mke[a] * hrs[a];
    }
    let (da, ma, j0a) = (d.abs(), m.abs(), j0.abs());
    let ra = vec_r(r).abs();
    let mkea = da.transpose() * ma * ra;
    let mut sh = 2.0 * j0a.transpose() * da.transpose() * ma * da * j0a;
    for a in 0..9 {
        sh += 2.0 * mkea[a] * hrs[a].abs();
    }
    LocalModel {
        f: e.dot(&mke),
        g: 2.0 * j0.transpose() * mke,
        hc,
        sf: ra.dot(&(ma * ra)),
        sg: 2.0 * j0a.transpose() * mkea,
        sh,
    }
}

/// Output of [`local_model`].
#[derive(Clone, Copy, Debug)]
pub struct LocalModel {
    /// `f = vec(R)^T M vec(R)`.
    pub f: f64,
    /// Gradient in the chart.
    pub g: Vector3<f64>,
    /// `H_C` (Hessian of `C_k` at 0).
    pub hc: Matrix3<f64>,
    /// Absolute-value scale of `f`.
    pub sf: f64,
    /// Absolute-value scale of `g`.
    pub sg: Vector3<f64>,
    /// Absolute-value scale of `H_C`.
    pub sh: Matrix3<f64>,
}

/// `F(s) = f(R(s) R)`, `R(s) = Rbar(s) / (1 + s^T s)` (docs/algorithm.md, `newton`), generic.
#[must_use]
pub fn chart_f<T: ComplexField<RealField = f64> + Copy>(m: &M9, r: &Matrix3<f64>, s: &[T; 3]) -> T {
    let rb = rbar_g(s);
    let den = c::<T>(1.0) + s[0] * s[0] + s[1] * s[1] + s[2] * s[2];
    let mut v = [c::<T>(0.0); 9];
    for i in 0..3 {
        for j in 0..3 {
            let mut acc = c::<T>(0.0);
            for k in 0..3 {
                acc += rb[3 * i + k] * c::<T>(r[(k, j)]);
            }
            v[3 * i + j] = acc / den;
        }
    }
    let mut f = c::<T>(0.0);
    for a in 0..9 {
        let mut row = c::<T>(0.0);
        for b in 0..9 {
            row += c::<T>(m[(a, b)]) * v[b];
        }
        f += v[a] * row;
    }
    f
}

/// The amplitude `A_u = (|a| + |b| + |c|)^T |M| (|a| + |b| + |c|)` of `phi -> f(Rot_u(phi) R)`
/// for a unit direction `u`, with `Rot_u(phi) = u u^T + cos(phi) (I - u u^T) + sin(phi) [u]x`,
/// `a = vec(u u^T R)`, `b = vec((I - u u^T) R)`, `c = vec([u]x R)`. Along the line `s = t u`
/// the chart rotation is `R(t u) = Rot_u(2 atan t)`, and `|d^n f / d phi^n| <= 2^n A_u`
/// (f is a trigonometric polynomial of degree 2 in phi whose coefficients are bounded by
/// the products in `A_u`); `crate::fd` turns this into bounds on the derivatives of `F(t u)`.
#[must_use]
pub fn chart_amplitude(m: &M9, r: &Matrix3<f64>, u: &Vector3<f64>) -> f64 {
    let p = u * u.transpose();
    let q = Matrix3::identity() - p;
    let sk = skew(&[u[0], u[1], u[2]]);
    let s = Matrix3::from_fn(|i, j| sk[i][j]);
    let w = vec_r(&(p * r)).abs() + vec_r(&(q * r)).abs() + vec_r(&(s * r)).abs();
    w.dot(&(m.abs() * w))
}

// ----------------------------------------------------------------------------------------------
// Determinant helpers

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
