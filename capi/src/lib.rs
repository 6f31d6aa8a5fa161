//! The C ABI of [eopnp](https://docs.rs/eopnp): camera pose from 2D-3D correspondences (EOPnP
//! followed by the maximum-likelihood Levenberg-Marquardt refinement), for C, C++ and every
//! language with a C foreign-function interface.
//!
//! The header `include/eopnp.h` is generated from this crate by cbindgen (and checked by
//! `tests/header_fresh.rs`); `include/eopnp.hpp` is the C++ interface over it. The CMake
//! project at the repository's root builds this crate with cargo and installs both.
//!
//! # Conventions (every function)
//!
//! - **Status.** Every function that can fail returns an [`EopnpStatus`]; `EOPNP_OK` (0) is
//!   success. On failure the outputs are left unspecified (not written, or partly written) and
//!   [`eopnp_last_error_message`] / [`eopnp_last_error`] describe the failure on the calling
//!   thread (each thread has its own last error). A successful call does not clear it.
//! - **Bad input.** A NULL pointer, a zero or mismatched count, a NaN, a stride too small, a
//!   misaligned pointer, an unknown enumeration value: a status and a message, never undefined
//!   behaviour. No panic crosses the boundary (`EOPNP_PANIC` if one ever happens).
//! - **Pose.** Every pose maps world to camera, `x_cam = R X + t`; `R` is stored row-major
//!   (`rotation[3 * row + col]`), `t` in world units.
//! - **Points.** World points are 3 consecutive `double`s (x, y, z), image points 2 (x, y);
//!   arrays of points have a stride (in `double`s, between the first coordinates of
//!   consecutive points; 0 means packed: 3 for world points, 2 for image points).
//! - **Ownership.** Handles (`EopnpSolver`, `EopnpRansac`, `EopnpCamera`, `EopnpRig`,
//!   `EopnpModel`) are created by a `*_create` / `*_new` / `*_read` function, owned by the
//!   caller, and released with their `*_free` function (`free(NULL)` does nothing). Arrays and
//!   result structs are owned by the caller; the library only reads the inputs during the
//!   call and keeps no pointer to them after it returns.
//! - **Threads.** Every function is thread-safe: handles are immutable during a solve, so one
//!   handle may be used by several threads at once for solving. A handle must not be modified
//!   (`*_set_*`) or freed while another thread uses it.

#![allow(non_camel_case_types)]
#![warn(missing_docs)]
// `!(x > 0.0)`: also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

mod error;
mod ffi;
mod handles;
mod types;

pub use error::{EopnpDegenerate, EopnpErrorInfo, EopnpInput, EopnpStatus};
pub use ffi::*;
pub use handles::{EopnpCamera, EopnpModel, EopnpRansac, EopnpRig, EopnpSolver};
pub use types::*;
