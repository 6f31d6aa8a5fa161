//! `eopnp.Rig` and the rig functions `eopnp.solve_generalized`,
//! `eopnp.solve_generalized_ransac` and `eopnp.refine_generalized` (the library's
//! `Problem::rig`): pixels observed by the cameras of a multi-camera rig, each in one camera,
//! and the rig's pose. Their arguments follow pycolmap's generalized functions
//! (`points2D, points3D, camera_idxs, cams_from_rig, cameras`); the batch forms are in `batch`.
//!
//! Camera indices are read as `i64` and checked here (`check`, in the library's order of
//! checks), so that a negative index is reported as an unknown camera with its value, and so
//! that a NaN pixel is rejected also when every point is in one camera (where the library
//! solves that camera's central problem, which would skip it as a pixel that cannot be
//! undistorted): as `solve(..., camera=)` rejects it.

use eopnp::camera::Camera;
use eopnp::ransac::{Ransac, RansacSolution};
use eopnp::{InputKind, PnpError, Problem, Rig, Solution, Solver};
use nalgebra::{Isometry3, Point2, Point3, Quaternion, Translation3, UnitQuaternion};
use numpy::{PyArray3, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use crate::camera::PyCamera;
use crate::convert::{array2, indices, points2, points3, vector};
use crate::errors::{option_error, pnp_error, unknown_camera};
use crate::gravity::{gravity_arg, PyGravity};
use crate::options::{solver_arg, KEYWORDS, REFINE_KEYWORDS};
use crate::pose::pose_arg_as;
use crate::ransac::{ransac_arg, ransac_info};
use crate::solution::PySolution;
use crate::solve::problem_with;

/// A multi-camera rig: calibrated cameras fixed to one body (a car's or a headset's cameras, a
/// stereo pair), each with its pose in the rig.
///
/// ``Rig(cameras, cams_from_rig)``: ``cameras`` a sequence of K ``Camera``, ``cams_from_rig``
/// a sequence of K poses, camera ``k``'s pose in the rig: ``x_cam = R_k @ x_rig + t_k``
/// (``cam_from_rig``, the convention of COLMAP's rigs and pycolmap's ``cams_from_rig``). Each
/// pose is a ``(rotation, t)`` pair (the rotation a (3, 3) matrix, a (3,) rotation vector or a
/// (4,) quaternion (w, x, y, z)), a (3, 4) ``[R | t]`` or a (4, 4) homogeneous matrix (a
/// (K, 3, 4) array is a sequence of K such matrices), or a ``Solution``, as ``refine``'s
/// ``initial``. From pycolmap: ``[p.matrix() for p in cams_from_rig]`` (``Rigid3d``) and
/// ``Camera(c.model.name, c.params, c.width, c.height)``.
///
/// The rig's own frame is any frame fixed to the body (often the first camera's: its pose is
/// then the identity). A problem on the rig (``solve_generalized``) gives the rig's pose in
/// the world, ``x_rig = R @ X + t`` (rig_from_world), and camera ``k``'s pose in the world is
/// ``x_cam = R_k @ (R @ X + t) + t_k``.
///
/// Immutable, comparable (``==``), picklable.
///
/// Attributes:
///     cameras: the K cameras, in index order.
///     cams_from_rig: each camera's ``[R_k | t_k]``, shape (K, 3, 4).
///     centres: each camera's centre in the rig frame, ``-R_k^T t_k``, shape (K, 3).
///
/// Raises:
///     InvalidOptionError: no camera (``option`` "cameras"), an entry of ``cameras`` that is
///         not a ``Camera``, not K poses, a pose not of the forms above, not finite, or whose
///         matrix is not a rotation to 1e-6 (``option`` "cams_from_rig").
#[pyclass(frozen, module = "eopnp", name = "Rig")]
pub(crate) struct PyRig {
    pub(crate) inner: Rig,
}

/// The entries of a sequence argument (`option`), or `InvalidOptionError` when it is not one.
fn items<'py>(
    obj: &Bound<'py, PyAny>,
    option: &str,
    what: &str,
) -> PyResult<Vec<Bound<'py, PyAny>>> {
    let bad = || {
        option_error(
            obj.py(),
            option,
            format!(
                "{option}: expected a sequence of {what}, got {}",
                obj.get_type()
                    .name()
                    .map_or_else(|_| "?".into(), |s| s.to_string())
            ),
        )
    };
    if obj.is_instance_of::<pyo3::types::PyString>() {
        return Err(bad());
    }
    obj.try_iter().map_err(|_| bad())?.collect()
}

