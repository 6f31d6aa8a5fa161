//! The checks of the cost kernels: the coefficients and the value of the quartic cost in the
//! Cayley parameters, its gradient and its Hessian (full and planar).

use crate::fd::{self, EVAL_ROUNDING, H_COMPLEX};
use crate::reference::{self as rf, M9};
use crate::report::{Measurement, Tracker};
use crate::strategies as st;
use eopnp::internals::kernels as k;
use nalgebra::{Matrix3, Vector3};
use num_complex::Complex64;

use super::{g64, sym3, TOL_POLY};

fn fmt3(s: &[f64; 3]) -> String {
    format!("[{:e}, {:e}, {:e}]", s[0], s[1], s[2])
}

/// Cost variant: the full 9 x 9 `M` or the planar restriction.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Variant {
    /// `cost_coefficients` / `cost_gradient` / `cost_hessian`.
    Full,
    /// `planar_cost_coefficients` / `planar_cost_gradient` / `planar_cost_hessian`.
    Planar,
}

impl Variant {
    fn matrix(self, rng: &mut rand_pcg::Pcg64) -> M9 {
        let m = st::cost_matrix(rng);
        match self {
            Variant::Full => m,
            Variant::Planar => rf::planar_restrict(&m),
        }
    }
    fn coefficients(self, m: &M9) -> [f64; 35] {
        match self {
            Variant::Full => k::cost_coefficients(&rf::m_upper45(m)),
            Variant::Planar => k::planar_cost_coefficients(&rf::m_upper21(m)),
        }
    }
    fn gradient(self, m: &M9, s: &[f64; 3]) -> Vector3<f64> {
        let g = match self {
            Variant::Full => k::cost_gradient(&k::cost_coefficients(&rf::m_upper45(m)), s),
            Variant::Planar => k::planar_cost_gradient(&rf::m_upper21(m), s),
        };
        Vector3::from(g)
    }
    fn hessian(self, m: &M9, s: &[f64; 3]) -> Matrix3<f64> {
        let h = match self {
            Variant::Full => k::cost_hessian(&k::cost_coefficients(&rf::m_upper45(m)), s),
            Variant::Planar => k::planar_cost_hessian(&rf::m_upper21(m), s),
        };
        sym3(&h)
    }
    fn name(self, full: &'static str, planar: &'static str) -> &'static str {
        match self {
            Variant::Full => full,
            Variant::Planar => planar,
        }
    }
}

/// Check 1: `sum_i c[i] s^e_i` (my monomial enumeration) vs `rbar^T M rbar` (nalgebra).
/// Norm: `|dC| / S_C`, `S_C = |rbar|_abs^T |M| |rbar|_abs`.
#[must_use]
pub fn cost_coefficients(variant: Variant, n: usize) -> Measurement {
    let seed = 11 + variant as u64;
    let mut rng = st::rng(seed);
    let mut t = Tracker::new(
        variant.name("cost_coefficients", "planar_cost_coefficients"),
        "sum c_i s^e_i vs rbar^T M rbar",
        "|dC| / S_C",
        format!("{TOL_POLY:.0e}"),
    );
    for i in 0..n {
        let m = variant.matrix(&mut rng);
        let s = st::cgr(&mut rng);
        let c = variant.coefficients(&m);
        let (v, _) = rf::eval_monomials(&c, &s);
        let (sc, _, _) = rf::cost_scales(&m, &s);
        let err = (v - rf::cost(&m, &s)).abs() / sc;
        t.record(err, TOL_POLY, || {
            format!("seed {seed} sample {i} s = {}", fmt3(&s))
        });
    }
    t.finish()
}

/// `cost(c, s)` (generated, from `cost_coefficients`) vs `rbar^T M rbar`. Norm `|dC| / S_C`.
#[must_use]
pub fn cost_value(variant: Variant, n: usize) -> Measurement {
    let seed = 21 + variant as u64;
    let mut rng = st::rng(seed);
    let mut t = Tracker::new(
        "cost",
        variant.name(
            "cost(cost_coefficients) vs rbar^T M rbar",
            "cost(planar_cost_coefficients) vs rbar^T M rbar",
        ),
        "|dC| / S_C",
        format!("{TOL_POLY:.0e}"),
    );
    for i in 0..n {
        let m = variant.matrix(&mut rng);
        let s = st::cgr(&mut rng);
        let v = k::cost(&variant.coefficients(&m), &s);
        let (sc, _, _) = rf::cost_scales(&m, &s);
        let err = (v - rf::cost(&m, &s)).abs() / sc;
        t.record(err, TOL_POLY, || {
            format!("seed {seed} sample {i} s = {}", fmt3(&s))
        });
    }
    t.finish()
}

