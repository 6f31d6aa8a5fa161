//! `eopnp.solve_batch`, `eopnp.solve_ransac_batch`, `eopnp.solve_batch_arrays` and
//! `eopnp.problem_seed`: many independent problems on rayon's threads, the GIL released while
//! they are solved; each problem gives what the one-problem call gives.
//!
//! No caller's buffer is read with the GIL released. With the GIL held, the calling thread
//! first checks every problem (type, dtype, shape: a malformed batch raises, naming the
//! problem, before anything is solved), then copies every problem's points into memory of the
//! call's own, each array read once, as the one-problem functions copy theirs; the solves read
//! only the copies, and the GIL is released for good once everything is copied. What other
//! Python threads write to the arrays during the call therefore never reaches a solve: each
//! problem's result is that of its arrays as the call copied them. (As for any function that
//! reads numpy arrays with the GIL held, a numpy operation of another thread that itself
//! releases the GIL while it writes to the same array is not excluded.)
//!
//! The copy is pipelined with the solves (`pipelined`): the problems are copied chunk by chunk,
//! and each chunk is handed to the pool's threads as soon as it is copied, so that they solve
//! while the calling thread copies the next chunks. The copies go to buffers kept from one
//! call to the next (`Buffers`), whose memory, when new, is touched with the GIL released
//! before the copy: on the 2-core VM of the measurements, the page faults of fresh memory and
//! returning it to the system cost more than the copy itself. (Copied before any solve, into
//! fresh memory on every call, the copy cost `solve_batch` 18 % of its throughput on 2 threads,
//! `solve_batch_arrays` 10 %: python/bench/batch.py.)
//!
//! Each problem's own failure (too few points, NaN, degenerate, no consensus, ...) is that
//! problem's result: the exception instance the one-problem function would raise.
//! `solve_batch` and `solve_ransac_batch` then create one Python result object per problem
//! (the `Solution`s themselves are built in the tasks); `solve_batch_arrays` takes stacked
//! arrays and writes every problem's pose into arrays allocated once, from the tasks: no
//! Python object per problem.

use std::collections::HashMap;
use std::mem::MaybeUninit;
use std::ops::Range;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Condvar, Mutex, PoisonError};

use eopnp::camera::Camera;
use eopnp::ransac::problem_seed as seed_of;
use eopnp::ransac::{Ransac, RansacSolution};
use eopnp::{Gravity, Problem};
use eopnp::{PnpError, Rig, Solution, Solver};
use nalgebra::{Point2, Point3};
use numpy::{PyArray1, PyArrayDyn, PyArrayMethods, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::{PyDict, PyList, PyModule, PyString, PyTuple};
use rayon::ThreadPool;

use crate::camera::PyCamera;
use crate::convert::{contiguous_array, points2, points3, readonly, shape_str, vector};
use crate::errors::{
    error, option_error, pnp_error, raise_option_error, shape_error, InvalidInputError,
};
use crate::gravity::PyGravity;
use crate::options::{options_arg, solver_arg, KEYWORDS};
use crate::ransac::{focal_arg, ransac_arg, ransac_info, ransac_rmse_px};
use crate::rig::{rig_error, PyRig, RigError, RigObs};
use crate::solution::{estimated_focal, PySolution};
use crate::solve::{
    check_finite, focal_arg as unknown_focal_arg, problem_with, with_intrinsics, IntrinsicsArg,
};

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

/// `gravity=`: None, one `Gravity` for every problem, or a sequence of one `Gravity` (or None)
/// per problem; each problem's known vertical.
fn gravities(
    py: Python<'_>,
    gravity: Option<&Bound<'_, PyAny>>,
    n: usize,
) -> PyResult<Vec<Option<Gravity>>> {
    let Some(g) = gravity.filter(|g| !g.is_none()) else {
        return Ok(vec![None; n]);
    };
    if let Ok(one) = g.cast::<PyGravity>() {
        return Ok(vec![Some(one.get().inner); n]);
    }
    if g.is_instance_of::<PyString>() {
        return Err(bad_gravity(g, n));
    }
    let bad = || bad_gravity(g, n);
    let list: Vec<Bound<'_, PyAny>> = g.try_iter().map_err(|_| bad())?.collect::<PyResult<_>>()?;
    if list.len() != n {
        return Err(option_error(
            py,
            "gravity",
            format!(
                "gravity: {} entries for {n} problems (give one Gravity or one per problem)",
                list.len()
            ),
        ));
    }
    list.iter()
        .map(|x| {
            if x.is_none() {
                Ok(None)
            } else {
                x.cast::<PyGravity>()
                    .map(|g| Some(g.get().inner))
                    .map_err(|_| bad())
            }
        })
        .collect()
}

/// The error of a `gravity=` that is not None, a `Gravity` or a sequence of them.
fn bad_gravity(g: &Bound<'_, PyAny>, n: usize) -> PyErr {
    option_error(
        g.py(),
        "gravity",
        format!(
            "gravity must be None, a Gravity or a sequence of {n} Gravity or None (one per \
             problem), got {}",
            g.get_type()
                .name()
                .map_or_else(|_| "?".into(), |s| s.to_string())
        ),
    )
}

/// A problem's array as the check left it: a C-contiguous `float64` array of `len` rows, read
/// when its chunk is copied, or its rows already converted (any other array-like, through
/// `convert`'s general path).
enum Source<'py, T> {
    Array(Bound<'py, PyArrayDyn<f64>>, usize),
    Converted(Vec<T>),
}

impl<T> Source<'_, T> {
    fn len(&self) -> usize {
        match self {
            Source::Array(_, n) => *n,
            Source::Converted(v) => v.len(),
        }
    }
}

/// `obj` as a `Source`: a C-contiguous `float64` array of `ndim` dimensions (the last of
/// `cols` entries, when given) as it is, anything else through `convert`.
fn source<'py, T>(
    obj: &Bound<'py, PyAny>,
    ndim: usize,
    cols: Option<usize>,
    convert: impl FnOnce() -> PyResult<Vec<T>>,
) -> PyResult<Source<'py, T>> {
    Ok(match c_array(obj, ndim, cols) {
        Some(a) => {
            let n = a.shape()[0];
            Source::Array(a, n)
        }
        None => Source::Converted(convert()?),
    })
}

/// A problem of a list batch, checked.
struct Entry<'py> {
    world: Source<'py, Point3<f64>>,
    image: Source<'py, Point2<f64>>,
    weights: Option<Source<'py, f64>>,
    /// Index into the batch's cameras.
    camera: Option<usize>,
    /// The known vertical (`gravity=`).
    gravity: Option<Gravity>,
}

/// A list batch, checked: its problems and cameras.
struct ListBatch<'py> {
    entries: Vec<Entry<'py>>,
    cameras: Vec<Bound<'py, PyCamera>>,
}