impl PyRig {
    /// The rig of `cameras` and `cams_from_rig` (`Rig(cameras, cams_from_rig)`).
    pub(crate) fn build(
        cameras: &Bound<'_, PyAny>,
        cams_from_rig: &Bound<'_, PyAny>,
    ) -> PyResult<Self> {
        let py = cameras.py();
        let cams = items(cameras, "cameras", "Camera")?;
        let poses = items(cams_from_rig, "cams_from_rig", "poses")?;
        if cams.is_empty() {
            return Err(option_error(
                py,
                "cameras",
                "cameras: a rig needs at least one camera".into(),
            ));
        }
        if cams.len() != poses.len() {
            return Err(option_error(
                py,
                "cams_from_rig",
                format!(
                    "cams_from_rig: {} poses for {} cameras (give one cam_from_rig pose per \
                     camera)",
                    poses.len(),
                    cams.len()
                ),
            ));
        }
        let mut parts = Vec::with_capacity(cams.len());
        for (k, (c, p)) in cams.iter().zip(&poses).enumerate() {
            let camera = c.cast::<PyCamera>().map_err(|_| {
                option_error(
                    py,
                    "cameras",
                    format!(
                        "cameras[{k}]: expected a Camera, got {}",
                        c.get_type()
                            .name()
                            .map_or_else(|_| "?".into(), |s| s.to_string())
                    ),
                )
            })?;
            let pose = pose_arg_as(p, "cams_from_rig", &format!("cams_from_rig[{k}]"))?;
            let finite = pose.translation.vector.iter().all(|v| v.is_finite())
                && pose.rotation.coords.iter().all(|v| v.is_finite());
            if !finite {
                return Err(option_error(
                    py,
                    "cams_from_rig",
                    format!("cams_from_rig[{k}]: the pose is not finite"),
                ));
            }
            parts.push((camera.get().inner, pose));
        }
        let inner = Rig::new(parts).map_err(|e| pnp_error(py, &e))?;
        Ok(PyRig { inner })
    }
}

#[pymethods]
impl PyRig {
    #[new]
    #[pyo3(signature = (cameras, cams_from_rig))]
    fn new(cameras: &Bound<'_, PyAny>, cams_from_rig: &Bound<'_, PyAny>) -> PyResult<Self> {
        PyRig::build(cameras, cams_from_rig)
    }

    /// The cameras, in index order (a new list on each access).
    #[getter]
    fn cameras(&self) -> Vec<PyCamera> {
        self.inner
            .cameras()
            .iter()
            .map(|c| PyCamera { inner: *c })
            .collect()
    }

    /// Each camera's pose in the rig, ``[R_k | t_k]`` with ``x_cam = R_k @ x_rig + t_k``,
    /// shape (K, 3, 4).
    #[getter]
    fn cams_from_rig<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray3<f64>> {
        let k = self.inner.cameras().len();
        let out = PyArray3::<f64>::zeros(py, [k, 3, 4], false);
        {
            let mut a = out.readwrite();
            let mut a = a.as_array_mut();
            for (j, p) in self.inner.cam_from_rig().iter().enumerate() {
                let r = p.rotation.to_rotation_matrix().into_inner();
                for row in 0..3 {
                    for col in 0..3 {
                        a[[j, row, col]] = r[(row, col)];
                    }
                    a[[j, row, 3]] = p.translation.vector[row];
                }
            }
        }
        out
    }

