//! `eopnp.RansacOptions` and `eopnp.solve_ransac`: robust estimation (P3P samples, MSAC
//! scoring with an SPRT, EOPnP local optimisation and final fit, seeded).

use eopnp::camera::Camera;
use eopnp::ransac::{Ransac, RansacSolution};
use eopnp::Problem;
use nalgebra::{Point2, Point3};
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use crate::camera::PyCamera;
use crate::convert::{points2, points3, vector};
use crate::errors::{option_error, pnp_error};
use crate::gravity::{gravity_arg, PyGravity};
use crate::options::{solver_arg, KEYWORDS};
use crate::solution::{estimated_focal, PySolution};
use crate::solve::{check_finite, focal_arg as unknown_focal_arg, problem_with, with_intrinsics};

/// RANSAC options (the Rust ``eopnp::ransac::Ransac``); every argument is also a settable
/// attribute. Out-of-range values raise ``InvalidOptionError`` when used.
///
/// Args:
///     threshold_px: inlier threshold on the pixel reprojection error (default 4.0).
///     confidence: probability of drawing at least one all-inlier sample, for the adaptive
///         iteration count (default 0.999).
///     max_iterations: hard bound on the samples drawn (default 10000).
///     min_iterations: samples always drawn (default 20).
///     seed: seed of the sampling generator (default 0): results are reproducible.
///     local_optimisation: refit every new best hypothesis by EOPnP (default True).
///     final_threshold_factor: the final inlier classification uses threshold_px times this
///         (default 2.0; 1.0 keeps the scoring threshold).
#[pyclass(module = "eopnp", name = "RansacOptions")]
#[derive(Clone, Debug)]
pub(crate) struct PyRansacOptions {
    #[pyo3(get, set)]
    threshold_px: f64,
    #[pyo3(get, set)]
    confidence: f64,
    #[pyo3(get, set)]
    max_iterations: i64,
    #[pyo3(get, set)]
    min_iterations: i64,
    #[pyo3(get, set)]
    seed: u64,
    #[pyo3(get, set)]
    local_optimisation: bool,
    #[pyo3(get, set)]
    final_threshold_factor: f64,
}

impl Default for PyRansacOptions {
    fn default() -> Self {
        let d = Ransac::default();
        PyRansacOptions {
            threshold_px: d.threshold_px,
            confidence: d.confidence,
            max_iterations: i64::from(d.max_iterations),
            min_iterations: i64::from(d.min_iterations),
            seed: d.seed,
            local_optimisation: d.local_optimisation,
            final_threshold_factor: d.final_threshold_factor,
        }
    }
}

impl PyRansacOptions {
    fn ransac(&self, py: Python<'_>) -> PyResult<Ransac> {
        let count = |v: i64, name: &str| {
            u32::try_from(v).map_err(|_| {
                option_error(
                    py,
                    name,
                    format!(
                        "RANSAC option `{name}` is out of range: it must be an integer in \
                         [0, {}], got {v}",
                        u32::MAX
                    ),
                )
            })
        };
        Ok(Ransac::default()
            .threshold_px(self.threshold_px)
            .confidence(self.confidence)
            .max_iterations(count(self.max_iterations, "max_iterations")?)
            .min_iterations(count(self.min_iterations, "min_iterations")?)
            .seed(self.seed)
            .local_optimisation(self.local_optimisation)
            .final_threshold_factor(self.final_threshold_factor))
    }
}