// ----------------------------------------------------------------------------------------------
// Gradient

/// Which independent gradient / Hessian to compare with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Against {
    /// The direct formulas `2 J^T M rbar`, `2 J^T M J + 2 sum (M rbar)_a HR_a`.
    Direct,
    /// Central differences (of the reference `C` for the gradient; of the generated gradient
    /// for the Hessian).
    FiniteDifference,
    /// Complex step of the reference `C` (gradient) or of the reference gradient (Hessian).
    ComplexStep,
}

/// Check 2 (gradient). Norms: `|dg|_inf / |S_g|_inf` (direct, complex step, bound 1e-12);
/// central differences: per component `|dg_k| <= bound_k` with
/// `bound_k = h^2/6 T3 + 2 E / (hp + hm) + |hp - hm| / 2 D2 + gamma_64 S_g,k + 2 u S_g,k`,
/// `h = u^(1/3) max(1, |s|)`, `T3`, `D2` bounds of the third and second derivative of `C` along
/// `e_k` on the stencil (`fd::cost_d3_bound`, `fd::cost_d2_bound`), `E = 64 u S_C(|s| + h)` the
/// rounding of one reference evaluation, `gamma_64 S_g,k` the kernel's own rounding.
#[must_use]
pub fn gradient(variant: Variant, against: Against, n: usize) -> Measurement {
    let seed = 31 + variant as u64 * 3 + against as u64;
    let mut rng = st::rng(seed);
    let (check, bound) = match against {
        Against::Direct => ("vs 2 J^T M rbar", format!("{TOL_POLY:.0e}")),
        Against::FiniteDifference => (
            "vs central differences of rbar^T M rbar",
            "derived per sample".to_string(),
        ),
        Against::ComplexStep => (
            "vs complex step of rbar^T M rbar",
            format!("{TOL_POLY:.0e}"),
        ),
    };
    let mut t = Tracker::new(
        variant.name("cost_gradient", "planar_cost_gradient"),
        check,
        "|dg|_inf / |S_g|_inf",
        bound,
    );
    for i in 0..n {
        let m = variant.matrix(&mut rng);
        let s = st::cgr(&mut rng);
        let g = variant.gradient(&m, &s);
        let (_, sg, _) = rf::cost_scales(&m, &s);
        let sgmax = sg.amax();
        let input = || format!("seed {seed} sample {i} s = {}", fmt3(&s));
        match against {
            Against::Direct => {
                let err = (g - rf::grad(&m, &s)).amax() / sgmax;
                t.record(err, TOL_POLY, input);
            }
            Against::ComplexStep => {
                let mut gc = Vector3::zeros();
                for kk in 0..3 {
                    let mut sc = [
                        Complex64::new(s[0], 0.0),
                        Complex64::new(s[1], 0.0),
                        Complex64::new(s[2], 0.0),
                    ];
                    sc[kk].im = H_COMPLEX;
                    gc[kk] = rf::cost_g(&m, &sc).im / H_COMPLEX;
                }
                let err = (g - gc).amax() / sgmax;
                t.record(err, TOL_POLY, input);
            }
            Against::FiniteDifference => {
                let h = fd::cost_step(&s);
                let (sc_big, sg_big, _) = rf::cost_scales(&m, &fd::s_big(&s, h));
                let e = EVAL_ROUNDING * sc_big;
                let mut worst_ratio = 0.0f64;
                let mut worst_err = 0.0f64;
                for kk in 0..3 {
                    let (sp, sm, hp, hm) = fd::nodes(&s, kk, h);
                    let fdk = (rf::cost(&m, &sp) - rf::cost(&m, &sm)) / (hp + hm);
                    let hmax = hp.max(hm);
                    let bound = hmax * hmax / 6.0 * fd::cost_d3_bound(&m, &s, kk, h)
                        + 2.0 * e / (hp + hm)
                        + (hp - hm).abs() / 2.0 * fd::cost_d2_bound(&m, &s, kk, h)
                        + (g64() + 2.0 * rf::U) * sg_big[kk];
                    let err = (g[kk] - fdk).abs();
                    worst_ratio = worst_ratio.max(err / bound);
                    worst_err = worst_err.max(err / sgmax);
                }
                t.record(
                    worst_err,
                    worst_err / worst_ratio.max(f64::MIN_POSITIVE),
                    input,
                );
            }
        }
    }
    t.finish()
}

