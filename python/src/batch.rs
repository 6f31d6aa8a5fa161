//! `eopnp.solve_batch`, `eopnp.solve_ransac_batch` and `eopnp.problem_seed`: many independent
//! problems on rayon's threads (the crate's `Solver::solve_batch` and `Ransac::estimate_batch`),
//! the GIL released for the whole batch.
//!
//! Every array of the batch is converted (and its shape checked) before anything is solved: a
//! malformed batch raises. Each problem's own failure (too few points, NaN, degenerate, no
//! consensus, ...) is returned in its place as the exception instance that the one-problem
//! function would raise.

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use eopnp::batch::{problem_seed as seed_of, Problem};
use eopnp::camera::Camera;
use eopnp::PnpError;
use nalgebra::{Point2, Point3};
use numpy::{PyArray2, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyList, PyTuple};
use rayon::ThreadPool;

use crate::camera::PyCamera;
use crate::convert::{points2, points3, vector};
use crate::errors::{error, option_error, pnp_error};
use crate::options::SolverOptions;
use crate::ransac::{focal_arg, ransac_arg, ransac_result};
use crate::solution::PySolution;
use crate::solve::check_finite;

/// One converted problem.
struct Converted {
    world: Vec<Point3<f64>>,
    image: Vec<Point2<f64>>,
    weights: Option<Vec<f64>>,
    /// Index into the batch's cameras.
    camera: Option<usize>,
    /// The package's own check of pixel input (NaN pixels), which the library would skip.
    rejected: Option<PnpError>,
}

/// The batch's problems and cameras, converted with the GIL held.
struct Batch<'py> {
    problems: Vec<Converted>,
    cameras: Vec<Bound<'py, PyCamera>>,
}

fn problems_error(py: Python<'_>, message: String) -> PyErr {
    error(
        py,
        "InvalidInputError",
        "Shape",
        message,
        vec![("argument", "problems".into())],
    )
}

/// The batch's cameras, and each problem's index into them.
type Cameras<'py> = (Vec<Bound<'py, PyCamera>>, Vec<Option<usize>>);

/// `camera=`: None, one `Camera` for every problem, or a sequence of one per problem.
fn cameras<'py>(
    py: Python<'py>,
    camera: Option<&Bound<'py, PyAny>>,
    n: usize,
) -> PyResult<Cameras<'py>> {
    let Some(c) = camera.filter(|c| !c.is_none()) else {
        return Ok((vec![], vec![None; n]));
    };
    if let Ok(one) = c.cast::<PyCamera>() {
        return Ok((vec![one.clone()], vec![Some(0); n]));
    }
    let bad =
        || {
            option_error(
                py,
                "camera",
                format!(
                "camera must be None, a Camera or a sequence of {n} Cameras (one per problem), \
                 got {}",
                c.get_type().name().map_or_else(|_| "?".into(), |s| s.to_string())
            ),
            )
        };
    let list: Vec<Bound<'py, PyAny>> = c.try_iter().map_err(|_| bad())?.collect::<PyResult<_>>()?;
    if list.len() != n {
        return Err(option_error(
            py,
            "camera",
            format!(
                "camera: {} cameras for {n} problems (give one Camera or one per problem)",
                list.len()
            ),
        ));
    }
    let cams = list
        .into_iter()
        .map(|x| x.cast_into::<PyCamera>().map_err(|_| bad()))
        .collect::<PyResult<Vec<_>>>()?;
    Ok((cams, (0..n).map(Some).collect()))
}

/// The rows of a C-contiguous `float64` array of shape `(N, C)`, copied; `None` for anything
/// else (then `convert`'s general path, with its checks and messages, reads it). The common
/// case of a batch, without the general path's per-array overhead (the serial part of a
/// batch call).
fn fast_rows<const C: usize, T>(
    obj: &Bound<'_, PyAny>,
    f: impl Fn(&[f64; C]) -> T,
) -> Option<Vec<T>> {
    let a = obj.cast::<PyArray2<f64>>().ok()?;
    if a.shape()[1] != C || !a.is_c_contiguous() {
        return None;
    }
    // SAFETY: the GIL is held and the data is copied before it is released, so nothing
    // mutates the array meanwhile (the same guarantee as a readonly borrow, without
    // registering one).
    let data = unsafe { a.as_slice() }.ok()?;
    Some(
        data.chunks_exact(C)
            .map(|r| f(r.try_into().expect("chunks of C")))
            .collect(),
    )
}