#[pymethods]
impl PyRansacOptions {
    #[new]
    #[pyo3(signature = (*, threshold_px = None, confidence = None, max_iterations = None,
        min_iterations = None, seed = None, local_optimisation = None,
        final_threshold_factor = None))]
    fn new(
        threshold_px: Option<f64>,
        confidence: Option<f64>,
        max_iterations: Option<i64>,
        min_iterations: Option<i64>,
        seed: Option<u64>,
        local_optimisation: Option<bool>,
        final_threshold_factor: Option<f64>,
    ) -> Self {
        let d = PyRansacOptions::default();
        PyRansacOptions {
            threshold_px: threshold_px.unwrap_or(d.threshold_px),
            confidence: confidence.unwrap_or(d.confidence),
            max_iterations: max_iterations.unwrap_or(d.max_iterations),
            min_iterations: min_iterations.unwrap_or(d.min_iterations),
            seed: seed.unwrap_or(d.seed),
            local_optimisation: local_optimisation.unwrap_or(d.local_optimisation),
            final_threshold_factor: final_threshold_factor.unwrap_or(d.final_threshold_factor),
        }
    }

    /// The options as a dict (``RansacOptions(**d)`` gives them back).
    fn as_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        d.set_item("threshold_px", self.threshold_px)?;
        d.set_item("confidence", self.confidence)?;
        d.set_item("max_iterations", self.max_iterations)?;
        d.set_item("min_iterations", self.min_iterations)?;
        d.set_item("seed", self.seed)?;
        d.set_item("local_optimisation", self.local_optimisation)?;
        d.set_item("final_threshold_factor", self.final_threshold_factor)?;
        Ok(d)
    }

    fn __repr__(&self) -> String {
        format!(
            "RansacOptions(threshold_px={:?}, confidence={:?}, max_iterations={}, \
             min_iterations={}, seed={}, local_optimisation={}, final_threshold_factor={:?})",
            self.threshold_px,
            self.confidence,
            self.max_iterations,
            self.min_iterations,
            self.seed,
            if self.local_optimisation {
                "True"
            } else {
                "False"
            },
            self.final_threshold_factor
        )
    }

    fn __eq__(&self, other: &Bound<'_, PyAny>) -> PyResult<bool> {
        let Ok(o) = other.cast::<PyRansacOptions>() else {
            return Ok(false);
        };
        let o = o.borrow();
        Ok(self.threshold_px == o.threshold_px
            && self.confidence == o.confidence
            && self.max_iterations == o.max_iterations
            && self.min_iterations == o.min_iterations
            && self.seed == o.seed
            && self.local_optimisation == o.local_optimisation
            && self.final_threshold_factor == o.final_threshold_factor)
    }

    /// Pickling: ``RansacOptions(**as_dict())``.
    fn __reduce__<'py>(
        slf: &Bound<'py, Self>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>, Bound<'py, PyDict>)> {
        let py = slf.py();
        let state = slf.borrow().as_dict(py)?;
        Ok((
            py.get_type::<PyRansacOptions>().into_any(),
            PyTuple::empty(py),
            state,
        ))
    }

    fn __setstate__(&mut self, state: &Bound<'_, PyDict>) -> PyResult<()> {
        let o: PyRansacOptions = ransac_from_dict(state)?;
        *self = o;
        Ok(())
    }
}

fn ransac_from_dict(d: &Bound<'_, PyDict>) -> PyResult<PyRansacOptions> {
    let py = d.py();
    let opts = Bound::new(py, PyRansacOptions::default())?;
    for (k, v) in d.iter() {
        let key: String = k.extract()?;
        let known = [
            "threshold_px",
            "confidence",
            "max_iterations",
            "min_iterations",
            "seed",
            "local_optimisation",
            "final_threshold_factor",
        ];
        if !known.contains(&key.as_str()) {
            return Err(option_error(
                py,
                &key,
                format!(
                    "unknown RANSAC option {key:?} (known: {})",
                    known.join(", ")
                ),
            ));
        }
        opts.setattr(key.as_str(), v)?;
    }
    let o = opts.borrow().clone();
    Ok(o)
}

/// `ransac=`: None (defaults), a `RansacOptions` or a dict of its fields.
pub(crate) fn ransac_arg(py: Python<'_>, arg: Option<&Bound<'_, PyAny>>) -> PyResult<Ransac> {
    match arg {
        None => PyRansacOptions::default().ransac(py),
        Some(a) => {
            if let Ok(o) = a.cast::<PyRansacOptions>() {
                o.borrow().ransac(py)
            } else if let Ok(d) = a.cast::<PyDict>() {
                ransac_from_dict(d)?.ransac(py)
            } else {
                Err(option_error(
                    py,
                    "ransac",
                    format!(
                        "ransac must be a RansacOptions, a dict of its fields or None, got {}",
                        a.get_type().name()?
                    ),
                ))
            }
        }
    }
}

/// `focal=`: one number (fx = fy) or two, `(fx, fy)`.
pub(crate) fn focal_arg(py: Python<'_>, f: &Bound<'_, PyAny>) -> PyResult<(f64, f64)> {
    if let Ok(v) = f.extract::<f64>() {
        return Ok((v, v));
    }
    match vector(f, "focal", false)?.as_slice() {
        [fx, fy] => Ok((*fx, *fy)),
        other => Err(option_error(
            py,
            "focal",
            format!(
                "focal must be one focal length or two, (fx, fy), got {} values",
                other.len()
            ),
        )),
    }
}

/// RMS pixel reprojection error over the inliers: through the camera, or with the focal
/// lengths on normalised residuals.
fn rmse_px(
    sol: &PySolution,
    world: &[Point3<f64>],
    image: &[Point2<f64>],
    inliers: &[bool],
    camera: Option<&Camera>,
    focal: (f64, f64),
) -> f64 {
    let r = sol.rotation();
    let t = sol.translation();
    let (mut s, mut k) = (0.0, 0usize);
    for ((x, m), inlier) in world.iter().zip(image).zip(inliers) {
        if !inlier {
            continue;
        }
        let p = [
            r[0] * x.x + r[1] * x.y + r[2] * x.z + t[0],
            r[3] * x.x + r[4] * x.y + r[5] * x.z + t[1],
            r[6] * x.x + r[7] * x.y + r[8] * x.z + t[2],
        ];
        let n = Point2::new(p[0] / p[2], p[1] / p[2]);
        s += match camera {
            Some(c) => (c.project(n) - m).norm_squared(),
            None => {
                let (dx, dy) = ((n.x - m.x) * focal.0, (n.y - m.y) * focal.1);
                dx * dx + dy * dy
            }
        };
        k += 1;
    }
    if k == 0 {
        f64::NAN
    } else {
        (s / k as f64).sqrt()
    }
}