    /// Each camera's centre in the rig frame, ``-R_k^T t_k``, shape (K, 3).
    #[getter]
    fn centres<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        let k = self.inner.cameras().len();
        let c: Vec<f64> = (0..k)
            .flat_map(|j| {
                let c = self.inner.centre(j);
                [c.x, c.y, c.z]
            })
            .collect();
        array2(py, k, 3, &c).into_any()
    }

    fn __len__(&self) -> usize {
        self.inner.cameras().len()
    }

    fn __repr__(&self) -> String {
        let cams: Vec<String> = self
            .inner
            .cameras()
            .iter()
            .enumerate()
            .map(|(k, c)| {
                let p = self.inner.centre(k);
                format!(
                    "{} at ({}, {}, {})",
                    c.model().name(),
                    short(p.x),
                    short(p.y),
                    short(p.z)
                )
            })
            .collect();
        let n = cams.len();
        format!(
            "Rig({n} camera{}: {})",
            if n == 1 { "" } else { "s" },
            cams.join(", ")
        )
    }

    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        other
            .cast::<PyRig>()
            .is_ok_and(|o| o.get().inner == self.inner)
    }

    /// Pickling: the cameras and each pose's quaternion (w, x, y, z) and translation, exactly.
    fn __reduce__<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        let rebuild = py.import("eopnp._eopnp")?.getattr("_rig_from_state")?;
        let poses: Vec<(Vec<f64>, Vec<f64>)> = self
            .inner
            .cam_from_rig()
            .iter()
            .map(|p| {
                let q = p.rotation.quaternion();
                (
                    vec![q.w, q.i, q.j, q.k],
                    p.translation.vector.as_slice().to_vec(),
                )
            })
            .collect();
        let state = (self.cameras(), poses).into_pyobject(py)?;
        Ok((rebuild, PyTuple::new(py, [state])?))
    }
}

/// A centre coordinate in `Rig`'s repr: up to six significant digits, no trailing zeros.
fn short(x: f64) -> String {
    let s = format!("{:.6}", x + 0.0);
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".into()
    } else {
        s.into()
    }
}

/// `Rig.__reduce__`'s state: the cameras, each pose's quaternion (w, x, y, z) and translation.
type RigState<'py> = (Vec<Bound<'py, PyCamera>>, Vec<(Vec<f64>, Vec<f64>)>);

/// Rebuilds a `Rig` from `__reduce__`'s state (private; for pickle).
#[pyfunction]
pub(crate) fn _rig_from_state<'py>(py: Python<'py>, state: RigState<'py>) -> PyResult<PyRig> {
    let (cameras, poses) = state;
    if cameras.len() != poses.len() {
        return Err(pyo3::exceptions::PyValueError::new_err("bad Rig state"));
    }
    let mut parts = Vec::with_capacity(cameras.len());
    for (c, (q, t)) in cameras.into_iter().zip(poses) {
        let ([w, i, j, k], [x, y, z]) = (q.as_slice(), t.as_slice()) else {
            return Err(pyo3::exceptions::PyValueError::new_err("bad Rig state"));
        };
        let pose = Isometry3::from_parts(
            Translation3::new(*x, *y, *z),
            UnitQuaternion::new_unchecked(Quaternion::new(*w, *i, *j, *k)),
        );
        parts.push((c.get().inner, pose));
    }
    let inner = Rig::new(parts).map_err(|e| pnp_error(py, &e))?;
    Ok(PyRig { inner })
}

