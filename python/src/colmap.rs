//! COLMAP models: `eopnp.read_colmap_model`, `eopnp.Model`, `eopnp.Image` and
//! `eopnp.register_image` and `eopnp.register_images` (`eopnp.Registration`).

use std::path::PathBuf;
use std::sync::Arc;

use eopnp::colmap::{self, Image, Model, Registrar, Registration};
use eopnp::ransac::{Ransac, RansacStats};
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyTuple};
use rayon::prelude::*;

use crate::batch::in_pool;

use crate::camera::PyCamera;
use crate::convert::{array1, array2};
use crate::errors::{model_error, register_error, registrations};
use crate::model_rigs::{PyFrame, PySensorRig};
use crate::options::{solver_arg, KEYWORDS};
use crate::ransac::ransac_arg;
use crate::solution::PySolution;
use crate::solve::{focal_arg, with_intrinsics};

/// A COLMAP sparse reconstruction, as read by ``read_colmap_model`` (read-only).
///
/// Poses are COLMAP's: world to camera, ``x_cam = R(q) X + t``.
#[pyclass(frozen, module = "eopnp", name = "Model")]
pub(crate) struct PyModel {
    pub(crate) inner: Arc<Model>,
}

/// An image of a COLMAP model: its pose, camera and 2D observations.
#[pyclass(frozen, module = "eopnp", name = "Image")]
pub(crate) struct PyImage {
    inner: Image,
}

fn image_by_id<'m>(py: Python<'_>, model: &'m Model, id: u32) -> PyResult<&'m Image> {
    model
        .images
        .get(&id)
        .ok_or_else(|| register_error(py, &colmap::RegisterError::UnknownImage(id)))
}

#[pymethods]
impl PyModel {
    /// Cameras by id (a new dict of new ``Camera`` objects on each access).
    #[getter]
    fn cameras<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for (id, c) in &self.inner.cameras {
            d.set_item(*id, PyCamera { inner: *c })?;
        }
        Ok(d)
    }

    /// Images by id (a new dict of new ``Image`` objects on each access).
    #[getter]
    fn images<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for (id, i) in &self.inner.images {
            d.set_item(*id, PyImage { inner: i.clone() })?;
        }
        Ok(d)
    }

    /// The image ids, ascending.
    #[getter]
    fn image_ids(&self) -> Vec<u32> {
        self.inner.images.keys().copied().collect()
    }

    /// Frames by id (a new dict of new ``Frame`` objects on each access): empty unless the
    /// model has rigs (COLMAP 3.12 and later).
    #[getter]
    fn frames<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for (id, f) in &self.inner.frames {
            d.set_item(*id, PyFrame { inner: f.clone() })?;
        }
        Ok(d)
    }

    /// The frame ids, ascending.
    #[getter]
    fn frame_ids(&self) -> Vec<u32> {
        self.inner.frames.keys().copied().collect()
    }

    /// Rigs by id (a new dict of new ``SensorRig`` objects on each access): empty unless the
    /// model has rigs.
    #[getter]
    fn rigs<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for (id, r) in &self.inner.rigs {
            d.set_item(*id, PySensorRig { inner: r.clone() })?;
        }
        Ok(d)
    }

    /// Number of 3D points.
    #[getter]
    #[allow(non_snake_case)]
    fn num_points3D(&self) -> usize {
        self.inner.points.len()
    }

    /// The 3D points' ids (ascending), shape (M,).
    #[getter]
    #[allow(non_snake_case)]
    fn point3D_ids<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<u64>> {
        PyArray1::from_iter(py, self.inner.points.keys().copied())
    }

    /// The 3D points' coordinates in the order of ``point3D_ids``, shape (M, 3).
    #[getter]
    #[allow(non_snake_case)]
    fn points3D<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        let xyz: Vec<f64> = self
            .inner
            .points
            .values()
            .flat_map(|p| [p.xyz.x, p.xyz.y, p.xyz.z])
            .collect();
        array2(py, self.inner.points.len(), 3, &xyz).into_any()
    }

    /// The image with this id. Raises ``UnknownIdError`` if there is none.
    fn image(&self, py: Python<'_>, image_id: u32) -> PyResult<PyImage> {
        let inner = image_by_id(py, &self.inner, image_id)?.clone();
        Ok(PyImage { inner })
    }

    /// The frame with this id. Raises ``UnknownIdError`` if there is none.
    fn frame(&self, py: Python<'_>, frame_id: u32) -> PyResult<PyFrame> {
        let inner = self
            .inner
            .frames
            .get(&frame_id)
            .ok_or_else(|| register_error(py, &colmap::RegisterError::UnknownFrame(frame_id)))?
            .clone();
        Ok(PyFrame { inner })
    }

    /// The camera of an image. Raises ``UnknownIdError``.
    fn camera_of(&self, py: Python<'_>, image_id: u32) -> PyResult<PyCamera> {
        let (_, cam) = self
            .inner
            .image_and_camera(image_id)
            .map_err(|e| register_error(py, &e))?;
        Ok(PyCamera { inner: *cam })
    }

    /// The 2D-3D correspondences of an image: ``(world (N, 3), pixels (N, 2))``, the
    /// observations that have a 3D point, in the image's order. Raises ``UnknownIdError``.
    fn correspondences<'py>(
        &self,
        py: Python<'py>,
        image_id: u32,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        image_by_id(py, &self.inner, image_id)?;
        let (w, p) = self.inner.correspondences(image_id);
        let wf: Vec<f64> = w.iter().flat_map(|x| [x.x, x.y, x.z]).collect();
        let pf: Vec<f64> = p.iter().flat_map(|x| [x.x, x.y]).collect();
        Ok((
            array2(py, w.len(), 3, &wf).into_any(),
            array2(py, p.len(), 2, &pf).into_any(),
        ))
    }

    fn __len__(&self) -> usize {
        self.inner.images.len()
    }

    fn __repr__(&self) -> String {
        format!(
            "Model({} cameras, {} images, {} points3D)",
            self.inner.cameras.len(),
            self.inner.images.len(),
            self.inner.points.len()
        )
    }
}

