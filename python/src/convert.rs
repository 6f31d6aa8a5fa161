//! Arrays in and out: any array-like of real numbers (float or integer dtype, any strides and
//! byte order) is read as `f64`; other dtypes and wrong shapes raise `InputTypeError` and
//! `InvalidInputError`. Results are new C-contiguous `float64` arrays.

use nalgebra::{
    Isometry3, Matrix3, Point2, Point3, Quaternion, Rotation3, Translation3, UnitQuaternion,
    Vector3,
};
use numpy::ndarray::Ix2;
use numpy::{PyArray1, PyArray2, PyArrayDyn, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::{PyList, PyModule, PyTuple};

use crate::errors::{dtype_error, error, option_error, shape_error};
use crate::solution::PySolution;

static NUMPY: PyOnceLock<Py<PyModule>> = PyOnceLock::new();

fn shape_str(shape: &[usize]) -> String {
    match shape {
        [n] => format!("({n},)"),
        _ => {
            let dims: Vec<String> = shape.iter().map(ToString::to_string).collect();
            format!("({})", dims.join(", "))
        }
    }
}

/// `obj` as a `float64` array: as is if it is one, otherwise through `numpy.asarray` when its
/// dtype is a float or integer type.
fn float_array<'py>(obj: &Bound<'py, PyAny>, name: &str) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    if let Ok(a) = obj.cast::<PyArrayDyn<f64>>() {
        return Ok(a.clone());
    }
    let py = obj.py();
    let np = NUMPY
        .get_or_try_init(py, || PyModule::import(py, "numpy").map(Bound::unbind))?
        .bind(py);
    let arr = np.call_method1("asarray", (obj,)).map_err(|e| {
        shape_error(
            py,
            name,
            format!("{name}: cannot be read as an array of numbers: {e}"),
        )
    })?;
    let dtype = arr.getattr("dtype")?;
    let kind: String = dtype.getattr("kind")?.extract()?;
    if !matches!(kind.as_str(), "f" | "i" | "u") {
        return Err(dtype_error(
            py,
            name,
            format!(
                "{name}: expected real numbers (a float or integer array), got dtype {}",
                dtype.str()?
            ),
        ));
    }
    let arr = arr.call_method1("astype", (np.getattr("float64")?,))?;
    Ok(arr.cast_into::<PyArrayDyn<f64>>()?)
}

/// The rows of an `(N, C)` array, each mapped by `f`.
fn rows<T>(
    obj: &Bound<'_, PyAny>,
    name: &str,
    cols: usize,
    f: impl Fn(&[f64]) -> T,
) -> PyResult<Vec<T>> {
    let arr = float_array(obj, name)?;
    let py = obj.py();
    let shape = arr.shape();
    if shape.len() != 2 || shape[1] != cols {
        return Err(shape_error(
            py,
            name,
            format!(
                "{name}: expected an array of shape (N, {cols}), got shape {}",
                shape_str(shape)
            ),
        ));
    }
    let ro = arr.try_readonly().map_err(|e| {
        error(
            py,
            "InvalidInputError",
            "Borrow",
            format!("{name}: {e}"),
            vec![],
        )
    })?;
    // `as_slice` also accepts Fortran order: the rows are contiguous only in C order.
    if ro.is_c_contiguous() {
        if let Ok(s) = ro.as_slice() {
            return Ok(s.chunks_exact(cols).map(f).collect());
        }
    }
    let view = ro
        .as_array()
        .into_dimensionality::<Ix2>()
        .expect("checked: two dimensions");
    let mut buf = [0.0; 4];
    Ok(view
        .rows()
        .into_iter()
        .map(|row| {
            for (b, x) in buf.iter_mut().zip(row.iter()) {
                *b = *x;
            }
            f(&buf[..cols])
        })
        .collect())
}

