//! The cost in the Cayley parameters: `rbar(s)`, its Jacobian and second derivatives, `C(s)`,
//! its gradient and Hessian with their absolute-value scales, and my own enumerations of the
//! kernels' monomials and input layouts.

use nalgebra::{ComplexField, Matrix3, Vector3};

use super::{c, skew, J93, M9, V9};

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
