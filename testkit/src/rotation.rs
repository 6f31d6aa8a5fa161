//! Rotations: Haar-uniform, axis-angle, the exponential map, near 180 degrees.

use nalgebra::{Matrix3, Quaternion, UnitQuaternion, Vector3};
use rand::Rng;
use rand_pcg::Pcg64;

use crate::seed::{gauss, unit_vector};

/// Haar-uniform rotation: unit quaternion from a normalised 4-D Gaussian (synth.py).
pub fn haar_rotation(rng: &mut Pcg64) -> Matrix3<f64> {
    loop {
        let q = Quaternion::new(gauss(rng), gauss(rng), gauss(rng), gauss(rng));
        if q.norm() > 1e-12 {
            return UnitQuaternion::from_quaternion(q)
                .to_rotation_matrix()
                .into_inner();
        }
    }
}

/// Rotation by `angle` (radians) about the unit `axis` (Rodrigues, exact at pi).
pub fn axis_angle(axis: &Vector3<f64>, angle: f64) -> Matrix3<f64> {
    let k = axis.cross_matrix();
    Matrix3::identity() + k * angle.sin() + k * k * (1.0 - angle.cos())
}

/// Exp map of so(3).
pub fn exp_so3(w: &Vector3<f64>) -> Matrix3<f64> {
    let th = w.norm();
    if th < 1e-300 {
        return Matrix3::identity() + w.cross_matrix();
    }
    axis_angle(&(w / th), th)
}

/// Rotation within `max_dev_deg` of 180 degrees: uniform axis, angle pi - U(0, max_dev),
/// exactly pi in 5 % of the draws (synth.py `rotation_near_180`).
pub fn rotation_near_180(rng: &mut Pcg64, max_dev_deg: f64) -> Matrix3<f64> {
    let axis = unit_vector(rng);
    let mut angle = std::f64::consts::PI - rng.random_range(0.0..max_dev_deg).to_radians();
    if rng.random::<f64>() < 0.05 {
        angle = std::f64::consts::PI;
    }
    axis_angle(&axis, angle)
}
