//! Shared test support of the eopnp workspace (tests, benches, examples, the comparison
//! program): seeded RNG, the synthetic
//! problem generator of docs/algorithm.md section 7 (the reference prototype's), the error metrics
//! of section 1, and an independent Levenberg-Marquardt reference ("LM from ground truth", the
//! maximum-likelihood floor).
//!
//! Reproducing a failure: every trial is generated from ONE `u64` seed, printed in every
//! assertion message. `Problem::generate(&ProblemOptions { seed, .. })` rebuilds it exactly.
//! Trial seeds derive from (suite seed, test name, trial index) via [`trial_seed`]; the suite
//! seed is [`DEFAULT_SUITE_SEED`] unless the environment variable `EOPNP_TEST_SEED` is set.

mod lm;
mod metrics;
mod polynomial;
mod problem;
mod rotation;
mod seed;

pub use lm::{
    lm_refine, lm_refine_focal, lm_refine_projection, lm_refine_vertical, reprojection_cost,
    Camera, LmFocalResult, LmResult, NORMALISED, PIXEL_CAMERA,
};
pub use metrics::{max_of, mean, median, pose_of, rot_err_deg, trans_err_pct, trans_err_rel};
pub use polynomial::{
    assert_roots_above, is_root_to_rounding, poly_from_roots, random_polynomial, uniform_stream,
};
pub use problem::{Problem, ProblemOptions, RotationKind, Scene};
pub use rotation::{axis_angle, exp_so3, haar_rotation, rotation_near_180};
pub use seed::{
    gauss, gauss3, name_hash, rng_from_seed, splitmix64, suite_seed, trial_seed, unit_vector,
};

/// Focal length of the synthetic camera, pixels (docs/algorithm.md section 7).
pub const F: f64 = 800.0;
/// Principal point x, pixels (640 x 480 image).
pub const CX: f64 = 320.0;
/// Principal point y, pixels.
pub const CY: f64 = 240.0;
/// Largest deviation from 180 degrees of `RotationKind::Near180` draws, degrees (synth.py).
pub const NEAR180_MAX_DEV_DEG: f64 = 1e-3;
/// Suite seed used unless `EOPNP_TEST_SEED` overrides it.
pub const DEFAULT_SUITE_SEED: u64 = 0x0E0F_2019_1A05;
