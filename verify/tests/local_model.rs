//! Check 3: `so3_local_model(m, r) -> [f, g0..g2, hc00, hc01, hc02, hc11, hc12, hc22]` at random
//! rotations (Haar-uniform, exact 180 deg rotations `2 a a^T - I`, exact axis flips), against
//! `vec(R)^T M vec(R)`, the explicit S6 formulas with `M_k = D^T M D` (1e-12 of the
//! absolute-value scales), and against derivatives of `F(s) = f(R(s) R)`: `g = grad F(0)`,
//! `H_C - 4 f I = hess F(0)`, by central / second differences and by the complex step, with
//! per-sample bounds derived in `eopnp_verify::fd` (derivatives of `F` along one-parameter
//! subgroups `t -> Rot_u(2 atan t)`).

use eopnp::kernels as k;
use eopnp_verify::checks::{self, LocalAgainst, N_COST, TOL_POLY};
use eopnp_verify::{reference as rf, strategies as st};
use nalgebra::{Matrix3, Vector3};
use proptest::prelude::*;

#[test]
fn value_vs_quadratic_form() {
    checks::local_model(LocalAgainst::Value, N_COST).assert_ok();
}

#[test]
fn explicit_formulas() {
    checks::local_model(LocalAgainst::Explicit, N_COST).assert_ok();
}

#[test]
fn gradient_vs_central_differences() {
    checks::local_model(LocalAgainst::FdGradient, N_COST).assert_ok();
}

#[test]
fn hessian_vs_second_differences() {
    checks::local_model(LocalAgainst::FdHessian, N_COST).assert_ok();
}

#[test]
fn gradient_vs_complex_step() {
    checks::local_model(LocalAgainst::CsGradient, N_COST).assert_ok();
}

#[test]
fn hessian_vs_complex_step_differences() {
    checks::local_model(LocalAgainst::CsHessian, N_COST).assert_ok();
}

/// Exactly 180 degrees about each coordinate axis and about a diagonal: finite outputs that
/// match the explicit formulas (1e-12 of the absolute-value scales).
#[test]
fn exact_half_turns() {
    let mut rng = st::rng(9);
    let m = st::cost_matrix(&mut rng);
    let a = Vector3::new(1.0, 1.0, 1.0) / 3f64.sqrt();
    let rs = [
        Matrix3::from_diagonal(&Vector3::new(1.0, -1.0, -1.0)),
        Matrix3::from_diagonal(&Vector3::new(-1.0, 1.0, -1.0)),
        Matrix3::from_diagonal(&Vector3::new(-1.0, -1.0, 1.0)),
        2.0 * a * a.transpose() - Matrix3::identity(),
    ];
    for r in rs {
        let r9: [f64; 9] = std::array::from_fn(|x| r[(x / 3, x % 3)]);
        let out = k::so3_local_model(&rf::m_upper45(&m), &r9);
        assert!(out.iter().all(|x| x.is_finite()));
        let lm = rf::local_model(&m, &r);
        assert!((out[0] - lm.f).abs() <= TOL_POLY * lm.sf);
        for i in 0..3 {
            assert!((out[1 + i] - lm.g[i]).abs() <= TOL_POLY * lm.sg[i]);
        }
    }
}

proptest! {
    /// `f`, `g`, `H_C` vs the explicit formulas over proptest strategies (1e-12 of the scales).
    #[test]
    fn prop_explicit(m in st::psd_matrix_strategy(), r in st::rotation_strategy()) {
        let r9: [f64; 9] = std::array::from_fn(|x| r[(x / 3, x % 3)]);
        let out = k::so3_local_model(&rf::m_upper45(&m), &r9);
        let lm = rf::local_model(&m, &r);
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