#[pymethods]
impl PyImage {
    /// Image id.
    #[getter]
    fn id(&self) -> u32 {
        self.inner.id
    }

    /// Image name.
    #[getter]
    fn name(&self) -> &str {
        &self.inner.name
    }

    /// Id of the image's camera.
    #[getter]
    fn camera_id(&self) -> u32 {
        self.inner.camera_id
    }

    /// The pose's quaternion (w, x, y, z) as stored, shape (4,).
    #[getter]
    fn q<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        array1(py, &self.inner.q).into_any()
    }

    /// The pose's translation, shape (3,).
    #[getter]
    fn t<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        let t = &self.inner.t;
        array1(py, &[t.x, t.y, t.z]).into_any()
    }

    /// The pose's rotation matrix (from the normalised quaternion), shape (3, 3).
    #[getter(R)]
    fn r<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        let (r, _) = self.inner.pose();
        let rows: Vec<f64> = (0..3)
            .flat_map(|i| (0..3).map(move |j| r[(i, j)]))
            .collect();
        array2(py, 3, 3, &rows).into_any()
    }

    /// The observations' pixels, shape (K, 2).
    #[getter]
    #[allow(non_snake_case)]
    fn points2D<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        let p: Vec<f64> = self
            .inner
            .points2d
            .iter()
            .flat_map(|(px, _)| [px.x, px.y])
            .collect();
        array2(py, self.inner.points2d.len(), 2, &p).into_any()
    }

    /// The observations' 3D point ids, -1 for an untriangulated observation, shape (K,).
    #[getter]
    #[allow(non_snake_case)]
    fn point3D_ids<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        PyArray1::from_iter(
            py,
            self.inner
                .points2d
                .iter()
                .map(|(_, id)| id.and_then(|i| i64::try_from(i).ok()).unwrap_or(-1)),
        )
    }

    fn __repr__(&self) -> String {
        format!(
            "Image(id={}, name={:?}, camera_id={}, {} observations)",
            self.inner.id,
            self.inner.name,
            self.inner.camera_id,
            self.inner.points2d.len()
        )
    }
}

/// Reads a COLMAP sparse model directory: ``cameras``, ``images`` and ``points3D``, and
/// ``rigs`` and ``frames`` when present (COLMAP 3.12 and later), in the text (``.txt``) or
/// binary (``.bin``) format (binary preferred when both are present), and checks its
/// cross-references.
///
/// Raises:
///     ModelError: a missing or malformed file, with the file, line or byte offset and reason.
#[pyfunction]
pub(crate) fn read_colmap_model(py: Python<'_>, path: PathBuf) -> PyResult<PyModel> {
    let model = py
        .detach(|| colmap::read_model(&path, &colmap::ReadOptions::default()))
        .map_err(|e| model_error(py, &e))?;
    Ok(PyModel {
        inner: Arc::new(model),
    })
}

