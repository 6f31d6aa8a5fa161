//! `newton`: the local model on SO(3) at a rotation `R`, the chart `F(s) = f(R(s) R)` and the
//! amplitude that bounds its derivatives.

use nalgebra::{ComplexField, Matrix3, Vector3};

use super::cost::{hr, jac, rbar_g};
use super::{c, skew, M9, V9};

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

/// A function on the CGR chart centred on a rotation, `F(s) = f(R(s) R)`, whose derivatives
/// `crate::fd` estimates: its generic value and the amplitude that bounds its derivatives along
/// a line `s = t u`.
pub trait Chart {
    /// `F(s)`, generic (`f64` and `Complex<f64>`).
    fn value<T: ComplexField<RealField = f64> + Copy>(&self, s: &[T; 3]) -> T;
    /// `A_u` with `|d^n f(Rot_u(phi) R) / d phi^n| <= 2^n A_u`.
    fn amplitude(&self, u: &Vector3<f64>) -> f64;
}

/// The quadratic cost `vec(R)^T M vec(R)` on the chart ([`chart_f`], [`chart_amplitude`]).
#[derive(Clone, Copy, Debug)]
pub struct QuadraticChart<'a> {
    /// The cost matrix.
    pub m: &'a M9,
    /// The chart's centre.
    pub r: &'a Matrix3<f64>,
}

impl Chart for QuadraticChart<'_> {
    fn value<T: ComplexField<RealField = f64> + Copy>(&self, s: &[T; 3]) -> T {
        chart_f(self.m, self.r, s)
    }
    fn amplitude(&self, u: &Vector3<f64>) -> f64 {
        chart_amplitude(self.m, self.r, u)
    }
}

/// The affine part `2 g^T vec(R) + k` on the chart ([`affine_chart_f`], [`affine_amplitude`]).
#[derive(Clone, Copy, Debug)]
pub struct AffineChart<'a> {
    /// The linear term.
    pub g: &'a V9,
    /// The constant term.
    pub k: f64,
    /// The chart's centre.
    pub r: &'a Matrix3<f64>,
}

impl Chart for AffineChart<'_> {
    fn value<T: ComplexField<RealField = f64> + Copy>(&self, s: &[T; 3]) -> T {
        affine_chart_f(self.g, self.k, self.r, s)
    }
    fn amplitude(&self, u: &Vector3<f64>) -> f64 {
        affine_amplitude(self.g, self.k, self.r, u)
    }
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

/// The explicit model of the generalized cost's affine part `2 g^T vec(R) + k` at `R`
/// (docs/algorithm.md, generalized EOPnP): with `g_k = D^T g`, `e = vec(I)`, `p(s) = 1 + s^T s`
/// and `A_k(s) = 2 p g_k^T rbar(s) + k p^2`: `f = 2 g_k^T e + k`, `g = 2 J0^T g_k`,
/// `H_C = 4 (g_k^T e + k) I + 2 sum_j (g_k)_j HR_j` (`p' = 0`, `p'' = 2 I` at 0), with their
/// absolute-value scales.
#[must_use]
pub fn affine_model(g: &V9, k: f64, r: &Matrix3<f64>) -> LocalModel {
    let d = blockdiag_rt(r);
    let gk = d.transpose() * g;
    let e = vec_r(&Matrix3::identity());
    let j0 = jac(&[0.0; 3]);
    let hrs = hr();
    let l0 = gk.dot(&e);
    let mut hc = 4.0 * (l0 + k) * Matrix3::identity();
    for a in 0..9 {
        hc += 2.0 * gk[a] * hrs[a];
    }
    let gka = d.abs().transpose() * g.abs();
    let l0a = gka.dot(&e);
    let mut sh = 4.0 * (l0a + k.abs()) * Matrix3::identity();
    for a in 0..9 {
        sh += 2.0 * gka[a] * hrs[a].abs();
    }
    LocalModel {
        f: 2.0 * l0 + k,
        g: 2.0 * j0.transpose() * gk,
        hc,
        sf: 2.0 * l0a + k.abs(),
        sg: 2.0 * j0.abs().transpose() * gka,
        sh,
    }
}

/// `F(s) = 2 g^T vec(R(s) R) + k`, generic (the affine part of the generalized cost on the chart).
#[must_use]
pub fn affine_chart_f<T: ComplexField<RealField = f64> + Copy>(
    g: &V9,
    k: f64,
    r: &Matrix3<f64>,
    s: &[T; 3],
) -> T {
    let rb = rbar_g(s);
    let den = c::<T>(1.0) + s[0] * s[0] + s[1] * s[1] + s[2] * s[2];
    let mut f = c::<T>(k);
    for i in 0..3 {
        for j in 0..3 {
            let mut acc = c::<T>(0.0);
            for l in 0..3 {
                acc += rb[3 * i + l] * c::<T>(r[(l, j)]);
            }
            f += c::<T>(2.0 * g[3 * i + j]) * acc / den;
        }
    }
    f
}

/// The amplitude `A_u = 2 |g|^T (|a| + |b| + |c|) + |k|` of `phi -> 2 g^T vec(Rot_u(phi) R) + k`
/// (`a`, `b`, `c` as in [`chart_amplitude`]): a trigonometric polynomial of degree 1 in `phi`, so
/// `|d^n f / d phi^n| <= A_u <= 2^n A_u` and `crate::fd`'s chart bounds hold for it.
#[must_use]
pub fn affine_amplitude(g: &V9, k: f64, r: &Matrix3<f64>, u: &Vector3<f64>) -> f64 {
    let p = u * u.transpose();
    let q = Matrix3::identity() - p;
    let sk = skew(&[u[0], u[1], u[2]]);
    let s = Matrix3::from_fn(|i, j| sk[i][j]);
    let w = vec_r(&(p * r)).abs() + vec_r(&(q * r)).abs() + vec_r(&(s * r)).abs();
    2.0 * g.abs().dot(&w) + k.abs()
}
