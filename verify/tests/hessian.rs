//! Check 2 (Hessian): `cost_hessian` and `planar_cost_hessian` against (a) the direct
//! `2 J^T M J + 2 sum_a (M rbar)_a HR_a`, (b) central differences of the *generated* gradient
//! (both `(j, k)` and `(k, j)`, so the symmetry of the model is checked too), with a per-sample
//! truncation + rounding bound (`eopnp_verify::checks::hessian`), (c) the complex step of the
//! reference gradient `2 J^T M rbar`. Norm for (a), (c): `|dH|_max / |S_H|_max` <= 1e-12.

use eopnp_verify::checks::{self, Against, Variant, N_COST};

#[test]
fn hessian_vs_direct() {
    checks::hessian(Variant::Full, Against::Direct, N_COST).assert_ok();
}

#[test]
fn hessian_vs_central_differences_of_gradient() {
    checks::hessian(Variant::Full, Against::FiniteDifference, N_COST).assert_ok();
}

#[test]
fn hessian_vs_complex_step() {
    checks::hessian(Variant::Full, Against::ComplexStep, N_COST).assert_ok();
}

#[test]
fn planar_hessian_vs_direct() {
    checks::hessian(Variant::Planar, Against::Direct, N_COST).assert_ok();
}

#[test]
fn planar_hessian_vs_central_differences_of_gradient() {
    checks::hessian(Variant::Planar, Against::FiniteDifference, N_COST).assert_ok();
}

#[test]
fn planar_hessian_vs_complex_step() {
    checks::hessian(Variant::Planar, Against::ComplexStep, N_COST).assert_ok();
}
