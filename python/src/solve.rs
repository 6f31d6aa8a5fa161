//! `eopnp.solve`, `eopnp.solve_all` and `eopnp.refine`: one problem, normalised or pixels
//! through a camera. The arrays are copied into points with the GIL held; the solve runs with
//! the GIL released.

use eopnp::{Gravity, Problem};
use eopnp::{InputKind, PnpError};
use nalgebra::{Point2, Point3};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::camera::PyCamera;
use crate::convert::{points2, points3, vector};
use crate::errors::{option_error, pnp_error};
use crate::gravity::{gravity_arg, PyGravity};
use crate::options::{solver_arg, KEYWORDS, REFINE_KEYWORDS};
use crate::pose::pose_arg;
use crate::solution::PySolution;

/// The intrinsics estimated with the pose: an unknown focal length (``estimate_focal=``,
/// ``focal_range=``: `None` when not estimated, else the range in pixels, if given), the
/// principal point (``refine_principal_point=``) and the distortion (``refine_distortion=``).
#[derive(Clone, Copy, Default)]
pub(crate) struct IntrinsicsArg {
    pub(crate) focal: Option<Option<(f64, f64)>>,
    pub(crate) principal_point: bool,
    pub(crate) distortion: bool,
}

impl IntrinsicsArg {
    /// These intrinsics, the principal point and the distortion refined when asked for.
    pub(crate) fn refining(self, principal_point: bool, distortion: bool) -> Self {
        IntrinsicsArg {
            principal_point,
            distortion,
            ..self
        }
    }
}

/// The ``estimate_focal`` and ``focal_range`` arguments (a range alone implies the estimate);
/// a range that is not two numbers raises ``InvalidOptionError`` (``"unknown_focal"``, the
/// library's option for a range that is not ``0 < min < max``).
pub(crate) fn focal_arg(
    estimate: bool,
    range: Option<&Bound<'_, PyAny>>,
) -> PyResult<IntrinsicsArg> {
    let range = match range.filter(|r| !r.is_none()) {
        None => None,
        Some(r) => match r.extract::<Vec<f64>>().as_deref() {
            Ok(&[lo, hi]) => Some((lo, hi)),
            _ => {
                return Err(option_error(
                    r.py(),
                    "unknown_focal",
                    format!(
                        "focal_range must be (min_px, max_px), two numbers, got {}",
                        r.repr().map_or_else(|_| "?".into(), |s| s.to_string())
                    ),
                ))
            }
        },
    };
    Ok(IntrinsicsArg {
        focal: (estimate || range.is_some()).then_some(range),
        ..IntrinsicsArg::default()
    })
}

/// `p` with the intrinsics `arg` estimated.
pub(crate) fn with_intrinsics(p: Problem<'_>, arg: IntrinsicsArg) -> Problem<'_> {
    let mut p = match arg.focal {
        None => p,
        Some(None) => p.unknown_focal(),
        Some(Some((lo, hi))) => p.unknown_focal_within(lo, hi),
    };
    if arg.principal_point {
        p = p.refine_principal_point();
    }
    if arg.distortion {
        p = p.refine_distortion();
    }
    p
}

/// `p` with its optional weights and known vertical.
pub(crate) fn problem_with<'a>(
    p: Problem<'a>,
    weights: Option<&'a [f64]>,
    gravity: Option<Gravity>,
) -> Problem<'a> {
    let p = match weights {
        Some(w) => p.weights(w),
        None => p,
    };
    match gravity {
        Some(g) => p.gravity(g),
        None => p,
    }
}

/// NaN or infinite input as the library reports it on normalised input (lengths first, then
/// the first offending index, world before image before weight). The pixel APIs of the library
/// would skip a NaN pixel as one that cannot be undistorted; the package rejects it instead.
pub(crate) fn check_finite(
    world: &[Point3<f64>],
    image: &[Point2<f64>],
    weights: Option<&[f64]>,
) -> Result<(), PnpError> {
    if world.len() != image.len() {
        return Err(PnpError::LengthMismatch {
            world: world.len(),
            image: image.len(),
        });
    }
    if let Some(w) = weights {
        if w.len() != world.len() {
            return Err(PnpError::WeightsLength {
                weights: w.len(),
                points: world.len(),
            });
        }
    }
    for (index, (x, p)) in world.iter().zip(image).enumerate() {
        let input = if !x.coords.iter().all(|v| v.is_finite()) {
            InputKind::World
        } else if !(p.x.is_finite() && p.y.is_finite()) {
            InputKind::Image
        } else if weights.is_some_and(|w| !w[index].is_finite()) {
            InputKind::Weight
        } else {
            continue;
        };
        return Err(PnpError::NonFinite { index, input });
    }
    Ok(())
}

