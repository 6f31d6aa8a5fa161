//! Check 2 (gradient): `cost_gradient` (from `cost_coefficients`) and `planar_cost_gradient`
//! against (a) `2 J^T M rbar`, (b) central differences of the independent `C = rbar^T M rbar`
//! with step `h = u^(1/3) max(1, |s|)` and a per-sample bound from the truncation and rounding
//! error (`eopnp_verify::checks::gradient` documents the formula), (c) the complex-step
//! derivative of `C` (no cancellation, so the bound is the same 1e-12 as (a)).
//! Norm for (a), (c): `|dg|_inf / |S_g|_inf`, `S_g = 2 |J|^T |M| |rbar|_abs`.

use eopnp_verify::checks::{self, Against, Variant, N_COST};

#[test]
fn gradient_vs_direct() {
    checks::gradient(Variant::Full, Against::Direct, N_COST).assert_ok();
}

#[test]
fn gradient_vs_central_differences() {
    // The bound is rigorous and nearly attained at s = 0 when one entry of M dominates: C is a
    // quartic, so the central-difference error is exactly h^2 C''' / 6, and |C'''| meets its
    // absolute-value bound when nothing cancels (worst error/bound ~0.99).
    checks::gradient(Variant::Full, Against::FiniteDifference, N_COST).assert_ok();
}

#[test]
fn gradient_vs_complex_step() {
    checks::gradient(Variant::Full, Against::ComplexStep, N_COST).assert_ok();
}

#[test]
fn planar_gradient_vs_direct() {
    checks::gradient(Variant::Planar, Against::Direct, N_COST).assert_ok();
}

#[test]
fn planar_gradient_vs_central_differences() {
    checks::gradient(Variant::Planar, Against::FiniteDifference, N_COST).assert_ok();
}

#[test]
fn planar_gradient_vs_complex_step() {
    checks::gradient(Variant::Planar, Against::ComplexStep, N_COST).assert_ok();
}