/// Robust camera pose from correspondences with outliers, by RANSAC: Lambda Twist P3P on
/// 3-point samples, MSAC scoring with an SPRT, adaptive iteration count, EOPnP local
/// optimisation of each new best hypothesis and an EOPnP final fit on the inliers; seeded.
///
/// Args:
///     world: world points, shape (N, 3).
///     image: image points, shape (N, 2): pixels with ``camera``, normalised with ``focal``.
///     weights: optional non-negative weight per point, shape (N,).
///     camera: a ``Camera``; the threshold applies to pixel reprojection errors through the
///         lens model. Pixels that cannot be undistorted are outliers.
///     focal: ``(fx, fy)`` (or one ``f``) in pixels, for normalised ``image``: the threshold
///         applies to ``sqrt(fx^2 dx^2 + fy^2 dy^2)``. Exactly one of ``camera`` and ``focal``.
///     gravity: a ``Gravity``: the known vertical; samples of two points (the upright
///         two-point pose), the final fit with it as a prior.
///     estimate_focal: the camera's focal length is unknown (``camera`` required, its focal
///         length the starting guess): samples of four points solved by P4Pf, the fits and the
///         final pose refined with the focal length; ``Solution.camera`` holds the camera.
///     focal_range: ``(min_px, max_px)``, the range of the unknown focal length (implies
///         ``estimate_focal``; default a tenth to ten times the guess).
///     refine_principal_point: the principal point is refined with the pose (``camera``
///         required; its principal point the starting guess), returned in ``Solution.camera``.
///     refine_distortion: the camera's distortion parameters are refined with the pose
///         (``camera`` required; its parameters the starting guess), returned in
///         ``Solution.camera``.
///     ransac: a ``RansacOptions``, a dict of its fields, or None (defaults: 4 px threshold,
///         confidence 0.999, at most 10000 samples, seed 0).
///     options: a ``SolverOptions`` (or a dict of its fields): the options of the EOPnP fits,
///         as ``solve``. Its ``loss`` is the loss of the fits' final refinement (the local
///         optimisations and the final fit on the inliers; ``s`` in pixels with ``camera``, in
///         normalised units with ``focal``; the inlier classification is unchanged). Its
///         ``covariance`` gives ``Solution.covariance`` of the returned pose from its inliers
///         (with their weights), the noise in pixels with ``camera`` and in normalised units
///         with ``focal`` (pycolmap's ``estimate_and_refine_absolute_pose(...,
///         return_covariance=True)``).
///     **keywords: the options of ``SolverOptions`` as keyword arguments instead, as
///         ``solve``.
///
/// Returns:
///     (Solution, dict): the pose fitted to the inliers, and ``info``: ``inliers`` (bool
///     array, shape (N,)), ``num_inliers``, ``inlier_ratio``, ``iterations`` (samples drawn),
///     ``hypotheses``, ``local_fits``, ``final_fits``, ``cost`` (the final fit's cost),
///     ``rmse`` (its normalised RMS residual), ``rmse_px`` (RMS pixel reprojection error over
///     the inliers) and ``micros`` (wall time).
///
/// Raises:
///     InvalidInputError: as ``solve``.
///     InvalidOptionError: a RANSAC or solver option out of range, a focal length not finite
///         and positive, neither or both of ``camera`` and ``focal``.
///     NoConsensusError: no pose with at least 4 inliers.
///     TypeError: as ``solve``.
#[pyfunction]
#[pyo3(signature = (world, image, weights = None, *, camera = None, focal = None, gravity = None,
    estimate_focal = false, focal_range = None,
    refine_principal_point = false, refine_distortion = false, ransac = None, options = None, **keywords))]
