//! `eopnp.solve_batch`, `eopnp.solve_ransac_batch`, `eopnp.solve_batch_arrays` and
//! `eopnp.problem_seed`: many independent problems on rayon's threads, the GIL released for the
//! whole batch; each problem gives what the one-problem call gives (the crate's
//! `Solver::solve_problem` and `Ransac::estimate_problem`, as `Solver::solve_batch` and
//! `Ransac::estimate_batch` call them).
//!
//! The serial part of a batch call, with the GIL held, is kept to what needs the interpreter:
//! every array's type, dtype, shape and layout is checked first (a malformed batch raises,
//! naming the problem, before anything is solved), and a C-contiguous, aligned `float64` array
//! is held (a reference) rather than copied. Each problem's task then reads its own
//! arrays, converts them to points and solves, with the GIL released; arrays of any other
//! layout or dtype are converted (copied) with the GIL held. Each problem's own failure (too
//! few points, NaN, degenerate, no consensus, ...) is that problem's result: the exception
//! instance the one-problem function would raise.
//!
//! `solve_batch` and `solve_ransac_batch` then create one Python result object per problem
//! (the `Solution`s themselves are built in the tasks); `solve_batch_arrays` takes stacked
//! arrays and writes every problem's pose into arrays allocated once, from the tasks: no
//! Python object per problem.

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use eopnp::camera::Camera;
use eopnp::ransac::problem_seed as seed_of;
use eopnp::ransac::{Ransac, RansacSolution};
use eopnp::Problem;
use eopnp::{PnpError, Solution, Solver};
use nalgebra::{Point2, Point3};
use numpy::{PyArray1, PyArrayDyn, PyArrayMethods, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::{PyDict, PyList, PyModule, PyTuple};
use rayon::iter::Either;
use rayon::prelude::*;
use rayon::ThreadPool;

use crate::camera::PyCamera;
use crate::convert::{contiguous_array, rows, shape_str, vector};
use crate::errors::{error, option_error, pnp_error, shape_error, InvalidInputError};
use crate::options::{options_arg, solver_arg, KEYWORDS};
use crate::ransac::{focal_arg, ransac_arg, ransac_info, ransac_rmse_px};
use crate::solution::PySolution;
use crate::solve::check_finite;

fn problems_error(py: Python<'_>, message: String) -> PyErr {
    error::<InvalidInputError>(py, "Shape", message, vec![("argument", "problems".into())])
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

/// An array of a problem as the GIL-held phase leaves it: held as it is (an index into the
/// batch's arrays), or converted by the general path of `convert`.
enum Held<T> {
    Borrowed(usize),
    Owned(Vec<T>),
}

/// `obj` when it is a C-contiguous, aligned `float64` array of `ndim` dimensions whose last has
/// `cols` entries (`None`: any); `None` for anything else (then the general path of `convert`,
/// with its checks and messages, reads it).
///
/// Not numpy's read-only borrow (`PyReadonlyArray`): it registers each borrow in a table per
/// base array and checks it against the others of that base, which costs O(B^2) for a batch
/// of B views of one array (`[(W[i], I[i]) for i in range(B)]`, N = 100, 1 thread, measured
/// on a loaded machine: 33 us per problem for B = 2,500 and 72-82 us for B = 10,000, against
/// 18-23 us for separate arrays).
fn borrow<'py>(
    obj: &Bound<'py, PyAny>,
    ndim: usize,
    cols: Option<usize>,
) -> Option<Bound<'py, PyArrayDyn<f64>>> {
    let a = obj.cast::<PyArrayDyn<f64>>().ok()?;
    let shape = a.shape();
    let fits = shape.len() == ndim
        && cols.is_none_or(|c| shape[ndim - 1] == c)
        && a.is_c_contiguous()
        && a.is_aligned();
    fits.then(|| a.clone())
}

/// One problem of a list batch, after the GIL-held phase.
struct Item {
    world: Held<[f64; 3]>,
    image: Held<[f64; 2]>,
    weights: Option<Held<f64>>,
    /// Index into the batch's cameras.
    camera: Option<usize>,
}

/// A list batch after the GIL-held phase: its problems, the arrays they index, the cameras.
struct Batch<'py> {
    items: Vec<Item>,
    arrays: Vec<Bound<'py, PyArrayDyn<f64>>>,
    cameras: Vec<Bound<'py, PyCamera>>,
}