/// `(N, 3)` world points.
pub(crate) fn points3(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<Point3<f64>>> {
    rows(obj, name, 3, |r| Point3::new(r[0], r[1], r[2]))
}

/// `(N, 2)` image points (normalised or pixels).
pub(crate) fn points2(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<Point2<f64>>> {
    rows(obj, name, 2, |r| Point2::new(r[0], r[1]))
}

/// A `(3, 3)` matrix, row-major.
pub(crate) fn matrix3(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<[[f64; 3]; 3]> {
    let r = rows(obj, name, 3, |r| [r[0], r[1], r[2]])?;
    if r.len() != 3 {
        return Err(shape_error(
            obj.py(),
            name,
            format!("{name}: expected a 3x3 matrix, got shape ({}, 3)", r.len()),
        ));
    }
    Ok([r[0], r[1], r[2]])
}

/// A one-dimensional array of numbers; with `flatten`, also a `(1, n)` or `(n, 1)` array (as
/// OpenCV returns distortion vectors).
pub(crate) fn vector(obj: &Bound<'_, PyAny>, name: &str, flatten: bool) -> PyResult<Vec<f64>> {
    let arr = float_array(obj, name)?;
    let py = obj.py();
    let shape = arr.shape();
    let ok = shape.len() == 1 || (flatten && shape.len() == 2 && (shape[0] == 1 || shape[1] == 1));
    if !ok {
        let want = if flatten {
            "(n,), (1, n) or (n, 1)"
        } else {
            "(n,)"
        };
        return Err(shape_error(
            py,
            name,
            format!(
                "{name}: expected an array of shape {want}, got shape {}",
                shape_str(shape)
            ),
        ));
    }
    let ro = arr.try_readonly().map_err(|e| {
        error(
            py,
            "InvalidInputError",
            "Borrow",
            format!("{name}: {e}"),
            vec![],
        )
    })?;
    let v = ro.as_array();
    Ok(v.iter().copied().collect())
}

/// A new `(rows, cols)` array holding `data` (row-major).
pub(crate) fn array2<'py>(
    py: Python<'py>,
    rows: usize,
    cols: usize,
    data: &[f64],
) -> Bound<'py, PyArray2<f64>> {
    debug_assert_eq!(rows * cols, data.len());
    // SAFETY: a new C-contiguous array that nothing else references yet.
    unsafe {
        let a = PyArray2::<f64>::new(py, [rows, cols], false);
        a.as_slice_mut()
            .expect("new array is contiguous")
            .copy_from_slice(data);
        a
    }
}

/// A new one-dimensional array holding `data`.
pub(crate) fn array1<'py>(py: Python<'py>, data: &[f64]) -> Bound<'py, PyArray1<f64>> {
    PyArray1::from_slice(py, data)
}

/// The largest `|R^T R - I|` entry and the least determinant accepted of a rotation matrix
/// given as an initial pose: float32 round-off passes, a scaled or reflected matrix does not.
const ROTATION_TOLERANCE: f64 = 1e-6;

/// A rotation given as a `(3, 3)` matrix, a `(3,)` rotation vector (OpenCV's rvec) or a `(4,)`
/// quaternion (w, x, y, z; normalised). A non-finite value gives a NaN quaternion (the library
/// rejects it with its own error); a finite matrix that is not a rotation, or a zero
/// quaternion, raises `InvalidOptionError` (`option` = `name`).
fn rotation_arg(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<UnitQuaternion<f64>> {
    let py = obj.py();
    let arr = float_array(obj, name)?;
    let shape = arr.shape().to_vec();
    let ro = arr.try_readonly().map_err(|e| {
        error(
            py,
            "InvalidInputError",
            "Borrow",
            format!("{name}: {e}"),
            vec![],
        )
    })?;
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
                    name,
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
                    name,
                    format!("{name}: the quaternion (w, x, y, z) is zero"),
                ));
            }
            Ok(UnitQuaternion::new_normalize(q))
        }
        _ => Err(option_error(
            py,
            name,
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
        let q = rotation_arg(rot, name)?;
        let t = vector(t, name, false)?;
        let [tx, ty, tz] = t.as_slice() else {
            return Err(option_error(
                py,
                name,
                format!("{name}: t must have shape (3,), got {} values", t.len()),
            ));
        };
        return Ok(Isometry3::from_parts(Translation3::new(*tx, *ty, *tz), q));
    }
    let bad = |what: String| {
        option_error(
            py,
            name,
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
    let q = rotation_arg(rot.as_any(), name)?;
    Ok(Isometry3::from_parts(
        Translation3::new(m[0][3], m[1][3], m[2][3]),
        q,
    ))
}