// One Rust parameter per Python parameter: the problem (world, image, weights), its camera or
// focal lengths, and the RANSAC and solver options (`options=`, `**keywords`).
#[allow(clippy::too_many_arguments)]
pub(crate) fn solve_ransac<'py>(
    world: &Bound<'py, PyAny>,
    image: &Bound<'py, PyAny>,
    weights: Option<&Bound<'py, PyAny>>,
    camera: Option<&Bound<'py, PyCamera>>,
    focal: Option<&Bound<'py, PyAny>>,
    gravity: Option<&Bound<'py, PyGravity>>,
    estimate_focal: bool,
    focal_range: Option<&Bound<'_, PyAny>>,
    refine_principal_point: bool,
    refine_distortion: bool,
    ransac: Option<&Bound<'py, PyAny>>,
    options: Option<&Bound<'py, PyAny>>,
    keywords: Option<&Bound<'py, PyDict>>,
) -> PyResult<(PySolution, Bound<'py, PyDict>)> {
    let py = world.py();
    let g = gravity_arg(gravity);
    let unknown = unknown_focal_arg(estimate_focal, focal_range)?
        .refining(refine_principal_point, refine_distortion);
    let solver = solver_arg(py, "solve_ransac", options, keywords, KEYWORDS)?;
    let ransac = ransac_arg(py, ransac)?;
    let focal = focal.map(|f| focal_arg(py, f)).transpose()?;
    let w = points3(world, "world")?;
    let img = points2(image, "image")?;
    let wts = weights.map(|w| vector(w, "weights", false)).transpose()?;
    let cam = camera.map(|c| &c.get().inner);
    let result =
        match (cam, focal) {
            (Some(_), Some(_)) => return Err(option_error(
                py,
                "focal",
                "solve_ransac: pass camera= (pixel input) or focal= (normalised input), not both"
                    .into(),
            )),
            (None, None) => {
                return Err(option_error(
                    py,
                    "focal",
                    "solve_ransac needs camera= (image points in pixels) or focal=(fx, fy) (image \
                 points normalised, the focal lengths in pixels for the threshold)"
                        .into(),
                ))
            }
            (Some(cam), None) => {
                check_finite(&w, &img, wts.as_deref()).map_err(|e| pnp_error(py, &e))?;
                py.detach(|| {
                    let p = problem_with(Problem::pixels(&w, &img, cam), wts.as_deref(), g);
                    ransac.estimate(&solver, &with_intrinsics(p, unknown))
                })
            }
            (None, Some(f)) => py.detach(|| {
                let p = Problem::normalised(&w, &img).focal(f.0, f.1);
                ransac.estimate(
                    &solver,
                    &with_intrinsics(problem_with(p, wts.as_deref(), g), unknown),
                )
            }),
        };
    let r = result.map_err(|e| pnp_error(py, &e))?;
    ransac_result(py, &r, &w, &img, cam, focal)
}

/// `solve_ransac`'s return value: the solution and the info dict.
pub(crate) fn ransac_result<'py>(
    py: Python<'py>,
    r: &RansacSolution,
    w: &[Point3<f64>],
    img: &[Point2<f64>],
    cam: Option<&Camera>,
    focal: Option<(f64, f64)>,
) -> PyResult<(PySolution, Bound<'py, PyDict>)> {
    let sol = PySolution::from(&r.solution);
    let px = ransac_rmse_px(&sol, r, w, img, cam, focal);
    let info = ransac_info(py, r, px)?;
    Ok((sol, info))
}

/// The info dict's `rmse_px` (no Python objects: the batch computes it in each problem's
/// task, with the GIL released).
pub(crate) fn ransac_rmse_px(
    sol: &PySolution,
    r: &RansacSolution,
    w: &[Point3<f64>],
    img: &[Point2<f64>],
    cam: Option<&Camera>,
    focal: Option<(f64, f64)>,
) -> f64 {
    // With an estimated focal length, the refinement of the inliers reports their RMS error
    // (through the camera at that focal length).
    if let Some((fx, fy)) = estimated_focal(&r.solution) {
        return r.solution.reprojection_rmse * fx.max(fy);
    }
    let focal = cam.map_or(focal.unwrap_or((1.0, 1.0)), Camera::focal_lengths);
    rmse_px(sol, w, img, &r.inliers, cam, focal)
}

/// The info dict of `solve_ransac`, with its `rmse_px`.
pub(crate) fn ransac_info<'py>(
    py: Python<'py>,
    r: &RansacSolution,
    rmse_px: f64,
) -> PyResult<Bound<'py, PyDict>> {
    let info = PyDict::new(py);
    info.set_item("inliers", PyArray1::from_slice(py, &r.inliers))?;
    info.set_item("num_inliers", r.num_inliers)?;
    info.set_item("inlier_ratio", r.stats.inlier_ratio)?;
    info.set_item("iterations", r.stats.iterations)?;
    info.set_item("hypotheses", r.stats.hypotheses)?;
    info.set_item("local_fits", r.stats.local_fits)?;
    info.set_item("final_fits", r.stats.final_fits)?;
    info.set_item("cost", r.solution.cost)?;
    info.set_item("rmse", r.solution.reprojection_rmse)?;
    info.set_item("rmse_px", rmse_px)?;
    info.set_item("micros", r.stats.micros)?;
    Ok(info)
}