/// The camera pose from 2D-3D correspondences.
///
/// Args:
///     world: world points, shape (N, 3), N >= 4.
///     image: their image points, shape (N, 2): normalised coordinates (x/z, y/z), or pixels
///         when ``camera`` is given.
///     weights: optional non-negative weight per point, shape (N,); a point of weight 0 is
///         ignored (exactly as if dropped), weights scale the squared residuals.
///     camera: a ``Camera``: ``image`` holds observed (distorted) pixels. They are undistorted
///         and, in the default mode, the refinement minimises the pixel reprojection error
///         through the camera model, distortion included. Pixels that cannot be undistorted
///         are left out and counted in ``Solution.skipped``.
///     gravity: a ``Gravity``: the known vertical; the pose is the maximum a posteriori one
///         with it as a prior (``GravityMismatchError`` if the images contradict it).
///     estimate_focal: the camera's focal length is unknown (``camera`` required; its focal
///         length is the starting guess): estimated with the pose, within a tenth and ten times
///         the guess, returned in ``Solution.camera``
///         (``Solution.focal``).
///     focal_range: ``(min_px, max_px)``, the range of the unknown focal length (implies
///         ``estimate_focal``).
///     refine_principal_point: the principal point is refined with the pose (``camera``
///         required; its principal point the starting guess), returned in ``Solution.camera``.
///     refine_distortion: the camera's distortion parameters are refined with the pose
///         (``camera`` required; its parameters the starting guess), returned in
///         ``Solution.camera``.
///     options: a ``SolverOptions`` (or a dict of its fields): refinement, planar branch,
///         iteration limits, robust ``loss``, ``covariance``. None: the defaults.
///     **keywords: the options of ``SolverOptions`` as keyword arguments instead
///         (``refinement="algebraic"``, ``loss=("cauchy", 2.0)``, ``covariance=1.0``, ...),
///         not together with ``options``. A ``loss`` scale or ``covariance`` noise is in
///         pixels with ``camera``, in normalised units otherwise.
///
/// Returns:
///     Solution: the pose (``R``, ``t``, ``rvec``, ``q``), its cost and diagnostics.
///
/// Raises:
///     InvalidInputError: wrong shapes, too few points, mismatched lengths, NaN or infinite
///         values, negative weights (``InputTypeError`` for non-numeric arrays).
///     DegenerateError: coincident or collinear world points, coincident image points.
///     NoSolutionError: numerical failure (not observed on valid input).
///     InvalidOptionError: an option out of its range.
///     TypeError: an unknown keyword, or both ``options`` and option keywords.
#[pyfunction]
#[pyo3(signature = (world, image, weights = None, *, camera = None, gravity = None,
    estimate_focal = false, focal_range = None,
    refine_principal_point = false, refine_distortion = false, options = None, **keywords))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn solve(
    py: Python<'_>,
    world: &Bound<'_, PyAny>,
    image: &Bound<'_, PyAny>,
    weights: Option<&Bound<'_, PyAny>>,
    camera: Option<&Bound<'_, PyCamera>>,
    gravity: Option<&Bound<'_, PyGravity>>,
    estimate_focal: bool,
    focal_range: Option<&Bound<'_, PyAny>>,
    refine_principal_point: bool,
    refine_distortion: bool,
    options: Option<&Bound<'_, PyAny>>,
    keywords: Option<&Bound<'_, PyDict>>,
) -> PyResult<PySolution> {
    let solver = solver_arg(py, "solve", options, keywords, KEYWORDS)?;
    let w = points3(world, "world")?;
    let img = points2(image, "image")?;
    let wts = weights.map(|w| vector(w, "weights", false)).transpose()?;
    let g = gravity_arg(gravity);
    let focal =
        focal_arg(estimate_focal, focal_range)?.refining(refine_principal_point, refine_distortion);
    let result = match camera {
        None => py.detach(|| {
            let p = problem_with(Problem::normalised(&w, &img), wts.as_deref(), g);
            solver.solve(&with_intrinsics(p, focal))
        }),
        Some(cam) => {
            let cam = &cam.get().inner;
            check_finite(&w, &img, wts.as_deref()).map_err(|e| pnp_error(py, &e))?;
            py.detach(|| {
                let p = problem_with(Problem::pixels(&w, &img, cam), wts.as_deref(), g);
                solver.solve(&with_intrinsics(p, focal))
            })
        }
    };
    match result {
        Ok(s) => Ok(PySolution::from(&s)),
        Err(e) => Err(pnp_error(py, &e)),
    }
}

