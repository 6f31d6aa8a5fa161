//! Check 3b: `so3_local_affine(g, k, r) -> [f, g0..g2, hc00, hc01, hc02, hc11, hc12, hc22]`, the
//! local model of the generalized cost's affine part `2 g^T vec(R) + k` (docs/algorithm.md,
//! generalized EOPnP), at random rotations and random `g`, `k` of mixed signs and magnitudes:
//! against `2 g^T vec(R) + k`, the explicit formulas with `g_k = D^T g` (1e-12 of the
//! absolute-value scales), and against derivatives of `F(s) = 2 g^T vec(R(s) R) + k` by central /
//! second differences and by the complex step, with the per-sample bounds of `eopnp_verify::fd`.

use eopnp::internals::kernels as k;
use eopnp_verify::checks::{self, LocalAgainst, N_COST, TOL_POLY};
use eopnp_verify::{reference as rf, strategies as st};
use nalgebra::Vector3;
use proptest::prelude::*;

#[test]
fn value_vs_affine_form() {
    checks::local_affine(LocalAgainst::Value, N_COST).assert_ok();
}

#[test]
fn explicit_formulas() {
    checks::local_affine(LocalAgainst::Explicit, N_COST).assert_ok();
}

#[test]
fn gradient_vs_central_differences() {
    checks::local_affine(LocalAgainst::FdGradient, N_COST).assert_ok();
}

#[test]
fn hessian_vs_second_differences() {
    checks::local_affine(LocalAgainst::FdHessian, N_COST).assert_ok();
}

#[test]
fn gradient_vs_complex_step() {
    checks::local_affine(LocalAgainst::CsGradient, N_COST).assert_ok();
}

#[test]
fn hessian_vs_complex_step_differences() {
    checks::local_affine(LocalAgainst::CsHessian, N_COST).assert_ok();
}

/// With `g = 0` the kernel is the constant `k` on the chart: `f = k`, `g = 0` and `H_C = 4 k I`
/// (so that the chart Hessian `H_C - 4 f I` vanishes), exactly.
#[test]
fn constant_term_only() {
    let r = st::rotation(&mut st::rng(5));
    let r9: [f64; 9] = std::array::from_fn(|x| r[(x / 3, x % 3)]);
    let out = k::so3_local_affine(&[0.0; 9], 2.5, &r9);
    assert_eq!(out[0], 2.5);
    assert_eq!(&out[1..4], &[0.0; 3]);
    assert_eq!(out[4], 10.0);
    assert_eq!(out[7], 10.0);
    assert_eq!(out[9], 10.0);
    assert_eq!([out[5], out[6], out[8]], [0.0; 3]);
}

proptest! {
    #![proptest_config(st::proptest_config())]

    /// `f`, `g`, `H_C` vs the explicit formulas over proptest strategies (1e-12 of the scales).
    #[test]
    fn prop_explicit(
        g in proptest::array::uniform9(-1e3f64..1e3),
        kk in -1e3f64..1e3,
        r in st::rotation_strategy(),
    ) {
        let r9: [f64; 9] = std::array::from_fn(|x| r[(x / 3, x % 3)]);
        let out = k::so3_local_affine(&g, kk, &r9);
        let lm = rf::affine_model(&rf::V9::from_row_slice(&g), kk, &r);
        prop_assert!((out[0] - lm.f).abs() <= TOL_POLY * lm.sf);
        let hc = checks::sym3(&[out[4], out[5], out[6], out[7], out[8], out[9]]);
        for i in 0..3 {
            prop_assert!((out[1 + i] - lm.g[i]).abs() <= TOL_POLY * lm.sg[i]);
            for j in 0..3 {
                prop_assert!((hc[(i, j)] - lm.hc[(i, j)]).abs() <= TOL_POLY * lm.sh[(i, j)]);
            }
        }
    }
}

/// A wrong term would not hide in the scales: the explicit model of a perturbed `g` (one entry
/// changed by 1e-6 of the scale) is told apart from the kernel's output.
#[test]
fn a_perturbed_input_is_detected() {
    let mut rng = st::rng(17);
    let r = st::rotation(&mut rng);
    let r9: [f64; 9] = std::array::from_fn(|x| r[(x / 3, x % 3)]);
    let g: [f64; 9] = std::array::from_fn(|_| st::normal(&mut rng));
    let out = k::so3_local_affine(&g, 0.3, &r9);
    let mut gp = rf::V9::from_row_slice(&g);
    gp[4] += 1e-6 * gp.amax();
    let lm = rf::affine_model(&gp, 0.3, &r);
    let grad = Vector3::new(out[1], out[2], out[3]);
    let hc = checks::sym3(&[out[4], out[5], out[6], out[7], out[8], out[9]]);
    let err = ((out[0] - lm.f).abs() / lm.sf)
        .max((grad - lm.g).amax() / lm.sg.amax())
        .max((hc - lm.hc).amax() / lm.sh.amax());
    assert!(err > 1e3 * TOL_POLY, "{err:e}");
}