impl<'py> ListBatch<'py> {
    /// Checks every problem of `problems` (a sequence of `(world, image)` or `(world, image,
    /// weights)` tuples) and `camera=`, raising on the first malformed one with its index in
    /// the message.
    fn new(
        py: Python<'py>,
        problems: &Bound<'py, PyAny>,
        camera: Option<&Bound<'py, PyAny>>,
        gravity: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Self> {
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
        let (cameras, which) = cameras(py, camera, items.len())?;
        let verticals = gravities(py, gravity, items.len())?;
        let mut entries = Vec::with_capacity(items.len());
        for (i, ((item, camera), gravity)) in items.iter().zip(which).zip(verticals).enumerate() {
            let Some(parts) = problem_parts(item) else {
                return Err(problems_error(
                    py,
                    format!(
                        "problems[{i}]: expected a (world, image) or (world, image, weights) \
                         tuple, got {}",
                        item.get_type().name()?
                    ),
                ));
            };
            let world = source(&parts.0, 2, Some(3), || {
                points3(&parts.0, &format!("problems[{i}] world"))
            })?;
            let image = source(&parts.1, 2, Some(2), || {
                points2(&parts.1, &format!("problems[{i}] image"))
            })?;
            let weights = match parts.2.as_ref().filter(|w| !w.is_none()) {
                Some(w) => Some(source(w, 1, None, || {
                    vector(w, &format!("problems[{i}] weights"), false)
                })?),
                None => None,
            };
            entries.push(Entry {
                world,
                image,
                weights,
                camera,
                gravity,
            });
        }
        Ok(ListBatch { entries, cameras })
    }

    /// The points of each kind of the problems `range`.
    fn totals(&self, range: Range<usize>) -> [usize; 3] {
        self.entries[range].iter().fold([0; 3], |[w, i, k], e| {
            [
                w + e.world.len(),
                i + e.image.len(),
                k + e.weights.as_ref().map_or(0, Source::len),
            ]
        })
    }
}

/// Copies the rows of `src` (mapped by `f`) into `out`, which has room for exactly them. An
/// array changed since it was checked (by Python code of another thread, run while an
/// array-like was converted) raises `InvalidInputError` naming it (`name`).
fn put<T: Copy, const C: usize>(
    src: &Source<'_, T>,
    out: &mut [MaybeUninit<T>],
    f: impl Fn(&[f64; C]) -> T,
    name: impl FnOnce() -> String,
) -> PyResult<()> {
    match src {
        Source::Converted(v) => {
            for (o, x) in out.iter_mut().zip(v) {
                o.write(*x);
            }
        }
        Source::Array(a, n) => {
            let ndim = if C == 1 { 1 } else { 2 };
            let fits = c_array(a.as_any(), ndim, (ndim == 2).then_some(C))
                .is_some_and(|a| a.shape()[0] == *n);
            if !fits {
                let name = name();
                return Err(shape_error(
                    a.py(),
                    &name,
                    format!("{name}: the array changed shape or layout during the call"),
                ));
            }
            // SAFETY: C-contiguous and aligned, checked just above; the slice lives only for
            // this copy, made with the GIL held and no Python code running, and nothing in
            // this crate borrows the array mutably.
            let flat = unsafe { a.as_slice() }.expect("checked: C-contiguous and aligned");
            for (o, r) in out.iter_mut().zip(flat.as_chunks::<C>().0) {
                o.write(f(r));
            }
        }
    }
    Ok(())
}

/// One problem of a list batch's chunk: its ranges of the chunk's points, its camera.
struct Item {
    world: Range<usize>,
    image: Range<usize>,
    weights: Option<Range<usize>>,
    camera: Option<usize>,
    gravity: Option<Gravity>,
}

/// A chunk of a list batch, copied: the index of its first problem, its problems' points (one
/// slice per kind) and where each problem's are.
struct Chunk<'b> {
    start: usize,
    items: Vec<Item>,
    world: &'b [Point3<f64>],
    image: &'b [Point2<f64>],
    weights: &'b [f64],
}

impl<'b> Chunk<'b> {
    /// The chunk's problems as their tasks read them.
    fn inputs<'a>(&'a self, cameras: &'a [&'a Camera]) -> impl Iterator<Item = Input<'a>> + 'a
    where
        'b: 'a,
    {
        self.items.iter().map(move |it| Input {
            world: &self.world[it.world.clone()],
            image: &self.image[it.image.clone()],
            weights: it.weights.clone().map(|w| &self.weights[w]),
            camera: it.camera.map(|c| cameras[c]),
            gravity: it.gravity,
        })
    }
}

/// The unwritten rest of a buffer, from which each chunk takes its part.
struct Rest<'b, T>(&'b mut [MaybeUninit<T>]);

impl<'b, T> Rest<'b, T> {
    /// The next `n` elements.
    fn take(&mut self, n: usize) -> &'b mut [MaybeUninit<T>] {
        let (head, tail) = std::mem::take(&mut self.0).split_at_mut(n);
        self.0 = tail;
        head
    }
}

/// `part`, every element of which has been written, as initialised.
fn written<T>(part: &mut [MaybeUninit<T>]) -> &[T] {
    // SAFETY: every element of `part` was written (the callers write all of them, or return an
    // error and drop `part` unread), and `MaybeUninit<T>` has the layout of `T`.
    unsafe { std::slice::from_raw_parts(part.as_ptr().cast::<T>(), part.len()) }
}

impl<'py> ListBatch<'py> {
    /// Copies the problems `range` (a chunk) into `rest`'s next parts.
    fn copy<'b>(
        &self,
        range: Range<usize>,
        rest: &mut (Rest<'b, Point3<f64>>, Rest<'b, Point2<f64>>, Rest<'b, f64>),
    ) -> PyResult<Chunk<'b>> {
        let [nw, ni, nk] = self.totals(range.clone());
        let (world, image, weights) = (rest.0.take(nw), rest.1.take(ni), rest.2.take(nk));
        let mut items = Vec::with_capacity(range.len());
        let (mut w, mut m, mut k) = (0, 0, 0);
        for i in range.clone() {
            let e = &self.entries[i];
            let wr = w..w + e.world.len();
            put(
                &e.world,
                &mut world[wr.clone()],
                |r: &[f64; 3]| Point3::new(r[0], r[1], r[2]),
                || format!("problems[{i}] world"),
            )?;
            let mr = m..m + e.image.len();
            put(
                &e.image,
                &mut image[mr.clone()],
                |r: &[f64; 2]| Point2::new(r[0], r[1]),
                || format!("problems[{i}] image"),
            )?;
            let kr = match &e.weights {
                Some(s) => {
                    let kr = k..k + s.len();
                    put(
                        s,
                        &mut weights[kr.clone()],
                        |r: &[f64; 1]| r[0],
                        || format!("problems[{i}] weights"),
                    )?;
                    Some(kr)
                }
                None => None,
            };
            (w, m, k) = (wr.end, mr.end, kr.as_ref().map_or(k, |r| r.end));
            items.push(Item {
                world: wr,
                image: mr,
                weights: kr,
                camera: e.camera,
                gravity: e.gravity,
            });
        }
        Ok(Chunk {
            start: range.start,
            items,
            world: written(world),
            image: written(image),
            weights: written(weights),
        })
    }
}

