//! A pose as a model file stores it, a quaternion and a translation: [`Pose`] (the rigs' and
//! frames' poses) and the closed-form rotation and the check that [`super::Image`]'s pose
//! shares.

use nalgebra::{Isometry3, Matrix3, Quaternion, Translation3, UnitQuaternion, Vector3};

/// A rigid transform as stored in a model file, `x_to = R(q) x_from + t`, with `q = (qw, qx,
/// qy, qz)` a Hamilton quaternion as stored (not renormalised; the methods normalise).
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    /// Rotation as a quaternion `(qw, qx, qy, qz)`.
    pub q: [f64; 4],
    /// Translation.
    pub t: Vector3<f64>,
}

impl Pose {
    /// The identity, `q = (1, 0, 0, 0)`, `t = 0`.
    #[must_use]
    pub fn identity() -> Self {
        Pose {
            q: [1.0, 0.0, 0.0, 0.0],
            t: Vector3::zeros(),
        }
    }

    /// The pose of an isometry: its unit quaternion and its translation.
    #[must_use]
    pub fn from_isometry(pose: &Isometry3<f64>) -> Self {
        let q = pose.rotation.quaternion();
        Pose {
            q: [q.w, q.i, q.j, q.k],
            t: pose.translation.vector,
        }
    }

    /// The rotation matrix of the normalised quaternion, in closed form (as
    /// [`super::Image::pose`]).
    #[must_use]
    pub fn rotation(&self) -> Matrix3<f64> {
        quaternion_to_matrix(self.q)
    }

    /// The pose as an isometry (the quaternion normalised).
    #[must_use]
    pub fn isometry(&self) -> Isometry3<f64> {
        let [w, x, y, z] = self.q;
        Isometry3::from_parts(
            Translation3::from(self.t),
            UnitQuaternion::from_quaternion(Quaternion::new(w, x, y, z)),
        )
    }

    /// Finite, with a non-zero quaternion: what the readers accept.
    pub(super) fn check(&self) -> Result<(), String> {
        check_quaternion(&self.q)?;
        if self.t.iter().all(|v| v.is_finite()) {
            Ok(())
        } else {
            Err("translation is not finite".to_string())
        }
    }
}

/// Rotation matrix of a quaternion `(w, x, y, z)` (normalised first), closed form.
/// A zero or non-finite quaternion gives a NaN matrix ([`super::read_model`] rejects those).
#[must_use]
pub(crate) fn quaternion_to_matrix(q: [f64; 4]) -> Matrix3<f64> {
    let n = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
    let (w, x, y, z) = (q[0] / n, q[1] / n, q[2] / n, q[3] / n);
    Matrix3::new(
        1.0 - 2.0 * (y * y + z * z),
        2.0 * (x * y - w * z),
        2.0 * (x * z + w * y),
        2.0 * (x * y + w * z),
        1.0 - 2.0 * (x * x + z * z),
        2.0 * (y * z - w * x),
        2.0 * (x * z - w * y),
        2.0 * (y * z + w * x),
        1.0 - 2.0 * (x * x + y * y),
    )
}

/// A quaternion must be finite and non-zero.
pub(crate) fn check_quaternion(q: &[f64; 4]) -> Result<(), String> {
    let n2: f64 = q.iter().map(|x| x * x).sum();
    if n2.is_finite() && n2 > 1e-12 {
        Ok(())
    } else {
        Err(format!(
            "quaternion ({}, {}, {}, {}) is zero or not finite",
            q[0], q[1], q[2], q[3]
        ))
    }
}