/// Converts every problem (`(world, image)` or `(world, image, weights)`), raising on the first
/// malformed one with its index in the message.
fn convert<'py>(
    py: Python<'py>,
    problems: &Bound<'py, PyAny>,
    camera: Option<&Bound<'py, PyAny>>,
) -> PyResult<Batch<'py>> {
    let items: Vec<Bound<'py, PyAny>> = problems
        .try_iter()
        .map_err(|_| {
            problems_error(
                py,
                "problems: expected a sequence of (world, image) or (world, image, weights) \
                 tuples"
                    .into(),
            )
        })?
        .collect::<PyResult<_>>()?;
    let (cams, which) = cameras(py, camera, items.len())?;
    let mut out = Vec::with_capacity(items.len());
    for (i, (item, cam)) in items.iter().zip(which).enumerate() {
        let parts: Vec<Bound<'py, PyAny>> = match item.cast::<PyTuple>() {
            Ok(t) => t.iter().collect(),
            Err(_) => match item.cast::<PyList>() {
                Ok(l) => l.iter().collect(),
                Err(_) => vec![],
            },
        };
        if !(parts.len() == 2 || parts.len() == 3) {
            return Err(problems_error(
                py,
                format!(
                    "problems[{i}]: expected a (world, image) or (world, image, weights) tuple, \
                     got {}",
                    item.get_type().name()?
                ),
            ));
        }
        let world = match fast_rows(&parts[0], |r: &[f64; 3]| Point3::new(r[0], r[1], r[2])) {
            Some(w) => w,
            None => points3(&parts[0], &format!("problems[{i}] world"))?,
        };
        let image = match fast_rows(&parts[1], |r: &[f64; 2]| Point2::new(r[0], r[1])) {
            Some(m) => m,
            None => points2(&parts[1], &format!("problems[{i}] image"))?,
        };
        let weights = match parts.get(2).filter(|w| !w.is_none()) {
            Some(w) => Some(vector(w, &format!("problems[{i}] weights"), false)?),
            None => None,
        };
        let rejected = cam.and_then(|_| check_finite(&world, &image, weights.as_deref()).err());
        out.push(Converted {
            world,
            image,
            weights,
            camera: cam,
            rejected,
        });
    }
    Ok(Batch {
        problems: out,
        cameras: cams,
    })
}

/// The crate's problems; a problem the package rejected is an empty placeholder (its result is
/// replaced by the rejection), so that indices, hence RANSAC seeds, are kept.
fn crate_problems<'a>(
    problems: &'a [Converted],
    cameras: &[&'a Camera],
    focal: (f64, f64),
) -> Vec<Problem<'a>> {
    problems
        .iter()
        .map(|p| {
            if p.rejected.is_some() {
                return Problem::normalised(&[], &[]);
            }
            let pr = match p.camera {
                Some(c) => Problem::pixels(&p.world, &p.image, cameras[c]),
                None => Problem::normalised_with_focal(&p.world, &p.image, focal),
            };
            match &p.weights {
                Some(w) => pr.weights(w),
                None => pr,
            }
        })
        .collect()
}

/// The pools of `threads=`, by thread count.
static POOLS: Mutex<Option<HashMap<usize, Arc<ThreadPool>>>> = Mutex::new(None);