/// Check 2 (Hessian). Norms: `|dH|_max / |S_H|_max` (direct, complex step of the reference
/// gradient, bound 1e-12); central differences of the *generated* gradient: per entry
/// `|dH_jk| <= h^2/6 T3_jk + 2 E_j / (hp + hm) + |hp - hm| / 2 D2_jk + (gamma_64 + 2u) S_H,jk`,
/// `T3_jk = |d^3 g_j / ds_k^3|` (constant, `fd::grad_d3_bound`), `D2_jk` (`fd::grad_d2_bound`),
/// `E_j = gamma_64 S_g,j(|s| + h)` the rounding of one generated gradient. Both `(j, k)` and
/// `(k, j)` are compared, so this also checks the symmetry of the model.
#[must_use]
pub fn hessian(variant: Variant, against: Against, n: usize) -> Measurement {
    let seed = 51 + variant as u64 * 3 + against as u64;
    let mut rng = st::rng(seed);
    let (check, bound) = match against {
        Against::Direct => (
            "vs 2 J^T M J + 2 sum (M rbar)_a HR_a",
            format!("{TOL_POLY:.0e}"),
        ),
        Against::FiniteDifference => (
            "vs central differences of the generated gradient",
            "derived per sample".to_string(),
        ),
        Against::ComplexStep => ("vs complex step of 2 J^T M rbar", format!("{TOL_POLY:.0e}")),
    };
    let mut t = Tracker::new(
        variant.name("cost_hessian", "planar_cost_hessian"),
        check,
        "|dH|_max / |S_H|_max",
        bound,
    );
    for i in 0..n {
        let m = variant.matrix(&mut rng);
        let s = st::cgr(&mut rng);
        let hk = variant.hessian(&m, &s);
        let (_, _, sh) = rf::cost_scales(&m, &s);
        let shmax = sh.amax();
        let input = || format!("seed {seed} sample {i} s = {}", fmt3(&s));
        match against {
            Against::Direct => {
                let err = (hk - rf::hess(&m, &s)).amax() / shmax;
                t.record(err, TOL_POLY, input);
            }
            Against::ComplexStep => {
                let mut hc = Matrix3::zeros();
                for kk in 0..3 {
                    let mut sc = [
                        Complex64::new(s[0], 0.0),
                        Complex64::new(s[1], 0.0),
                        Complex64::new(s[2], 0.0),
                    ];
                    sc[kk].im = H_COMPLEX;
                    let gcol = rf::grad_g(&m, &sc);
                    for j in 0..3 {
                        hc[(j, kk)] = gcol[j].im / H_COMPLEX;
                    }
                }
                let err = (hk - hc).amax() / shmax;
                t.record(err, TOL_POLY, input);
            }
            Against::FiniteDifference => {
                let h = fd::cost_step(&s);
                let (_, sg_big, sh_big) = rf::cost_scales(&m, &fd::s_big(&s, h));
                let mut worst_ratio = 0.0f64;
                let mut worst_err = 0.0f64;
                for kk in 0..3 {
                    let (sp, sm, hp, hm) = fd::nodes(&s, kk, h);
                    let d = (variant.gradient(&m, &sp) - variant.gradient(&m, &sm)) / (hp + hm);
                    let hmax = hp.max(hm);
                    for j in 0..3 {
                        let bound = hmax * hmax / 6.0 * fd::grad_d3_bound(&m, j, kk)
                            + 2.0 * g64() * sg_big[j] / (hp + hm)
                            + (hp - hm).abs() / 2.0 * fd::grad_d2_bound(&m, &s, j, kk, h)
                            + (g64() + 2.0 * rf::U) * sh_big[(j, kk)];
                        let err = (hk[(j, kk)] - d[j]).abs();
                        worst_ratio = worst_ratio.max(err / bound);
                        worst_err = worst_err.max(err / shmax);
                    }
                }
                t.record(
                    worst_err,
                    worst_err / worst_ratio.max(f64::MIN_POSITIVE),
                    input,
                );
            }
        }
    }
    t.finish()
}
