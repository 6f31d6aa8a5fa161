//! # eopnp
//!
//! Camera pose from 2D-3D point correspondences (the Perspective-n-Point problem) with EOPnP
//! (Lipu Zhou and Michael Kaess, "An Efficient and Accurate Algorithm for the
//! Perspective-n-Point Problem", IROS 2019), followed by default by a Levenberg-Marquardt
//! refinement of the reprojection error, which makes the result the maximum-likelihood pose.
//!
//! - Any N >= 4, planar or not, any rotation (including 180 degrees), O(N) and allocation-free.
//! - Every polynomial of the method (the quartic cost in the Cayley parameters, its gradient and
//!   Hessian, the Sylvester resultants of the null-space cases) is generated at build time by
//!   exact symbolic algebra ([`kernels`]) and verified numerically (the `eopnp-verify` crate).
//! - Bad input gives a typed [`PnpError`], never a panic or a silent wrong pose.
//!
//! ```
//! use eopnp::{solve, Solver, Refinement};
//! use nalgebra::{Point2, Point3, Rotation3, Vector3};
//!
//! // A camera looking at six points.
//! let r = Rotation3::from_euler_angles(0.1, -0.2, 0.3);
//! let t = Vector3::new(0.1, -0.2, 5.0);
//! let world = [
//!     Point3::new(-1.0, -1.0, 0.5), Point3::new(1.0, -1.0, -0.5), Point3::new(1.0, 1.0, 0.2),
//!     Point3::new(-1.0, 1.0, -0.1), Point3::new(0.3, 0.2, 1.0), Point3::new(-0.4, 0.6, -0.8),
//! ];
//! // Normalised image coordinates (x/z, y/z) of each point.
//! let image: Vec<Point2<f64>> = world
//!     .iter()
//!     .map(|x| { let p = r * x.coords + t; Point2::new(p.x / p.z, p.y / p.z) })
//!     .collect();
//!
//! let sol = solve(&world, &image)?;
//! assert!((sol.pose.translation.vector - t).norm() < 1e-9);
//!
//! // The paper's algorithm alone, without the reprojection refinement:
//! let alg = Solver::default().refinement(Refinement::Algebraic).solve(&world, &image)?;
//! assert!(alg.cheirality_ok);
//! # Ok::<(), eopnp::PnpError>(())
//! ```
//!
//! Image points are normalised coordinates; for pixels use [`Solver::solve_pixels`] with a
//! [`camera::Camera`]. The pose maps world to camera: `x_cam = R X + t`.
#![warn(missing_docs)]
// `!(x > 0.0)` is used on purpose throughout: unlike `x <= 0.0` it also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod camera;
/// The `eopnp` command line (the binary is a thin `main` around [`cli::run`]). Public so that
/// the fuzz targets can drive the input parsers; not a stable API.
#[cfg(feature = "cli")]
#[doc(hidden)]
pub mod cli;
pub mod colmap;
mod error;
pub mod kernels;
mod numeric;
mod pipeline;
mod robust;
mod solver;
#[cfg(test)]
#[path = "../tests/unit/test_data.rs"]
mod test_data;

/// The fixed-capacity list type of [`Solutions`] and [`p3p::P3pSolutions`] (the `arrayvec`
/// crate's), re-exported so that callers need not depend on `arrayvec` themselves.
pub use arrayvec::ArrayVec;
pub use error::{DegenerateKind, InputKind, PnpError};
pub use numeric::roots;
#[cfg(eopnp_bench)]
#[doc(hidden)]
pub use pipeline::bench_hooks;
pub use pipeline::{CandidateSource, PlanarDetection, Refinement, Solution, Solutions};
pub use robust::{p3p, ransac};
pub use solver::{solve, Solver};

/// Error metrics of docs/algorithm.md section 1 (the paper's).
///
/// ```
/// use eopnp::metrics::{rotation_error_deg, translation_error_pct};
/// use nalgebra::{Rotation3, Vector3};
///
/// let r = Rotation3::from_euler_angles(0.0, 0.0, 0.01_f64.to_radians());
/// // The largest angle between corresponding columns: 0.01 degrees.
/// assert!((rotation_error_deg(r.matrix(), &Rotation3::identity().into_inner()) - 0.01).abs() < 1e-12);
/// let t = Vector3::new(0.0, 0.0, 10.0);
/// assert!((translation_error_pct(&Vector3::new(0.0, 0.1, 10.0), &t) - 1.0).abs() < 1e-12);
/// ```
pub mod metrics {
    pub use crate::numeric::rotation::{rotation_error_deg, translation_error_pct};
}

/// The README's code, compiled and run as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;