/// Holds (as it is, or converted) the `(N, C)` array `obj` of a problem.
fn hold_rows<'py, const C: usize>(
    obj: &Bound<'py, PyAny>,
    name: impl FnOnce() -> String,
    arrays: &mut Vec<Bound<'py, PyArrayDyn<f64>>>,
) -> PyResult<Held<[f64; C]>> {
    if let Some(b) = borrow(obj, 2, Some(C)) {
        arrays.push(b);
        return Ok(Held::Borrowed(arrays.len() - 1));
    }
    let rows = rows(obj, &name(), C, |r| {
        let mut a = [0.0; C];
        a.copy_from_slice(r);
        a
    })?;
    Ok(Held::Owned(rows))
}

/// A problem's world, image and weights (if given).
type Parts<'py> = (
    Bound<'py, PyAny>,
    Bound<'py, PyAny>,
    Option<Bound<'py, PyAny>>,
);

/// The entries of a problem, a `(world, image)` or `(world, image, weights)` tuple (or list);
/// `None` for anything else. (Read in place: no vector per problem in the batch's serial
/// part.)
fn problem_parts<'py>(item: &Bound<'py, PyAny>) -> Option<Parts<'py>> {
    let (len, get): (usize, &dyn Fn(usize) -> Option<Bound<'py, PyAny>>) =
        if let Ok(t) = item.cast::<PyTuple>() {
            (t.len(), &move |k| t.get_item(k).ok())
        } else if let Ok(l) = item.cast::<PyList>() {
            (l.len(), &move |k| l.get_item(k).ok())
        } else {
            return None;
        };
    if !(len == 2 || len == 3) {
        return None;
    }
    Some((get(0)?, get(1)?, if len == 3 { get(2) } else { None }))
}

/// Checks every problem (`(world, image)` or `(world, image, weights)`) and holds its arrays,
/// raising on the first malformed one with its index in the message.
fn gather<'py>(
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
    let mut arrays = Vec::with_capacity(2 * items.len());
    for (i, (item, cam)) in items.iter().zip(which).enumerate() {
        let Some(parts) = problem_parts(item) else {
            return Err(problems_error(
                py,
                format!(
                    "problems[{i}]: expected a (world, image) or (world, image, weights) tuple, \
                     got {}",
                    item.get_type().name()?
                ),
            ));
        };
        let world = hold_rows(&parts.0, || format!("problems[{i}] world"), &mut arrays)?;
        let image = hold_rows(&parts.1, || format!("problems[{i}] image"), &mut arrays)?;
        let weights = match parts.2.as_ref().filter(|w| !w.is_none()) {
            Some(w) => Some(match borrow(w, 1, None) {
                Some(b) => {
                    arrays.push(b);
                    Held::Borrowed(arrays.len() - 1)
                }
                None => Held::Owned(vector(w, &format!("problems[{i}] weights"), false)?),
            }),
            None => None,
        };
        out.push(Item {
            world,
            image,
            weights,
            camera: cam,
        });
    }
    Ok(Batch {
        items: out,
        arrays,
        cameras: cams,
    })
}

/// One problem as its task reads it: slices of the caller's arrays (or of their converted
/// copies) and its camera.
#[derive(Clone, Copy)]
struct Input<'a> {
    world: &'a [[f64; 3]],
    image: &'a [[f64; 2]],
    weights: Option<&'a [f64]>,
    camera: Option<&'a Camera>,
}

impl<'py> Batch<'py> {
    /// The problems' inputs, borrowing from this batch.
    fn inputs<'a>(&'a self, cameras: &[&'a Camera]) -> Vec<Input<'a>> {
        let slice = |k: usize| -> &'a [f64] {
            // SAFETY: checked C-contiguous and aligned; the batch holds a reference to the
            // array, so its memory lives as long as the slice. The slice is read with the GIL
            // released: as numpy's own functions that release the GIL, the call requires that
            // no other thread modifies the array meanwhile (documented).
            unsafe { self.arrays[k].as_slice() }.expect("checked: C-contiguous and aligned")
        };
        self.items
            .iter()
            .map(|it| Input {
                world: match &it.world {
                    Held::Borrowed(k) => slice(*k).as_chunks::<3>().0,
                    Held::Owned(v) => v,
                },
                image: match &it.image {
                    Held::Borrowed(k) => slice(*k).as_chunks::<2>().0,
                    Held::Owned(v) => v,
                },
                weights: it.weights.as_ref().map(|w| match w {
                    Held::Borrowed(k) => slice(*k),
                    Held::Owned(v) => v.as_slice(),
                }),
                camera: it.camera.map(|c| cameras[c]),
            })
            .collect()
    }
}