/// A batch's copies: one buffer per kind, taken from and given back to `SPARE` (when it is at
/// most `SPARE_BYTES`), so that a call copies into memory an earlier one touched: no page
/// faults, and nothing returned to the system, on every call.
#[derive(Default)]
struct Buffers {
    world: Vec<Point3<f64>>,
    image: Vec<Point2<f64>>,
    weights: Vec<f64>,
}

/// Writes a byte of every page of `buf`: the kernel maps its pages now.
fn touch<T>(buf: &mut [MaybeUninit<T>]) {
    let bytes = buf.as_mut_ptr().cast::<u8>();
    for k in (0..size_of_val(buf)).step_by(4096) {
        // SAFETY: `k` is within `buf`, and any byte of a `MaybeUninit` may be written (volatile:
        // not a store the compiler may drop because the copy overwrites it).
        unsafe { std::ptr::write_volatile(bytes.add(k), 0) };
    }
}

/// The buffers kept for the next batch (at most one set).
static SPARE: Mutex<Option<Buffers>> = Mutex::new(None);

/// The largest buffers kept for the next batch: 64 MiB (a batch of 10,000 problems of 100
/// points, weighted, takes 44 MB).
const SPARE_BYTES: usize = 64 << 20;

impl Buffers {
    /// Buffers for `[world, image, weights]` points (the spare ones, grown if needed), their
    /// memory touched (with the GIL released) when it is new: the page faults of fresh memory
    /// (about 2 us per 4 KiB page on the 2-core VM: docs/python-log.md) are then not paid while
    /// the copy holds the GIL.
    fn take(py: Python<'_>, sizes: [usize; 3]) -> Self {
        let mut b = SPARE
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .take()
            .unwrap_or_default();
        b.world.clear();
        b.image.clear();
        b.weights.clear();
        let before = b.bytes();
        b.world.reserve_exact(sizes[0]);
        b.image.reserve_exact(sizes[1]);
        b.weights.reserve_exact(sizes[2]);
        if b.bytes() != before {
            py.detach(|| {
                touch(b.world.spare_capacity_mut());
                touch(b.image.spare_capacity_mut());
                touch(b.weights.spare_capacity_mut());
            });
        }
        b
    }

    fn bytes(&self) -> usize {
        size_of::<Point3<f64>>() * self.world.capacity()
            + size_of::<Point2<f64>>() * self.image.capacity()
            + size_of::<f64>() * self.weights.capacity()
    }

    /// Gives the buffers back for the next batch (the larger set, if another call gave its own
    /// meanwhile; none above `SPARE_BYTES`).
    fn give_back(self) {
        if self.bytes() > SPARE_BYTES {
            return;
        }
        let mut spare = SPARE.lock().unwrap_or_else(PoisonError::into_inner);
        if spare.as_ref().is_none_or(|s| s.bytes() < self.bytes()) {
            *spare = Some(self);
        }
    }

    /// The unwritten parts of the buffers, `sizes` long.
    fn rest(
        &mut self,
        sizes: [usize; 3],
    ) -> (Rest<'_, Point3<f64>>, Rest<'_, Point2<f64>>, Rest<'_, f64>) {
        (
            Rest(&mut self.world.spare_capacity_mut()[..sizes[0]]),
            Rest(&mut self.image.spare_capacity_mut()[..sizes[1]]),
            Rest(&mut self.weights.spare_capacity_mut()[..sizes[2]]),
        )
    }
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

/// `obj` when it is a C-contiguous, aligned `float64` array of `ndim` dimensions whose last has
/// `cols` entries (`None`: any); `None` for anything else (then the general path of `convert`,
/// with its checks and messages, reads it).
fn c_array<'py>(
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

/// One problem as its task reads it: slices of the call's copies, and its camera.
#[derive(Clone, Copy)]
struct Input<'a> {
    world: &'a [Point3<f64>],
    image: &'a [Point2<f64>],
    weights: Option<&'a [f64]>,
    camera: Option<&'a Camera>,
    gravity: Option<Gravity>,
}

impl<'a> Input<'a> {
    /// The crate's problem (normalised points with `focal`, or pixels through the camera),
    /// with its weights, known vertical and unknown focal length (`unknown`), after the
    /// package's own check of pixel input (a NaN pixel is rejected, as `solve` rejects it; the
    /// library would skip it as one that cannot be undistorted).
    fn problem(&self, focal: (f64, f64), unknown: IntrinsicsArg) -> Result<Problem<'a>, PnpError> {
        let p = match self.camera {
            Some(c) => {
                check_finite(self.world, self.image, self.weights)?;
                Problem::pixels(self.world, self.image, c)
            }
            None => Problem::normalised(self.world, self.image).focal(focal.0, focal.1),
        };
        Ok(with_intrinsics(
            problem_with(p, self.weights, self.gravity),
            unknown,
        ))
    }

    /// `solve` on this problem.
    fn solve(&self, solver: &Solver, unknown: IntrinsicsArg) -> Result<Solution, PnpError> {
        solver.solve(&self.problem((1.0, 1.0), unknown)?)
    }
}

/// The pools of `threads=`, by thread count.
static POOLS: Mutex<Option<HashMap<usize, Arc<ThreadPool>>>> = Mutex::new(None);

/// The pool of `threads=`: None for rayon's global pool, or a cached pool of `threads`
/// threads.
fn pool(py: Python<'_>, threads: Option<i64>) -> PyResult<Option<Arc<ThreadPool>>> {
    let Some(n) = threads else {
        return Ok(None);
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
    let mut pools = POOLS.lock().unwrap_or_else(PoisonError::into_inner);
    let pools = pools.get_or_insert_with(HashMap::new);
    if let Some(p) = pools.get(&n) {
        return Ok(Some(Arc::clone(p)));
    }
    let p = rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .thread_name(|i| format!("eopnp-{i}"))
        .build()
        .map_err(|e| option_error(py, "threads", format!("threads: {e}")))?;
    let p = Arc::new(p);
    pools.insert(n, Arc::clone(&p));
    Ok(Some(p))
}

/// Runs `f` on rayon's global pool (`threads` None) or on a cached pool of `threads` threads,
/// with the GIL released.
pub(crate) fn in_pool<T: Send>(
    py: Python<'_>,
    threads: Option<i64>,
    f: impl FnOnce() -> T + Send,
) -> PyResult<T> {
    Ok(match pool(py, threads)? {
        None => py.detach(f),
        Some(p) => py.detach(|| p.install(f)),
    })
}

/// The number of problems per chunk of a pipelined batch of `n` problems on `threads`
/// threads: at least 4 chunks per thread (for the balance between the threads), at most 64
/// problems (the first chunk, copied before any thread starts, stays short).
fn chunk_len(n: usize, threads: usize) -> usize {
    n.div_ceil(4 * threads.max(1)).clamp(1, 64)
}

/// Counts the chunks solved, for the calling thread to wait on with the GIL released.
#[derive(Default)]
struct Latch {
    done: Mutex<usize>,
    changed: Condvar,
}

impl Latch {
    fn wait(&self, n: usize) {
        let mut done = self.done.lock().unwrap_or_else(PoisonError::into_inner);
        while *done < n {
            done = self
                .changed
                .wait(done)
                .unwrap_or_else(PoisonError::into_inner);
        }
    }
}

/// Counts one chunk as done when dropped (also when its task panics).
struct Done<'a>(&'a Latch);

