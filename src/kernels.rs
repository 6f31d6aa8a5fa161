//! Generated polynomial kernels (straight-line code emitted by `eopnp-codegen`).
//!
//! Every function here is generated from the symbolic definitions in `codegen/src/defs/` (the
//! cost in `cost.rs`, the resultants in `resultant.rs`, the camera models' distortion in
//! `camera.rs`) by the emitter in
//! `codegen/src/emit.rs`, and checked numerically by the `eopnp-verify` crate (`verify/`).
//! The formatted output is committed in `generated/` (and shipped in the package); `build.rs`
//! puts it into `OUT_DIR`, copied from `generated/` by default or rendered afresh with feature
//! `regenerate`, and this module includes it from there. `tests/generated_fresh.rs` proves
//! `generated/` byte-identical to a fresh rendering. Read it there, or print one kernel with
//! `cargo run -p eopnp-codegen -- show NAME`.
//!
//! | kernel | what it computes (docs/algorithm.md) |
//! |---|---|
//! | [`cost_coefficients`] | the 35 coefficients of the quartic cost C(s) from the 45 entries of M (G1) |
//! | [`cost`], [`cost_gradient`], [`cost_hessian`] | C, grad C, hess C at s from the coefficients (G2) |
//! | [`planar_cost_coefficients`], [`planar_cost_gradient`], [`planar_cost_hessian`] | the planar analogue on the first two columns of R (G3) |
//! | [`so3_local_model`] | f, gradient and Hessian in the CGR chart centred on a rotation (`newton`) |
//! | [`case2_resultant`], [`case2_cubics`] | case 2: the quartic in beta = alpha2^2 and the back-substitution cubics (G4) |
//! | [`case3_quartic`], [`case3_resultant`], [`case3_cubics`] | case 3: the bivariate quartic, its degree-9 resultant, the cubics (G5) |
//! | [`case4_matrix`], [`case4_determinant`] | case 4: M(k1) and its degree-8 determinant (G6) |
//! | [`distortion_simple_radial`], [`distortion_radial`], [`distortion_opencv`], [`distortion_fisheye`] | a camera model's polynomial lens distortion at a normalised point, its 2x2 Jacobian and radial factor (`codegen/src/defs/camera.rs`) |
//! | [`distortion_full_opencv`], [`distortion_thin_prism`] | the polynomial pieces (numerator, denominator, tangential and thin-prism terms) of the rational models and their derivatives |
//!
//! Symbols follow docs/algorithm.md: `s1, s2, s3` are the CGR parameters, `mIJ` the entry `M[I][J]`,
//! `rIJ` the rotation entry `R[I-1][J-1]`.
//!
//! The solver calls the case kernels (`nullspace`, `planar`); `eopnp::camera` calls the distortion
//! kernels. `so3_local_model` defines `newton`'s local model, which the solver evaluates in a
//! factored form for 4-wide vectors (`pipeline::newton::local_model`: 630 instead of 1,773
//! instructions per call, measured with callgrind in the AVX2 build; a unit test holds the two
//! equal to rounding). The global-chart cost kernels (`cost_coefficients`, `cost`, `cost_gradient`,
//! `cost_hessian` and their planar analogues) are the paper's form of the same cost, kept as an
//! exactly and numerically checked reference (the solver works in a chart centred on each iterate
//! instead).
//!
//! ```
//! use eopnp::internals::kernels::{cost, cost_coefficients};
//!
//! // M = I (upper triangle, row-major): f(R) = |vec(R)|^2 = 3 for every rotation, so the
//! // cost polynomial C(s) = (1 + |s|^2)^2 f(R(s)) = 3 (1 + |s|^2)^2.
//! let mut m45 = [0.0; 45];
//! let mut k = 0;
//! for i in 0..9 {
//!     for j in i..9 {
//!         m45[k] = if i == j { 1.0 } else { 0.0 };
//!         k += 1;
//!     }
//! }
//! let c = cost_coefficients(&m45);
//! let s = [0.1, -0.2, 0.3];
//! let n2: f64 = s.iter().map(|x| x * x).sum();
//! assert!((cost(&c, &s) - 3.0 * (1.0 + n2).powi(2)).abs() < 1e-12);
//! ```

/// Operation counts of one generated kernel, as emitted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct KernelOps {
    /// Kernel (function) name.
    pub name: &'static str,
    /// Multiplications in the emitted code.
    pub mul: usize,
    /// Additions and subtractions in the emitted code.
    pub add: usize,
    /// Multiplications of the naive term-by-term evaluation of the fully expanded outputs.
    pub naive_mul: usize,
    /// Additions of the naive evaluation.
    pub naive_add: usize,
    /// Terms of the fully expanded outputs.
    pub naive_terms: usize,
}

pub use generated::*;

#[allow(
    clippy::all,
    clippy::pedantic,
    clippy::nursery,
    unused_parens,
    clippy::excessive_precision
)]
#[rustfmt::skip]
mod generated {
    use super::KernelOps;
    include!(concat!(env!("OUT_DIR"), "/cost_coefficients.rs"));
    include!(concat!(env!("OUT_DIR"), "/cost.rs"));
    include!(concat!(env!("OUT_DIR"), "/cost_gradient.rs"));
    include!(concat!(env!("OUT_DIR"), "/cost_hessian.rs"));
    include!(concat!(env!("OUT_DIR"), "/planar_cost_coefficients.rs"));
    include!(concat!(env!("OUT_DIR"), "/planar_cost_gradient.rs"));
    include!(concat!(env!("OUT_DIR"), "/planar_cost_hessian.rs"));
    include!(concat!(env!("OUT_DIR"), "/so3_local_model.rs"));
    include!(concat!(env!("OUT_DIR"), "/so3_local_affine.rs"));
    include!(concat!(env!("OUT_DIR"), "/case2_resultant.rs"));
    include!(concat!(env!("OUT_DIR"), "/case2_cubics.rs"));
    include!(concat!(env!("OUT_DIR"), "/case3_quartic.rs"));
    include!(concat!(env!("OUT_DIR"), "/case3_resultant.rs"));
    include!(concat!(env!("OUT_DIR"), "/case3_cubics.rs"));
    include!(concat!(env!("OUT_DIR"), "/case4_matrix.rs"));
    include!(concat!(env!("OUT_DIR"), "/case4_determinant.rs"));
    include!(concat!(env!("OUT_DIR"), "/distortion_simple_radial.rs"));
    include!(concat!(env!("OUT_DIR"), "/distortion_radial.rs"));
    include!(concat!(env!("OUT_DIR"), "/distortion_opencv.rs"));
    include!(concat!(env!("OUT_DIR"), "/distortion_fisheye.rs"));
    include!(concat!(env!("OUT_DIR"), "/distortion_full_opencv.rs"));
    include!(concat!(env!("OUT_DIR"), "/distortion_thin_prism.rs"));
    include!(concat!(env!("OUT_DIR"), "/gp3p_elimination.rs"));
    include!(concat!(env!("OUT_DIR"), "/up2p_quadratic.rs"));
    include!(concat!(env!("OUT_DIR"), "/p4pf_quadrics.rs"));
    include!(concat!(env!("OUT_DIR"), "/e3q3_octic.rs"));
    include!(concat!(env!("OUT_DIR"), "/index.rs"));
}