/// A problem's points, read from its arrays (in its task).
struct Points {
    world: Vec<Point3<f64>>,
    image: Vec<Point2<f64>>,
}

impl Input<'_> {
    fn points(&self) -> Points {
        Points {
            world: self
                .world
                .iter()
                .map(|r| Point3::new(r[0], r[1], r[2]))
                .collect(),
            image: self.image.iter().map(|r| Point2::new(r[0], r[1])).collect(),
        }
    }

    /// The crate's problem on `pts` (normalised points with `focal`, or pixels through the
    /// camera), after the package's own check of pixel input (a NaN pixel is rejected, as
    /// `solve` rejects it; the library would skip it as one that cannot be undistorted).
    fn problem<'a>(&'a self, pts: &'a Points, focal: (f64, f64)) -> Result<Problem<'a>, PnpError> {
        let p = match self.camera {
            Some(c) => {
                check_finite(&pts.world, &pts.image, self.weights)?;
                Problem::pixels(&pts.world, &pts.image, c)
            }
            None => Problem::normalised(&pts.world, &pts.image).focal(focal.0, focal.1),
        };
        Ok(match self.weights {
            Some(w) => p.weights(w),
            None => p,
        })
    }

    /// `solve` on this problem.
    fn solve(&self, solver: &Solver) -> Result<Solution, PnpError> {
        let pts = self.points();
        solver.solve(&self.problem(&pts, (1.0, 1.0))?)
    }
}

/// The pools of `threads=`, by thread count.
static POOLS: Mutex<Option<HashMap<usize, Arc<ThreadPool>>>> = Mutex::new(None);

/// Runs `f` on rayon's global pool (`threads` None) or on a cached pool of `threads` threads.
pub(crate) fn in_pool<T: Send>(
    py: Python<'_>,
    threads: Option<i64>,
    f: impl FnOnce() -> T + Send,
) -> PyResult<T> {
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
/// C-contiguous float64 arrays are read in place by the threads, with the GIL released (as
/// numpy's own functions that release it): do not modify them from another thread during
/// the call. Any other array-like is converted first.
///
/// Args:
///     problems: a sequence of ``(world, image)`` or ``(world, image, weights)`` tuples, as
///         ``solve``'s arguments (weights may be None).
///     camera: None (normalised image points), a ``Camera`` for every problem, or a sequence
///         of one ``Camera`` per problem (image points in pixels).
///     options: a ``SolverOptions`` (or a dict of its fields), as ``solve``, for every
///         problem.
///     threads: None (rayon's global pool: one thread per core, or ``RAYON_NUM_THREADS``) or
///         the number of threads (a pool per count, built once and kept).
///     **keywords: the options of ``SolverOptions`` as keyword arguments instead, as
///         ``solve``.
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
///     TypeError: as ``solve``.
#[pyfunction]
#[pyo3(signature = (problems, *, camera = None, options = None, threads = None, **keywords))]
pub(crate) fn solve_batch<'py>(
    py: Python<'py>,
    problems: &Bound<'py, PyAny>,
    camera: Option<&Bound<'py, PyAny>>,
    options: Option<&Bound<'py, PyAny>>,
    threads: Option<i64>,
    keywords: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyList>> {
    let solver = solver_arg(py, "solve_batch", options, keywords, KEYWORDS)?;
    let batch = gather(py, problems, camera)?;
    let cams: Vec<&Camera> = batch.cameras.iter().map(|c| &c.get().inner).collect();
    let inputs = batch.inputs(&cams);
    let results = in_pool(py, threads, || {
        inputs
            .par_iter()
            .map(|p| p.solve(&solver).map(|s| PySolution::from(&s)))
            .collect::<Vec<_>>()
    })?;
    let out = PyList::empty(py);
    for r in results {
        match r {
            Ok(s) => out.append(untracked(Bound::new(py, s)?))?,
            Err(e) => out.append(pnp_error(py, &e).into_value(py))?,
        }
    }
    Ok(out)
}

/// `obj` taken off the garbage collector's lists. PyO3 makes every `#[pyclass]` a GC type, so
/// each new `Solution` joined the youngest generation, and a batch's thousands of them
/// triggered collections that traversed them all: untracked, the batch's serial part went
/// from 1,410 to 1,168 instructions per problem (callgrind, N = 100). A `Solution` holds no reference to a Python
/// object (numbers, a static string, an optional array of numbers), so it can never be part
/// of a reference cycle: CPython untracks its own tuples of numbers for the same reason.
fn untracked<T>(obj: Bound<'_, T>) -> Bound<'_, T> {
    // SAFETY: `obj` is a live object of a GC type (every `#[pyclass]` is one), held with the
    // GIL; untracking is always allowed, and PyO3's `tp_dealloc` untracks again, which
    // CPython accepts for an object that is not tracked.
    unsafe { pyo3::ffi::PyObject_GC_UnTrack(obj.as_ptr().cast()) };
    obj
}

/// `obj` as a stacked array of `shape` (`None`: any length; the entries of `want`, known from
/// `world`, must match), C-contiguous `float64` (converted once when it is not).
fn stacked<'py>(
    obj: &Bound<'py, PyAny>,
    name: &str,
    shape: &[Option<usize>],
    want: &str,
) -> PyResult<PyReadonlyArrayDyn<'py, f64>> {
    let a = contiguous_array(obj, name)?;
    let got = a.shape();
    if got.len() != shape.len()
        || got
            .iter()
            .zip(shape)
            .any(|(g, s)| s.is_some_and(|s| s != *g))
    {
        return Err(shape_error(
            obj.py(),
            name,
            format!(
                "{name}: expected an array of shape {want}, got shape {}",
                shape_str(got)
            ),
        ));
    }
    a.try_readonly().map_err(|e| {
        error::<InvalidInputError>(obj.py(), "Borrow", format!("{name}: {e}"), vec![])
    })
}