/// The rig of a one-problem call: `rig=`, or a new `Rig` of `cams_from_rig` and `cameras`
/// (pycolmap's form); exactly one of the two forms.
pub(crate) fn rig_arg<'py>(
    py: Python<'py>,
    function: &str,
    cams_from_rig: Option<&Bound<'py, PyAny>>,
    cameras: Option<&Bound<'py, PyAny>>,
    rig: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyRig>> {
    fn given<'a, 'py>(x: Option<&'a Bound<'py, PyAny>>) -> Option<&'a Bound<'py, PyAny>> {
        x.filter(|x| !x.is_none())
    }
    match (given(cams_from_rig), given(cameras), given(rig)) {
        (None, None, Some(r)) => r.cast::<PyRig>().cloned().map_err(|_| {
            option_error(
                py,
                "rig",
                format!(
                    "{function}: rig must be a Rig, got {}",
                    r.get_type()
                        .name()
                        .map_or_else(|_| "?".into(), |s| s.to_string())
                ),
            )
        }),
        (Some(p), Some(c), None) => Bound::new(py, PyRig::build(c, p)?),
        (p, c, r) => {
            let what = if r.is_some() {
                "not both"
            } else if p.is_none() && c.is_none() {
                "got neither"
            } else if p.is_none() {
                "got cameras without cams_from_rig"
            } else {
                "got cams_from_rig without cameras"
            };
            Err(option_error(
                py,
                "rig",
                format!(
                    "{function} needs the rig: cams_from_rig and cameras (as pycolmap takes \
                     them), or rig= (a Rig); {what}"
                ),
            ))
        }
    }
}

/// A rig problem's error: the library's, or an unknown camera found by `check` (whose index
/// may be negative, which the library's `u32` indices cannot hold).
pub(crate) enum RigError {
    Pnp(PnpError),
    UnknownCamera { index: usize, camera: i64 },
}

impl From<PnpError> for RigError {
    fn from(e: PnpError) -> Self {
        RigError::Pnp(e)
    }
}

/// The exception of a rig problem's error.
pub(crate) fn rig_error(py: Python<'_>, e: &RigError) -> PyErr {
    match e {
        RigError::Pnp(e) => pnp_error(py, e),
        RigError::UnknownCamera { index, camera } => unknown_camera(py, *index, *camera),
    }
}

/// A rig problem as copied from its arrays: world points, pixels, camera indices (as given)
/// and weights, and the rig.
#[derive(Clone, Copy)]
pub(crate) struct RigObs<'a> {
    pub(crate) world: &'a [Point3<f64>],
    pub(crate) image: &'a [Point2<f64>],
    pub(crate) cameras: &'a [i64],
    pub(crate) weights: Option<&'a [f64]>,
    pub(crate) rig: &'a Rig,
    /// The known vertical, in the rig's frame (`gravity=`).
    pub(crate) gravity: Option<eopnp::Gravity>,
}

