//! Check 1: the cost coefficients (`cost_coefficients`, `planar_cost_coefficients`) and the
//! value kernel `cost`, against `C(s) = rbar(s)^T M rbar(s)` evaluated with nalgebra.
//!
//! Norm: `|dC| / S_C`, `S_C = |rbar|_abs^T |M| |rbar|_abs` (the absolute-value scale, see
//! `eopnp_verify::checks`): the rounding of any evaluation of `C` is bounded by a small multiple
//! of `u S_C`, whereas `|C|` itself can cancel to ~0 for `M = K^T K`. Tolerance 1e-12: both
//! sides have depth <= 40, so their first-order error bound is `gamma_40 S_C ~ 4.4e-15 S_C`.

use eopnp::internals::kernels as k;
use eopnp_verify::checks::{self, Variant, N_COST, TOL_POLY};
use eopnp_verify::{reference as rf, strategies as st};
use proptest::prelude::*;

#[test]
fn cost_coefficients_vs_quadratic_form() {
    checks::cost_coefficients(Variant::Full, N_COST).assert_ok();
}

#[test]
fn planar_cost_coefficients_vs_quadratic_form() {
    checks::cost_coefficients(Variant::Planar, N_COST).assert_ok();
}

#[test]
fn cost_value_vs_quadratic_form() {
    checks::cost_value(Variant::Full, N_COST).assert_ok();
    checks::cost_value(Variant::Planar, N_COST).assert_ok();
}

/// The layout tables of the kernels agree with my own enumeration of docs/algorithm.md G1/G3.
#[test]
fn layouts_match_algorithm_md() {
    let mons: Vec<[u8; 3]> = rf::cost_monomials();
    assert_eq!(mons.as_slice(), &k::COST_MONOMIALS[..]);
    let up: Vec<[u8; 2]> = rf::upper_pairs(&[0, 1, 2, 3, 4, 5, 6, 7, 8])
        .iter()
        .map(|&(i, j)| [i as u8, j as u8])
        .collect();
    assert_eq!(up.as_slice(), &k::COST_M_UPPER[..]);
    let pl: Vec<[u8; 2]> = rf::upper_pairs(&rf::PLANAR)
        .iter()
        .map(|&(i, j)| [i as u8, j as u8])
        .collect();
    assert_eq!(pl.as_slice(), &k::PLANAR_M_UPPER[..]);
}

/// Every entry of `M` on its own (the basis `E_ab + E_ba`): each of the 45 inputs enters the
/// 35 coefficients with exactly the weights of the quadratic form. Checked at 50 points `s`
/// (more than the 35 monomials, so the coefficients are determined), same norm and bound.
#[test]
fn cost_coefficients_basis_matrices() {
    let mut rng = st::rng(7);
    let pts: Vec<[f64; 3]> = (0..50).map(|_| st::cgr(&mut rng)).collect();
    for (i, j) in rf::upper_pairs(&[0, 1, 2, 3, 4, 5, 6, 7, 8]) {
        let mut m = rf::M9::zeros();
        m[(i, j)] = 1.0;
        m[(j, i)] = 1.0;
        let c = k::cost_coefficients(&rf::m_upper45(&m));
        for s in &pts {
            let (v, _) = rf::eval_monomials(&c, s);
            let (sc, _, _) = rf::cost_scales(&m, s);
            assert!(
                (v - rf::cost(&m, s)).abs() <= TOL_POLY * sc,
                "entry ({i}, {j}) at s = {s:?}"
            );
        }
    }
}

/// NaN probe: the kernels stay finite at exact zeros (s = 0, M = 0) and at |s| = 1e6.
#[test]
fn cost_kernels_finite_at_extremes() {
    let mut rng = st::rng(8);
    let m = st::cost_matrix(&mut rng);
    for s in [[0.0; 3], [1e6, -1e6, 1e6], [0.0, 0.0, 1e6]] {
        for mm in [m, rf::M9::zeros()] {
            let c = k::cost_coefficients(&rf::m_upper45(&mm));
            assert!(c.iter().all(|x| x.is_finite()));
            assert!(k::cost(&c, &s).is_finite());
            assert!(k::cost_gradient(&c, &s).iter().all(|x| x.is_finite()));
            assert!(k::cost_hessian(&c, &s).iter().all(|x| x.is_finite()));
        }
    }
}

proptest! {
    #![proptest_config(st::proptest_config())]

    /// The same check as `cost_coefficients_vs_quadratic_form`, over proptest strategies
    /// (shrinkable inputs), same norm and 1e-12 bound.
    #[test]
    fn prop_cost_coefficients(m in st::psd_matrix_strategy(), s in st::cgr_strategy()) {
        let c = k::cost_coefficients(&rf::m_upper45(&m));
        let (v, _) = rf::eval_monomials(&c, &s);
        let (sc, _, _) = rf::cost_scales(&m, &s);
        prop_assert!((v - rf::cost(&m, &s)).abs() <= TOL_POLY * sc);
    }
}
