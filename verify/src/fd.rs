//! Finite differences (central, and complex-step) with their error bounds.
//!
//! A central difference `(f(x + h) - f(x - h)) / (2 h)` of a function whose third derivative is
//! bounded by `T3` on `[x - h, x + h]` and whose values carry absolute rounding errors `<= E`
//! has error `<= h^2 T3 / 6 + E / h` (Taylor with remainder; two rounded values over `2 h`).
//! The optimal step is `h ~ (3 E / T3)^(1/3)`, hence `h = u^(1/3) * scale`. The floating-point
//! nodes `fl(x +- h)` make the two actual steps `hp`, `hm` differ by a few ulps; the quotient
//! `(f(x + hp) - f(x - hm)) / (hp + hm)` then has the extra first-order term
//! `|hp - hm| / 2 * |f''|`, which the bounds below include.
//!
//! A second difference `(f(x + h) - 2 f(x) + f(x - h)) / h^2` has error `<= h^2 T4 / 12 + 4 E / h^2`.
//!
//! The complex step `Im f(x + i h) / h` (h = 1e-30) has no subtractive cancellation: its error
//! is the rounding of the evaluation of the derivative itself (`O(u)` relative to the
//! absolute-value scale) plus `h^2 T3 / 6`, negligible.

use crate::reference::{self, Chart, M9};
use nalgebra::Vector3;

/// `u^(1/3)`, the relative central-difference step.
pub const H_REL: f64 = 6.055454452393343e-6; // (2^-53)^(1/3)

/// The complex step.
pub const H_COMPLEX: f64 = 1e-30;

/// Central-difference nodes along coordinate `k`: `(s_plus, s_minus, hp, hm)` with
/// `hp = fl(s_k + h) - s_k`, `hm = s_k - fl(s_k - h)` (the actual steps, exact to rounding).
#[must_use]
pub fn nodes(s: &[f64; 3], k: usize, h: f64) -> ([f64; 3], [f64; 3], f64, f64) {
    let mut sp = *s;
    let mut sm = *s;
    sp[k] = s[k] + h;
    sm[k] = s[k] - h;
    (sp, sm, sp[k] - s[k], s[k] - sm[k])
}

/// The step `h = u^(1/3) max(1, |s|)` used for the cost polynomial (scale of `s`).
#[must_use]
pub fn cost_step(s: &[f64; 3]) -> f64 {
    let n = (s[0] * s[0] + s[1] * s[1] + s[2] * s[2]).sqrt();
    H_REL * n.max(1.0)
}

/// `|s| + h` componentwise: every absolute-value scale below is monotone in `|s_i|`, so
/// evaluating it there bounds it on the whole difference stencil.
#[must_use]
pub fn s_big(s: &[f64; 3], h: f64) -> [f64; 3] {
    [s[0].abs() + h, s[1].abs() + h, s[2].abs() + h]
}

/// Bound on `|d^3 C / ds_k^3|` on the stencil. Along `t -> s + t e_k`, `u(t) = rbar` is
/// quadratic with `u' = J e_k + t HR[.][k][k]`, `u'' = HR[.][k][k]`, so
/// `d^3 (u^T M u) / dt^3 = 6 u''^T M u'`: bounded by `6 |u''|^T |M| (|J(s_big) e_k| + h |u''|)`.
#[must_use]
pub fn cost_d3_bound(m: &M9, s: &[f64; 3], k: usize, h: f64) -> f64 {
    let hrs = reference::hr();
    let upp = nalgebra::SVector::<f64, 9>::from_fn(|a, _| hrs[a][(k, k)].abs());
    let jk = reference::jac(&s_big(s, h)).column(k).abs();
    6.0 * upp.dot(&(m.abs() * (jk + h * upp)))
}

/// Bound on `|d^2 C / ds_k^2|` on the stencil: the absolute-value scale of the Hessian at
/// `s_big`.
#[must_use]
pub fn cost_d2_bound(m: &M9, s: &[f64; 3], k: usize, h: f64) -> f64 {
    reference::cost_scales(m, &s_big(s, h)).2[(k, k)]
}