impl Drop for Done<'_> {
    fn drop(&mut self) {
        *self.0.done.lock().unwrap_or_else(PoisonError::into_inner) += 1;
        self.0.changed.notify_all();
    }
}

/// Solves a batch chunk by chunk (`sinks`: one per chunk, where its results go), the copy of
/// the inputs pipelined with the solves: on the calling thread, with the GIL held, `copy(k)`
/// copies chunk `k`'s inputs into memory of the call's own, and the copy is handed to the
/// pool, where `work(copy, sink)` solves it, while the calling thread copies the next chunk.
/// Once every chunk is copied, the GIL is released until every chunk is solved: the calling
/// thread never waits for the pool with the GIL held, and no task reads a caller's buffer.
///
/// An error of `copy` stops the copying; the chunks not yet started are skipped, and the
/// error is returned once the others have finished.
fn pipelined<C: Send, S: Send>(
    py: Python<'_>,
    pool: Option<&ThreadPool>,
    sinks: Vec<S>,
    mut copy: impl FnMut(usize) -> PyResult<C>,
    work: impl Fn(C, S) + Sync,
) -> PyResult<()> {
    let latch = Latch::default();
    let cancel = AtomicBool::new(false);
    let shared = (&work, &latch, &cancel);
    match pool {
        Some(p) => p.in_place_scope(|scope| feed(py, scope, sinks, &mut copy, shared)),
        None => rayon::in_place_scope(|scope| feed(py, scope, sinks, &mut copy, shared)),
    }
}

/// `pipelined`'s calling thread, in the scope of the tasks it spawns.
fn feed<'scope, C: Send + 'scope, S: Send + 'scope, W: Fn(C, S) + Sync>(
    py: Python<'_>,
    scope: &rayon::Scope<'scope>,
    sinks: Vec<S>,
    copy: &mut impl FnMut(usize) -> PyResult<C>,
    (work, latch, cancel): (&'scope W, &'scope Latch, &'scope AtomicBool),
) -> PyResult<()> {
    let mut handed = 0;
    let mut result = Ok(());
    for (k, sink) in sinks.into_iter().enumerate() {
        match copy(k) {
            Ok(chunk) => {
                handed += 1;
                scope.spawn(move |_| {
                    let _done = Done(latch);
                    if !cancel.load(Ordering::Relaxed) {
                        work(chunk, sink);
                    }
                });
            }
            Err(e) => {
                cancel.store(true, Ordering::Relaxed);
                result = Err(e);
                break;
            }
        }
    }
    // Every task handed over is done before the scope ends: the scope's own wait, with the
    // GIL held, is then immediate.
    py.detach(|| latch.wait(handed));
    result
}

/// The number of threads of `pool` (None: rayon's global pool).
fn threads_of(pool: Option<&ThreadPool>) -> usize {
    pool.map_or_else(rayon::current_num_threads, ThreadPool::current_num_threads)
}

/// Solves many independent problems in parallel (``solve`` on each), the GIL released while
/// they are solved.
///
/// Each array is copied once, with the GIL held, and the solves read the copy (as ``solve``
/// does): what other threads write to the arrays after the call copied them does not change
/// its results.
///
/// Args:
///     problems: a sequence of ``(world, image)`` or ``(world, image, weights)`` tuples, as
///         ``solve``'s arguments (weights may be None).
///     camera: None (normalised image points), a ``Camera`` for every problem, or a sequence
///         of one ``Camera`` per problem (image points in pixels).
///     gravity: None, a ``Gravity`` for every problem, or a sequence of one ``Gravity`` (or
///         None) per problem: the known vertical, as ``solve``'s.
///     estimate_focal: every problem's focal length is unknown, as ``solve``'s (``camera``
///         required: each problem's camera's focal length is its starting guess).
///     focal_range: ``(min_px, max_px)``, as ``solve``'s, for every problem (implies
///         ``estimate_focal``).
///     refine_principal_point: every problem's principal point is refined, as ``solve``'s.
///     refine_distortion: every problem's distortion parameters are refined, as ``solve``'s.
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
///     InvalidOptionError: an option out of range, a bad ``camera``, ``gravity`` or
///         ``threads``; an unknown focal length without ``camera``, with a known vertical or
///         an empty ``focal_range`` (``option`` "unknown_focal"): raised, as by ``solve``,
///         not returned per problem.
///     TypeError: as ``solve``.
#[pyfunction]
#[pyo3(signature = (problems, *, camera = None, gravity = None, estimate_focal = false,
    focal_range = None, refine_principal_point = false, refine_distortion = false,
    options = None, threads = None, **keywords))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn solve_batch<'py>(
    py: Python<'py>,
    problems: &Bound<'py, PyAny>,
    camera: Option<&Bound<'py, PyAny>>,
    gravity: Option<&Bound<'py, PyAny>>,
    estimate_focal: bool,
    focal_range: Option<&Bound<'_, PyAny>>,
    refine_principal_point: bool,
    refine_distortion: bool,
    options: Option<&Bound<'py, PyAny>>,
    threads: Option<i64>,
    keywords: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyList>> {
    let solver = solver_arg(py, "solve_batch", options, keywords, KEYWORDS)?;
    let unknown = unknown_focal_arg(estimate_focal, focal_range)?
        .refining(refine_principal_point, refine_distortion);
    let batch = ListBatch::new(py, problems, camera, gravity)?;
    let pool = pool(py, threads)?;
    let n = batch.entries.len();
    let len = chunk_len(n, threads_of(pool.as_deref()));
    let cams: Vec<&Camera> = batch.cameras.iter().map(|c| &c.get().inner).collect();
    let sizes = batch.totals(0..n);
    let mut buffers = Buffers::take(py, sizes);
    let mut rest = buffers.rest(sizes);
    let mut results: Vec<Option<Result<PySolution, PnpError>>> = (0..n).map(|_| None).collect();
    let done = pipelined(
        py,
        pool.as_deref(),
        results.chunks_mut(len).collect(),
        |k| batch.copy(k * len..((k + 1) * len).min(n), &mut rest),
        |chunk: Chunk<'_>, out: &mut [Option<Result<PySolution, PnpError>>]| {
            for (slot, p) in out.iter_mut().zip(chunk.inputs(&cams)) {
                *slot = Some(p.solve(&solver, unknown).map(|s| PySolution::from(&s)));
            }
        },
    );
    buffers.give_back();
    done?;
    raise_option_error(
        py,
        results
            .iter()
            .filter_map(|r| r.as_ref().and_then(|r| r.as_ref().err())),
    )?;
    let out = PyList::empty(py);
    for r in results {
        match r.expect("every chunk solved") {
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
/// `world`, must match), C-contiguous `float64` (converted once when it is not), borrowed
/// read-only for the call's copy.
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
    readonly(&a, name)
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

/// A chunk of rows of `solve_batch_arrays`'s stacked arrays, copied: its first problem's index
/// and its problems' points, N per problem.
struct RowsIn<'b> {
    start: usize,
    world: &'b [Point3<f64>],
    image: &'b [Point2<f64>],
    weights: Option<&'b [f64]>,
}

/// A chunk's rows of `solve_batch_arrays`'s outputs, and its errors.
struct Rows<'a> {
    r: &'a mut [f64],
    t: &'a mut [f64],
    cost: &'a mut [f64],
    rmse: &'a mut [f64],
    ok: &'a mut [bool],
    cov: Option<(&'a mut [f64], &'a mut [f64])>,
    focal: Option<&'a mut [f64]>,
    errors: &'a mut Vec<(usize, PnpError)>,
}

