//! `eopnp.Camera`: COLMAP's camera models and OpenCV's `K` + distortion coefficients.

use eopnp::camera::{Camera, CameraModel};
use nalgebra::{Matrix3, Point2};
use numpy::PyArray2;
use pyo3::prelude::*;
use pyo3::types::PyTuple;

use crate::convert::{array1, array2, matrix3, points2, vector};
use crate::errors::{camera_error, error, CameraError};

/// A camera: a model, its parameters in COLMAP's order, and the image size.
///
/// ``Camera(model, params, width=0, height=0)`` takes COLMAP's model name and parameters, e.g.
/// ``Camera("SIMPLE_RADIAL", [f, cx, cy, k], 1200, 1600)``. Models: SIMPLE_PINHOLE (f, cx, cy),
/// PINHOLE (fx, fy, cx, cy), SIMPLE_RADIAL (f, cx, cy, k), RADIAL (f, cx, cy, k1, k2), OPENCV
/// (fx, fy, cx, cy, k1, k2, p1, p2), OPENCV_FISHEYE (fx, fy, cx, cy, k1, k2, k3, k4),
/// FULL_OPENCV (fx, fy, cx, cy, k1, k2, p1, p2, k3, k4, k5, k6), SIMPLE_RADIAL_FISHEYE
/// (f, cx, cy, k), RADIAL_FISHEYE (f, cx, cy, k1, k2), and OpenCV's full model
/// OPENCV_THIN_PRISM_TILTED (the 12 of FULL_OPENCV, s1, s2, s3, s4, tau_x, tau_y; not a COLMAP
/// model). The size is recorded only (no computation uses it).
///
/// Pixels follow COLMAP's convention (the upper-left image corner is (0, 0)) for cameras built
/// from COLMAP parameters, and OpenCV's (the centre of the upper-left pixel is (0, 0)) for
/// cameras built by ``from_opencv``: the mapping is the one the parameters define, with no
/// half-pixel shift.
///
/// Raises:
///     CameraError: an unknown model, the wrong number of parameters, a non-finite parameter
///         or a non-positive focal length.
#[pyclass(frozen, module = "eopnp", name = "Camera")]
#[derive(Clone)]
pub(crate) struct PyCamera {
    pub(crate) inner: Camera,
}

/// OpenCV's `K` (3x3) and distortion vector (None: no coefficients), as both OpenCV
/// constructors read them.
fn opencv_inputs(
    k: &Bound<'_, PyAny>,
    dist: Option<&Bound<'_, PyAny>>,
) -> PyResult<(Matrix3<f64>, Vec<f64>)> {
    let m = matrix3(k, "K")?;
    let d = match dist {
        Some(d) => vector(d, "dist", true)?,
        None => Vec::new(),
    };
    Ok((Matrix3::from_fn(|i, j| m[i][j]), d))
}

/// `(K, dist)` as new arrays, as both OpenCV exports return them.
fn opencv_arrays<'py>(
    py: Python<'py>,
    k: &Matrix3<f64>,
    d: &[f64],
) -> (Bound<'py, PyAny>, Bound<'py, PyAny>) {
    let rows: Vec<f64> = (0..3)
        .flat_map(|i| (0..3).map(move |j| k[(i, j)]))
        .collect();
    (array2(py, 3, 3, &rows).into_any(), array1(py, d).into_any())
}

#[pymethods]
impl PyCamera {
    #[new]
    #[pyo3(signature = (model, params, width = 0, height = 0))]
    fn new(
        py: Python<'_>,
        model: &str,
        params: &Bound<'_, PyAny>,
        width: i64,
        height: i64,
    ) -> PyResult<Self> {
        let params = vector(params, "params", false)?;
        let size = |v: i64, name: &str| {
            u64::try_from(v).map_err(|_| {
                error::<CameraError>(
                    py,
                    "InvalidParams",
                    format!("invalid camera parameters: {name} must be >= 0, got {v}"),
                    vec![],
                )
            })
        };
        let (w, h) = (size(width, "width")?, size(height, "height")?);
        let model: CameraModel = model.parse().map_err(|e| camera_error(py, &e))?;
        let inner = Camera::new(model, w, h, params).map_err(|e| camera_error(py, &e))?;
        Ok(PyCamera { inner })
    }

    /// A camera from OpenCV's camera matrix ``K`` (3x3, zero skew) and distortion vector
    /// ``dist`` in OpenCV's order (k1, k2, p1, p2[, k3[, k4, k5, k6[, s1, s2, s3, s4[, tauX,
    /// tauY]]]]): 0, 4, 5, 8, 12 or 14 coefficients (None: no distortion), shape (n,), (1, n)
    /// or (n, 1). ``project`` then equals ``cv2.projectPoints`` with rvec = tvec = 0; pixels
    /// are in OpenCV's convention. The model follows from the length: PINHOLE (0), OPENCV (4),
    /// FULL_OPENCV (5, 8), OPENCV_THIN_PRISM_TILTED (12, 14).
    #[staticmethod]
    #[pyo3(signature = (K, dist = None))]
    #[allow(non_snake_case)]
    fn from_opencv(
        py: Python<'_>,
        K: &Bound<'_, PyAny>,
        dist: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let (k, d) = opencv_inputs(K, dist)?;
        let inner = Camera::from_opencv(&k, &d).map_err(|e| camera_error(py, &e))?;
        Ok(PyCamera { inner })
    }