/// A new C-contiguous `float64` array of `shape`, left uninitialised: the tasks write every
/// element (`write_row`), so that the memory is first touched in parallel.
fn output<'py>(py: Python<'py>, shape: &[usize]) -> Bound<'py, PyArrayDyn<f64>> {
    // SAFETY: every element is written before the array is returned to Python.
    unsafe { PyArrayDyn::<f64>::new(py, shape, false) }
}

static BATCH: PyOnceLock<Py<PyModule>> = PyOnceLock::new();

/// Writes a problem's result into its rows of the output arrays (NaN where it failed).
fn write_row(
    res: &Result<Solution, PnpError>,
    r: &mut [f64],
    t: &mut [f64],
    cost: &mut f64,
    rmse: &mut f64,
    ok: &mut bool,
    cov: Option<(&mut [f64], &mut f64)>,
) {
    let Ok(s) = res else {
        r.fill(f64::NAN);
        t.fill(f64::NAN);
        (*cost, *rmse, *ok) = (f64::NAN, f64::NAN, false);
        if let Some((c, sigma)) = cov {
            c.fill(f64::NAN);
            *sigma = f64::NAN;
        }
        return;
    };
    for (k, v) in r.iter_mut().enumerate() {
        *v = s.rotation[(k / 3, k % 3)];
    }
    t.copy_from_slice(s.translation.as_slice());
    (*cost, *rmse, *ok) = (s.cost, s.reprojection_rmse, true);
    if let Some((c, sigma)) = cov {
        match &s.covariance {
            Some(m) => {
                for (k, v) in c.iter_mut().enumerate() {
                    *v = m.matrix[(k / 6, k % 6)];
                }
                *sigma = m.sigma;
            }
            None => {
                c.fill(f64::NAN);
                *sigma = f64::NAN;
            }
        }
    }
}