/// Solves a batch of problems given as stacked arrays (``solve`` on each), in parallel with the
/// GIL released, and returns the poses as stacked arrays: the form for throughput (no Python
/// object per problem).
///
/// Each array is copied once, with the GIL held, and the solves read the copy (as ``solve``
/// does): what other threads write to the arrays after the call copied them does not change
/// its results. Any array-like of real numbers is accepted.
///
/// Args:
///     world: world points of every problem, shape (B, N, 3).
///     image: their image points, shape (B, N, 2): normalised, or pixels with ``camera``.
///     weights: optional non-negative weights, shape (B, N), as ``solve``'s. Problems with
///         fewer points: pad them (any finite values) with weight 0, which ``solve`` ignores
///         exactly as if the points were dropped; or use ``solve_batch``.
///     camera: None (normalised image points), a ``Camera`` for every problem, or a sequence
///         of B ``Camera`` (pixels).
///     gravity: None, a ``Gravity`` for every problem, or a sequence of B ``Gravity`` (or
///         None), as ``solve``'s.
///     estimate_focal: every problem's focal length is unknown, as ``solve``'s (``camera``
///         required); the estimates in ``BatchResult.focal``.
///     focal_range: ``(min_px, max_px)``, as ``solve``'s, for every problem (implies
///         ``estimate_focal``).
///     options: a ``SolverOptions`` (or a dict of its fields), as ``solve``, for every
///         problem.
///     threads: as ``solve_batch``.
///     **keywords: the options of ``SolverOptions`` as keyword arguments instead, as
///         ``solve``.
///
/// Returns:
///     BatchResult: ``R`` (B, 3, 3), ``t`` (B, 3), ``cost`` (B,), ``reprojection_rmse``
///     (B,), ``ok`` (B,) bool, ``covariance`` (B, 6, 6) and ``sigma`` (B,) with a
///     ``covariance`` option (else None), ``focal`` (B, 2) with ``estimate_focal`` (else None),
///     and ``errors``: {index: the exception ``solve`` would raise for that problem} (its rows
///     are NaN and ``ok`` False). Row ``i`` equals ``solve(world[i], image[i], weights[i],
///     ...)`` exactly, whatever the thread count.
///
/// Raises:
///     InvalidInputError: an array of the wrong shape (world not (B, N, 3), image not
///         (B, N, 2) or weights not (B, N) with world's B and N), before anything is solved.
///     InputTypeError: an array that is not real numbers.
///     InvalidOptionError: an option out of range, a bad ``camera``, ``gravity`` or
///         ``threads``; an unknown focal length as ``solve_batch`` (raised).
///     TypeError: as ``solve``.
#[pyfunction]
#[pyo3(signature = (world, image, weights = None, *, camera = None, gravity = None,
    estimate_focal = false, focal_range = None, options = None, threads = None, **keywords))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn solve_batch_arrays<'py>(
    world: &Bound<'py, PyAny>,
    image: &Bound<'py, PyAny>,
    weights: Option<&Bound<'py, PyAny>>,
    camera: Option<&Bound<'py, PyAny>>,
    gravity: Option<&Bound<'py, PyAny>>,
    estimate_focal: bool,
    focal_range: Option<&Bound<'_, PyAny>>,
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
    let verticals = gravities(py, gravity, b)?;
    let unknown = unknown_focal_arg(estimate_focal, focal_range)?;
    let pool = pool(py, threads)?;
    let len = chunk_len(b, threads_of(pool.as_deref()));

    let want_cov = options.wants_covariance();
    let r_out = output(py, &[b, 3, 3]);
    let t_out = output(py, &[b, 3]);
    let cost_out = output(py, &[b]);
    let rmse_out = output(py, &[b]);
    // Not `zeros`: numpy's zeroed allocation (calloc) releases the GIL for a large array, which
    // would let other threads write the inputs before they are copied (found by
    // tests/test_batch_copies.py). Zeroed here, with the GIL held.
    // SAFETY: a new array of `b` bools; its bytes are set to 0 (false) before any reference to
    // them is made.
    let ok_out = unsafe {
        let a = PyArray1::<bool>::new(py, b, false);
        std::ptr::write_bytes(a.data(), 0, b);
        a
    };
    let cov_out = want_cov.then(|| (output(py, &[b, 6, 6]), output(py, &[b])));
    let focal_out = unknown.focal.is_some().then(|| output(py, &[b, 2]));
    // SAFETY: new arrays, referenced by nothing else until they are returned.
    let (r, t, cost, rmse, ok, cov, focal) = unsafe {
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
            focal_out
                .as_ref()
                .map(|f| f.as_slice_mut().expect("new array")),
        )
    };
    let chunks = b.div_ceil(len);
    let mut errors: Vec<Vec<(usize, PnpError)>> = (0..chunks).map(|_| Vec::new()).collect();
    let covs: Vec<Option<(&mut [f64], &mut [f64])>> = match cov {
        Some((c, s)) => c
            .chunks_mut(36 * len)
            .zip(s.chunks_mut(len))
            .map(Some)
            .collect(),
        None => (0..chunks).map(|_| None).collect(),
    };
    let focals: Vec<Option<&mut [f64]>> = match focal {
        Some(f) => f.chunks_mut(2 * len).map(Some).collect(),
        None => (0..chunks).map(|_| None).collect(),
    };
    let sinks: Vec<Rows<'_>> = r
        .chunks_mut(9 * len)
        .zip(t.chunks_mut(3 * len))
        .zip(cost.chunks_mut(len))
        .zip(rmse.chunks_mut(len))
        .zip(ok.chunks_mut(len))
        .zip(covs)
        .zip(focals)
        .zip(errors.iter_mut())
        .map(
            |(((((((r, t), cost), rmse), ok), cov), focal), errors)| Rows {
                r,
                t,
                cost,
                rmse,
                ok,
                cov,
                focal,
                errors,
            },
        )
        .collect();
    let (ws, ms) = (
        w.as_slice().expect("contiguous"),
        m.as_slice().expect("contiguous"),
    );
    let wts = wt.as_ref().map(|x| x.as_slice().expect("contiguous"));
    let sizes = [b * n, b * n, if wts.is_some() { b * n } else { 0 }];
    let mut buffers = Buffers::take(py, sizes);
    let mut rest = buffers.rest(sizes);
    let done = pipelined(
        py,
        pool.as_deref(),
        sinks,
        // The rows of chunk `k`, copied with the GIL held (the arrays borrowed read-only).
        |k| {
            let rows = k * len..((k + 1) * len).min(b);
            let points = rows.start * n..rows.end * n;
            let (world, image) = (rest.0.take(points.len()), rest.1.take(points.len()));
            let src = ws[3 * points.start..3 * points.end].as_chunks::<3>().0;
            for (o, r) in world.iter_mut().zip(src) {
                o.write(Point3::new(r[0], r[1], r[2]));
            }
            let src = ms[2 * points.start..2 * points.end].as_chunks::<2>().0;
            for (o, r) in image.iter_mut().zip(src) {
                o.write(Point2::new(r[0], r[1]));
            }
            let weights = wts.map(|x| {
                let out = rest.2.take(points.len());
                for (o, v) in out.iter_mut().zip(&x[points.clone()]) {
                    o.write(*v);
                }
                written(out)
            });
            Ok(RowsIn {
                start: rows.start,
                world: written(world),
                image: written(image),
                weights,
            })
        },
        |input: RowsIn<'_>, out: Rows<'_>| {
            let Rows {
                r,
                t,
                cost,
                rmse,
                ok,
                mut cov,
                mut focal,
                errors,
            } = out;
            for j in 0..ok.len() {
                let i = input.start + j;
                let p = Input {
                    world: &input.world[j * n..(j + 1) * n],
                    image: &input.image[j * n..(j + 1) * n],
                    weights: input.weights.map(|x| &x[j * n..(j + 1) * n]),
                    camera: which[i].map(|c| cams[c]),
                    gravity: verticals[i],
                };
                let res = p.solve(&solver, unknown);
                if let Some(f) = focal.as_deref_mut() {
                    let f = &mut f[2 * j..2 * (j + 1)];
                    match res.as_ref().ok().and_then(estimated_focal) {
                        Some((fx, fy)) => f.copy_from_slice(&[fx, fy]),
                        None => f.fill(f64::NAN),
                    }
                }
                let cov = cov
                    .as_mut()
                    .map(|(c, s)| (&mut c[36 * j..36 * (j + 1)], &mut s[j]));
                write_row(
                    &res,
                    &mut r[9 * j..9 * (j + 1)],
                    &mut t[3 * j..3 * (j + 1)],
                    &mut cost[j],
                    &mut rmse[j],
                    &mut ok[j],
                    cov,
                );
                if let Err(e) = res {
                    errors.push((i, e));
                }
            }
        },
    );
    buffers.give_back();
    done?;
    drop((w, m, wt));
    raise_option_error(py, errors.iter().flatten().map(|(_, e)| e))?;

    let errs = PyDict::new(py);
    for (i, e) in errors.iter().flatten() {
        errs.set_item(*i, pnp_error(py, e).into_value(py))?;
    }
    let module = BATCH.get_or_try_init(py, || {
        PyModule::import(py, "eopnp._batch").map(Bound::unbind)
    })?;
    let (cov, sigma) = match cov_out {
        Some((c, s)) => (c.into_any(), s.into_any()),
        None => (py.None().into_bound(py), py.None().into_bound(py)),
    };
    let focal = match focal_out {
        Some(f) => f.into_any(),
        None => py.None().into_bound(py),
    };
    module.bind(py).getattr("BatchResult")?.call1((
        r_out, t_out, cost_out, rmse_out, ok_out, cov, sigma, errs, focal,
    ))
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
///     gravity: None, a ``Gravity`` for every problem, or a sequence of one ``Gravity`` (or
///         None) per problem, as ``solve_ransac``'s.
///     estimate_focal: every problem's focal length is unknown, as ``solve_ransac``'s
///         (``camera`` required).
///     focal_range: ``(min_px, max_px)``, as ``solve_ransac``'s, for every problem.
///     refine_principal_point: every problem's principal point is refined, as ``solve``'s.
///     refine_distortion: every problem's distortion parameters are refined, as ``solve``'s.
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
#[pyo3(signature = (problems, *, camera = None, focal = None, gravity = None,
    estimate_focal = false, focal_range = None, refine_principal_point = false,
    refine_distortion = false, ransac = None, options = None, threads = None,
    **keywords))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn solve_ransac_batch<'py>(
    problems: &Bound<'py, PyAny>,
    camera: Option<&Bound<'py, PyAny>>,
    focal: Option<&Bound<'py, PyAny>>,
    gravity: Option<&Bound<'py, PyAny>>,
    estimate_focal: bool,
    focal_range: Option<&Bound<'_, PyAny>>,
    refine_principal_point: bool,
    refine_distortion: bool,
    ransac: Option<&Bound<'py, PyAny>>,
    options: Option<&Bound<'py, PyAny>>,
    threads: Option<i64>,
    keywords: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyList>> {
    let py = problems.py();
    let solver = solver_arg(py, "solve_ransac_batch", options, keywords, KEYWORDS)?;
    let ransac = ransac_arg(py, ransac)?;
    let unknown = unknown_focal_arg(estimate_focal, focal_range)?
        .refining(refine_principal_point, refine_distortion);
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
    let batch = ListBatch::new(py, problems, camera, gravity)?;
    let pool = pool(py, threads)?;
    let n = batch.entries.len();
    let len = chunk_len(n, threads_of(pool.as_deref()));
    let cams: Vec<&Camera> = batch.cameras.iter().map(|c| &c.get().inner).collect();
    let sizes = batch.totals(0..n);
    let mut buffers = Buffers::take(py, sizes);
    let mut rest = buffers.rest(sizes);
    let mut results: Vec<Option<Estimate>> = (0..n).map(|_| None).collect();
    let done = pipelined(
        py,
        pool.as_deref(),
        results.chunks_mut(len).collect(),
        |k| batch.copy(k * len..((k + 1) * len).min(n), &mut rest),
        |chunk: Chunk<'_>, out: &mut [Option<Estimate>]| {
            for (j, (slot, p)) in out.iter_mut().zip(chunk.inputs(&cams)).enumerate() {
                *slot = Some(estimate(
                    &ransac,
                    &solver,
                    chunk.start + j,
                    &p,
                    focal,
                    unknown,
                ));
            }
        },
    );
    buffers.give_back();
    done?;
    let results: Vec<Estimate> = results
        .into_iter()
        .map(|r| r.expect("every chunk solved"))
        .collect();
    raise_option_error(py, results.iter().filter_map(|r| r.as_ref().err()))?;
    let out = PyList::empty(py);
    for r in results {
        match r {
            Ok((sol, r, px)) => out.append((sol, ransac_info(py, &r, px)?))?,
            Err(e) => out.append(pnp_error(py, &e).into_value(py))?,
        }
    }
    Ok(out)
}