/// The result of ``register_image``.
///
/// Attributes:
///     image_id, name: the image.
///     n: its 2D-3D correspondences.
///     inliers: correspondences the pose was fitted to (all that could be undistorted, or
///         RANSAC's inliers).
///     skipped: observations whose pixel could not be undistorted.
///     solution: the estimated pose (``Solution``).
///     ransac: RANSAC's statistics (dict: iterations, hypotheses, local_fits, final_fits,
///         inliers, inlier_ratio, micros), or None without RANSAC.
///     rotation_error_deg: rotation difference to the model's pose, degrees.
///     translation_error_pct: translation difference, percent of the model's ``|t|``.
///     rmse_px: RMS pixel reprojection error of the estimated pose over the fitted points
///         (through the estimated camera with ``estimate_focal``).
///     model_rmse_px: the same for the model's own pose and camera.
///     focal_error_pct: with ``estimate_focal`` (or another intrinsic refined), the estimated
///         focal length's error against the model camera's, percent; None otherwise.
///     micros: wall time of undistortion plus solve, microseconds.
#[pyclass(frozen, module = "eopnp", name = "Registration")]
pub(crate) struct PyRegistration {
    /// The image's id.
    #[pyo3(get)]
    image_id: u32,
    /// The image's name.
    #[pyo3(get)]
    name: String,
    /// The image's 2D-3D correspondences.
    #[pyo3(get)]
    n: usize,
    /// Correspondences the pose was fitted to (all that could be undistorted, or RANSAC's
    /// inliers).
    #[pyo3(get)]
    inliers: usize,
    /// Observations whose pixel could not be undistorted.
    #[pyo3(get)]
    skipped: usize,
    /// The estimated pose.
    #[pyo3(get)]
    solution: Py<PySolution>,
    /// RANSAC's statistics (iterations, hypotheses, local_fits, final_fits, inliers,
    /// inlier_ratio, micros), or None without RANSAC.
    #[pyo3(get)]
    ransac: Option<Py<PyDict>>,
    /// Rotation difference to the model's pose, degrees.
    #[pyo3(get)]
    rotation_error_deg: f64,
    /// Translation difference, percent of the model's ``|t|``.
    #[pyo3(get)]
    translation_error_pct: f64,
    /// RMS pixel reprojection error of the estimated pose over the fitted points.
    #[pyo3(get)]
    rmse_px: f64,
    /// The same for the model's own pose.
    #[pyo3(get)]
    model_rmse_px: f64,
    /// With ``estimate_focal`` (or another intrinsic refined): the estimated focal length's
    /// error against the model camera's, percent (the larger of the two axes'); None
    /// otherwise.
    #[pyo3(get)]
    focal_error_pct: Option<f64>,
    /// Wall time of undistortion plus solve, microseconds.
    #[pyo3(get)]
    micros: f64,
}

#[pymethods]
impl PyRegistration {
    fn __repr__(&self) -> String {
        format!(
            "Registration(image_id={}, name={:?}, n={}, inliers={}, rotation_error_deg={:.3e}, \
             rmse_px={:.4})",
            self.image_id, self.name, self.n, self.inliers, self.rotation_error_deg, self.rmse_px
        )
    }

    /// Pickling: the fields (the solution and RANSAC's dict pickle themselves).
    fn __reduce__<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        let rebuild = py
            .import("eopnp._eopnp")?
            .getattr("_registration_from_state")?;
        let state: RegistrationState = (
            (self.image_id, self.name.clone()),
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
            self.focal_error_pct,
        );
        Ok((rebuild, PyTuple::new(py, [state.into_pyobject(py)?])?))
    }
}

type RegistrationState = (
    (u32, String),
    (usize, usize, usize),
    Py<PySolution>,
    Option<Py<PyDict>>,
    (f64, f64, f64, f64, f64),
    Option<f64>,
);