/// Every distinct local minimum of the cost, best first: poses with most points in front of
/// the camera first, then by increasing reprojection error (at most 32). For N <= 6 and for
/// planar scenes several poses can explain the data about equally well; this lists them.
///
/// ``world`` (N, 3) and ``image`` (N, 2) normalised, and ``options`` or the option keywords,
/// as ``solve`` (no weights or camera: undistort pixels first with ``Camera.undistort``);
/// ``covariance`` gives each pose its own, ``loss`` is in normalised units.
///
/// Returns:
///     list[Solution]: at least one.
///
/// Raises:
///     As ``solve``.
#[pyfunction]
#[pyo3(signature = (world, image, *, options = None, **keywords))]
pub(crate) fn solve_all<'py>(
    py: Python<'py>,
    world: &Bound<'py, PyAny>,
    image: &Bound<'py, PyAny>,
    options: Option<&Bound<'py, PyAny>>,
    keywords: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyList>> {
    let solver = solver_arg(py, "solve_all", options, keywords, KEYWORDS)?;
    let w = points3(world, "world")?;
    let img = points2(image, "image")?;
    let all = py
        .detach(|| solver.solve_all(&Problem::normalised(&w, &img)))
        .map_err(|e| pnp_error(py, &e))?;
    PyList::new(py, all.iter().map(PySolution::from))
}

/// Seconds per solve of `repeats` solves of the same problem in Rust, with the GIL released
/// and no conversion: the benchmark's reference for the Python call overhead (private).
#[pyfunction]
#[pyo3(signature = (world, image, repeats, *, options = None))]
pub(crate) fn _time_solve(
    py: Python<'_>,
    world: &Bound<'_, PyAny>,
    image: &Bound<'_, PyAny>,
    repeats: u32,
    options: Option<&Bound<'_, PyAny>>,
) -> PyResult<f64> {
    let solver = solver_arg(py, "_time_solve", options, None, KEYWORDS)?;
    let w = points3(world, "world")?;
    let img = points2(image, "image")?;
    let r = py.detach(|| {
        let start = std::time::Instant::now();
        let mut last = None;
        for _ in 0..repeats.max(1) {
            last = Some(solver.solve(&Problem::normalised(
                std::hint::black_box(&w),
                std::hint::black_box(&img),
            )));
        }
        (
            start.elapsed().as_secs_f64() / f64::from(repeats.max(1)),
            last,
        )
    });
    match r.1 {
        Some(Err(e)) => Err(pnp_error(py, &e)),
        _ => Ok(r.0),
    }
}

