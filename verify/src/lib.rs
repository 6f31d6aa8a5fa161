//! Independent numeric verification of the generated kernels of `eopnp` (`eopnp::internals::kernels`).
//!
//! Nothing here calls `eopnp-codegen`: every kernel is compared with the mathematical definition
//! in docs/algorithm.md evaluated numerically with nalgebra (`reference`), with finite differences and
//! complex-step derivatives (`fd`), and, for the resultants, with nalgebra's determinant of the
//! numerically built Sylvester matrix and with systems constructed to have a known root.
//!
//! - `reference`: the direct definitions and their absolute-value (rounding) scales.
//! - `fd`: finite differences and their error bounds.
//! - `strategies`: seeded random inputs spanning scales, and proptest strategies.
//! - `checks`: one function per check, returning a `report::Measurement`; shared by the tests
//!   (which assert the bounds) and `cargo run -p eopnp-verify --release` (which prints them).
//! - `camera`: the camera distortion kernels against the hand-written maps they replace
//!   (values, complex step) and against central differences.
//! - `report`: the measurement type and the Markdown table.
#![warn(missing_docs)]

pub mod camera;
pub mod checks;
pub mod fd;
pub mod reference;
pub mod report;
pub mod strategies;
