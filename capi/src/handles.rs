//! The opaque handles: Rust values behind pointers that C holds (created and freed by the
//! functions of `ffi`).

use eopnp::camera::Camera;
use eopnp::colmap::Model;
use eopnp::ransac::Ransac;
use eopnp::{Rig, Solver};

/// Solver options (the library's `Solver`): an opaque handle. Create with
/// `eopnp_solver_create` (the recommended defaults), change with the `eopnp_solver_set_*`
/// functions, release with `eopnp_solver_free`.
pub struct EopnpSolver {
    pub(crate) solver: Solver,
}

/// RANSAC options (the library's `Ransac`): an opaque handle. Create with
/// `eopnp_ransac_create` (the recommended defaults: threshold 4 px, confidence 0.999, at most
/// 10000 and at least 20 samples, seed 0, local optimisation on, final threshold factor 2),
/// change with the `eopnp_ransac_set_*` functions, release with `eopnp_ransac_free`.
pub struct EopnpRansac {
    pub(crate) ransac: Ransac,
}

/// A camera model (the library's `Camera`: COLMAP's models, OpenCV's `K` + distortion): an
/// opaque, immutable handle. Release with `eopnp_camera_free`.
pub struct EopnpCamera {
    pub(crate) camera: Camera,
}

/// A multi-camera rig (the library's `Rig`): cameras and their poses in the rig frame. An
/// opaque, immutable handle; release with `eopnp_rig_free`.
pub struct EopnpRig {
    pub(crate) rig: Rig,
}

/// A COLMAP reconstruction read from disk (the library's `colmap::Model`): an opaque,
/// immutable handle. Release with `eopnp_model_free`.
pub struct EopnpModel {
    pub(crate) model: Model,
}
