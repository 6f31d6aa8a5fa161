//! The public error metrics (`eopnp::internals::metrics`). (Formerly in `src/numeric/rotation/tests.rs`.)

use eopnp::internals::metrics::{rotation_error_deg, translation_error_pct};
use nalgebra::{Matrix3, Rotation3, Vector3};

#[test]
fn rotation_error_metric() {
    let r = Rotation3::from_scaled_axis(Vector3::new(0.0, 0.0, 1e-12)).into_inner();
    let e = rotation_error_deg(&r, &Matrix3::identity());
    // atan2 resolves 1e-12 rad to relative rounding.
    assert!((e - 1e-12f64.to_degrees()).abs() < 1e-24);
    let flip = Matrix3::from_diagonal(&Vector3::new(1.0, -1.0, -1.0));
    assert!((rotation_error_deg(&flip, &Matrix3::identity()) - 180.0).abs() < 1e-12);
    let t = translation_error_pct(&Vector3::new(1.0, 0.0, 0.01), &Vector3::new(1.0, 0.0, 0.0));
    assert!((t - 1.0).abs() < 1e-12);
}
