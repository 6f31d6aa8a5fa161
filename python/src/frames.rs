//! The registration of a COLMAP model's frames (COLMAP 3.12 and later): `eopnp.register_frame`
//! and `eopnp.register_frames` (`eopnp.FrameRegistration`): a frame's rig pose re-estimated
//! from the correspondences of all its images at once, as `register_image` does an image's
//! pose. The frames and rigs themselves are `model_rigs.rs`.

use std::sync::Arc;

use eopnp::colmap::{self, FrameRegistration, Model, Registrar, SensorId};
use numpy::{PyArray3, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyTuple};
use rayon::prelude::*;

use crate::batch::in_pool;
use crate::colmap::{ransac_stats, registration_ransac, PyModel};
use crate::convert::array2;
use crate::errors::{register_error, registrations};
use crate::model_rigs::rt_rows;
use crate::options::{solver_arg, KEYWORDS};
use crate::solution::PySolution;

/// The result of ``register_frame``: a frame's rig pose, as ``Registration`` is an image's
/// camera pose. Picklable.
///
/// Attributes:
///     frame_id, rig_id: the frame and its rig.
///     image_ids: the frame's images, in the frame's order.
///     n: their 2D-3D correspondences, all images together.
///     inliers: correspondences the pose was fitted to (all that could be undistorted, or
///         RANSAC's inliers).
///     skipped: observations whose pixel could not be undistorted.
///     solution: the estimated rig pose, rig_from_world ``x_rig = R @ X + t`` (``Solution``).
///     ransac: RANSAC's statistics (dict, as ``Registration.ransac``), or None without RANSAC.
///     rotation_error_deg: rotation difference to the model's rig_from_world, degrees.
///     translation_error_pct: translation difference, percent of the model's ``|t|``.
///     rmse_px: RMS pixel reprojection error of the estimated pose over the fitted points, each
///         through its own camera.
///     model_rmse_px: the same for the model's frame pose.
///     micros: wall time of undistortion plus solve, microseconds.
///     model_rig_from_world: the model's frame pose ``[R | t]``, shape (3, 4).
///     cams_from_world: each image's camera pose from the estimate, ``[R_k | t_k]`` =
///         cam_from_rig composed with ``solution``, in the order of ``image_ids``, shape
///         (K, 3, 4).
#[pyclass(frozen, module = "eopnp", name = "FrameRegistration")]
pub(crate) struct PyFrameRegistration {
    /// The frame's id.
    #[pyo3(get)]
    frame_id: u32,
    /// The frame's rig's id.
    #[pyo3(get)]
    rig_id: u32,
    /// The frame's images, in the frame's order: camera ``k`` of the solved rig is image
    /// ``image_ids[k]``'s camera.
    #[pyo3(get)]
    image_ids: Vec<u32>,
    /// The 2D-3D correspondences of the frame's images.
    #[pyo3(get)]
    n: usize,
    /// Correspondences the pose was fitted to (all that could be undistorted, or RANSAC's
    /// inliers).
    #[pyo3(get)]
    inliers: usize,
    /// Observations whose pixel could not be undistorted.
    #[pyo3(get)]
    skipped: usize,
    /// The estimated rig pose, rig_from_world (``x_rig = R @ X + t``).
    #[pyo3(get)]
    solution: Py<PySolution>,
    /// RANSAC's statistics (iterations, hypotheses, local_fits, final_fits, inliers,
    /// inlier_ratio, micros), or None without RANSAC.
    #[pyo3(get)]
    ransac: Option<Py<PyDict>>,
    /// Rotation difference to the model's rig_from_world, degrees.
    #[pyo3(get)]
    rotation_error_deg: f64,
    /// Translation difference, percent of the model's ``|t|``.
    #[pyo3(get)]
    translation_error_pct: f64,
    /// RMS pixel reprojection error of the estimated pose over the fitted points, each through
    /// its own camera.
    #[pyo3(get)]
    rmse_px: f64,
    /// The same for the model's frame pose.
    #[pyo3(get)]
    model_rmse_px: f64,
    /// Wall time of undistortion plus solve, microseconds.
    #[pyo3(get)]
    micros: f64,
    /// The model's frame pose, `[R | t]` row by row.
    model_pose: [f64; 12],
    /// Each image's composed camera pose, `[R | t]` row by row.
    cam_poses: Vec<[f64; 12]>,
}