/// Rebuilds a `Registration` from `__reduce__`'s state (private; for pickle).
#[pyfunction]
pub(crate) fn _registration_from_state(state: RegistrationState) -> PyRegistration {
    let ((image_id, name), (n, inliers, skipped), solution, ransac, errors, focal_error_pct) =
        state;
    let (rotation_error_deg, translation_error_pct, rmse_px, model_rmse_px, micros) = errors;
    PyRegistration {
        image_id,
        name,
        n,
        inliers,
        skipped,
        solution,
        ransac,
        rotation_error_deg,
        translation_error_pct,
        rmse_px,
        model_rmse_px,
        focal_error_pct,
        micros,
    }
}

/// Re-estimates an image's pose from its 2D-3D correspondences alone and compares it with the
/// model's pose.
///
/// Args:
///     model: a ``Model`` from ``read_colmap_model``.
///     image_id: the image.
///     ransac: None or False: ``solve`` on every correspondence through the image's camera;
///         True (default options), a ``RansacOptions`` or a dict of its fields: robust, as
///         ``solve_ransac``.
///     estimate_focal: the image's focal length is re-estimated with its pose, the model's
///         camera the starting guess (as pycolmap's ``estimate_focal_length`` and
///         ``refine_focal_length``); ``Registration.solution.camera`` holds the estimated
///         camera, ``Registration.focal_error_pct`` its error against the model's.
///     focal_range: ``(min_px, max_px)``, the range of the focal length sought (implies
///         ``estimate_focal``; default a tenth to ten times the model camera's).
///     refine_principal_point, refine_distortion: the principal point, the distortion
///         parameters refined with the pose too, as ``solve``'s.
///     options: a ``SolverOptions`` (or a dict of its fields), as ``solve``: ``loss``'s scale
///         and ``covariance``'s noise in pixels; ``Registration.solution.covariance`` is from
///         every correspondence used, or with RANSAC from the inliers.
///     **keywords: the options of ``SolverOptions`` as keyword arguments instead, as
///         ``solve``.
///
/// Returns:
///     Registration: the pose, its errors against the model's, RANSAC's statistics.
///
/// Raises:
///     UnknownIdError: no such image (or its camera is missing).
///     InvalidInputError, DegenerateError, NoConsensusError, ...: as ``solve`` and
///         ``solve_ransac`` on the image's correspondences.
///     InvalidOptionError: an option out of range (e.g. a bad ``focal_range``).
#[pyfunction]
#[pyo3(signature = (model, image_id, *, ransac = None, estimate_focal = false,
    focal_range = None, refine_principal_point = false, refine_distortion = false,
    options = None, **keywords))]
// One Rust parameter per Python parameter.
#[allow(clippy::too_many_arguments)]
pub(crate) fn register_image(
    py: Python<'_>,
    model: &Bound<'_, PyModel>,
    image_id: u32,
    ransac: Option<&Bound<'_, PyAny>>,
    estimate_focal: bool,
    focal_range: Option<&Bound<'_, PyAny>>,
    refine_principal_point: bool,
    refine_distortion: bool,
    options: Option<&Bound<'_, PyAny>>,
    keywords: Option<&Bound<'_, PyDict>>,
) -> PyResult<PyRegistration> {
    let intrinsics = focal_arg(estimate_focal, focal_range)?
        .refining(refine_principal_point, refine_distortion);
    let solver = solver_arg(py, "register_image", options, keywords, KEYWORDS)?;
    let ransac = registration_ransac(py, ransac)?;
    let m = Arc::clone(&model.get().inner);
    let reg = py
        .detach(|| {
            colmap::register_image_with(&m, image_id, &solver, ransac.as_ref(), |p| {
                with_intrinsics(p, intrinsics)
            })
        })
        .map_err(|e| register_error(py, &e))?;
    to_py(py, reg)
}

/// The RANSAC options of ``register_image``'s ``ransac``: None or False (plain), True
/// (defaults), a ``RansacOptions`` or a dict.
pub(crate) fn registration_ransac(
    py: Python<'_>,
    ransac: Option<&Bound<'_, PyAny>>,
) -> PyResult<Option<Ransac>> {
    Ok(match ransac {
        None => None,
        Some(r) if r.is_instance_of::<pyo3::types::PyBool>() => {
            if r.extract::<bool>()? {
                Some(ransac_arg(py, None)?)
            } else {
                None
            }
        }
        Some(r) => Some(ransac_arg(py, Some(r))?),
    })
}

