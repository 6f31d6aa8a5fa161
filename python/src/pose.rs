//! Poses given to `eopnp.refine`: a `Solution`, a `(rotation, t)` pair (the rotation as a
//! matrix, a rotation vector or a quaternion) or a `[R | t]` / homogeneous matrix, as an
//! `Isometry3` for the library.

use nalgebra::{Isometry3, Matrix3, Quaternion, Rotation3, Translation3, UnitQuaternion, Vector3};
use numpy::PyUntypedArrayMethods;
use pyo3::prelude::*;
use pyo3::types::{PyList, PyTuple};

use crate::convert::{array2, float_array, readonly, rows, shape_str, vector};
use crate::errors::option_error;
use crate::solution::PySolution;

/// The largest `|R^T R - I|` entry and the least determinant accepted of a rotation matrix
/// given as an initial pose: float32 round-off passes, a scaled or reflected matrix does not.
const ROTATION_TOLERANCE: f64 = 1e-6;

/// A rotation given as a `(3, 3)` matrix, a `(3,)` rotation vector (OpenCV's rvec) or a `(4,)`
/// quaternion (w, x, y, z; normalised). A non-finite value gives a NaN quaternion (the library
/// rejects it with its own error); a finite matrix that is not a rotation, or a zero
/// quaternion, raises `InvalidOptionError` (`option`; the message names the argument `name`).
fn rotation_arg(obj: &Bound<'_, PyAny>, option: &str, name: &str) -> PyResult<UnitQuaternion<f64>> {
    let py = obj.py();
    let arr = float_array(obj, name)?;
    let shape = arr.shape().to_vec();
    let ro = readonly(&arr, name)?;
    let v: Vec<f64> = ro.as_array().iter().copied().collect();
    let nan =
        UnitQuaternion::new_unchecked(Quaternion::new(f64::NAN, f64::NAN, f64::NAN, f64::NAN));
    if !v.iter().all(|x| x.is_finite()) {
        return Ok(nan);
    }
    match shape.as_slice() {
        [3, 3] => {
            let m = Matrix3::from_row_slice(&v);
            let off = (m.transpose() * m - Matrix3::identity()).abs().max();
            let det = m.determinant();
            if off > ROTATION_TOLERANCE || det <= 0.0 {
                return Err(option_error(
                    py,
                    option,
                    format!(
                        "{name}: the 3x3 matrix is not a rotation (max |R^T R - I| = {off:.3e}, \
                         det = {det}; at most {ROTATION_TOLERANCE:e} and > 0 accepted)"
                    ),
                ));
            }
            let q = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(m));
            Ok(UnitQuaternion::new_normalize(q.into_inner()))
        }
        [3] => Ok(UnitQuaternion::from_scaled_axis(Vector3::new(
            v[0], v[1], v[2],
        ))),
        [4] => {
            let q = Quaternion::new(v[0], v[1], v[2], v[3]);
            if q.norm() == 0.0 {
                return Err(option_error(
                    py,
                    option,
                    format!("{name}: the quaternion (w, x, y, z) is zero"),
                ));
            }
            Ok(UnitQuaternion::new_normalize(q))
        }
        _ => Err(option_error(
            py,
            option,
            format!(
                "{name}: the rotation must be a (3, 3) matrix, a (3,) rotation vector or a (4,) \
                 quaternion (w, x, y, z), got shape {}",
                shape_str(&shape)
            ),
        )),
    }
}

/// A pose `x_cam = R X + t` (world to camera) given as a `Solution`, a `(rotation, t)` pair
/// (the rotation as `rotation_arg` reads it, `t` of shape (3,)), or a `(3, 4)` `[R | t]` or
/// `(4, 4)` homogeneous matrix. Non-finite values reach the library, which rejects them.
pub(crate) fn pose_arg(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Isometry3<f64>> {
    pose_arg_as(obj, name, name)
}

/// `pose_arg` for an entry of a sequence of poses: errors are `InvalidOptionError` with
/// `option` (the argument, e.g. "cams_from_rig"), their messages name the entry, `name` (e.g.
/// "cams_from_rig[1]").
pub(crate) fn pose_arg_as(
    obj: &Bound<'_, PyAny>,
    option: &str,
    name: &str,
) -> PyResult<Isometry3<f64>> {
    let py = obj.py();
    if let Ok(s) = obj.cast::<PySolution>() {
        // The library's own quaternion: the solution's pose exactly.
        let s = s.get();
        let (q, t) = (s.quaternion(), s.translation());
        return Ok(Isometry3::from_parts(
            Translation3::new(t[0], t[1], t[2]),
            UnitQuaternion::new_unchecked(Quaternion::new(q[0], q[1], q[2], q[3])),
        ));
    }
    // A 2-sequence is a (rotation, t) pair; anything else is read as a matrix.
    let parts: Vec<Bound<'_, PyAny>> = if let Ok(t) = obj.cast::<PyTuple>() {
        t.iter().collect()
    } else if let Ok(l) = obj.cast::<PyList>() {
        l.iter().collect()
    } else {
        vec![]
    };
    if let [rot, t] = parts.as_slice() {
        let q = rotation_arg(rot, option, name)?;
        let t = vector(t, name, false)?;
        let [tx, ty, tz] = t.as_slice() else {
            return Err(option_error(
                py,
                option,
                format!("{name}: t must have shape (3,), got {} values", t.len()),
            ));
        };
        return Ok(Isometry3::from_parts(Translation3::new(*tx, *ty, *tz), q));
    }
    let bad = |what: String| {
        option_error(
            py,
            option,
            format!(
                "{name}: expected a Solution, a (rotation, t) pair, or a (3, 4) [R | t] or \
                 (4, 4) matrix, {what}"
            ),
        )
    };
    let arr = float_array(obj, name).map_err(|_| {
        bad(format!(
            "got {}",
            obj.get_type()
                .name()
                .map_or_else(|_| "?".into(), |s| s.to_string())
        ))
    })?;
    let shape = arr.shape().to_vec();
    if !matches!(shape.as_slice(), [3, 4] | [4, 4]) {
        return Err(bad(format!("got an array of shape {}", shape_str(&shape))));
    }
    let m = rows(obj, name, 4, |r| [r[0], r[1], r[2], r[3]])?;
    if m.len() == 4 && m[3] != [0.0, 0.0, 0.0, 1.0] {
        return Err(bad(format!(
            "got a (4, 4) matrix whose last row is {:?}, not [0, 0, 0, 1]",
            m[3]
        )));
    }
    let r: Vec<f64> = m[..3].iter().flat_map(|row| row[..3].to_vec()).collect();
    let rot = array2(py, 3, 3, &r);
    let q = rotation_arg(rot.as_any(), option, name)?;
    Ok(Isometry3::from_parts(
        Translation3::new(m[0][3], m[1][3], m[2][3]),
        q,
    ))
}