/// Solves a batch of problems given as stacked arrays (``solve`` on each), in parallel with the
/// GIL released, and returns the poses as stacked arrays: the form for throughput (no Python
/// object per problem).
///
/// C-contiguous float64 arrays are read in place by the threads, with the GIL released (as
/// numpy's own functions that release it): do not modify them from another thread during
/// the call. Any other array-like of real numbers is converted once (a copy).
///
/// Args:
///     world: world points of every problem, shape (B, N, 3).
///     image: their image points, shape (B, N, 2): normalised, or pixels with ``camera``.
///     weights: optional non-negative weights, shape (B, N), as ``solve``'s. Problems with
///         fewer points: pad them (any finite values) with weight 0, which ``solve`` ignores
///         exactly as if the points were dropped; or use ``solve_batch``.
///     camera: None (normalised image points), a ``Camera`` for every problem, or a sequence
///         of B ``Camera`` (pixels).
///     options: a ``SolverOptions`` (or a dict of its fields), as ``solve``, for every
///         problem.
///     threads: as ``solve_batch``.
///     **keywords: the options of ``SolverOptions`` as keyword arguments instead, as
///         ``solve``.
///
/// Returns:
///     BatchResult: ``R`` (B, 3, 3), ``t`` (B, 3), ``cost`` (B,), ``reprojection_rmse``
///     (B,), ``ok`` (B,) bool, ``covariance`` (B, 6, 6) and ``sigma`` (B,) with a
///     ``covariance`` option (else None), and ``errors``: {index: the exception ``solve``
///     would raise for that problem} (its rows are NaN and ``ok`` False). Row ``i`` equals
///     ``solve(world[i], image[i], weights[i], ...)`` exactly, whatever the thread count.
///
/// Raises:
///     InvalidInputError: an array of the wrong shape (world not (B, N, 3), image not
///         (B, N, 2) or weights not (B, N) with world's B and N), before anything is solved.
///     InputTypeError: an array that is not real numbers.
///     InvalidOptionError: an option out of range, a bad ``camera`` or ``threads``.
///     TypeError: as ``solve``.
#[pyfunction]
#[pyo3(signature = (world, image, weights = None, *, camera = None, options = None,
    threads = None, **keywords))]
pub(crate) fn solve_batch_arrays<'py>(
    world: &Bound<'py, PyAny>,
    image: &Bound<'py, PyAny>,
    weights: Option<&Bound<'py, PyAny>>,
    camera: Option<&Bound<'py, PyAny>>,
    options: Option<&Bound<'py, PyAny>>,
    threads: Option<i64>,
    keywords: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyAny>> {
    let py = world.py();
    let options = options_arg(py, "solve_batch_arrays", options, keywords, KEYWORDS)?;
    let solver = options.solver();
    let w = stacked(world, "world", &[None, None, Some(3)], "(B, N, 3)")?;
    let (b, n) = (w.shape()[0], w.shape()[1]);
    let bn = format!("(B, N, 2) = ({b}, {n}, 2)");
    let m = stacked(image, "image", &[Some(b), Some(n), Some(2)], &bn)?;
    let wt = match weights.filter(|x| !x.is_none()) {
        Some(x) => Some(stacked(
            x,
            "weights",
            &[Some(b), Some(n)],
            &format!("(B, N) = ({b}, {n})"),
        )?),
        None => None,
    };
    let (cams, which) = cameras(py, camera, b)?;
    let cams: Vec<&Camera> = cams.iter().map(|c| &c.get().inner).collect();

    let want_cov = options.wants_covariance();
    let r_out = output(py, &[b, 3, 3]);
    let t_out = output(py, &[b, 3]);
    let cost_out = output(py, &[b]);
    let rmse_out = output(py, &[b]);
    let ok_out = PyArray1::<bool>::zeros(py, b, false);
    let cov_out = want_cov.then(|| (output(py, &[b, 6, 6]), output(py, &[b])));

    let ws = w.as_slice().expect("contiguous").as_chunks::<3>().0;
    let ms = m.as_slice().expect("contiguous").as_chunks::<2>().0;
    let wts = wt.as_ref().map(|x| x.as_slice().expect("contiguous"));
    let input = |i: usize| Input {
        world: &ws[i * n..(i + 1) * n],
        image: &ms[i * n..(i + 1) * n],
        weights: wts.map(|x| &x[i * n..(i + 1) * n]),
        camera: which[i].map(|c| cams[c]),
    };
    // SAFETY: new arrays, referenced by nothing else until they are returned.
    let (r, t, cost, rmse, ok, cov) = unsafe {
        (
            r_out.as_slice_mut().expect("new array"),
            t_out.as_slice_mut().expect("new array"),
            cost_out.as_slice_mut().expect("new array"),
            rmse_out.as_slice_mut().expect("new array"),
            ok_out.as_slice_mut().expect("new array"),
            cov_out.as_ref().map(|(c, s)| {
                (
                    c.as_slice_mut().expect("new array"),
                    s.as_slice_mut().expect("new array"),
                )
            }),
        )
    };
    let errors = in_pool(py, threads, || {
        let cov = match cov {
            Some((c, s)) => Either::Left(c.par_chunks_mut(36).zip(s.par_iter_mut()).map(Some)),
            None => Either::Right((0..b).into_par_iter().map(|_| None)),
        };
        r.par_chunks_mut(9)
            .zip(t.par_chunks_mut(3))
            .zip(cost.par_iter_mut())
            .zip(rmse.par_iter_mut())
            .zip(ok.par_iter_mut())
            .zip(cov)
            .enumerate()
            .filter_map(|(i, (((((r, t), cost), rmse), ok), cov))| {
                let res = input(i).solve(&solver);
                write_row(&res, r, t, cost, rmse, ok, cov);
                res.err().map(|e| (i, e))
            })
            .collect::<Vec<_>>()
    })?;
    drop((w, m, wt));

    let errs = PyDict::new(py);
    for (i, e) in &errors {
        errs.set_item(*i, pnp_error(py, e).into_value(py))?;
    }
    let module = BATCH.get_or_try_init(py, || {
        PyModule::import(py, "eopnp._batch").map(Bound::unbind)
    })?;
    let (cov, sigma) = match cov_out {
        Some((c, s)) => (c.into_any(), s.into_any()),
        None => (py.None().into_bound(py), py.None().into_bound(py)),
    };
    module
        .bind(py)
        .getattr("BatchResult")?
        .call1((r_out, t_out, cost_out, rmse_out, ok_out, cov, sigma, errs))
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
///     options: a ``SolverOptions`` (or a dict of its fields), as ``solve_ransac``, for every
///         problem.
///     threads: as ``solve_batch``.
///     **keywords: the options of ``SolverOptions`` as keyword arguments instead, as
///         ``solve``.
///
/// Returns:
///     list: one entry per problem, in order: ``(Solution, info)`` as ``solve_ransac``
///     returns with ``RansacOptions(seed=problem_seed(seed, i))``, or the exception instance
///     it would raise (e.g. ``NoConsensusError``).
///
/// Raises:
///     As ``solve_batch``; InvalidOptionError also for neither or both of camera and focal.
#[pyfunction]
#[pyo3(signature = (problems, *, camera = None, focal = None, ransac = None, options = None,
    threads = None, **keywords))]