impl RigObs<'_> {
    /// The checks of the library's rig problems, in its order (lengths, camera indices'
    /// count, weights' count, then for each correspondence in turn: a non-finite world point,
    /// pixel or weight, a negative weight, an unknown camera); the camera indices as the
    /// library takes them.
    fn check(&self) -> Result<Vec<u32>, RigError> {
        let n = self.world.len();
        if self.image.len() != n {
            return Err(PnpError::LengthMismatch {
                world: n,
                image: self.image.len(),
            }
            .into());
        }
        if self.cameras.len() != n {
            return Err(PnpError::CameraIndicesLength {
                indices: self.cameras.len(),
                points: n,
            }
            .into());
        }
        if let Some(w) = self.weights {
            if w.len() != n {
                return Err(PnpError::WeightsLength {
                    weights: w.len(),
                    points: n,
                }
                .into());
            }
        }
        let k = self.rig.cameras().len();
        let mut out = Vec::with_capacity(n);
        for i in 0..n {
            let input = if !self.world[i].coords.iter().all(|v| v.is_finite()) {
                Some(InputKind::World)
            } else if !(self.image[i].x.is_finite() && self.image[i].y.is_finite()) {
                Some(InputKind::Image)
            } else if self.weights.is_some_and(|w| !w[i].is_finite()) {
                Some(InputKind::Weight)
            } else {
                None
            };
            if let Some(input) = input {
                return Err(PnpError::NonFinite { index: i, input }.into());
            }
            if self.weights.is_some_and(|w| w[i] < 0.0) {
                return Err(PnpError::InvalidWeight { index: i }.into());
            }
            let c = self.cameras[i];
            match u32::try_from(c) {
                Ok(c) if (c as usize) < k => out.push(c),
                _ => {
                    return Err(RigError::UnknownCamera {
                        index: i,
                        camera: c,
                    })
                }
            }
        }
        Ok(out)
    }

    /// The library's problem on `cams` (`check`'s indices).
    fn problem<'b>(&'b self, cams: &'b [u32]) -> Problem<'b> {
        problem_with(
            Problem::rig(self.world, self.image, cams, self.rig),
            self.weights,
            self.gravity,
        )
    }

    /// `solve_generalized` on this problem.
    pub(crate) fn solve(&self, solver: &Solver) -> Result<Solution, RigError> {
        let cams = self.check()?;
        Ok(solver.solve(&self.problem(&cams))?)
    }

    /// `refine_generalized` on this problem.
    pub(crate) fn refine(
        &self,
        solver: &Solver,
        initial: &Isometry3<f64>,
    ) -> Result<Solution, RigError> {
        let cams = self.check()?;
        Ok(solver.refine(&self.problem(&cams), initial)?)
    }

    /// `solve_generalized_ransac` on this problem: the library's result and the info's
    /// `rmse_px`.
    pub(crate) fn estimate(
        &self,
        ransac: &Ransac,
        solver: &Solver,
    ) -> Result<(RansacSolution, f64), RigError> {
        let cams = self.check()?;
        let r = ransac.estimate(solver, &self.problem(&cams))?;
        let px = self.rmse_px(&r.solution, &r.inliers, &cams);
        Ok((r, px))
    }

    /// RMS pixel reprojection error over the inliers, each through its camera:
    /// `x_cam = R_k (R X + t) + t_k`.
    fn rmse_px(&self, sol: &Solution, inliers: &[bool], cams: &[u32]) -> f64 {
        let (mut s, mut n) = (0.0, 0usize);
        for i in (0..self.world.len()).filter(|&i| inliers[i]) {
            let k = cams[i] as usize;
            let x_rig = sol.rotation * self.world[i].coords + sol.translation;
            let p = self.rig.cam_from_rig()[k] * Point3::from(x_rig);
            let camera: &Camera = &self.rig.cameras()[k];
            let px = camera.project(Point2::new(p.x / p.z, p.y / p.z));
            s += (px - self.image[i]).norm_squared();
            n += 1;
        }
        if n == 0 {
            f64::NAN
        } else {
            (s / n as f64).sqrt()
        }
    }
}

/// A one-problem call's arrays, copied (with the GIL held).
struct Copied {
    world: Vec<Point3<f64>>,
    image: Vec<Point2<f64>>,
    cameras: Vec<i64>,
    weights: Option<Vec<f64>>,
}

impl Copied {
    #[allow(non_snake_case)]
    fn new(
        points2D: &Bound<'_, PyAny>,
        points3D: &Bound<'_, PyAny>,
        camera_idxs: &Bound<'_, PyAny>,
        weights: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        Ok(Copied {
            image: points2(points2D, "points2D")?,
            world: points3(points3D, "points3D")?,
            cameras: indices(camera_idxs, "camera_idxs")?,
            weights: weights
                .filter(|w| !w.is_none())
                .map(|w| vector(w, "weights", false))
                .transpose()?,
        })
    }

    fn obs<'a>(&'a self, rig: &'a Rig, gravity: Option<eopnp::Gravity>) -> RigObs<'a> {
        RigObs {
            world: &self.world,
            image: &self.image,
            cameras: &self.cameras,
            weights: self.weights.as_deref(),
            rig,
            gravity,
        }
    }
}

