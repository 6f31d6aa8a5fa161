//! The fuzz harnesses: bytes in, the library exercised, every property checked with `assert!`.
//!
//! Shared by the cargo-fuzz targets (`fuzz/fuzz_targets/*.rs`, coverage-guided) and by the
//! stable test `tests/fuzz_corpus.rs`, which replays the committed corpus and the named
//! regression inputs through the same functions on every CI run.
//!
//! Properties (any input whatsoever):
//! - no panic, no hang (every call is bounded);
//! - `Ok` only for finite input, with a finite pose, an orthonormal rotation (det +1) equal to
//!   the quaternion's, finite non-negative costs, and a reprojection rmse that is finite or
//!   (algebraic mode, a point in the focal plane) +inf, never NaN;
//! - `Err` for every input with a NaN or infinity, with the matching typed error;
//! - on well-posed exact problems the pose reprojects exactly (`check_exact`): on the decoded
//!   problem when the fuzzer made it exact (rare: every noise value must be 0), and on an
//!   exact, well-conditioned problem derived from every input (`derive_exact`), so that the
//!   assertion runs on almost every input (`tests/fuzz_corpus.rs` asserts >= 90 % of the
//!   committed `solve` inputs; `fuzz/examples/exact_share.rs` prints the share for any corpus);
//! - RANSAC options out of range give `InvalidOption`; the inlier mask has one entry per point
//!   and agrees with the inlier count;
//! - parsers return a typed error with a message, never a panic; a parsed model or problem is
//!   then solved under the same properties;
//! - a parsed COLMAP model written (text and binary, in memory and to disk) reads back
//!   identical, bit for bit, with no temporary files left (`colmap_write`).

// Each target family in its own file. `#[path]`, relative to this file's directory: this file
// is also included as a module by `cli/tests/fuzz_corpus.rs`.
#[path = "harness/cli.rs"]
mod cli;
#[path = "harness/colmap.rs"]
mod colmap;
#[path = "harness/decode.rs"]
mod decode;
#[path = "harness/solve.rs"]
mod solve;

pub use cli::{cli_input, small_input_limits};
pub use colmap::{assert_same_model, colmap_binary, colmap_text, colmap_write, small_model_limits};
pub use decode::{decode_problem, decode_solver, Problem, Reader, MAX_POINTS};
pub use solve::{
    check_solution, derive_exact, ransac, solve, solve_report, ExactProblem, SolveReport,
};