pub(crate) fn solve_ransac_batch<'py>(
    problems: &Bound<'py, PyAny>,
    camera: Option<&Bound<'py, PyAny>>,
    focal: Option<&Bound<'py, PyAny>>,
    ransac: Option<&Bound<'py, PyAny>>,
    options: Option<&Bound<'py, PyAny>>,
    threads: Option<i64>,
    keywords: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyList>> {
    let py = problems.py();
    let solver = solver_arg(py, "solve_ransac_batch", options, keywords, KEYWORDS)?;
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
    let batch = gather(py, problems, camera)?;
    let cams: Vec<&Camera> = batch.cameras.iter().map(|c| &c.get().inner).collect();
    let inputs = batch.inputs(&cams);
    let results = in_pool(py, threads, || {
        inputs
            .par_iter()
            .enumerate()
            .map(|(i, p)| estimate(&ransac, &solver, i, p, focal))
            .collect::<Vec<_>>()
    })?;
    let out = PyList::empty(py);
    for r in results {
        match r {
            Ok((sol, r, px)) => out.append((sol, ransac_info(py, &r, px)?))?,
            Err(e) => out.append(pnp_error(py, &e).into_value(py))?,
        }
    }
    Ok(out)
}

/// `solve_ransac` on problem `index` of a batch (seed `problem_seed(ransac.seed, index)`):
/// the solution, the crate's result and the info's `rmse_px`.
fn estimate(
    ransac: &Ransac,
    solver: &Solver,
    index: usize,
    p: &Input<'_>,
    focal: Option<(f64, f64)>,
) -> Result<(PySolution, RansacSolution, f64), PnpError> {
    let pts = p.points();
    let problem = p.problem(&pts, focal.unwrap_or((1.0, 1.0)))?;
    let r = ransac
        .seed(seed_of(ransac.seed, index))
        .estimate(solver, &problem)?;
    let sol = PySolution::from(&r.solution);
    let px = ransac_rmse_px(&sol, &r, &pts.world, &pts.image, p.camera, focal);
    Ok((sol, r, px))
}

/// The RANSAC seed of problem ``index`` of a batch whose base seed is ``base``
/// (``solve_ransac_batch``): ``solve_ransac(..., ransac=RansacOptions(seed=problem_seed(base,
/// i)))`` equals entry ``i`` of the batch.
#[pyfunction]
pub(crate) fn problem_seed(base: u64, index: usize) -> u64 {
    seed_of(base, index)
}