/// Runs `f` on rayon's global pool (`threads` None) or on a cached pool of `threads` threads.
fn run<T: Send>(py: Python<'_>, threads: Option<i64>, f: impl FnOnce() -> T + Send) -> PyResult<T> {
    let Some(n) = threads else {
        return Ok(py.detach(f));
    };
    let n = usize::try_from(n)
        .ok()
        .filter(|n| (1..=1024).contains(n))
        .ok_or_else(|| {
            option_error(
                py,
                "threads",
                format!("threads must be None or an integer in [1, 1024], got {n}"),
            )
        })?;
    let pool = {
        let mut pools = POOLS
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        let pools = pools.get_or_insert_with(HashMap::new);
        match pools.get(&n) {
            Some(p) => Arc::clone(p),
            None => {
                let p = rayon::ThreadPoolBuilder::new()
                    .num_threads(n)
                    .thread_name(|i| format!("eopnp-{i}"))
                    .build()
                    .map_err(|e| option_error(py, "threads", format!("threads: {e}")))?;
                let p = Arc::new(p);
                pools.insert(n, Arc::clone(&p));
                p
            }
        }
    };
    Ok(py.detach(|| pool.install(f)))
}

/// Solves many independent problems in parallel (``solve`` on each), the GIL released for the
/// whole batch.
///
/// Args:
///     problems: a sequence of ``(world, image)`` or ``(world, image, weights)`` tuples, as
///         ``solve``'s arguments (weights may be None).
///     camera: None (normalised image points), a ``Camera`` for every problem, or a sequence
///         of one ``Camera`` per problem (image points in pixels).
///     refinement, planar, newton_iterations, newton_step_tolerance, reprojection_iterations,
///         exhaustive, covariance, loss: as ``solve``, for every problem.
///     threads: None (rayon's global pool: one thread per core, or ``RAYON_NUM_THREADS``) or
///         the number of threads (a pool per count, built once and kept).
///
/// Returns:
///     list: one entry per problem, in order: its ``Solution``, or the exception instance
///     (a ``PnpError``) that ``solve`` would raise for it (as
///     ``asyncio.gather(return_exceptions=True)``). Each entry equals ``solve``'s, whatever
///     the thread count.
///
/// Raises:
///     InvalidInputError: a malformed batch (not a sequence of 2- or 3-tuples, an array of the
///         wrong shape; the message names the problem's index), before anything is solved.
///     InputTypeError: an array that is not real numbers.
///     InvalidOptionError: an option out of range, a bad ``camera`` or ``threads``.
#[pyfunction]
#[pyo3(signature = (problems, *, camera = None, refinement = "ml", planar = "auto",
    newton_iterations = None, newton_step_tolerance = None, reprojection_iterations = None,
    exhaustive = false, covariance = None, loss = None, threads = None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn solve_batch<'py>(
    py: Python<'py>,
    problems: &Bound<'py, PyAny>,
    camera: Option<&Bound<'py, PyAny>>,
    refinement: &str,
    planar: &str,
    newton_iterations: Option<i64>,
    newton_step_tolerance: Option<f64>,
    reprojection_iterations: Option<i64>,
    exhaustive: bool,
    covariance: Option<&Bound<'py, PyAny>>,
    loss: Option<&Bound<'py, PyAny>>,
    threads: Option<i64>,
) -> PyResult<Bound<'py, PyList>> {
    let solver = SolverOptions {
        refinement,
        planar,
        newton_iterations,
        newton_step_tolerance,
        reprojection_iterations,
        exhaustive,
        loss,
        covariance,
    }
    .solver(py)?;
    let batch = convert(py, problems, camera)?;
    let cams: Vec<&Camera> = batch.cameras.iter().map(|c| &c.get().inner).collect();
    let probs = crate_problems(&batch.problems, &cams, (1.0, 1.0));
    let results = run(py, threads, || solver.solve_batch(&probs))?;
    let out = PyList::empty(py);
    for (p, r) in batch.problems.iter().zip(results) {
        match (&p.rejected, &r) {
            (Some(e), _) | (None, Err(e)) => out.append(pnp_error(py, e).into_value(py))?,
            (None, Ok(s)) => out.append(PySolution::from(s))?,
        }
    }
    Ok(out)
}