/// The pose of a multi-camera rig from pixels observed by its cameras (the generalized PnP
/// problem): each correspondence ``i`` is the world point ``points3D[i]`` observed at pixel
/// ``points2D[i]`` of camera ``camera_idxs[i]``. Generalized EOPnP, then by default
/// Levenberg-Marquardt on every pixel's reprojection error through its own camera (lens
/// distortion included): the maximum-likelihood pose. When every point is in one camera, that
/// camera's central problem (``solve`` with that camera), composed with its pose in the rig.
///
/// The arguments follow pycolmap's ``estimate_and_refine_generalized_absolute_pose(points2D,
/// points3D, camera_idxs, cams_from_rig, cameras)``: pixels first, unlike ``solve(world,
/// image)``.
///
/// Args:
///     points2D: the observed (distorted) pixels, shape (N, 2), N >= 4.
///     points3D: their world points, shape (N, 3).
///     camera_idxs: the camera of each correspondence, integers of shape (N,), indices into
///         ``cameras``.
///     cams_from_rig: each camera's pose in the rig, ``x_cam = R_k @ x_rig + t_k`` (camera
///         from rig, as pycolmap's ``cams_from_rig``), one per camera, in any form ``Rig``
///         takes.
///     cameras: the rig's cameras (``Camera``), indexed by ``camera_idxs``.
///     rig: a ``Rig`` instead of ``cams_from_rig`` and ``cameras`` (built once, e.g. for many
///         frames of one rig): give either ``cams_from_rig`` and ``cameras``, or ``rig``.
///     weights: optional non-negative weight per correspondence, shape (N,), as ``solve``.
///     options: a ``SolverOptions`` (or a dict of its fields), as ``solve``: ``loss`` scale
///         and ``covariance`` noise in pixels.
///     **keywords: the options of ``SolverOptions`` as keyword arguments instead, as
///         ``solve``.
///
/// Returns:
///     Solution: the rig's pose in the world, ``x_rig = R @ X + t`` (rig_from_world, as
///     pycolmap's ``rig_from_world``); camera ``k`` is at ``x_cam = R_k @ (R @ X + t) + t_k``.
///     ``cost`` is the pixel cost over every camera; ``reprojection_rmse`` is the RMS pixel
///     error divided by the largest focal length of the rig's cameras (that camera's own
///     normalised RMS when every point is in one camera); ``covariance`` is of the rig's pose.
///
/// Raises:
///     InvalidInputError: as ``solve``, and camera indices not one per point (kind
///         ``"CameraIndicesLength"``) or naming a camera the rig does not have (kind
///         ``"UnknownCamera"``, with the correspondence's ``index`` and its ``camera``).
///     InputTypeError: arrays that are not real numbers, camera indices that are not
///         integers.
///     DegenerateError, NoSolutionError: as ``solve``.
///     InvalidOptionError: an option out of range; a rig given in neither or both forms, or
///         not as ``Rig`` takes it.
///     TypeError: as ``solve``.
#[pyfunction]
#[pyo3(signature = (points2D, points3D, camera_idxs, cams_from_rig = None, cameras = None, *,
    rig = None, weights = None, gravity = None, options = None, **keywords))]
#[allow(non_snake_case, clippy::too_many_arguments)]
pub(crate) fn solve_generalized(
    py: Python<'_>,
    points2D: &Bound<'_, PyAny>,
    points3D: &Bound<'_, PyAny>,
    camera_idxs: &Bound<'_, PyAny>,
    cams_from_rig: Option<&Bound<'_, PyAny>>,
    cameras: Option<&Bound<'_, PyAny>>,
    rig: Option<&Bound<'_, PyAny>>,
    weights: Option<&Bound<'_, PyAny>>,
    gravity: Option<&Bound<'_, PyGravity>>,
    options: Option<&Bound<'_, PyAny>>,
    keywords: Option<&Bound<'_, PyDict>>,
) -> PyResult<PySolution> {
    let solver = solver_arg(py, "solve_generalized", options, keywords, KEYWORDS)?;
    let rig = rig_arg(py, "solve_generalized", cams_from_rig, cameras, rig)?;
    let c = Copied::new(points2D, points3D, camera_idxs, weights)?;
    let rig = &rig.get().inner;
    let g = gravity_arg(gravity);
    let result = py.detach(|| c.obs(rig, g).solve(&solver));
    match result {
        Ok(s) => Ok(PySolution::from(&s)),
        Err(e) => Err(rig_error(py, &e)),
    }
}