    /// A camera from ``cv2.fisheye``'s ``K`` (zero skew) and its 4 coefficients (k1, k2, k3,
    /// k4): the OPENCV_FISHEYE model.
    #[staticmethod]
    #[pyo3(signature = (K, dist))]
    #[allow(non_snake_case)]
    fn from_opencv_fisheye(
        py: Python<'_>,
        K: &Bound<'_, PyAny>,
        dist: &Bound<'_, PyAny>,
    ) -> PyResult<Self> {
        let (k, d) = opencv_inputs(K, Some(dist))?;
        let d: [f64; 4] = d.as_slice().try_into().map_err(|_| {
            error::<CameraError>(
                py,
                "InvalidParams",
                format!(
                    "invalid camera parameters: cv2.fisheye takes 4 distortion coefficients, got {}",
                    d.len()
                ),
                vec![],
            )
        })?;
        let inner = Camera::from_opencv_fisheye(&k, &d).map_err(|e| camera_error(py, &e))?;
        Ok(PyCamera { inner })
    }

    /// A pinhole camera without distortion (COLMAP's PINHOLE, image size 0).
    #[staticmethod]
    fn pinhole(py: Python<'_>, fx: f64, fy: f64, cx: f64, cy: f64) -> PyResult<Self> {
        let inner = Camera::pinhole(fx, fy, cx, cy).map_err(|e| camera_error(py, &e))?;
        Ok(PyCamera { inner })
    }

    /// The model's name, e.g. "SIMPLE_RADIAL".
    #[getter]
    fn model(&self) -> &'static str {
        self.inner.model().name()
    }

    /// Image width (0: unknown).
    #[getter]
    fn width(&self) -> u64 {
        self.inner.width()
    }

    /// Image height (0: unknown).
    #[getter]
    fn height(&self) -> u64 {
        self.inner.height()
    }

    /// The parameters in COLMAP's order, shape (n,).
    #[getter]
    fn params<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        array1(py, self.inner.params()).into_any()
    }

    /// The focal lengths (fx, fy) in pixels.
    #[getter]
    fn focal(&self) -> (f64, f64) {
        self.inner.focal_lengths()
    }

    /// The principal point (cx, cy) in pixels.
    #[getter]
    fn principal_point(&self) -> (f64, f64) {
        self.inner.principal_point()
    }

    /// Whether the model has (non-zero) distortion terms.
    #[getter]
    fn has_distortion(&self) -> bool {
        self.inner.has_distortion()
    }

    /// OpenCV's ``(K, dist)`` of this camera for ``cv2.projectPoints`` / ``cv2.solvePnP``, or
    /// None for the fisheye models (see ``to_opencv_fisheye``).
    fn to_opencv<'py>(&self, py: Python<'py>) -> Option<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        let (k, d) = self.inner.to_opencv()?;
        Some(opencv_arrays(py, &k, &d))
    }

    /// ``cv2.fisheye``'s ``(K, dist)`` of an OPENCV_FISHEYE camera, else None.
    fn to_opencv_fisheye<'py>(
        &self,
        py: Python<'py>,
    ) -> Option<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        let (k, d) = self.inner.to_opencv_fisheye()?;
        Some(opencv_arrays(py, &k, &d))
    }

    /// Pixels of normalised image points (x/z, y/z), shape (N, 2) -> (N, 2).
    fn project<'py>(
        &self,
        py: Python<'py>,
        normalised: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let pts = points2(normalised, "normalised")?;
        let out: Vec<f64> = pts
            .iter()
            .flat_map(|p| {
                let q = self.inner.project(*p);
                [q.x, q.y]
            })
            .collect();
        Ok(array2(py, pts.len(), 2, &out))
    }

    /// Normalised image points (x/z, y/z) of pixels, shape (N, 2) -> (N, 2), by iterative
    /// undistortion. A pixel that cannot be undistorted (NaN, outside the region where the
    /// lens model is invertible, beyond 90 degrees of a fisheye) gives a row of NaN.
    fn undistort<'py>(
        &self,
        py: Python<'py>,
        pixels: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let pts = points2(pixels, "pixels")?;
        let out: Vec<f64> = pts
            .iter()
            .flat_map(|p| match self.inner.undistort(Point2::new(p.x, p.y)) {
                Ok(n) => [n.x, n.y],
                Err(_) => [f64::NAN, f64::NAN],
            })
            .collect();
        Ok(array2(py, pts.len(), 2, &out))
    }

    fn __repr__(&self) -> String {
        let params: Vec<String> = self.inner.params().iter().map(|p| format!("{p}")).collect();
        format!(
            "Camera({:?}, [{}], width={}, height={})",
            self.inner.model().name(),
            params.join(", "),
            self.inner.width(),
            self.inner.height()
        )
    }

    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        other
            .cast::<PyCamera>()
            .is_ok_and(|o| o.get().inner == self.inner)
    }

    /// Pickling: ``Camera(model, params, width, height)``.
    fn __reduce__<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        let cls = py.get_type::<PyCamera>().into_any();
        let args = (
            self.inner.model().name(),
            self.inner.params().to_vec(),
            self.inner.width(),
            self.inner.height(),
        )
            .into_pyobject(py)?;
        Ok((cls, args))
    }
}