/// A problem's result of `solve_ransac_batch`: the solution, the crate's result and the info's
/// `rmse_px`.
type Estimate = Result<(PySolution, RansacSolution, f64), PnpError>;

/// `solve_ransac` on problem `index` of a batch (seed `problem_seed(ransac.seed, index)`).
fn estimate(
    ransac: &Ransac,
    solver: &Solver,
    index: usize,
    p: &Input<'_>,
    focal: Option<(f64, f64)>,
    unknown: IntrinsicsArg,
) -> Estimate {
    let problem = p.problem(focal.unwrap_or((1.0, 1.0)), unknown)?;
    let r = ransac
        .seed(seed_of(ransac.seed, index))
        .estimate(solver, &problem)?;
    let sol = PySolution::from(&r.solution);
    let px = ransac_rmse_px(&sol, &r, p.world, p.image, p.camera, focal);
    Ok((sol, r, px))
}

/// The RANSAC seed of problem ``index`` of a batch whose base seed is ``base``
/// (``solve_ransac_batch``): ``solve_ransac(..., ransac=RansacOptions(seed=problem_seed(base,
/// i)))`` equals entry ``i`` of the batch.
#[pyfunction]
pub(crate) fn problem_seed(base: u64, index: usize) -> u64 {
    seed_of(base, index)
}