#[pymethods]
impl PyFrameRegistration {
    /// The model's frame pose (rig_from_world) ``[R | t]``, shape (3, 4).
    #[getter]
    fn model_rig_from_world<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        array2(py, 3, 4, &self.model_pose).into_any()
    }

    /// Each image's camera pose from the estimated rig pose, ``[R_k | t_k]`` (its
    /// cam_from_rig composed with ``solution``: ``x_cam = R_k @ X + t_k``), in the order of
    /// ``image_ids``, shape (K, 3, 4).
    #[getter]
    fn cams_from_world<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray3<f64>> {
        let out = PyArray3::<f64>::zeros(py, [self.cam_poses.len(), 3, 4], false);
        {
            let mut a = out.readwrite();
            let mut a = a.as_array_mut();
            for (k, m) in self.cam_poses.iter().enumerate() {
                for i in 0..3 {
                    for j in 0..4 {
                        a[[k, i, j]] = m[4 * i + j];
                    }
                }
            }
        }
        out
    }

    fn __repr__(&self) -> String {
        format!(
            "FrameRegistration(frame_id={}, rig_id={}, image_ids={:?}, n={}, inliers={}, \
             rotation_error_deg={:.3e}, rmse_px={:.4})",
            self.frame_id,
            self.rig_id,
            self.image_ids,
            self.n,
            self.inliers,
            self.rotation_error_deg,
            self.rmse_px
        )
    }

    /// Pickling: the fields (the solution and RANSAC's dict pickle themselves).
    fn __reduce__<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        let rebuild = py
            .import("eopnp._eopnp")?
            .getattr("_frame_registration_from_state")?;
        let state: FrameState = (
            (self.frame_id, self.rig_id, self.image_ids.clone()),
            (self.n, self.inliers, self.skipped),
            self.solution.clone_ref(py),
            self.ransac.as_ref().map(|d| d.clone_ref(py)),
            (
                self.rotation_error_deg,
                self.translation_error_pct,
                self.rmse_px,
                self.model_rmse_px,
                self.micros,
            ),
            self.model_pose.to_vec(),
            self.cam_poses.iter().flatten().copied().collect(),
        );
        Ok((rebuild, PyTuple::new(py, [state.into_pyobject(py)?])?))
    }
}

type FrameState = (
    (u32, u32, Vec<u32>),
    (usize, usize, usize),
    Py<PySolution>,
    Option<Py<PyDict>>,
    (f64, f64, f64, f64, f64),
    Vec<f64>,
    Vec<f64>,
);

/// Rebuilds a `FrameRegistration` from `__reduce__`'s state (private; for pickle).
#[pyfunction]
pub(crate) fn _frame_registration_from_state(state: FrameState) -> PyResult<PyFrameRegistration> {
    let ((frame_id, rig_id, image_ids), (n, inliers, skipped), solution, ransac, errors, m, c) =
        state;
    let bad = || pyo3::exceptions::PyValueError::new_err("bad FrameRegistration state");
    let model_pose: [f64; 12] = m.try_into().map_err(|_| bad())?;
    if c.len() != 12 * image_ids.len() {
        return Err(bad());
    }
    let cam_poses = c
        .chunks_exact(12)
        .map(|x| x.try_into().expect("chunks of 12"))
        .collect();
    let (rotation_error_deg, translation_error_pct, rmse_px, model_rmse_px, micros) = errors;
    Ok(PyFrameRegistration {
        frame_id,
        rig_id,
        image_ids,
        n,
        inliers,
        skipped,
        solution,
        ransac,
        rotation_error_deg,
        translation_error_pct,
        rmse_px,
        model_rmse_px,
        micros,
        model_pose,
        cam_poses,
    })
}

/// A ``FrameRegistration`` of `reg`, a registration of a frame of `model`.
fn to_py(py: Python<'_>, model: &Model, reg: FrameRegistration) -> PyResult<PyFrameRegistration> {
    let model_pose = model.frames.get(&reg.frame_id).map_or([f64::NAN; 12], |f| {
        rt_rows(&f.rig_from_world.rotation(), &f.rig_from_world.t)
    });
    let (r, t) = (reg.solution.rotation, reg.solution.translation);
    let rig = model.rigs.get(&reg.rig_id);
    // Registered, so each image's camera has a pose in the rig (else NaN, never reached).
    let cam_poses = reg
        .image_ids
        .iter()
        .map(|id| {
            let cam_from_rig = model
                .images
                .get(id)
                .and_then(|img| rig?.sensor_from_rig(SensorId::camera(img.camera_id)));
            cam_from_rig.map_or([f64::NAN; 12], |p| {
                let rk = p.rotation();
                rt_rows(&(rk * r), &(rk * t + p.t))
            })
        })
        .collect();
    Ok(PyFrameRegistration {
        frame_id: reg.frame_id,
        rig_id: reg.rig_id,
        n: reg.n,
        inliers: reg.inliers,
        skipped: reg.skipped,
        solution: Py::new(py, PySolution::from(&reg.solution))?,
        ransac: reg.ransac.map(|s| ransac_stats(py, &s)).transpose()?,
        rotation_error_deg: reg.rotation_error_deg,
        translation_error_pct: reg.translation_error_pct,
        rmse_px: reg.rmse_px,
        model_rmse_px: reg.model_rmse_px,
        micros: reg.micros,
        image_ids: reg.image_ids,
        model_pose,
        cam_poses,
    })
}

