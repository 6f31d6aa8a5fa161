//! `eopnp.Gravity`: a known vertical (the direction of gravity measured by an IMU), given to
//! the solves as ``gravity=``.

use eopnp::Gravity;
use nalgebra::Vector3;
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::PyTuple;

use crate::convert::{array1, vector};
use crate::errors::pnp_error;

/// The direction of gravity (or any direction known in both frames) measured in the camera's
/// frame and known in the world's, with the measurement's uncertainty.
///
/// Args:
///     in_camera: the direction in the camera's frame, shape (3,) (for a rig: the rig's frame),
///         e.g. an IMU's gravity vector rotated into the camera. Any non-zero length.
///     in_world: the same direction in the world's frame, shape (3,): ``(0, 0, -1)`` for a
///         world whose z axis points up. "Down" in both, or "up" in both.
///     sigma_deg: the measurement's standard deviation in degrees, about each of the two axes
///         across the direction (an IMU's tilt accuracy, 0.1 to 1 degree).
///
/// Passed as ``gravity=`` to ``solve``, ``refine``, ``solve_ransac``, ``solve_generalized``,
/// ``solve_generalized_ransac`` and ``refine_generalized``: the pose is then the maximum a
/// posteriori one with the vertical as a prior, RANSAC draws samples of two points (the upright
/// two-point pose), and a vertical the images contradict raises ``GravityMismatchError``.
///
/// Raises:
///     InvalidOptionError: a zero or non-finite direction, or ``sigma_deg`` not finite and
///         > 0 (``option`` ``"gravity"``).
#[pyclass(frozen, module = "eopnp", name = "Gravity")]
pub(crate) struct PyGravity {
    pub(crate) inner: Gravity,
}

fn vector3(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Vector3<f64>> {
    let v = vector(obj, name, false)?;
    match v.as_slice() {
        [x, y, z] => Ok(Vector3::new(*x, *y, *z)),
        _ => Err(pnp_error(
            obj.py(),
            &eopnp::PnpError::InvalidOption { option: "gravity" },
        )),
    }
}

#[pymethods]
impl PyGravity {
    #[new]
    fn new(
        in_camera: &Bound<'_, PyAny>,
        in_world: &Bound<'_, PyAny>,
        sigma_deg: f64,
    ) -> PyResult<Self> {
        let py = in_camera.py();
        let c = vector3(in_camera, "in_camera")?;
        let w = vector3(in_world, "in_world")?;
        Gravity::new(c, w, sigma_deg)
            .map(|inner| PyGravity { inner })
            .map_err(|e| pnp_error(py, &e))
    }

    /// The direction in the camera's (rig's) frame, unit length, shape (3,).
    #[getter]
    fn in_camera<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        array1(py, self.inner.in_camera().as_slice())
    }

    /// The direction in the world's frame, unit length, shape (3,).
    #[getter]
    fn in_world<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        array1(py, self.inner.in_world().as_slice())
    }

    /// The measurement's standard deviation, degrees.
    #[getter]
    fn sigma_deg(&self) -> f64 {
        self.inner.sigma_deg()
    }

    fn __repr__(&self) -> String {
        let (c, w) = (self.inner.in_camera(), self.inner.in_world());
        format!(
            "Gravity([{}, {}, {}], [{}, {}, {}], sigma_deg={})",
            c.x,
            c.y,
            c.z,
            w.x,
            w.y,
            w.z,
            self.inner.sigma_deg()
        )
    }

    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        other
            .cast::<PyGravity>()
            .is_ok_and(|o| o.get().inner == self.inner)
    }

    /// Pickling: ``Gravity(in_camera, in_world, sigma_deg)`` (the unit vectors: the same
    /// object again).
    fn __reduce__<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        let cls = py.get_type::<PyGravity>().into_any();
        let (c, w) = (self.inner.in_camera(), self.inner.in_world());
        let args = (
            vec![c.x, c.y, c.z],
            vec![w.x, w.y, w.z],
            self.inner.sigma_deg(),
        )
            .into_pyobject(py)?;
        Ok((cls, args))
    }
}

/// The library's vertical of an optional ``gravity=`` argument.
pub(crate) fn gravity_arg(g: Option<&Bound<'_, PyGravity>>) -> Option<Gravity> {
    g.map(|g| g.get().inner)
}