/// `rig=` of the rig batches: one `Rig` for every problem, or a sequence of one per problem;
/// the batch's rigs and each problem's index into them.
fn rigs<'py>(
    py: Python<'py>,
    rig: &Bound<'py, PyAny>,
    n: usize,
) -> PyResult<(Vec<Bound<'py, PyRig>>, Vec<usize>)> {
    if let Ok(one) = rig.cast::<PyRig>() {
        return Ok((vec![one.clone()], vec![0; n]));
    }
    let bad = || {
        option_error(
            py,
            "rig",
            format!(
                "rig must be a Rig or a sequence of {n} Rigs (one per problem), got {}",
                rig.get_type()
                    .name()
                    .map_or_else(|_| "?".into(), |s| s.to_string())
            ),
        )
    };
    let list: Vec<Bound<'py, PyAny>> = rig
        .try_iter()
        .map_err(|_| bad())?
        .collect::<PyResult<_>>()?;
    if list.len() != n {
        return Err(option_error(
            py,
            "rig",
            format!(
                "rig: {} rigs for {n} problems (give one Rig or one per problem)",
                list.len()
            ),
        ));
    }
    let rigs = list
        .into_iter()
        .map(|x| x.cast_into::<PyRig>().map_err(|_| bad()))
        .collect::<PyResult<Vec<_>>>()?;
    Ok((rigs, (0..n).collect()))
}

/// A problem of a rig batch: `(points2D, points3D, camera_idxs)` or `(points2D, points3D,
/// camera_idxs, weights)`, a tuple or list; `None` for anything else.
fn rig_parts<'py>(item: &Bound<'py, PyAny>) -> Option<[Option<Bound<'py, PyAny>>; 4]> {
    let list: Vec<Bound<'py, PyAny>> = if let Ok(t) = item.cast::<PyTuple>() {
        t.iter().collect()
    } else if let Ok(l) = item.cast::<PyList>() {
        l.iter().collect()
    } else {
        return None;
    };
    if !(list.len() == 3 || list.len() == 4) {
        return None;
    }
    let mut it = list.into_iter();
    Some([it.next(), it.next(), it.next(), it.next()])
}

/// A rig batch, checked: its problems as a list batch (each entry's `camera` is the index of
/// its rig), each problem's camera indices (copied here, with the GIL held, as the one-problem
/// functions copy them), and the rigs.
struct RigBatch<'py> {
    list: ListBatch<'py>,
    indices: Vec<Vec<i64>>,
    rigs: Vec<Bound<'py, PyRig>>,
}

impl<'py> RigBatch<'py> {
    /// Checks every problem of `problems` and `rig=`, raising on the first malformed one with
    /// its index in the message.
    fn new(
        py: Python<'py>,
        problems: &Bound<'py, PyAny>,
        rig: &Bound<'py, PyAny>,
        gravity: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Self> {
        let expected = "(points2D, points3D, camera_idxs) or (points2D, points3D, camera_idxs, \
                        weights) tuple";
        let items: Vec<Bound<'py, PyAny>> = problems
            .try_iter()
            .map_err(|_| {
                problems_error(py, format!("problems: expected a sequence of {expected}s"))
            })?
            .collect::<PyResult<_>>()?;
        let (rigs, which) = rigs(py, rig, items.len())?;
        let verticals = gravities(py, gravity, items.len())?;
        let mut entries = Vec::with_capacity(items.len());
        let mut indices = Vec::with_capacity(items.len());
        for (i, ((item, r), gravity)) in items.iter().zip(which).zip(verticals).enumerate() {
            let Some([Some(p2), Some(p3), Some(idx), w]) = rig_parts(item) else {
                return Err(problems_error(
                    py,
                    format!(
                        "problems[{i}]: expected a {expected}, got {}",
                        item.get_type().name()?
                    ),
                ));
            };
            let image = source(&p2, 2, Some(2), || {
                points2(&p2, &format!("problems[{i}] points2D"))
            })?;
            let world = source(&p3, 2, Some(3), || {
                points3(&p3, &format!("problems[{i}] points3D"))
            })?;
            indices.push(crate::convert::indices(
                &idx,
                &format!("problems[{i}] camera_idxs"),
            )?);
            let weights = match w.as_ref().filter(|w| !w.is_none()) {
                Some(w) => Some(source(w, 1, None, || {
                    vector(w, &format!("problems[{i}] weights"), false)
                })?),
                None => None,
            };
            entries.push(Entry {
                world,
                image,
                weights,
                camera: Some(r),
                gravity,
            });
        }
        Ok(RigBatch {
            list: ListBatch {
                entries,
                cameras: Vec::new(),
            },
            indices,
            rigs,
        })
    }
}

impl Chunk<'_> {
    /// The chunk's problems of a rig batch, as their tasks read them.
    fn rig_problems<'a>(
        &'a self,
        indices: &'a [Vec<i64>],
        rigs: &'a [&'a Rig],
    ) -> impl Iterator<Item = RigObs<'a>> + 'a {
        self.items.iter().enumerate().map(move |(j, it)| RigObs {
            world: &self.world[it.world.clone()],
            image: &self.image[it.image.clone()],
            cameras: &indices[self.start + j],
            weights: it.weights.clone().map(|w| &self.weights[w]),
            rig: rigs[it.camera.expect("a rig batch's problems have a rig")],
            gravity: it.gravity,
        })
    }
}