/// Re-estimates the pose of a frame's rig from the 2D-3D correspondences of all its images at
/// once and compares it with the model's frame pose (rig_from_world): the frame's images are
/// the cameras of a rig, each with its cam_from_rig from ``Model.rigs``, as
/// ``solve_generalized`` (``solve_generalized_ransac`` with RANSAC) solves it, every
/// observation through its own camera, distortion included.
///
/// Args:
///     model: a ``Model`` from ``read_colmap_model`` of a model with rigs (COLMAP 3.12+).
///     frame_id: the frame (``Model.frame_ids``).
///     ransac: None or False: on every correspondence; True (default options), a
///         ``RansacOptions`` or a dict of its fields: robust, as ``register_image``.
///     options, **keywords: the solver's options, as ``register_image``.
///
/// Returns:
///     FrameRegistration: the rig pose, its errors against the model's, RANSAC's statistics,
///     each image's camera pose.
///
/// Raises:
///     UnknownIdError: no such frame (kind ``"UnknownFrame"``), or its rig, an image or a
///         camera is missing, or a camera has no known pose in the rig (``"NoSensorPose"``).
///     InvalidInputError: a frame without images (``"EmptyFrame"``); and as
///         ``register_image``: InvalidInputError, DegenerateError, NoConsensusError, ... on
///         the frame's correspondences.
#[pyfunction]
#[pyo3(signature = (model, frame_id, *, ransac = None, options = None, **keywords))]
pub(crate) fn register_frame(
    py: Python<'_>,
    model: &Bound<'_, PyModel>,
    frame_id: u32,
    ransac: Option<&Bound<'_, PyAny>>,
    options: Option<&Bound<'_, PyAny>>,
    keywords: Option<&Bound<'_, PyDict>>,
) -> PyResult<PyFrameRegistration> {
    let solver = solver_arg(py, "register_frame", options, keywords, KEYWORDS)?;
    let ransac = registration_ransac(py, ransac)?;
    let m = Arc::clone(&model.get().inner);
    let reg = py
        .detach(|| colmap::register_frame(&m, frame_id, &solver, ransac.as_ref()))
        .map_err(|e| register_error(py, &e))?;
    to_py(py, &m, reg)
}

/// Registers many frames of a model (``register_frame`` on each), in parallel, the GIL
/// released for the whole call, as ``register_images``.
///
/// Args:
///     model: a ``Model`` from ``read_colmap_model``.
///     frame_ids: the frames (any iterable of ids), or None for every frame in id order.
///     ransac, options, **keywords: as ``register_frame``.
///     threads: None (rayon's global pool) or the number of threads, as ``solve_batch``.
///
/// Returns:
///     list: one entry per id, in order: its ``FrameRegistration``, or the exception
///     ``register_frame`` would raise for it (an instance, not raised). Equal to
///     ``register_frame`` one by one but the times, whatever ``threads``.
///
/// Raises:
///     InvalidOptionError: an option out of range or a bad ``threads``.
///     TypeError: as ``solve``.
#[pyfunction]
#[pyo3(signature = (model, frame_ids = None, *, ransac = None, options = None, threads = None,
    **keywords))]
pub(crate) fn register_frames<'py>(
    py: Python<'py>,
    model: &Bound<'py, PyModel>,
    frame_ids: Option<&Bound<'py, PyAny>>,
    ransac: Option<&Bound<'py, PyAny>>,
    options: Option<&Bound<'py, PyAny>>,
    threads: Option<i64>,
    keywords: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyList>> {
    let solver = solver_arg(py, "register_frames", options, keywords, KEYWORDS)?;
    let ransac = registration_ransac(py, ransac)?;
    let m = Arc::clone(&model.get().inner);
    let ids: Vec<u32> = match frame_ids {
        None => m.frames.keys().copied().collect(),
        // Each id as `register_frame`'s `frame_id` argument is extracted.
        Some(ids) => ids
            .try_iter()?
            .map(|id| id?.extract::<u32>())
            .collect::<PyResult<_>>()?,
    };
    let results = in_pool(py, threads, || {
        ids.par_iter()
            .map_init(
                || Registrar::new(&m),
                |r, id| r.register_frame(*id, &solver, ransac.as_ref()),
            )
            .collect::<Vec<_>>()
    })?;
    registrations(py, results, |reg| to_py(py, &m, reg))
}