/// Robust pose of a multi-camera rig from correspondences with outliers, by RANSAC:
/// generalized three-point poses (gP3P) of samples spread over the cameras, MSAC scoring of
/// each pixel's reprojection error through its own camera with an SPRT, adaptive iteration
/// count, generalized EOPnP local optimisation and final fit on the inliers; seeded. With
/// every point in one camera, that camera's ``solve_ransac``, composed with its pose in the
/// rig.
///
/// The arguments follow pycolmap's ``estimate_and_refine_generalized_absolute_pose(points2D,
/// points3D, camera_idxs, cams_from_rig, cameras)``: pixels first, unlike ``solve_ransac``.
///
/// Args:
///     points2D, points3D, camera_idxs, cams_from_rig, cameras, rig, weights: as
///         ``solve_generalized``.
///     ransac: a ``RansacOptions``, a dict of its fields, or None (defaults: 4 px threshold,
///         confidence 0.999, at most 10000 samples, seed 0); the threshold is on each pixel's
///         reprojection error through its camera.
///     options: a ``SolverOptions`` (or a dict of its fields), as ``solve_ransac``: the options
///         of the fits; ``loss`` scale and ``covariance`` noise in pixels.
///     **keywords: the options of ``SolverOptions`` as keyword arguments instead, as
///         ``solve``.
///
/// Returns:
///     (Solution, dict): the rig's pose fitted to the inliers (``x_rig = R @ X + t``,
///     rig_from_world), and ``info`` as ``solve_ransac``'s: ``inliers`` (bool array, shape
///     (N,)), ``num_inliers``, ``inlier_ratio``, ``iterations``, ``hypotheses``,
///     ``local_fits``, ``final_fits``, ``cost``, ``rmse``, ``rmse_px`` (RMS pixel
///     reprojection error over the inliers, each through its camera) and ``micros``.
///
/// Raises:
///     As ``solve_generalized``; InvalidOptionError also for a RANSAC option out of range;
///     NoConsensusError: no pose with enough inliers.
#[pyfunction]
#[pyo3(signature = (points2D, points3D, camera_idxs, cams_from_rig = None, cameras = None, *,
    rig = None, weights = None, gravity = None, ransac = None, options = None, **keywords))]
#[allow(non_snake_case, clippy::too_many_arguments)]
pub(crate) fn solve_generalized_ransac<'py>(
    py: Python<'py>,
    points2D: &Bound<'py, PyAny>,
    points3D: &Bound<'py, PyAny>,
    camera_idxs: &Bound<'py, PyAny>,
    cams_from_rig: Option<&Bound<'py, PyAny>>,
    cameras: Option<&Bound<'py, PyAny>>,
    rig: Option<&Bound<'py, PyAny>>,
    weights: Option<&Bound<'py, PyAny>>,
    gravity: Option<&Bound<'py, PyGravity>>,
    ransac: Option<&Bound<'py, PyAny>>,
    options: Option<&Bound<'py, PyAny>>,
    keywords: Option<&Bound<'py, PyDict>>,
) -> PyResult<(PySolution, Bound<'py, PyDict>)> {
    let solver = solver_arg(py, "solve_generalized_ransac", options, keywords, KEYWORDS)?;
    let ransac = ransac_arg(py, ransac)?;
    let rig = rig_arg(py, "solve_generalized_ransac", cams_from_rig, cameras, rig)?;
    let c = Copied::new(points2D, points3D, camera_idxs, weights)?;
    let rig = &rig.get().inner;
    let g = gravity_arg(gravity);
    let (r, px) = py
        .detach(|| c.obs(rig, g).estimate(&ransac, &solver))
        .map_err(|e| rig_error(py, &e))?;
    Ok((PySolution::from(&r.solution), ransac_info(py, &r, px)?))
}

