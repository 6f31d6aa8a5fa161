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

use nalgebra::{ComplexField, SMatrix, SVector};

mod cost;
mod determinants;
mod local_model;
mod nullspace;

pub use cost::{
    cost, cost_g, cost_monomials, cost_scales, eval_monomials, grad, grad_g, hess, hr, jac, jac_g,
    m_upper21, m_upper45, planar_restrict, rbar, rbar_abs, rbar_g, upper_pairs, PLANAR,
};
pub use determinants::{
    bezout, bezout_abs_permanent, det_with_bound, hadamard, permanent, poly_eval, sylvester,
};
pub use local_model::{
    affine_amplitude, affine_chart_f, affine_model, blockdiag_rt, chart_amplitude, chart_f,
    local_model, vec_r, AffineChart, Chart, LocalModel, QuadraticChart,
};
pub use nullspace::{
    case2_cubics, case2_inputs, case3_cubics, case3_k, case3_monomials, case3_table, case4_layout,
    case4_layout_at, case4_m_from_t, case4_t_at, h_upper21,
};

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