/// RANSAC's statistics as ``Registration.ransac``'s dict.
pub(crate) fn ransac_stats(py: Python<'_>, s: &RansacStats) -> PyResult<Py<PyDict>> {
    let d = PyDict::new(py);
    d.set_item("iterations", s.iterations)?;
    d.set_item("hypotheses", s.hypotheses)?;
    d.set_item("local_fits", s.local_fits)?;
    d.set_item("final_fits", s.final_fits)?;
    d.set_item("inliers", s.inliers)?;
    d.set_item("inlier_ratio", s.inlier_ratio)?;
    d.set_item("micros", s.micros)?;
    Ok(d.unbind())
}

/// A ``Registration`` of `reg`.
fn to_py(py: Python<'_>, reg: Registration) -> PyResult<PyRegistration> {
    let stats = reg.ransac.map(|s| ransac_stats(py, &s)).transpose()?;
    Ok(PyRegistration {
        image_id: reg.image_id,
        name: reg.name,
        n: reg.n,
        inliers: reg.inliers,
        skipped: reg.skipped,
        solution: Py::new(py, PySolution::from(&reg.solution))?,
        ransac: stats,
        rotation_error_deg: reg.rotation_error_deg,
        translation_error_pct: reg.translation_error_pct,
        rmse_px: reg.rmse_px,
        model_rmse_px: reg.model_rmse_px,
        focal_error_pct: reg.focal_error_pct,
        micros: reg.micros,
    })
}

/// Registers many images of a model (``register_image`` on each), in parallel, the GIL
/// released for the whole call: each thread looks the model's 3D points up in a table it
/// builds once (``register_image`` builds one per call).
///
/// Args:
///     model: a ``Model`` from ``read_colmap_model``.
///     image_ids: the images (any iterable of ids), or None for every image in id order.
///     ransac, estimate_focal, focal_range, refine_principal_point, refine_distortion,
///     options, **keywords: as ``register_image``.
///     threads: None (rayon's global pool) or the number of threads, as ``solve_batch``.
///
/// Returns:
///     list: one entry per id, in order: its ``Registration``, or the exception
///     ``register_image`` would raise for it (an instance, not raised). Equal to
///     ``register_image`` one by one but the times, whatever ``threads``.
///
/// Raises:
///     InvalidOptionError: an option out of range or a bad ``threads``.
///     TypeError: as ``solve``.
#[pyfunction]
#[pyo3(signature = (model, image_ids = None, *, ransac = None, estimate_focal = false,
    focal_range = None, refine_principal_point = false, refine_distortion = false,
    options = None, threads = None, **keywords))]
// One Rust parameter per Python parameter.
#[allow(clippy::too_many_arguments)]
pub(crate) fn register_images<'py>(
    py: Python<'py>,
    model: &Bound<'py, PyModel>,
    image_ids: Option<&Bound<'py, PyAny>>,
    ransac: Option<&Bound<'py, PyAny>>,
    estimate_focal: bool,
    focal_range: Option<&Bound<'py, PyAny>>,
    refine_principal_point: bool,
    refine_distortion: bool,
    options: Option<&Bound<'py, PyAny>>,
    threads: Option<i64>,
    keywords: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyList>> {
    let intrinsics = focal_arg(estimate_focal, focal_range)?
        .refining(refine_principal_point, refine_distortion);
    let solver = solver_arg(py, "register_images", options, keywords, KEYWORDS)?;
    let ransac = registration_ransac(py, ransac)?;
    let m = Arc::clone(&model.get().inner);
    let ids: Vec<u32> = match image_ids {
        None => m.images.keys().copied().collect(),
        // Each id as `register_image`'s `image_id` argument is extracted.
        Some(ids) => ids
            .try_iter()?
            .map(|id| id?.extract::<u32>())
            .collect::<PyResult<_>>()?,
    };
    let results = in_pool(py, threads, || {
        ids.par_iter()
            .map_init(
                || Registrar::new(&m),
                |r, id| {
                    r.register_with(*id, &solver, ransac.as_ref(), |p| {
                        with_intrinsics(p, intrinsics)
                    })
                },
            )
            .collect::<Vec<_>>()
    })?;
    registrations(py, results, |reg| to_py(py, reg))
}