/// Refines a prior pose of a multi-camera rig (tracking: the previous frame's pose) to the
/// maximum-likelihood pose of the basin it starts in: Levenberg-Marquardt on every pixel's
/// reprojection error through its own camera, from ``rig_from_world``, without the global
/// search (``refine`` for rigs; pycolmap's ``refine_generalized_absolute_pose``). From a start
/// in the basin of ``solve_generalized``'s pose, the same pose.
///
/// The arguments follow pycolmap's ``refine_generalized_absolute_pose(rig_from_world,
/// points2D, points3D, inlier_mask, camera_idxs, cams_from_rig, cameras)``, without
/// ``inlier_mask``: pass ``weights=inlier_mask.astype(float)`` (a point of weight 0 is
/// ignored exactly).
///
/// Args:
///     rig_from_world: the starting pose of the rig, ``x_rig = R @ X + t``: a ``Solution``
///         (e.g. the previous frame's), a ``(rotation, t)`` pair, a (3, 4) ``[R | t]`` or a
///         (4, 4) matrix, as ``refine``'s ``initial``.
///     points2D, points3D, camera_idxs, cams_from_rig, cameras, rig, weights: as
///         ``solve_generalized``.
///     options: a ``SolverOptions`` (or a dict of its fields), as ``refine``.
///     **keywords: ``loss``, ``covariance``, ``newton_iterations``, ``newton_step_tolerance``
///         and ``reprojection_iterations`` as keyword arguments instead, as ``refine``.
///
/// Returns:
///     Solution: the refined pose of the rig (``x_rig = R @ X + t``); ``converged`` says
///     whether the refinement reached a minimum, ``source`` is "initial".
///
/// Raises:
///     As ``solve_generalized``; InvalidOptionError (``option`` "rig_from_world") for a
///     starting pose that is not finite or not of the forms above.
#[pyfunction]
#[pyo3(signature = (rig_from_world, points2D, points3D, camera_idxs, cams_from_rig = None,
    cameras = None, *, rig = None, weights = None, gravity = None, options = None, **keywords))]
#[allow(non_snake_case, clippy::too_many_arguments)]
pub(crate) fn refine_generalized(
    py: Python<'_>,
    rig_from_world: &Bound<'_, PyAny>,
    points2D: &Bound<'_, PyAny>,
    points3D: &Bound<'_, PyAny>,
    camera_idxs: &Bound<'_, PyAny>,
    cams_from_rig: Option<&Bound<'_, PyAny>>,
    cameras: Option<&Bound<'_, PyAny>>,
    rig: Option<&Bound<'_, PyAny>>,
    weights: Option<&Bound<'_, PyAny>>,
    gravity: Option<&Bound<'_, PyGravity>>,
    options: Option<&Bound<'_, PyAny>>,
    keywords: Option<&Bound<'_, PyDict>>,
) -> PyResult<PySolution> {
    let solver = solver_arg(py, "refine_generalized", options, keywords, REFINE_KEYWORDS)?;
    let initial = pose_arg_as(rig_from_world, "rig_from_world", "rig_from_world")?;
    let finite = initial.translation.vector.iter().all(|v| v.is_finite())
        && initial.rotation.coords.iter().all(|v| v.is_finite());
    if !finite {
        return Err(option_error(
            py,
            "rig_from_world",
            "rig_from_world: the initial pose is not finite".into(),
        ));
    }
    let rig = rig_arg(py, "refine_generalized", cams_from_rig, cameras, rig)?;
    let c = Copied::new(points2D, points3D, camera_idxs, weights)?;
    let rig = &rig.get().inner;
    let g = gravity_arg(gravity);
    let result = py.detach(|| c.obs(rig, g).refine(&solver, &initial));
    match result {
        Ok(s) => Ok(PySolution::from(&s)),
        Err(e) => Err(rig_error(py, &e)),
    }
}