/// A rig batch's serial setup and pipelined solves: `work(problem index, problem)` gives each
/// problem's result, on the pool's threads with the GIL released.
fn run_rig_batch<'py, T: Send>(
    py: Python<'py>,
    batch: &RigBatch<'py>,
    threads: Option<i64>,
    work: impl Fn(usize, &RigObs<'_>) -> T + Sync,
) -> PyResult<Vec<T>> {
    let pool = pool(py, threads)?;
    let n = batch.list.entries.len();
    let len = chunk_len(n, threads_of(pool.as_deref()));
    let rigs: Vec<&Rig> = batch.rigs.iter().map(|r| &r.get().inner).collect();
    let indices = &batch.indices;
    let sizes = batch.list.totals(0..n);
    let mut buffers = Buffers::take(py, sizes);
    let mut rest = buffers.rest(sizes);
    let mut results: Vec<Option<T>> = (0..n).map(|_| None).collect();
    let done = pipelined(
        py,
        pool.as_deref(),
        results.chunks_mut(len).collect(),
        |k| batch.list.copy(k * len..((k + 1) * len).min(n), &mut rest),
        |chunk: Chunk<'_>, out: &mut [Option<T>]| {
            for (j, (slot, p)) in out
                .iter_mut()
                .zip(chunk.rig_problems(indices, &rigs))
                .enumerate()
            {
                *slot = Some(work(chunk.start + j, &p));
            }
        },
    );
    buffers.give_back();
    done?;
    Ok(results
        .into_iter()
        .map(|r| r.expect("every chunk solved"))
        .collect())
}

/// Solves many independent rig problems in parallel (``solve_generalized`` on each), the GIL
/// released while they are solved.
///
/// Each array is copied once, with the GIL held, and the solves read the copy (as
/// ``solve_generalized`` does): what other threads write to the arrays after the call copied
/// them does not change its results.
///
/// Args:
///     problems: a sequence of ``(points2D, points3D, camera_idxs)`` or ``(points2D, points3D,
///         camera_idxs, weights)`` tuples, as ``solve_generalized``'s arguments (pixels first;
///         weights may be None).
///     rig: a ``Rig`` for every problem, or a sequence of one ``Rig`` per problem.
///     gravity: None, a ``Gravity`` for every problem, or a sequence of one ``Gravity`` (or
///         None) per problem: the known vertical in the rig's frame, as
///         ``solve_generalized``'s.
///     options: a ``SolverOptions`` (or a dict of its fields), as ``solve_generalized``, for
///         every problem.
///     threads: as ``solve_batch``.
///     **keywords: the options of ``SolverOptions`` as keyword arguments instead, as
///         ``solve``.
///
/// Returns:
///     list: one entry per problem, in order: its ``Solution`` (the rig's pose), or the
///     exception instance that ``solve_generalized`` would raise for it. Each entry equals
///     ``solve_generalized``'s, whatever the thread count.
///
/// Raises:
///     InvalidInputError: a malformed batch (not a sequence of 3- or 4-tuples, an array of the
///         wrong shape; the message names the problem's index), before anything is solved.
///     InputTypeError: an array that is not real numbers, camera indices that are not
///         integers.
///     InvalidOptionError: an option out of range, a bad ``rig``, ``gravity`` or ``threads``.
///     TypeError: as ``solve``.
#[pyfunction]
#[pyo3(signature = (problems, *, rig, gravity = None, options = None, threads = None,
    **keywords))]
pub(crate) fn solve_generalized_batch<'py>(
    py: Python<'py>,
    problems: &Bound<'py, PyAny>,
    rig: &Bound<'py, PyAny>,
    gravity: Option<&Bound<'py, PyAny>>,
    options: Option<&Bound<'py, PyAny>>,
    threads: Option<i64>,
    keywords: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyList>> {
    let solver = solver_arg(py, "solve_generalized_batch", options, keywords, KEYWORDS)?;
    let batch = RigBatch::new(py, problems, rig, gravity)?;
    let results = run_rig_batch(py, &batch, threads, |_, p| {
        p.solve(&solver).map(|s| PySolution::from(&s))
    })?;
    let out = PyList::empty(py);
    for r in results {
        match r {
            Ok(s) => out.append(untracked(Bound::new(py, s)?))?,
            Err(e) => out.append(rig_error(py, &e).into_value(py))?,
        }
    }
    Ok(out)
}

/// Robust estimation of many independent rig problems in parallel
/// (``solve_generalized_ransac`` on each), the GIL released for the whole batch. Problem
/// ``i`` uses the seed ``problem_seed(ransac.seed, i)``, so results do not depend on the
/// thread count.
///
/// Args:
///     problems: as ``solve_generalized_batch``.
///     rig: a ``Rig`` for every problem, or a sequence of one ``Rig`` per problem.
///     gravity: None, a ``Gravity`` for every problem, or a sequence of one ``Gravity`` (or
///         None) per problem, as ``solve_generalized_ransac``'s.
///     ransac: a ``RansacOptions``, a dict of its fields, or None; ``seed`` is the base seed.
///     options: a ``SolverOptions`` (or a dict of its fields), as
///         ``solve_generalized_ransac``, for every problem.
///     threads: as ``solve_batch``.
///     **keywords: the options of ``SolverOptions`` as keyword arguments instead, as
///         ``solve``.
///
/// Returns:
///     list: one entry per problem, in order: ``(Solution, info)`` as
///     ``solve_generalized_ransac`` returns with ``RansacOptions(seed=problem_seed(seed,
///     i))``, or the exception instance it would raise (e.g. ``NoConsensusError``).
///
/// Raises:
///     As ``solve_generalized_batch``.
#[pyfunction]
#[pyo3(signature = (problems, *, rig, gravity = None, ransac = None, options = None,
    threads = None, **keywords))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn solve_generalized_ransac_batch<'py>(
    py: Python<'py>,
    problems: &Bound<'py, PyAny>,
    rig: &Bound<'py, PyAny>,
    gravity: Option<&Bound<'py, PyAny>>,
    ransac: Option<&Bound<'py, PyAny>>,
    options: Option<&Bound<'py, PyAny>>,
    threads: Option<i64>,
    keywords: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyList>> {
    let solver = solver_arg(
        py,
        "solve_generalized_ransac_batch",
        options,
        keywords,
        KEYWORDS,
    )?;
    let ransac = ransac_arg(py, ransac)?;
    let batch = RigBatch::new(py, problems, rig, gravity)?;
    let results = run_rig_batch(py, &batch, threads, |i, p| {
        let r = ransac.seed(seed_of(ransac.seed, i));
        p.estimate(&r, &solver)
            .map(|(r, px)| (PySolution::from(&r.solution), r, px))
    })?;
    raise_option_error(
        py,
        results.iter().filter_map(|r| match r {
            Err(RigError::Pnp(e)) => Some(e),
            _ => None,
        }),
    )?;
    let out = PyList::empty(py);
    for r in results {
        match r {
            Ok((sol, r, px)) => out.append((sol, ransac_info(py, &r, px)?))?,
            Err(e) => out.append(rig_error(py, &e).into_value(py))?,
        }
    }
    Ok(out)
}