/// Refines a prior pose (tracking: the previous frame's pose) to the maximum-likelihood pose
/// of the basin it starts in: Levenberg-Marquardt on the reprojection error from
/// ``initial``, without EOPnP's global search (OpenCV's ``solvePnPRefineLM``, PoseLib's
/// ``refine_absolute_pose``). From a start in the basin of ``solve``'s pose, the same pose.
///
/// Args:
///     world: world points, shape (N, 3), N >= 4.
///     image: their image points, shape (N, 2): normalised, or pixels with ``camera``.
///     initial: the starting pose (world to camera, ``x_cam = R @ X + t``): a ``Solution``
///         (e.g. the previous frame's), a pair ``(rotation, t)`` with ``t`` of shape (3,) and
///         the rotation as a (3, 3) matrix ``R``, a (3,) rotation vector (OpenCV's ``rvec``)
///         or a (4,) quaternion (w, x, y, z; COLMAP's order, normalised here), or a (3, 4)
///         matrix ``[R | t]`` (``Solution.Rt``) or a (4, 4) homogeneous matrix. A matrix ``R``
///         must be a rotation to 1e-6 (``R^T R = I``, ``det R > 0``).
///     weights: optional non-negative weight per point, shape (N,), as ``solve``.
///     camera: a ``Camera``: ``image`` holds observed pixels; the refinement minimises the
///         pixel residuals through the camera model, as ``solve``.
///     gravity: a ``Gravity``: the known vertical, a prior of the refinement, as ``solve``.
///     estimate_focal: the camera's focal length is unknown (``camera`` required; its focal
///         length is the starting guess): refined with the pose from ``initial`` and the
///         guess, within a tenth and ten times the guess, returned in ``Solution.camera``
///         (``Solution.focal``).
///     focal_range: ``(min_px, max_px)``, the range of the unknown focal length (implies
///         ``estimate_focal``).
///     refine_principal_point: the principal point is refined with the pose (``camera``
///         required; its principal point the starting guess), returned in ``Solution.camera``.
///     refine_distortion: the camera's distortion parameters are refined with the pose
///         (``camera`` required; its parameters the starting guess), returned in
///         ``Solution.camera``.
///     options: a ``SolverOptions`` (or a dict of its fields), as ``solve``. Its ``planar``
///         and ``exhaustive`` (of the global search) have no effect here, and ``refine``
///         always ends with the Levenberg-Marquardt refinement: ``refinement="algebraic"``
///         only iterates the Newton start on to ``newton_step_tolerance`` (otherwise at least
///         1e-6).
///     **keywords: ``loss``, ``covariance``, ``newton_iterations``, ``newton_step_tolerance``
///         and ``reprojection_iterations`` as keyword arguments instead, as ``solve``.
///
/// Returns:
///     Solution: the refined pose; ``converged`` says whether the refinement reached a
///     minimum, ``source`` is "initial".
///
/// Raises:
///     As ``solve``; InvalidOptionError (``option`` "initial") for an initial pose that is
///     not finite (the library's message) or not of the forms above.
#[pyfunction]
#[pyo3(signature = (world, image, initial, *, weights = None, camera = None, gravity = None,
    estimate_focal = false, focal_range = None,
    refine_principal_point = false, refine_distortion = false, options = None, **keywords))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn refine(
    world: &Bound<'_, PyAny>,
    image: &Bound<'_, PyAny>,
    initial: &Bound<'_, PyAny>,
    weights: Option<&Bound<'_, PyAny>>,
    camera: Option<&Bound<'_, PyCamera>>,
    gravity: Option<&Bound<'_, PyGravity>>,
    estimate_focal: bool,
    focal_range: Option<&Bound<'_, PyAny>>,
    refine_principal_point: bool,
    refine_distortion: bool,
    options: Option<&Bound<'_, PyAny>>,
    keywords: Option<&Bound<'_, PyDict>>,
) -> PyResult<PySolution> {
    let py = world.py();
    let focal =
        focal_arg(estimate_focal, focal_range)?.refining(refine_principal_point, refine_distortion);
    let solver = solver_arg(py, "refine", options, keywords, REFINE_KEYWORDS)?;
    let initial = pose_arg(initial, "initial")?;
    let w = points3(world, "world")?;
    let img = points2(image, "image")?;
    let wts = weights.map(|w| vector(w, "weights", false)).transpose()?;
    let g = gravity_arg(gravity);
    let result = match camera {
        None => py.detach(|| {
            let p = problem_with(Problem::normalised(&w, &img), wts.as_deref(), g);
            solver.refine(&with_intrinsics(p, focal), &initial)
        }),
        Some(cam) => {
            let cam = &cam.get().inner;
            check_finite(&w, &img, wts.as_deref()).map_err(|e| pnp_error(py, &e))?;
            py.detach(|| {
                let p = problem_with(Problem::pixels(&w, &img, cam), wts.as_deref(), g);
                solver.refine(&with_intrinsics(p, focal), &initial)
            })
        }
    };
    match result {
        Ok(s) => Ok(PySolution::from(&s)),
        Err(e) => Err(pnp_error(py, &e)),
    }
}
