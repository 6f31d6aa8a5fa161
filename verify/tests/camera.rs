//! The camera distortion kernels (`distortion_*`, `codegen/src/defs/camera.rs`): values vs the
//! hand-written maps they replace, derivatives vs the complex step of those maps and vs central
//! differences of the kernels' own values (bounds in `eopnp_verify::camera`).

use eopnp_verify::camera::{self, CameraAgainst, MODELS, N_CAMERA};

#[test]
fn values_vs_hand_written_maps() {
    for m in MODELS {
        camera::distortion(m, CameraAgainst::Values, N_CAMERA).assert_ok();
    }
}

#[test]
fn derivatives_vs_complex_step() {
    for m in MODELS {
        camera::distortion(m, CameraAgainst::ComplexStep, N_CAMERA).assert_ok();
    }
}

#[test]
fn derivatives_vs_central_differences() {
    for m in MODELS {
        camera::distortion(m, CameraAgainst::FiniteDifference, N_CAMERA).assert_ok();
    }
}
