//! The rigs and frames of a COLMAP model (COLMAP 3.12 and later): `eopnp.Frame` and
//! `eopnp.SensorRig`, read from `eopnp.Model.frames` and `eopnp.Model.rigs` (the model's data,
//! as `eopnp.Image` is; their registration is `frames.rs`).

use eopnp::colmap::{Frame, Pose, SensorRig, SensorType};
use nalgebra::{Matrix3, Vector3};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::convert::{array1, array2};

/// `[R | t]` row by row.
pub(crate) fn rt_rows(r: &Matrix3<f64>, t: &Vector3<f64>) -> [f64; 12] {
    let mut m = [0.0; 12];
    for i in 0..3 {
        for j in 0..3 {
            m[4 * i + j] = r[(i, j)];
        }
        m[4 * i + 3] = t[i];
    }
    m
}

/// A frame of a COLMAP model with rigs: the images one rig took at once, and the rig's pose
/// then (``rig_from_world``: ``x_rig = R(q) X + t``).
#[pyclass(frozen, module = "eopnp", name = "Frame")]
pub(crate) struct PyFrame {
    pub(crate) inner: Frame,
}

#[pymethods]
impl PyFrame {
    /// Frame id.
    #[getter]
    fn id(&self) -> u32 {
        self.inner.id
    }

    /// Id of the frame's rig (in ``Model.rigs``).
    #[getter]
    fn rig_id(&self) -> u32 {
        self.inner.rig_id
    }

    /// The frame's images' ids, in the frame's order (data of other sensors left out).
    #[getter]
    fn image_ids(&self) -> Vec<u32> {
        self.inner.image_ids().collect()
    }

    /// The rig's pose (rig_from_world): its quaternion (w, x, y, z) as stored, shape (4,).
    #[getter]
    fn q<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        array1(py, &self.inner.rig_from_world.q).into_any()
    }

    /// The rig's pose: its translation, shape (3,).
    #[getter]
    fn t<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        let t = &self.inner.rig_from_world.t;
        array1(py, &[t.x, t.y, t.z]).into_any()
    }

    /// The rig's pose: its rotation matrix (from the normalised quaternion), shape (3, 3).
    #[getter(R)]
    fn r<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        let r = self.inner.rig_from_world.rotation();
        let rows: Vec<f64> = (0..3)
            .flat_map(|i| (0..3).map(move |j| r[(i, j)]))
            .collect();
        array2(py, 3, 3, &rows).into_any()
    }

    fn __repr__(&self) -> String {
        let ids: Vec<u32> = self.inner.image_ids().collect();
        format!(
            "Frame(id={}, rig_id={}, image_ids={:?})",
            self.inner.id, self.inner.rig_id, ids
        )
    }
}

/// A rig of a COLMAP model with rigs: cameras fixed to one body, each with its pose in the rig
/// (``cam_from_rig``: ``x_cam = R x_rig + t``); the reference camera's is the identity. Only
/// the rig's cameras are shown (COLMAP's other sensors, IMUs, are left out).
#[pyclass(frozen, module = "eopnp", name = "SensorRig")]
pub(crate) struct PySensorRig {
    pub(crate) inner: SensorRig,
}

#[pymethods]
impl PySensorRig {
    /// Rig id.
    #[getter]
    fn id(&self) -> u32 {
        self.inner.id
    }

    /// The reference camera's id, or None if the reference sensor is not a camera.
    #[getter]
    fn ref_camera_id(&self) -> Option<u32> {
        self.inner
            .ref_sensor
            .filter(|s| s.kind == SensorType::Camera)
            .map(|s| s.id)
    }

    /// The rig's cameras by id, the reference first: each camera's ``[R | t]``
    /// (cam_from_rig), shape (3, 4), or None if the model does not know it (a new dict on
    /// each access).
    #[getter]
    fn cams_from_rig<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        let reference = self.inner.ref_sensor.into_iter().map(|s| (s, None));
        let others = self.inner.sensors.iter().map(|(s, p)| (*s, Some(*p)));
        for (sensor, given) in reference.chain(others) {
            if sensor.kind != SensorType::Camera {
                continue;
            }
            let pose: Option<Pose> = match given {
                None => Some(Pose::identity()),
                Some(p) => p,
            };
            match pose {
                Some(p) => {
                    d.set_item(sensor.id, array2(py, 3, 4, &rt_rows(&p.rotation(), &p.t)))?
                }
                None => d.set_item(sensor.id, py.None())?,
            }
        }
        Ok(d)
    }

    fn __repr__(&self) -> String {
        let ids: Vec<u32> = self
            .inner
            .ref_sensor
            .into_iter()
            .chain(self.inner.sensors.iter().map(|(s, _)| *s))
            .filter(|s| s.kind == SensorType::Camera)
            .map(|s| s.id)
            .collect();
        format!("SensorRig(id={}, camera_ids={ids:?})", self.inner.id)
    }
}