/// Robust estimation of many independent problems in parallel (``solve_ransac`` on each),
/// the GIL released for the whole batch. Problem ``i`` uses the seed
/// ``problem_seed(ransac.seed, i)``, so results do not depend on the thread count.
///
/// Args:
///     problems: as ``solve_batch``.
///     camera: a ``Camera`` for every problem or a sequence of one per problem (pixels), or
///         None with ``focal``.
///     focal: ``(fx, fy)`` (or one ``f``) in pixels for every problem, for normalised image
///         points (exactly one of ``camera`` and ``focal``).
///     ransac: a ``RansacOptions``, a dict of its fields, or None; ``seed`` is the base seed.
///     refinement, planar, newton_iterations, newton_step_tolerance, reprojection_iterations,
///         exhaustive, loss: as ``solve_ransac``.
///     threads: as ``solve_batch``.
///
/// Returns:
///     list: one entry per problem, in order: ``(Solution, info)`` as ``solve_ransac``
///     returns with ``RansacOptions(seed=problem_seed(seed, i))``, or the exception instance
///     it would raise (e.g. ``NoConsensusError``).
///
/// Raises:
///     As ``solve_batch``; InvalidOptionError also for neither or both of camera and focal.
#[pyfunction]
#[pyo3(signature = (problems, *, camera = None, focal = None, ransac = None, refinement = "ml",
    planar = "auto", newton_iterations = None, newton_step_tolerance = None,
    reprojection_iterations = None, exhaustive = false, loss = None, threads = None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn solve_ransac_batch<'py>(
    py: Python<'py>,
    problems: &Bound<'py, PyAny>,
    camera: Option<&Bound<'py, PyAny>>,
    focal: Option<&Bound<'py, PyAny>>,
    ransac: Option<&Bound<'py, PyAny>>,
    refinement: &str,
    planar: &str,
    newton_iterations: Option<i64>,
    newton_step_tolerance: Option<f64>,
    reprojection_iterations: Option<i64>,
    exhaustive: bool,
    loss: Option<&Bound<'py, PyAny>>,
    threads: Option<i64>,
) -> PyResult<Bound<'py, PyList>> {
    let solver = SolverOptions {
        refinement,
        planar,
        newton_iterations,
        newton_step_tolerance,
        reprojection_iterations,
        exhaustive,
        loss,
        covariance: None,
    }
    .solver(py)?;
    let ransac = ransac_arg(py, ransac)?;
    let focal = focal.map(|f| focal_arg(py, f)).transpose()?;
    let has_camera = camera.is_some_and(|c| !c.is_none());
    if has_camera == focal.is_some() {
        return Err(option_error(
            py,
            "focal",
            "solve_ransac_batch needs exactly one of camera= (image points in pixels) and \
             focal=(fx, fy) (image points normalised)"
                .into(),
        ));
    }
    let batch = convert(py, problems, camera)?;
    let cams: Vec<&Camera> = batch.cameras.iter().map(|c| &c.get().inner).collect();
    let probs = crate_problems(&batch.problems, &cams, focal.unwrap_or((1.0, 1.0)));
    let results = run(py, threads, || ransac.estimate_batch(&solver, &probs))?;
    let out = PyList::empty(py);
    for (p, r) in batch.problems.iter().zip(results) {
        match (&p.rejected, &r) {
            (Some(e), _) | (None, Err(e)) => out.append(pnp_error(py, e).into_value(py))?,
            (None, Ok(r)) => {
                let cam = p.camera.map(|c| cams[c]);
                out.append(ransac_result(py, r, &p.world, &p.image, cam, focal)?)?;
            }
        }
    }
    Ok(out)
}

/// The RANSAC seed of problem ``index`` of a batch whose base seed is ``base``
/// (``solve_ransac_batch``): ``solve_ransac(..., ransac=RansacOptions(seed=problem_seed(base,
/// i)))`` equals entry ``i`` of the batch.
#[pyfunction]
pub(crate) fn problem_seed(base: u64, index: usize) -> u64 {
    seed_of(base, index)
}
