//! Arrays in and out: any array-like of real numbers (float or integer dtype, any strides and
//! byte order) is read as `f64`; other dtypes and wrong shapes raise `InputTypeError` and
//! `InvalidInputError`. The arrays are copied into Rust's memory with the GIL held, before
//! any solve releases it. Results are new C-contiguous `float64` arrays.

use nalgebra::{Point2, Point3};
use numpy::ndarray::Ix2;
use numpy::{PyArray1, PyArray2, PyArrayDyn, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::PyModule;

use crate::errors::{dtype_error, error, shape_error, InvalidInputError};

static NUMPY: PyOnceLock<Py<PyModule>> = PyOnceLock::new();

pub(crate) fn shape_str(shape: &[usize]) -> String {
    match shape {
        [n] => format!("({n},)"),
        _ => {
            let dims: Vec<String> = shape.iter().map(ToString::to_string).collect();
            format!("({})", dims.join(", "))
        }
    }
}

/// A read-only view of `arr`, or `InvalidInputError` naming `name` when it is borrowed mutably
/// elsewhere.
pub(crate) fn readonly<'py, D: numpy::ndarray::Dimension>(
    arr: &Bound<'py, numpy::PyArray<f64, D>>,
    name: &str,
) -> PyResult<numpy::PyReadonlyArray<'py, f64, D>> {
    arr.try_readonly()
        .map_err(|e| error::<InvalidInputError>(arr.py(), "Borrow", format!("{name}: {e}"), vec![]))
}

/// `obj` as a `float64` array: as is if it is one, otherwise through `numpy.asarray` when its
/// dtype is a float or integer type.
pub(crate) fn float_array<'py>(
    obj: &Bound<'py, PyAny>,
    name: &str,
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
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

/// `obj` as a C-contiguous, aligned `float64` array that can be read as one slice: itself when
/// it is one, otherwise one converted copy (`float_array`, then `ndarray.copy()`, C order).
pub(crate) fn contiguous_array<'py>(
    obj: &Bound<'py, PyAny>,
    name: &str,
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let arr = float_array(obj, name)?;
    if arr.is_c_contiguous() && arr.is_aligned() {
        return Ok(arr);
    }
    Ok(arr.call_method0("copy")?.cast_into::<PyArrayDyn<f64>>()?)
}

/// The rows of `obj` mapped by `f` when it is a C-contiguous, aligned `float64` array of
/// shape `(N, cols)`, read straight from numpy's buffer into the result (one copy, without the
/// dynamic borrow bookkeeping of `readonly`: about 900 instructions per array, 40 % of a
/// call's own work at N = 10, and O(B^2) for a batch of B views of one array); `None` for
/// anything else.
pub(crate) fn fast_rows<T>(
    obj: &Bound<'_, PyAny>,
    cols: usize,
    f: impl Fn(&[f64]) -> T,
) -> Option<Vec<T>> {
    let arr = obj.cast::<PyArrayDyn<f64>>().ok()?;
    let shape = arr.shape();
    if shape.len() != 2 || shape[1] != cols || !arr.is_c_contiguous() || !arr.is_aligned() {
        return None;
    }
    // SAFETY: C-contiguous and aligned, checked above; the slice lives only for the copy
    // below, made with the GIL held (`obj` is bound to it), so no Python code can write to
    // the array meanwhile, and nothing in this crate borrows it mutably.
    let flat = unsafe { arr.as_slice() }.ok()?;
    Some(flat.chunks_exact(cols).map(f).collect())
}

/// The one-dimensional C-contiguous, aligned `float64` array `obj` copied, as `fast_rows`;
/// `None` for anything else.
pub(crate) fn fast_vector(obj: &Bound<'_, PyAny>) -> Option<Vec<f64>> {
    let arr = obj.cast::<PyArrayDyn<f64>>().ok()?;
    if arr.shape().len() != 1 || !arr.is_c_contiguous() || !arr.is_aligned() {
        return None;
    }
    // SAFETY: as `fast_rows`.
    Some(unsafe { arr.as_slice() }.ok()?.to_vec())
}

/// The rows of an `(N, C)` array, each mapped by `f`, copied with the GIL held.
pub(crate) fn rows<T>(
    obj: &Bound<'_, PyAny>,
    name: &str,
    cols: usize,
    f: impl Fn(&[f64]) -> T,
) -> PyResult<Vec<T>> {
    if let Some(rows) = fast_rows(obj, cols, &f) {
        return Ok(rows);
    }
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
    // A C-order aligned array of another dtype, converted by `float_array`.
    if let Some(rows) = fast_rows(arr.as_any(), cols, &f) {
        return Ok(rows);
    }
    let ro = readonly(&arr, name)?;
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
    if let Some(v) = fast_vector(obj) {
        return Ok(v);
    }
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
    let ro = readonly(&arr, name)?;
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

/// A one-dimensional array of integers (any integer dtype; an empty sequence of any dtype), as
/// `i64` (an unsigned value beyond `i64::MAX` saturates): a rig problem's camera indices,
/// checked against the rig later (`rig::check`). Floats, booleans and other dtypes raise
/// `InputTypeError`, other shapes `InvalidInputError`.
pub(crate) fn indices(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<i64>> {
    if let Ok(a) = obj.cast::<PyArrayDyn<i64>>() {
        if a.shape().len() == 1 {
            let ro = a.try_readonly().map_err(|e| {
                error::<InvalidInputError>(obj.py(), "Borrow", format!("{name}: {e}"), vec![])
            })?;
            return Ok(ro.as_array().iter().copied().collect());
        }
    }
    let py = obj.py();
    let np = NUMPY
        .get_or_try_init(py, || PyModule::import(py, "numpy").map(Bound::unbind))?
        .bind(py);
    let arr = np.call_method1("asarray", (obj,)).map_err(|e| {
        shape_error(
            py,
            name,
            format!("{name}: cannot be read as an array of integers: {e}"),
        )
    })?;
    let shape: Vec<usize> = arr.getattr("shape")?.extract()?;
    if shape.len() != 1 {
        return Err(shape_error(
            py,
            name,
            format!(
                "{name}: expected an array of shape (N,), got shape {}",
                shape_str(&shape)
            ),
        ));
    }
    if shape[0] == 0 {
        return Ok(Vec::new());
    }
    let dtype = arr.getattr("dtype")?;
    let kind: String = dtype.getattr("kind")?.extract()?;
    let (target, unsigned) = match kind.as_str() {
        "i" => ("int64", false),
        "u" => ("uint64", true),
        _ => {
            return Err(dtype_error(
                py,
                name,
                format!(
                    "{name}: expected integers (camera indices), got dtype {}",
                    dtype.str()?
                ),
            ))
        }
    };
    let arr = arr.call_method1("astype", (np.getattr(target)?,))?;
    let borrow = |e: numpy::BorrowError| {
        error::<InvalidInputError>(py, "Borrow", format!("{name}: {e}"), vec![])
    };
    Ok(if unsigned {
        let a = arr.cast_into::<PyArrayDyn<u64>>()?;
        let ro = a.try_readonly().map_err(borrow)?;
        ro.as_array()
            .iter()
            .map(|&v| i64::try_from(v).unwrap_or(i64::MAX))
            .collect()
    } else {
        let a = arr.cast_into::<PyArrayDyn<i64>>()?;
        let ro = a.try_readonly().map_err(borrow)?;
        ro.as_array().iter().copied().collect()
    })
}