/// Bound on `|d^3 g_j / ds_k^3|` (constant): with `g_j = 2 sum_ab M_ab (d_j rbar_a) rbar_b`,
/// `d_j rbar_a` is linear along `e_k` (slope `HR_a[j][k]`) and `rbar_b` quadratic (curvature
/// `HR_b[k][k]`), so `d^3 g_j / dt^3 = 6 sum_ab M_ab HR_a[j][k] HR_b[k][k]`.
#[must_use]
pub fn grad_d3_bound(m: &M9, j: usize, k: usize) -> f64 {
    let hrs = reference::hr();
    let a = nalgebra::SVector::<f64, 9>::from_fn(|x, _| hrs[x][(j, k)].abs());
    let b = nalgebra::SVector::<f64, 9>::from_fn(|x, _| hrs[x][(k, k)].abs());
    6.0 * a.dot(&(m.abs() * b))
}

/// Bound on `|d^2 g_j / ds_k^2|` on the stencil: `2 sum_ab M_ab (2 lin'_a quad'_b + lin_a quad''_b)`
/// with `lin = d_j rbar`, `quad = rbar` along `e_k`.
#[must_use]
pub fn grad_d2_bound(m: &M9, s: &[f64; 3], j: usize, k: usize, h: f64) -> f64 {
    let hrs = reference::hr();
    let jb = reference::jac(&s_big(s, h)).abs();
    let hjk = nalgebra::SVector::<f64, 9>::from_fn(|x, _| hrs[x][(j, k)].abs());
    let hkk = nalgebra::SVector::<f64, 9>::from_fn(|x, _| hrs[x][(k, k)].abs());
    let ma = m.abs();
    2.0 * (2.0 * hjk.dot(&(ma * jb.column(k))) + jb.column(j).dot(&(ma * hkk)))
}

/// Derivative bounds of `F(t u) = f(Rot_u(phi(t)) R)`, `phi = 2 atan t`, for `|t| <= 1e-3`,
/// in units of the amplitude `A_u` (`reference::chart_amplitude`), from `|f^(n)(phi)| <= 2^n A_u`
/// and `phi' = 2 / (1 + t^2)`, `phi'' = -4 t / (1 + t^2)^2`, `phi''' = (12 t^2 - 4) / (1 + t^2)^3`,
/// `phi'''' = 48 t (1 - t^2) / (1 + t^2)^4`:
///
/// `F''' = f''' phi'^3 + 3 f'' phi' phi'' + f' phi'''` <= `64 + 96 t + 8 + 24 t^2` < 73 (`A_u`);
/// `F'''' = f'''' phi'^4 + 6 f''' phi'^2 phi'' + f'' (3 phi''^2 + 4 phi' phi''') + f' phi''''`
/// <= `256 + 768 t + 4 (48 t^2 + 32 + 96 t^2) + 96 t` < 386 (`A_u`).
/// `F' <= 2 * 2 = 4` (`A_u`).
pub const CHART_D1: f64 = 4.0;
/// See [`CHART_D1`].
pub const CHART_D3: f64 = 73.0;
/// See [`CHART_D1`].
pub const CHART_D4: f64 = 386.0;

/// Rounding bound of one evaluation of `F` (or of the cost `C`) in units of its
/// absolute-value scale: the entries of `R(s) R` (or `rbar`) carry a few roundings each
/// (<= 8 u relative), the 9-term inner products of the quadratic form 2 x 9 more: 64 u is a
/// generous `gamma`.
pub const EVAL_ROUNDING: f64 = 64.0 * reference::U;

/// Central-difference gradient of `F` at 0 along the unit vector `u`, step `h`.
#[must_use]
pub fn chart_central(f: &impl Chart, u: &Vector3<f64>, h: f64) -> f64 {
    let sp = [h * u[0], h * u[1], h * u[2]];
    let sm = [-h * u[0], -h * u[1], -h * u[2]];
    (f.value(&sp) - f.value(&sm)) / (2.0 * h)
}

/// Second difference of `F` at 0 along `u`, step `h`: `u^T hess F(0) u + O(h^2)`.
#[must_use]
pub fn chart_second(f: &impl Chart, u: &Vector3<f64>, h: f64) -> f64 {
    let sp = [h * u[0], h * u[1], h * u[2]];
    let sm = [-h * u[0], -h * u[1], -h * u[2]];
    let f0 = f.value(&[0.0; 3]);
    (f.value(&sp) - 2.0 * f0 + f.value(&sm)) / (h * h)
}

/// Complex-step derivative `d/dt F(t u)` at `t`: `Im F((t + i h) u) / h`.
#[must_use]
pub fn chart_complex_step(f: &impl Chart, u: &Vector3<f64>, t: f64) -> f64 {
    use num_complex::Complex64;
    let z = Complex64::new(t, H_COMPLEX);
    let s = [z * u[0], z * u[1], z * u[2]];
    f.value(&s).im / H_COMPLEX
}
