//! The exported functions and the opaque handles.

use std::borrow::Cow;
use std::collections::HashMap;
use std::ffi::{c_char, CStr};
use std::ptr;
use std::sync::{Arc, Mutex};

use eopnp::camera::Camera;
use eopnp::colmap::{self, FrameRegistration, ReadOptions, Registrar, Registration};
use eopnp::covariance::NoiseModel;
use eopnp::ransac::Ransac;
use eopnp::{Gravity, Loss, PlanarDetection, Problem, Refinement, Rig, Solver};
use nalgebra::{
    Isometry3, Matrix3, Point2, Point3, Quaternion, Rotation3, Translation3, UnitQuaternion,
    Vector3,
};

use crate::error::{guard, last_info, last_message, EopnpErrorInfo, EopnpStatus, Failure};
use crate::handles::{EopnpCamera, EopnpModel, EopnpRansac, EopnpRig, EopnpSolver};
use crate::types::*;

// Packed point arrays are read in place as nalgebra points: the same layout as `[f64; 3]` and
// `[f64; 2]` (nalgebra's `OPoint` and `ArrayStorage` are `#[repr(C)]`).
const _: () = assert!(std::mem::size_of::<Point3<f64>>() == 24);
const _: () = assert!(std::mem::align_of::<Point3<f64>>() == 8);
const _: () = assert!(std::mem::size_of::<Point2<f64>>() == 16);
const _: () = assert!(std::mem::align_of::<Point2<f64>>() == 8);

type Res<T> = Result<T, Failure>;

// ---------------------------------------------------------------------------------------------
// Pointer checks.

fn aligned<T>(p: *const T, name: &str) -> Res<()> {
    if !p.is_aligned() {
        return Err(Failure::invalid(format!(
            "`{name}` is not aligned for its type ({} bytes)",
            std::mem::align_of::<T>()
        )));
    }
    Ok(())
}

/// `p` as a reference: not NULL, aligned.
///
/// # Safety
/// A non-NULL `p` must point to a valid `T` for `'a`.
unsafe fn get<'a, T>(p: *const T, name: &str) -> Res<&'a T> {
    if p.is_null() {
        return Err(Failure::null(name));
    }
    aligned(p, name)?;
    Ok(&*p)
}

/// `p` as a mutable reference: not NULL, aligned.
///
/// # Safety
/// A non-NULL `p` must point to memory valid for writing a `T` for `'a`.
unsafe fn get_mut<'a, T>(p: *mut T, name: &str) -> Res<&'a mut T> {
    if p.is_null() {
        return Err(Failure::null(name));
    }
    aligned(p, name)?;
    Ok(&mut *p)
}

/// Writes `v` to `*p`: not NULL, aligned (the old contents are not read).
///
/// # Safety
/// A non-NULL `p` must point to memory valid for writing a `T`.
unsafe fn put<T>(p: *mut T, name: &str, v: T) -> Res<()> {
    if p.is_null() {
        return Err(Failure::null(name));
    }
    aligned(p, name)?;
    p.write(v);
    Ok(())
}

/// `n` elements at `p` as a slice: not NULL (even for `n = 0`), aligned, size in range.
///
/// # Safety
/// A non-NULL `p` must point to `n` valid `T`s for `'a`.
unsafe fn slice<'a, T>(p: *const T, n: usize, name: &str) -> Res<&'a [T]> {
    if p.is_null() {
        return Err(Failure::null(name));
    }
    aligned(p, name)?;
    bytes_in_range::<T>(n, 1, name)?;
    Ok(std::slice::from_raw_parts(p, n))
}

/// `n` elements at `p` as a mutable slice (the checks of `slice`).
///
/// # Safety
/// A non-NULL `p` must point to memory valid for writing `n` `T`s for `'a`, not aliased.
unsafe fn slice_mut<'a, T>(p: *mut T, n: usize, name: &str) -> Res<&'a mut [T]> {
    if p.is_null() {
        return Err(Failure::null(name));
    }
    aligned(p, name)?;
    bytes_in_range::<T>(n, 1, name)?;
    Ok(std::slice::from_raw_parts_mut(p, n))
}

fn bytes_in_range<T>(n: usize, stride: usize, name: &str) -> Res<()> {
    let bytes = n
        .checked_mul(stride)
        .and_then(|k| k.checked_mul(std::mem::size_of::<T>().max(1)));
    match bytes {
        Some(b) if b <= isize::MAX as usize => Ok(()),
        _ => Err(Failure::invalid(format!(
            "`{name}`: {n} elements (stride {stride}) overflow the address space"
        ))),
    }
}

/// `n` points of `D` coordinates at `p`, `stride` doubles apart (0: packed): in place when
/// packed, copied otherwise. `P` is `Point3<f64>` (`D = 3`) or `Point2<f64>` (`D = 2`).
///
/// # Safety
/// A non-NULL `p` must point to `n` points as described, valid for `'a`.
unsafe fn points<'a, P: Clone, const D: usize>(
    p: *const f64,
    n: usize,
    stride: usize,
    name: &str,
    make: impl Fn(&[f64]) -> P,
) -> Res<Cow<'a, [P]>> {
    if p.is_null() {
        return Err(Failure::null(name));
    }
    aligned(p, name)?;
    let stride = if stride == 0 { D } else { stride };
    if stride < D {
        return Err(Failure::invalid(format!(
            "`{name}_stride` is {stride}: it must be 0 (packed) or at least {D} doubles"
        )));
    }
    bytes_in_range::<f64>(n, stride, name)?;
    if stride == D {
        // Packed: `P` has the layout of `[f64; D]` (the assertions above).
        Ok(Cow::Borrowed(std::slice::from_raw_parts(p.cast::<P>(), n)))
    } else {
        let len = if n == 0 { 0 } else { (n - 1) * stride + D };
        let all = std::slice::from_raw_parts(p, len);
        Ok(Cow::Owned(
            (0..n)
                .map(|i| make(&all[i * stride..i * stride + D]))
                .collect(),
        ))
    }
}

/// A NUL-terminated UTF-8 string.
///
/// # Safety
/// A non-NULL `p` must point to a NUL-terminated string.
unsafe fn string<'a>(p: *const c_char, name: &str) -> Res<&'a str> {
    if p.is_null() {
        return Err(Failure::null(name));
    }
    CStr::from_ptr(p)
        .to_str()
        .map_err(|_| Failure::invalid(format!("`{name}` is not UTF-8")))
}

// ---------------------------------------------------------------------------------------------
// Problems and poses.

enum Observed<'a> {
    Normalised,
    Pixels(&'a Camera),
    Rig(&'a Rig, &'a [u32]),
}

/// The checked, borrowed (or, for strided arrays, copied) inputs of one `EopnpProblem`.
struct Inputs<'a> {
    world: Cow<'a, [Point3<f64>]>,
    image: Cow<'a, [Point2<f64>]>,
    weights: Option<&'a [f64]>,
    observed: Observed<'a>,
    focal: Option<(f64, f64)>,
    gravity: Option<Gravity>,
    free: Free,
}

/// The free intrinsics of a problem (`EopnpProblem`'s `unknown_focal`, `focal_min_px`,
/// `focal_max_px`, `refine_principal_point`, `refine_distortion`) or of a registration
/// (`EopnpFreeIntrinsics`' fields of the same names), checked; none by default.
#[derive(Clone, Copy, Debug, Default)]
struct Free {
    /// The focal length is unknown: in the default range (`None`) or in `(min_px, max_px)`.
    unknown_focal: Option<Option<(f64, f64)>>,
    /// The principal point is refined.
    refine_principal_point: bool,
    /// The distortion parameters are refined.
    refine_distortion: bool,
}

impl Free {
    /// The fields' one check: a range without `unknown_focal` is `EOPNP_INVALID_ARGUMENT`. The
    /// library checks the rest when it solves (a bad range, input these options do not take:
    /// `InvalidOption` naming the option).
    fn new(
        unknown_focal: bool,
        focal_min_px: f64,
        focal_max_px: f64,
        refine_principal_point: bool,
        refine_distortion: bool,
    ) -> Res<Self> {
        let range =
            (focal_min_px != 0.0 || focal_max_px != 0.0).then_some((focal_min_px, focal_max_px));
        if range.is_some() && !unknown_focal {
            return Err(Failure::invalid(
                "`focal_min_px`/`focal_max_px` are set without `unknown_focal`",
            ));
        }
        Ok(Free {
            unknown_focal: unknown_focal.then_some(range),
            refine_principal_point,
            refine_distortion,
        })
    }

    fn of_problem(p: &EopnpProblem) -> Res<Self> {
        Free::new(
            p.unknown_focal,
            p.focal_min_px,
            p.focal_max_px,
            p.refine_principal_point,
            p.refine_distortion,
        )
    }

    /// A registration's: none for NULL.
    ///
    /// # Safety
    /// `f` NULL or a readable `EopnpFreeIntrinsics`.
    unsafe fn of_registration(f: *const EopnpFreeIntrinsics) -> Res<Self> {
        if f.is_null() {
            return Ok(Free::default());
        }
        let f = get(f, "intrinsics")?;
        Free::new(
            f.unknown_focal,
            f.focal_min_px,
            f.focal_max_px,
            f.refine_principal_point,
            f.refine_distortion,
        )
    }

    /// `problem` with these intrinsics free.
    fn apply<'p>(&self, mut problem: Problem<'p>) -> Problem<'p> {
        problem = match self.unknown_focal {
            Some(Some((lo, hi))) => problem.unknown_focal_within(lo, hi),
            Some(None) => problem.unknown_focal(),
            None => problem,
        };
        // The library checks the input these need (pixels through one camera, no vertical):
        // `InvalidOption` naming the option otherwise.
        if self.refine_principal_point {
            problem = problem.refine_principal_point();
        }
        if self.refine_distortion {
            problem = problem.refine_distortion();
        }
        problem
    }

    /// The focal length is unknown: a solution's `focal_estimated` (`EopnpSolution::of`).
    fn focal(&self) -> bool {
        self.unknown_focal.is_some()
    }
}

/// The known vertical of a problem: `None` without one; `EOPNP_INVALID_ARGUMENT` for a half-set
/// one, the library's `InvalidOption("gravity")` for a zero direction or a bad sigma.
///
/// # Safety
/// `camera` and `world` NULL or 3 readable doubles each.
unsafe fn gravity(camera: *const f64, world: *const f64, sigma_deg: f64) -> Res<Option<Gravity>> {
    match (camera.is_null(), world.is_null()) {
        (true, true) => {
            if sigma_deg != 0.0 {
                return Err(Failure::invalid(
                    "`gravity_sigma_deg` is set without `gravity_camera` and `gravity_world`: \
                     set the three, or none",
                ));
            }
            Ok(None)
        }
        (false, false) => {
            let c = slice(camera, 3, "gravity_camera")?;
            let w = slice(world, 3, "gravity_world")?;
            let v = |x: &[f64]| Vector3::new(x[0], x[1], x[2]);
            Ok(Some(Gravity::new(v(c), v(w), sigma_deg)?))
        }
        _ => Err(Failure::invalid(
            "a vertical needs both `gravity_camera` and `gravity_world` (and \
             `gravity_sigma_deg`): set the three, or none",
        )),
    }
}

impl<'a> Inputs<'a> {
    /// # Safety
    /// The pointers of `p` must be as `EopnpProblem` documents them.
    unsafe fn new(p: &'a EopnpProblem) -> Res<Self> {
        let n = p.n;
        let world = points::<_, 3>(p.world, n, p.world_stride, "world", |c| {
            Point3::new(c[0], c[1], c[2])
        })?;
        let image = points::<_, 2>(p.image, n, p.image_stride, "image", |c| {
            Point2::new(c[0], c[1])
        })?;
        let weights = if p.weights.is_null() {
            None
        } else {
            Some(slice(p.weights, n, "weights")?)
        };
        let observed = match (p.camera.is_null(), p.rig.is_null()) {
            (true, true) => {
                if !p.rig_cameras.is_null() {
                    return Err(Failure::invalid(
                        "`rig_cameras` is set without a `rig`: set both, or neither",
                    ));
                }
                Observed::Normalised
            }
            (false, true) => {
                if !p.rig_cameras.is_null() {
                    return Err(Failure::invalid(
                        "`rig_cameras` is set without a `rig`: set both, or neither",
                    ));
                }
                Observed::Pixels(&get(p.camera, "camera")?.camera)
            }
            (true, false) => Observed::Rig(
                &get(p.rig, "rig")?.rig,
                slice(p.rig_cameras, n, "rig_cameras")?,
            ),
            (false, false) => {
                return Err(Failure::invalid(
                    "a problem has a `camera` or a `rig`, not both",
                ))
            }
        };
        let focal = (p.focal_x != 0.0 || p.focal_y != 0.0).then_some((p.focal_x, p.focal_y));
        let gravity = gravity(p.gravity_camera, p.gravity_world, p.gravity_sigma_deg)?;
        let free = Free::of_problem(p)?;
        Ok(Inputs {
            world,
            image,
            weights,
            observed,
            focal,
            gravity,
            free,
        })
    }

    fn problem(&self) -> Problem<'_> {
        let mut problem = match self.observed {
            Observed::Normalised => Problem::normalised(&self.world, &self.image),
            Observed::Pixels(camera) => Problem::pixels(&self.world, &self.image, camera),
            Observed::Rig(rig, cameras) => Problem::rig(&self.world, &self.image, cameras, rig),
        };
        if let Some(w) = self.weights {
            problem = problem.weights(w);
        }
        if let Some((fx, fy)) = self.focal {
            problem = problem.focal(fx, fy);
        }
        if let Some(g) = self.gravity {
            problem = problem.gravity(g);
        }
        self.free.apply(problem)
    }

    /// A solution of this problem for C (`focal_estimated` with an unknown focal length).
    fn solution(&self, s: &eopnp::Solution) -> EopnpSolution {
        EopnpSolution::of(s, self.free.focal())
    }

    fn n(&self) -> usize {
        self.world.len()
    }
}

/// The largest `|R^T R - I|` entry and the least determinant accepted of a rotation matrix
/// given as a pose (the Python package's tolerance): float32 round-off passes, a scaled or
/// reflected matrix does not.
const ROTATION_TOLERANCE: f64 = 1e-6;

/// An `EopnpPose` as an isometry. A non-finite entry gives a NaN pose, which the library
/// rejects with its own error (`"initial"`, `"cam_from_rig"`); a finite matrix that is not a
/// rotation is `EOPNP_INVALID_ARGUMENT`.
fn isometry(p: &EopnpPose, name: &str) -> Res<Isometry3<f64>> {
    let t = Translation3::new(p.translation[0], p.translation[1], p.translation[2]);
    if !p.rotation.iter().all(|x| x.is_finite()) {
        let nan = Quaternion::new(f64::NAN, f64::NAN, f64::NAN, f64::NAN);
        return Ok(Isometry3::from_parts(t, UnitQuaternion::new_unchecked(nan)));
    }
    let m = Matrix3::from_row_slice(&p.rotation);
    let off = (m.transpose() * m - Matrix3::identity()).abs().max();
    let det = m.determinant();
    if !(off <= ROTATION_TOLERANCE && det > 0.0) {
        return Err(Failure::invalid(format!(
            "{name}: the 3x3 matrix is not a rotation (max |R^T R - I| = {off:.3e}, det = \
             {det}; at most {ROTATION_TOLERANCE:e} and > 0 accepted)"
        )));
    }
    let q = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(m));
    Ok(Isometry3::from_parts(
        t,
        UnitQuaternion::new_normalize(q.into_inner()),
    ))
}

// ---------------------------------------------------------------------------------------------
// Thread pools of the batch functions.

/// A rayon pool per thread count, built on first use and kept (like the Python package's).
fn pool(threads: usize) -> Res<Option<Arc<rayon::ThreadPool>>> {
    static POOLS: Mutex<Option<HashMap<usize, Arc<rayon::ThreadPool>>>> = Mutex::new(None);
    if threads == 0 {
        return Ok(None);
    }
    let mut pools = POOLS.lock().unwrap_or_else(|e| e.into_inner());
    let pools = pools.get_or_insert_with(HashMap::new);
    if let Some(p) = pools.get(&threads) {
        return Ok(Some(p.clone()));
    }
    let p = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| Failure::invalid(format!("cannot start {threads} threads: {e}")))?;
    let p = Arc::new(p);
    pools.insert(threads, p.clone());
    Ok(Some(p))
}

fn run_in<R: Send>(threads: usize, f: impl FnOnce() -> R + Send) -> Res<R> {
    Ok(match pool(threads)? {
        Some(p) => p.install(f),
        None => f(),
    })
}

/// The batch functions' result: `EOPNP_OK` if every problem succeeded, otherwise the status of
/// the first that failed, recorded with its index.
fn first_failure(failures: Vec<(usize, Failure)>) -> Res<()> {
    match failures.into_iter().next() {
        None => Ok(()),
        Some((i, mut f)) => {
            f.message = format!("problem {i}: {}", f.message);
            f.info.index = i as u64;
            Err(f)
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Errors and version.

/// The message of the last failure on the calling thread (`""` if none yet), NUL-terminated
/// UTF-8. The string is owned by the library and valid until the next failing call on the same
/// thread; copy it to keep it. Never NULL.
#[no_mangle]
pub extern "C" fn eopnp_last_error_message() -> *const c_char {
    // `last_message` cannot panic (thread-local access through `try_with`).
    last_message()
}

/// Writes the details of the last failure on the calling thread into `*out` (its `status` is
/// `EOPNP_OK` if no call of this thread has failed yet). Returns `EOPNP_NULL_POINTER` for a NULL
/// `out` (which then becomes the last error).
///
/// # Safety
/// `out` must be NULL or point to a writable `EopnpErrorInfo`.
#[no_mangle]
pub unsafe extern "C" fn eopnp_last_error(out: *mut EopnpErrorInfo) -> EopnpStatus {
    let info = last_info();
    guard(|| put(out, "out", info))
}

/// The name of a status code (`"EOPNP_OK"`, `"EOPNP_DEGENERATE"`, ...), a static
/// NUL-terminated string; `"EOPNP_UNKNOWN_STATUS"` for a value that is no status. Never NULL.
#[no_mangle]
pub extern "C" fn eopnp_status_name(status: i32) -> *const c_char {
    let name: &'static CStr = match status {
        0 => c"EOPNP_OK",
        1 => c"EOPNP_NULL_POINTER",
        2 => c"EOPNP_INVALID_ARGUMENT",
        3 => c"EOPNP_TOO_FEW_POINTS",
        4 => c"EOPNP_LENGTH_MISMATCH",
        5 => c"EOPNP_WEIGHTS_LENGTH",
        6 => c"EOPNP_NON_FINITE",
        7 => c"EOPNP_CAMERA_INDICES_LENGTH",
        8 => c"EOPNP_UNKNOWN_CAMERA",
        9 => c"EOPNP_INVALID_WEIGHT",
        10 => c"EOPNP_DEGENERATE",
        11 => c"EOPNP_NO_SOLUTION",
        12 => c"EOPNP_INVALID_OPTION",
        13 => c"EOPNP_NO_CONSENSUS",
        14 => c"EOPNP_CAMERA_ERROR",
        15 => c"EOPNP_MODEL_ERROR",
        16 => c"EOPNP_REGISTER_ERROR",
        17 => c"EOPNP_BUFFER_TOO_SMALL",
        18 => c"EOPNP_PANIC",
        19 => c"EOPNP_GRAVITY_MISMATCH",
        _ => c"EOPNP_UNKNOWN_STATUS",
    };
    name.as_ptr()
}

/// The version of the library (`"0.1.0"`), a static NUL-terminated string. Never NULL.
#[no_mangle]
pub extern "C" fn eopnp_version() -> *const c_char {
    static VERSION: &str = concat!(env!("CARGO_PKG_VERSION"), "\0");
    VERSION.as_ptr().cast()
}

// ---------------------------------------------------------------------------------------------
// Solver options.

/// Creates solver options with the recommended defaults (EOPnP, then the maximum-likelihood
/// refinement; squared loss; no covariance) into `*out`, owned by the caller (release with
/// `eopnp_solver_free`).
///
/// # Safety
/// `out` must be NULL or point to a writable `EopnpSolver*`.
#[no_mangle]
pub unsafe extern "C" fn eopnp_solver_create(out: *mut *mut EopnpSolver) -> EopnpStatus {
    guard(|| {
        let out = get_mut(out, "out")?;
        *out = Box::into_raw(Box::new(EopnpSolver {
            solver: Solver::default(),
        }));
        Ok(())
    })
}

/// Releases solver options created by `eopnp_solver_create`; NULL does nothing.
///
/// # Safety
/// `solver` must be NULL or a handle from `eopnp_solver_create` not yet freed, used by no
/// other thread.
#[no_mangle]
pub unsafe extern "C" fn eopnp_solver_free(solver: *mut EopnpSolver) {
    if !solver.is_null() {
        drop(Box::from_raw(solver));
    }
}

/// Applies `f` to the solver's options.
///
/// # Safety
/// `solver` must be NULL or a live handle not used by another thread.
unsafe fn set_solver(
    solver: *mut EopnpSolver,
    f: impl FnOnce(Solver) -> Res<Solver>,
) -> EopnpStatus {
    guard(|| {
        let s = get_mut(solver, "solver")?;
        s.solver = f(s.solver)?;
        Ok(())
    })
}

/// Which cost the returned pose minimises: an `EopnpRefinement` value (default
/// `EOPNP_REFINEMENT_REPROJECTION`). Another value is `EOPNP_INVALID_ARGUMENT`.
///
/// # Safety
/// `solver` must be NULL or a live handle, not used by another thread during the call.
#[no_mangle]
pub unsafe extern "C" fn eopnp_solver_set_refinement(
    solver: *mut EopnpSolver,
    refinement: i32,
) -> EopnpStatus {
    set_solver(solver, |s| {
        let r = match refinement {
            0 => Refinement::Reprojection,
            1 => Refinement::Algebraic,
            _ => {
                return Err(Failure::invalid(format!(
                    "refinement {refinement} is not an EopnpRefinement value (0 or 1)"
                )))
            }
        };
        Ok(s.refinement(r))
    })
}

/// The planar branch selection: an `EopnpPlanarDetection` value (default `EOPNP_PLANAR_AUTO`).
/// Another value is `EOPNP_INVALID_ARGUMENT`.
///
/// # Safety
/// As `eopnp_solver_set_refinement`.
#[no_mangle]
pub unsafe extern "C" fn eopnp_solver_set_planar_detection(
    solver: *mut EopnpSolver,
    detection: i32,
) -> EopnpStatus {
    set_solver(solver, |s| {
        let p = match detection {
            0 => PlanarDetection::Auto,
            1 => PlanarDetection::Planar,
            2 => PlanarDetection::NonPlanar,
            _ => {
                return Err(Failure::invalid(format!(
                    "planar detection {detection} is not an EopnpPlanarDetection value (0, 1 or 2)"
                )))
            }
        };
        Ok(s.planar_detection(p))
    })
}

/// Maximum damped-Newton iterations per candidate (default 50).
///
/// # Safety
/// As `eopnp_solver_set_refinement`.
#[no_mangle]
pub unsafe extern "C" fn eopnp_solver_set_newton_iterations(
    solver: *mut EopnpSolver,
    iterations: u32,
) -> EopnpStatus {
    set_solver(solver, |s| Ok(s.newton_iterations(iterations)))
}

/// The damped-Newton step tolerance (radians, roughly; default 1e-12): finite and >= 0, else
/// `EOPNP_INVALID_ARGUMENT`.
///
/// # Safety
/// As `eopnp_solver_set_refinement`.
#[no_mangle]
pub unsafe extern "C" fn eopnp_solver_set_newton_step_tolerance(
    solver: *mut EopnpSolver,
    tolerance: f64,
) -> EopnpStatus {
    set_solver(solver, |s| {
        if !(tolerance.is_finite() && tolerance >= 0.0) {
            return Err(Failure::invalid(format!(
                "newton step tolerance {tolerance} must be finite and >= 0"
            )));
        }
        Ok(s.newton_step_tolerance(tolerance))
    })
}

/// Maximum Levenberg-Marquardt iterations of the reprojection refinement (default 200).
///
/// # Safety
/// As `eopnp_solver_set_refinement`.
#[no_mangle]
pub unsafe extern "C" fn eopnp_solver_set_reprojection_iterations(
    solver: *mut EopnpSolver,
    iterations: u32,
) -> EopnpStatus {
    set_solver(solver, |s| Ok(s.reprojection_iterations(iterations)))
}

/// `true`: every candidate generator and every start refined for every problem (no certified
/// early exit). Default `false`.
///
/// # Safety
/// As `eopnp_solver_set_refinement`.
#[no_mangle]
pub unsafe extern "C" fn eopnp_solver_set_exhaustive(
    solver: *mut EopnpSolver,
    exhaustive: bool,
) -> EopnpStatus {
    set_solver(solver, |s| Ok(s.exhaustive(exhaustive)))
}

/// The loss of the final refinement: an `EopnpLoss` value and its scale `s` in the units of the
/// residuals (pixels for pixel input, normalised units for normalised input; ignored for
/// `EOPNP_LOSS_SQUARED`). An unknown kind is `EOPNP_INVALID_ARGUMENT`; a scale that is not
/// finite and > 0 with a normal square and reciprocal square (about `1e-154 < s < 1e154`) is
/// `EOPNP_INVALID_OPTION`.
///
/// # Safety
/// As `eopnp_solver_set_refinement`.
#[no_mangle]
pub unsafe extern "C" fn eopnp_solver_set_loss(
    solver: *mut EopnpSolver,
    loss: i32,
    scale: f64,
) -> EopnpStatus {
    set_solver(solver, |s| {
        let l = match loss {
            0 => Loss::Squared,
            1 => Loss::Huber(scale),
            2 => Loss::Cauchy(scale),
            _ => {
                return Err(Failure::invalid(format!(
                    "loss {loss} is not an EopnpLoss value (0, 1 or 2)"
                )))
            }
        };
        if !l.is_valid() {
            return Err(eopnp::PnpError::InvalidOption { option: "loss" }.into());
        }
        Ok(s.loss(l))
    })
}

/// Whether and how solutions carry the pose's 6 x 6 covariance (`EopnpSolution::covariance`):
/// an `EopnpCovariance` value, and for `EOPNP_COVARIANCE_SIGMA` the standard deviation of each
/// image coordinate in the units of the observations (finite and > 0, else
/// `EOPNP_INVALID_OPTION`; ignored otherwise). Default `EOPNP_COVARIANCE_NONE`.
///
/// # Safety
/// As `eopnp_solver_set_refinement`.
#[no_mangle]
pub unsafe extern "C" fn eopnp_solver_set_covariance(
    solver: *mut EopnpSolver,
    covariance: i32,
    sigma: f64,
) -> EopnpStatus {
    set_solver(solver, |s| {
        let noise = match covariance {
            0 => None,
            1 => Some(NoiseModel::Estimated),
            2 => {
                if !(sigma.is_finite() && sigma > 0.0) {
                    return Err(Failure::new(
                        EopnpStatus::EOPNP_INVALID_OPTION,
                        format!("covariance sigma {sigma} must be finite and > 0"),
                    ));
                }
                Some(NoiseModel::Sigma(sigma))
            }
            _ => {
                return Err(Failure::invalid(format!(
                    "covariance {covariance} is not an EopnpCovariance value (0, 1 or 2)"
                )))
            }
        };
        Ok(s.covariance(noise))
    })
}

// ---------------------------------------------------------------------------------------------
// RANSAC options.

/// Creates RANSAC options with the recommended defaults into `*out`, owned by the caller
/// (release with `eopnp_ransac_free`).
///
/// # Safety
/// `out` must be NULL or point to a writable `EopnpRansac*`.
#[no_mangle]
pub unsafe extern "C" fn eopnp_ransac_create(out: *mut *mut EopnpRansac) -> EopnpStatus {
    guard(|| {
        let out = get_mut(out, "out")?;
        *out = Box::into_raw(Box::new(EopnpRansac {
            ransac: Ransac::default(),
        }));
        Ok(())
    })
}

/// Releases RANSAC options created by `eopnp_ransac_create`; NULL does nothing.
///
/// # Safety
/// `ransac` must be NULL or a live handle from `eopnp_ransac_create`, used by no other thread.
#[no_mangle]
pub unsafe extern "C" fn eopnp_ransac_free(ransac: *mut EopnpRansac) {
    if !ransac.is_null() {
        drop(Box::from_raw(ransac));
    }
}

/// # Safety
/// `ransac` must be NULL or a live handle not used by another thread.
unsafe fn set_ransac(
    ransac: *mut EopnpRansac,
    f: impl FnOnce(Ransac) -> Res<Ransac>,
) -> EopnpStatus {
    guard(|| {
        let r = get_mut(ransac, "ransac")?;
        r.ransac = f(r.ransac)?;
        Ok(())
    })
}

fn finite_option(value: f64, option: &str) -> Res<()> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(Failure::new(
            EopnpStatus::EOPNP_INVALID_OPTION,
            format!("RANSAC option `{option}` is {value}: it must be finite"),
        ))
    }
}

/// The inlier threshold, in pixels for pixel input (and for normalised input with the
/// problem's focal lengths), else in normalised units (default 4). Not finite:
/// `EOPNP_INVALID_OPTION` here; finite but out of range (> 0 with a normal square): at
/// estimation.
///
/// # Safety
/// `ransac` must be NULL or a live handle, not used by another thread during the call.
#[no_mangle]
pub unsafe extern "C" fn eopnp_ransac_set_threshold_px(
    ransac: *mut EopnpRansac,
    threshold_px: f64,
) -> EopnpStatus {
    set_ransac(ransac, |r| {
        finite_option(threshold_px, "threshold_px")?;
        Ok(r.threshold_px(threshold_px))
    })
}

/// The probability of having drawn one all-inlier sample when the sampling stops (default
/// 0.999; in (0, 1), checked at estimation; not finite: `EOPNP_INVALID_OPTION` here).
///
/// # Safety
/// As `eopnp_ransac_set_threshold_px`.
#[no_mangle]
pub unsafe extern "C" fn eopnp_ransac_set_confidence(
    ransac: *mut EopnpRansac,
    confidence: f64,
) -> EopnpStatus {
    set_ransac(ransac, |r| {
        finite_option(confidence, "confidence")?;
        Ok(r.confidence(confidence))
    })
}

/// The most samples drawn (default 10000; at least 1, checked at estimation).
///
/// # Safety
/// As `eopnp_ransac_set_threshold_px`.
#[no_mangle]
pub unsafe extern "C" fn eopnp_ransac_set_max_iterations(
    ransac: *mut EopnpRansac,
    iterations: u32,
) -> EopnpStatus {
    set_ransac(ransac, |r| Ok(r.max_iterations(iterations)))
}

/// The fewest samples drawn (default 20).
///
/// # Safety
/// As `eopnp_ransac_set_threshold_px`.
#[no_mangle]
pub unsafe extern "C" fn eopnp_ransac_set_min_iterations(
    ransac: *mut EopnpRansac,
    iterations: u32,
) -> EopnpStatus {
    set_ransac(ransac, |r| Ok(r.min_iterations(iterations)))
}

/// The seed of the sampling generator (default 0): the same seed, the same result.
///
/// # Safety
/// As `eopnp_ransac_set_threshold_px`.
#[no_mangle]
pub unsafe extern "C" fn eopnp_ransac_set_seed(ransac: *mut EopnpRansac, seed: u64) -> EopnpStatus {
    set_ransac(ransac, |r| Ok(r.seed(seed)))
}

/// Local optimisation of each new best hypothesis by an EOPnP fit on its inliers (default on).
///
/// # Safety
/// As `eopnp_ransac_set_threshold_px`.
#[no_mangle]
pub unsafe extern "C" fn eopnp_ransac_set_local_optimisation(
    ransac: *mut EopnpRansac,
    on: bool,
) -> EopnpStatus {
    set_ransac(ransac, |r| Ok(r.local_optimisation(on)))
}

/// The final fit's threshold as a multiple of the threshold (default 2; finite and >= 1,
/// checked at estimation; not finite: `EOPNP_INVALID_OPTION` here).
///
/// # Safety
/// As `eopnp_ransac_set_threshold_px`.
#[no_mangle]
pub unsafe extern "C" fn eopnp_ransac_set_final_threshold_factor(
    ransac: *mut EopnpRansac,
    factor: f64,
) -> EopnpStatus {
    set_ransac(ransac, |r| {
        finite_option(factor, "final_threshold_factor")?;
        Ok(r.final_threshold_factor(factor))
    })
}

// ---------------------------------------------------------------------------------------------
// Cameras.

fn new_camera(out: *mut *mut EopnpCamera, camera: Camera) -> Res<()> {
    // SAFETY: the callers check `out` first (`get_mut`).
    unsafe {
        out.write(Box::into_raw(Box::new(EopnpCamera { camera })));
    }
    Ok(())
}

/// Creates a camera of a COLMAP model into `*out`, owned by the caller (release with
/// `eopnp_camera_free`): `model` is COLMAP's name (`"PINHOLE"`, `"SIMPLE_RADIAL"`, `"OPENCV"`,
/// `"FULL_OPENCV"`, ...; NUL-terminated), `width` and `height` in pixels (not used by any
/// computation), `params` the model's `n_params` parameters in COLMAP's order (pixels in COLMAP's
/// convention: the centre of the upper-left pixel is (0.5, 0.5)). An unknown name, a wrong
/// count, a non-finite or invalid parameter: `EOPNP_CAMERA_ERROR`.
///
/// # Safety
/// `model` must be NULL or NUL-terminated; `params` NULL or `n_params` doubles; `out` NULL or a
/// writable `EopnpCamera*`.
#[no_mangle]
pub unsafe extern "C" fn eopnp_camera_from_colmap(
    model: *const c_char,
    width: u64,
    height: u64,
    params: *const f64,
    n_params: usize,
    out: *mut *mut EopnpCamera,
) -> EopnpStatus {
    guard(|| {
        get_mut(out, "out")?;
        let model = string(model, "model")?;
        let params = slice(params, n_params, "params")?;
        new_camera(
            out,
            Camera::from_colmap(model, width, height, params.to_vec())?,
        )
    })
}

/// Creates a camera from OpenCV's intrinsics into `*out`, owned by the caller: `k` the 3 x 3
/// camera matrix `[[fx, 0, cx], [0, fy, cy], [0, 0, 1]]` row-major (9 doubles), `dist` OpenCV's
/// distortion coefficients `(k1, k2, p1, p2[, k3[, k4, k5, k6[, s1, s2, s3, s4[, tx, ty]]]])`,
/// `n_dist` of them: 0 (then `dist` may be NULL), 4, 5, 8, 12 or 14. Pixels in OpenCV's
/// convention (the centre of the upper-left pixel is (0, 0)), as `cv::solvePnP` takes them.
/// A bad `k` or count: `EOPNP_CAMERA_ERROR`.
///
/// # Safety
/// `k` must be NULL or 9 doubles; `dist` NULL or `n_dist` doubles; `out` NULL or a writable
/// `EopnpCamera*`.
#[no_mangle]
pub unsafe extern "C" fn eopnp_camera_from_opencv(
    k: *const f64,
    dist: *const f64,
    n_dist: usize,
    out: *mut *mut EopnpCamera,
) -> EopnpStatus {
    guard(|| {
        get_mut(out, "out")?;
        let k = Matrix3::from_row_slice(slice(k, 9, "k")?);
        let dist: &[f64] = if n_dist == 0 && dist.is_null() {
            &[]
        } else {
            slice(dist, n_dist, "dist")?
        };
        new_camera(out, Camera::from_opencv(&k, dist)?)
    })
}

/// Creates a camera from OpenCV's fisheye model (`cv::fisheye`): `k` as for
/// `eopnp_camera_from_opencv`, `dist` the 4 coefficients `(k1, k2, k3, k4)`.
///
/// # Safety
/// `k` must be NULL or 9 doubles; `dist` NULL or 4 doubles; `out` NULL or a writable
/// `EopnpCamera*`.
#[no_mangle]
pub unsafe extern "C" fn eopnp_camera_from_opencv_fisheye(
    k: *const f64,
    dist: *const f64,
    out: *mut *mut EopnpCamera,
) -> EopnpStatus {
    guard(|| {
        get_mut(out, "out")?;
        let k = Matrix3::from_row_slice(slice(k, 9, "k")?);
        let d = slice(dist, 4, "dist")?;
        new_camera(
            out,
            Camera::from_opencv_fisheye(&k, &[d[0], d[1], d[2], d[3]])?,
        )
    })
}

/// Creates a pinhole camera (no distortion) with focal lengths `fx, fy > 0` and principal point
/// `(cx, cy)`, in pixels, into `*out`, owned by the caller.
///
/// # Safety
/// `out` must be NULL or point to a writable `EopnpCamera*`.
#[no_mangle]
pub unsafe extern "C" fn eopnp_camera_pinhole(
    fx: f64,
    fy: f64,
    cx: f64,
    cy: f64,
    out: *mut *mut EopnpCamera,
) -> EopnpStatus {
    guard(|| {
        get_mut(out, "out")?;
        new_camera(out, Camera::pinhole(fx, fy, cx, cy)?)
    })
}

/// Releases a camera; NULL does nothing. Problems and rigs that use it must not be used after.
///
/// # Safety
/// `camera` must be NULL or a live camera handle, used by no other thread.
#[no_mangle]
pub unsafe extern "C" fn eopnp_camera_free(camera: *mut EopnpCamera) {
    if !camera.is_null() {
        drop(Box::from_raw(camera));
    }
}

/// The pixel of the normalised image point `normalised = (x/z, y/z)` (2 doubles), through the
/// camera model (distortion included), into `pixel` (2 doubles).
///
/// # Safety
/// `camera` must be NULL or a live handle; `normalised` NULL or 2 doubles; `pixel` NULL or 2
/// writable doubles.
#[no_mangle]
pub unsafe extern "C" fn eopnp_camera_project(
    camera: *const EopnpCamera,
    normalised: *const f64,
    pixel: *mut f64,
) -> EopnpStatus {
    guard(|| {
        let cam = &get(camera, "camera")?.camera;
        let m = slice(normalised, 2, "normalised")?;
        let out = slice_mut(pixel, 2, "pixel")?;
        if !(m[0].is_finite() && m[1].is_finite()) {
            return Err(eopnp::camera::CameraError::NonFinite.into());
        }
        let p = cam.project(Point2::new(m[0], m[1]));
        out.copy_from_slice(&[p.x, p.y]);
        Ok(())
    })
}

/// The normalised image point `(x/z, y/z)` of `pixel` (2 doubles), the camera model inverted,
/// into `normalised` (2 doubles). A pixel that cannot be undistorted: `EOPNP_CAMERA_ERROR`.
///
/// # Safety
/// As `eopnp_camera_project`, the roles of the arrays swapped.
#[no_mangle]
pub unsafe extern "C" fn eopnp_camera_undistort(
    camera: *const EopnpCamera,
    pixel: *const f64,
    normalised: *mut f64,
) -> EopnpStatus {
    guard(|| {
        let cam = &get(camera, "camera")?.camera;
        let p = slice(pixel, 2, "pixel")?;
        let out = slice_mut(normalised, 2, "normalised")?;
        let m = cam.undistort(Point2::new(p[0], p[1]))?;
        out.copy_from_slice(&[m.x, m.y]);
        Ok(())
    })
}

/// The camera's description into `*out`: its model's COLMAP name, the image size, the number of
/// its parameters and its focal lengths in pixels.
///
/// # Safety
/// `camera` must be NULL or a live handle; `out` NULL or a writable `EopnpCameraInfo`.
#[no_mangle]
pub unsafe extern "C" fn eopnp_camera_info(
    camera: *const EopnpCamera,
    out: *mut EopnpCameraInfo,
) -> EopnpStatus {
    guard(|| {
        let cam = &get(camera, "camera")?.camera;
        let out = get_mut(out, "out")?;
        *out = EopnpCameraInfo::of(cam);
        Ok(())
    })
}

/// The camera's parameters, in its model's COLMAP order: `*count` receives their number,
/// `params[0 .. min(*count, capacity)]` the values. More than `capacity`:
/// `EOPNP_BUFFER_TOO_SMALL` (the first `capacity` written). `params` may be NULL when
/// `capacity` is 0 (to ask the count; `EopnpCameraInfo::n_params` has it too).
///
/// # Safety
/// `camera` NULL or live; `params` NULL or `capacity` writable doubles; `count` NULL or
/// writable.
#[no_mangle]
pub unsafe extern "C" fn eopnp_camera_params(
    camera: *const EopnpCamera,
    params: *mut f64,
    capacity: usize,
    count: *mut usize,
) -> EopnpStatus {
    guard(|| {
        let cam = &get(camera, "camera")?.camera;
        let count = get_mut(count, "count")?;
        let out: &mut [f64] = if capacity == 0 && params.is_null() {
            &mut []
        } else {
            slice_mut(params, capacity, "params")?
        };
        let p = cam.params();
        *count = p.len();
        for (o, v) in out.iter_mut().zip(p) {
            *o = *v;
        }
        if p.len() > capacity {
            return Err(Failure::new(
                EopnpStatus::EOPNP_BUFFER_TOO_SMALL,
                format!("{} parameters, room for {capacity}", p.len()),
            ));
        }
        Ok(())
    })
}

// ---------------------------------------------------------------------------------------------
// Rigs.

/// Creates a rig of `count` cameras into `*out`, owned by the caller (release with
/// `eopnp_rig_free`): camera `k` is `cameras[k]` (copied: the camera handles may be freed
/// after), its pose in the rig `cam_from_rig[k]`, `x_cam = R x_rig + t`. No camera
/// (`count = 0`) or a non-finite pose: `EOPNP_INVALID_OPTION`; a matrix that is not a rotation:
/// `EOPNP_INVALID_ARGUMENT`.
///
/// # Safety
/// `cameras` must be NULL or `count` pointers to live cameras; `cam_from_rig` NULL or `count`
/// poses; `out` NULL or a writable `EopnpRig*`.
#[no_mangle]
pub unsafe extern "C" fn eopnp_rig_create(
    cameras: *const *const EopnpCamera,
    cam_from_rig: *const EopnpPose,
    count: usize,
    out: *mut *mut EopnpRig,
) -> EopnpStatus {
    guard(|| {
        let out = get_mut(out, "out")?;
        let cams = slice(cameras, count, "cameras")?;
        let poses = slice(cam_from_rig, count, "cam_from_rig")?;
        let mut parts = Vec::with_capacity(count);
        for (k, (c, p)) in cams.iter().zip(poses).enumerate() {
            let cam = get(*c, &format!("cameras[{k}]"))?;
            parts.push((cam.camera, isometry(p, &format!("cam_from_rig[{k}]"))?));
        }
        *out = Box::into_raw(Box::new(EopnpRig {
            rig: Rig::new(parts)?,
        }));
        Ok(())
    })
}

/// Releases a rig; NULL does nothing.
///
/// # Safety
/// `rig` must be NULL or a live rig handle, used by no other thread.
#[no_mangle]
pub unsafe extern "C" fn eopnp_rig_free(rig: *mut EopnpRig) {
    if !rig.is_null() {
        drop(Box::from_raw(rig));
    }
}

// ---------------------------------------------------------------------------------------------
// Solves.

/// The pose of a problem (the library's `Solver::solve`): EOPnP's global search, then in the
/// default mode the maximum-likelihood refinement; into `*out`.
///
/// Errors: `EOPNP_NULL_POINTER` / `EOPNP_INVALID_ARGUMENT` for the pointers and strides of the
/// problem; then the library's checks in its order (`EOPNP_TOO_FEW_POINTS` for `n < 4`,
/// `EOPNP_NON_FINITE`, `EOPNP_INVALID_WEIGHT`, `EOPNP_DEGENERATE`, ...).
///
/// # Safety
/// `solver` must be NULL or a live handle; `problem` NULL or a problem whose pointers are as
/// `EopnpProblem` documents; `out` NULL or a writable `EopnpSolution`.
#[no_mangle]
pub unsafe extern "C" fn eopnp_solve(
    solver: *const EopnpSolver,
    problem: *const EopnpProblem,
    out: *mut EopnpSolution,
) -> EopnpStatus {
    guard(|| {
        let solver = &get(solver, "solver")?.solver;
        let inputs = Inputs::new(get(problem, "problem")?)?;
        let out = get_mut(out, "out")?;
        let sol = solver.solve(&inputs.problem())?;
        *out = inputs.solution(&sol);
        Ok(())
    })
}

/// Every distinct local minimum of the problem's cost that the search finds (the library's
/// `Solver::solve_all`), best first (the poses with more than half of the points in front
/// before the others, then by increasing reprojection error): `*count` receives their number (at most
/// `EOPNP_MAX_SOLUTIONS`), `out[0 .. min(*count, capacity)]` the solutions. More than `capacity`:
/// `EOPNP_BUFFER_TOO_SMALL` (the first `capacity` written). `out` may be NULL when `capacity` is
/// 0.
///
/// # Safety
/// As `eopnp_solve`; `out` NULL or `capacity` writable solutions; `count` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn eopnp_solve_all(
    solver: *const EopnpSolver,
    problem: *const EopnpProblem,
    out: *mut EopnpSolution,
    capacity: usize,
    count: *mut usize,
) -> EopnpStatus {
    guard(|| {
        let solver = &get(solver, "solver")?.solver;
        let inputs = Inputs::new(get(problem, "problem")?)?;
        let count = get_mut(count, "count")?;
        let out: &mut [EopnpSolution] = if capacity == 0 && out.is_null() {
            &mut []
        } else {
            slice_mut(out, capacity, "out")?
        };
        let all = solver.solve_all(&inputs.problem())?;
        *count = all.len();
        for (o, s) in out.iter_mut().zip(all.iter()) {
            *o = inputs.solution(s);
        }
        if all.len() > capacity {
            return Err(Failure::new(
                EopnpStatus::EOPNP_BUFFER_TOO_SMALL,
                format!(
                    "{} local minima found, room for {capacity}: pass EOPNP_MAX_SOLUTIONS",
                    all.len()
                ),
            ));
        }
        Ok(())
    })
}

/// Refines the prior pose `initial` (`x_cam = R X + t`; e.g. the previous frame's) to the
/// maximum-likelihood pose of the basin it starts in, without the global search (the library's
/// `Solver::refine`; OpenCV's `solvePnPRefineLM`). A non-finite pose: `EOPNP_INVALID_OPTION`;
/// a matrix that is not a rotation: `EOPNP_INVALID_ARGUMENT`.
///
/// # Safety
/// As `eopnp_solve`; `initial` NULL or a readable `EopnpPose`.
#[no_mangle]
pub unsafe extern "C" fn eopnp_refine(
    solver: *const EopnpSolver,
    problem: *const EopnpProblem,
    initial: *const EopnpPose,
    out: *mut EopnpSolution,
) -> EopnpStatus {
    guard(|| {
        let solver = &get(solver, "solver")?.solver;
        let inputs = Inputs::new(get(problem, "problem")?)?;
        let initial = isometry(get(initial, "initial")?, "initial")?;
        let out = get_mut(out, "out")?;
        let sol = solver.refine(&inputs.problem(), &initial)?;
        *out = inputs.solution(&sol);
        Ok(())
    })
}

fn write_mask(mask: &mut [u8], inliers: &[bool]) {
    for (m, i) in mask.iter_mut().zip(inliers) {
        *m = u8::from(*i);
    }
}

/// Robust estimation by RANSAC (the library's `Ransac::estimate`): P3P hypotheses, local
/// optimisation, a final EOPnP fit on the inliers with `solver`'s options. Writes the pose to
/// `*out`, and when not NULL, `inlier_mask[i]` (1: correspondence `i` is an inlier of the
/// returned pose, 0: not; `n` bytes) and the statistics `*stats`. No consensus:
/// `EOPNP_NO_CONSENSUS`; an option out of range: `EOPNP_INVALID_OPTION`.
///
/// # Safety
/// As `eopnp_solve`; `ransac` NULL or a live handle; `inlier_mask` NULL or `problem->n`
/// writable bytes; `stats` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn eopnp_ransac_estimate(
    ransac: *const EopnpRansac,
    solver: *const EopnpSolver,
    problem: *const EopnpProblem,
    out: *mut EopnpSolution,
    inlier_mask: *mut u8,
    stats: *mut EopnpRansacStats,
) -> EopnpStatus {
    guard(|| {
        let ransac = &get(ransac, "ransac")?.ransac;
        let solver = &get(solver, "solver")?.solver;
        let inputs = Inputs::new(get(problem, "problem")?)?;
        let out = get_mut(out, "out")?;
        let mask = if inlier_mask.is_null() {
            None
        } else {
            Some(slice_mut(inlier_mask, inputs.n(), "inlier_mask")?)
        };
        let stats = if stats.is_null() {
            None
        } else {
            Some(get_mut(stats, "stats")?)
        };
        let r = ransac.estimate(solver, &inputs.problem())?;
        *out = inputs.solution(&r.solution);
        if let Some(mask) = mask {
            write_mask(mask, &r.inliers);
        }
        if let Some(stats) = stats {
            *stats = EopnpRansacStats::from(&r.stats);
        }
        Ok(())
    })
}

/// Solves `count` problems (each as `eopnp_solve`) in parallel on `threads` threads (0: rayon's
/// global pool, one thread per core): `out[i]` and `statuses[i]` are problem `i`'s solution and
/// status, each exactly what `eopnp_solve` gives for it. Returns `EOPNP_OK` if every problem
/// was solved, otherwise the status of the first problem that failed (its message names it,
/// `EopnpErrorInfo::index` is its index; the others are in `statuses`). `count = 0` does
/// nothing (the pointers must not be NULL all the same).
///
/// # Safety
/// `solver` NULL or live; `problems` NULL or `count` problems as `EopnpProblem` documents;
/// `out` and `statuses` NULL or `count` writable elements each.
#[no_mangle]
pub unsafe extern "C" fn eopnp_solve_batch(
    solver: *const EopnpSolver,
    problems: *const EopnpProblem,
    count: usize,
    threads: usize,
    out: *mut EopnpSolution,
    statuses: *mut EopnpStatus,
) -> EopnpStatus {
    guard(|| {
        let solver = &get(solver, "solver")?.solver;
        let problems = slice(problems, count, "problems")?;
        let out = slice_mut(out, count, "out")?;
        let statuses = slice_mut(statuses, count, "statuses")?;
        let mut failures = Vec::new();
        let inputs: Vec<Option<Inputs<'_>>> = problems
            .iter()
            .enumerate()
            .map(|(i, p)| match Inputs::new(p) {
                Ok(x) => Some(x),
                Err(f) => {
                    failures.push((i, f));
                    None
                }
            })
            .collect();
        let valid: Vec<(usize, &Inputs<'_>, Problem<'_>)> = inputs
            .iter()
            .enumerate()
            .filter_map(|(i, x)| x.as_ref().map(|x| (i, x, x.problem())))
            .collect();
        let just: Vec<Problem<'_>> = valid.iter().map(|(_, _, p)| *p).collect();
        let results = run_in(threads, || solver.solve_batch(&just))?;
        for ((i, x, _), r) in valid.iter().zip(results) {
            match r {
                Ok(s) => {
                    out[*i] = x.solution(&s);
                    statuses[*i] = OK;
                }
                Err(e) => failures.push((*i, e.into())),
            }
        }
        failures.sort_by_key(|(i, _)| *i);
        for (i, f) in &failures {
            statuses[*i] = f.info.status;
        }
        first_failure(failures)
    })
}

/// RANSAC on `count` problems in parallel (each as `eopnp_ransac_estimate`, problem `i` with
/// the library's seed `problem_seed(seed, i)`, so that the results do not depend on the
/// threads) on `threads` threads (0: rayon's global pool). `out[i]`, `statuses[i]` as in
/// `eopnp_solve_batch`; when not NULL, `inlier_masks[i]` (itself NULL, or `problems[i].n`
/// bytes) and `stats[i]`.
///
/// # Safety
/// As `eopnp_solve_batch`; `ransac` NULL or live; `inlier_masks` NULL or `count` pointers as
/// described; `stats` NULL or `count` writable elements.
#[no_mangle]
pub unsafe extern "C" fn eopnp_ransac_batch(
    ransac: *const EopnpRansac,
    solver: *const EopnpSolver,
    problems: *const EopnpProblem,
    count: usize,
    threads: usize,
    out: *mut EopnpSolution,
    inlier_masks: *const *mut u8,
    stats: *mut EopnpRansacStats,
    statuses: *mut EopnpStatus,
) -> EopnpStatus {
    guard(|| {
        let ransac = &get(ransac, "ransac")?.ransac;
        let solver = &get(solver, "solver")?.solver;
        let problems = slice(problems, count, "problems")?;
        let out = slice_mut(out, count, "out")?;
        let statuses = slice_mut(statuses, count, "statuses")?;
        let masks = if inlier_masks.is_null() {
            None
        } else {
            Some(slice(inlier_masks, count, "inlier_masks")?)
        };
        let mut stats = if stats.is_null() {
            None
        } else {
            Some(slice_mut(stats, count, "stats")?)
        };
        let mut failures = Vec::new();
        let mut valid_inputs = Vec::new();
        let mut valid_masks: Vec<Option<&mut [u8]>> = Vec::new();
        for (i, p) in problems.iter().enumerate() {
            let checked = Inputs::new(p).and_then(|x| {
                let m = match masks.map(|m| m[i]) {
                    Some(m) if !m.is_null() => {
                        Some(slice_mut(m, x.n(), &format!("inlier_masks[{i}]"))?)
                    }
                    _ => None,
                };
                Ok((x, m))
            });
            match checked {
                Ok((x, m)) => {
                    valid_inputs.push((i, x));
                    valid_masks.push(m);
                }
                Err(f) => failures.push((i, f)),
            }
        }
        // The library's batch seeds problem `i` of its slice with `problem_seed(seed, i)`: with
        // invalid problems left out, the indices would shift; so each valid problem is run
        // with its own index's seed here (what `estimate_batch` does for a full slice).
        let jobs: Vec<(usize, &Inputs<'_>, Problem<'_>)> = valid_inputs
            .iter()
            .map(|(i, x)| (*i, x, x.problem()))
            .collect();
        let results = run_in(threads, || {
            use rayon::prelude::*;
            jobs.par_iter()
                .map(|(i, _, p)| {
                    ransac
                        .seed(eopnp::ransac::problem_seed(ransac.seed, *i))
                        .estimate(solver, p)
                })
                .collect::<Vec<_>>()
        })?;
        for (((i, x, _), r), mask) in jobs.iter().zip(results).zip(valid_masks) {
            match r {
                Ok(r) => {
                    out[*i] = x.solution(&r.solution);
                    statuses[*i] = OK;
                    if let Some(m) = mask {
                        write_mask(m, &r.inliers);
                    }
                    if let Some(s) = stats.as_deref_mut() {
                        s[*i] = EopnpRansacStats::from(&r.stats);
                    }
                }
                Err(e) => failures.push((*i, e.into())),
            }
        }
        failures.sort_by_key(|(i, _)| *i);
        for (i, f) in &failures {
            statuses[*i] = f.info.status;
        }
        first_failure(failures)
    })
}

// ---------------------------------------------------------------------------------------------
// COLMAP models.

/// Reads the COLMAP model in directory `dir` (NUL-terminated path; binary `cameras.bin`,
/// `images.bin`, `points3D.bin` or the text `.txt` files, detected; the library's
/// `colmap::read_model` with its default limits) into `*out`, owned by the caller (release with
/// `eopnp_model_free`). A missing or malformed file: `EOPNP_MODEL_ERROR`.
///
/// # Safety
/// `dir` must be NULL or NUL-terminated; `out` NULL or a writable `EopnpModel*`.
#[no_mangle]
pub unsafe extern "C" fn eopnp_model_read(
    dir: *const c_char,
    out: *mut *mut EopnpModel,
) -> EopnpStatus {
    guard(|| {
        let out = get_mut(out, "out")?;
        if dir.is_null() {
            return Err(Failure::null("dir"));
        }
        let bytes = CStr::from_ptr(dir).to_bytes();
        #[cfg(unix)]
        let path = std::path::PathBuf::from(
            <std::ffi::OsStr as std::os::unix::ffi::OsStrExt>::from_bytes(bytes),
        );
        #[cfg(not(unix))]
        let path = std::path::PathBuf::from(
            std::str::from_utf8(bytes).map_err(|_| Failure::invalid("`dir` is not UTF-8"))?,
        );
        let model = colmap::read_model(&path, &ReadOptions::default())?;
        *out = Box::into_raw(Box::new(EopnpModel { model }));
        Ok(())
    })
}

/// Releases a model; NULL does nothing.
///
/// # Safety
/// `model` must be NULL or a live model handle, used by no other thread.
#[no_mangle]
pub unsafe extern "C" fn eopnp_model_free(model: *mut EopnpModel) {
    if !model.is_null() {
        drop(Box::from_raw(model));
    }
}

/// The ids of the model's images, ascending: `*count` receives their number,
/// `ids[0 .. min(*count, capacity)]` the ids. More than `capacity`: `EOPNP_BUFFER_TOO_SMALL`
/// (the first `capacity` written). `ids` may be NULL when `capacity` is 0 (to ask the count).
///
/// # Safety
/// `model` NULL or live; `ids` NULL or `capacity` writable `uint32_t`; `count` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn eopnp_model_image_ids(
    model: *const EopnpModel,
    ids: *mut u32,
    capacity: usize,
    count: *mut usize,
) -> EopnpStatus {
    guard(|| {
        let model = &get(model, "model")?.model;
        let count = get_mut(count, "count")?;
        let ids: &mut [u32] = if capacity == 0 && ids.is_null() {
            &mut []
        } else {
            slice_mut(ids, capacity, "ids")?
        };
        *count = model.images.len();
        for (o, id) in ids.iter_mut().zip(model.images.keys()) {
            *o = *id;
        }
        if model.images.len() > capacity {
            return Err(Failure::new(
                EopnpStatus::EOPNP_BUFFER_TOO_SMALL,
                format!("{} images, room for {capacity}", model.images.len()),
            ));
        }
        Ok(())
    })
}

/// A copy of the model's camera `camera_id` into `*out`, owned by the caller (release with
/// `eopnp_camera_free`). An unknown id: `EOPNP_REGISTER_ERROR`.
///
/// # Safety
/// `model` NULL or live; `out` NULL or a writable `EopnpCamera*`.
#[no_mangle]
pub unsafe extern "C" fn eopnp_model_camera(
    model: *const EopnpModel,
    camera_id: u32,
    out: *mut *mut EopnpCamera,
) -> EopnpStatus {
    guard(|| {
        let model = &get(model, "model")?.model;
        get_mut(out, "out")?;
        let cam = model
            .cameras
            .get(&camera_id)
            .ok_or_else(|| Failure::from(colmap::RegisterError::UnknownCamera(camera_id)))?;
        new_camera(out, *cam)
    })
}

/// `r` for C; `free`: the intrinsics it was registered with.
fn registration(r: &Registration, free: &Free) -> EopnpRegistration {
    EopnpRegistration {
        image_id: r.image_id,
        has_ransac: r.ransac.is_some(),
        n: r.n as u64,
        inliers: r.inliers as u64,
        skipped: r.skipped as u64,
        // `focal_estimated` with an unknown focal length; the estimated camera whenever an
        // intrinsic was free (the solution has one).
        solution: EopnpSolution::of(&r.solution, free.focal()),
        ransac: r
            .ransac
            .as_ref()
            .map_or(EopnpRansacStats::ZERO, EopnpRansacStats::from),
        rotation_error_deg: r.rotation_error_deg,
        translation_error_pct: r.translation_error_pct,
        rmse_px: r.rmse_px,
        model_rmse_px: r.model_rmse_px,
        micros: r.micros,
        has_focal_error: r.focal_error_pct.is_some(),
        focal_error_pct: r.focal_error_pct.unwrap_or(0.0),
    }
}

/// The optional RANSAC handle of the registration functions: none for NULL.
///
/// # Safety
/// `ransac` NULL or live.
unsafe fn optional_ransac<'a>(ransac: *const EopnpRansac) -> Res<Option<&'a Ransac>> {
    if ransac.is_null() {
        Ok(None)
    } else {
        Ok(Some(&get(ransac, "ransac")?.ransac))
    }
}

/// `eopnp_model_register_with`'s body (`eopnp_model_register`: `intrinsics` NULL).
///
/// # Safety
/// As `eopnp_model_register_with`.
unsafe fn register_one(
    model: *const EopnpModel,
    image_id: u32,
    solver: *const EopnpSolver,
    ransac: *const EopnpRansac,
    intrinsics: *const EopnpFreeIntrinsics,
    out: *mut EopnpRegistration,
) -> Res<()> {
    let model = &get(model, "model")?.model;
    let solver = &get(solver, "solver")?.solver;
    let ransac = optional_ransac(ransac)?;
    let free = Free::of_registration(intrinsics)?;
    let out = get_mut(out, "out")?;
    let r = colmap::register_image_with(model, image_id, solver, ransac, |p| free.apply(p))?;
    *out = registration(&r, &free);
    Ok(())
}

/// Registers image `image_id` of the model: its pose from its 2D points with a 3D point,
/// through its camera (the library's `colmap::register_image`), with RANSAC when `ransac` is
/// not NULL, else by a plain solve; with the errors against the model's own pose. Into `*out`.
/// An unknown image or camera: `EOPNP_REGISTER_ERROR`; a solver failure: its own status.
/// `eopnp_model_register_with` also re-estimates intrinsics.
///
/// # Safety
/// `model`, `solver` NULL or live; `ransac` NULL or live; `out` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn eopnp_model_register(
    model: *const EopnpModel,
    image_id: u32,
    solver: *const EopnpSolver,
    ransac: *const EopnpRansac,
    out: *mut EopnpRegistration,
) -> EopnpStatus {
    guard(|| register_one(model, image_id, solver, ransac, ptr::null(), out))
}

/// Registers image `image_id` of the model as `eopnp_model_register` does, re-estimating with
/// the pose the intrinsics that `*intrinsics` makes free, the model's camera the starting guess
/// (the library's `colmap::register_image_with`: with `unknown_focal`, COLMAP's registration
/// with an unknown focal length). `intrinsics` NULL (or all zero): none, as
/// `eopnp_model_register`.
/// `out->solution` has the estimated camera (`focal_estimated` with `unknown_focal`,
/// `camera_estimated` and `camera_params` with any), `out->focal_error_pct` its focal length's
/// error against the model camera's, and `out->rmse_px` is through it. Bad options:
/// `EopnpProblem`'s statuses for its fields of the same names (`EOPNP_INVALID_OPTION` for a
/// bad range, `EOPNP_INVALID_ARGUMENT` for a range without `unknown_focal`,
/// `EOPNP_TOO_FEW_POINTS` for fewer correspondences than half the free parameters).
///
/// # Safety
/// As `eopnp_model_register`; `intrinsics` NULL or a readable `EopnpFreeIntrinsics`.
#[no_mangle]
pub unsafe extern "C" fn eopnp_model_register_with(
    model: *const EopnpModel,
    image_id: u32,
    solver: *const EopnpSolver,
    ransac: *const EopnpRansac,
    intrinsics: *const EopnpFreeIntrinsics,
    out: *mut EopnpRegistration,
) -> EopnpStatus {
    guard(|| register_one(model, image_id, solver, ransac, intrinsics, out))
}

/// `eopnp_model_register_batch_with`'s body (`eopnp_model_register_batch`: `intrinsics`
/// NULL).
///
/// # Safety
/// As `eopnp_model_register_batch_with`.
#[allow(clippy::too_many_arguments)]
unsafe fn register_many(
    model: *const EopnpModel,
    image_ids: *const u32,
    count: usize,
    solver: *const EopnpSolver,
    ransac: *const EopnpRansac,
    intrinsics: *const EopnpFreeIntrinsics,
    threads: usize,
    out: *mut EopnpRegistration,
    statuses: *mut EopnpStatus,
) -> Res<()> {
    let model = &get(model, "model")?.model;
    let solver = &get(solver, "solver")?.solver;
    let ransac = optional_ransac(ransac)?;
    let free = Free::of_registration(intrinsics)?;
    let ids = slice(image_ids, count, "image_ids")?;
    let out = slice_mut(out, count, "out")?;
    let statuses = slice_mut(statuses, count, "statuses")?;
    let results = run_in(threads, || {
        use rayon::prelude::*;
        ids.par_iter()
            .map_init(
                || Registrar::new(model),
                |reg, id| reg.register_with(*id, solver, ransac, |p| free.apply(p)),
            )
            .collect::<Vec<_>>()
    })?;
    let mut failures = Vec::new();
    for (i, r) in results.into_iter().enumerate() {
        match r {
            Ok(r) => {
                out[i] = registration(&r, &free);
                statuses[i] = OK;
            }
            Err(e) => {
                let f = Failure::from(e);
                statuses[i] = f.info.status;
                failures.push((i, f));
            }
        }
    }
    first_failure(failures)
}

/// Registers `count` images of the model (each as `eopnp_model_register`) in parallel on
/// `threads` threads (0: rayon's global pool): `out[i]`, `statuses[i]` for `image_ids[i]`.
/// Returns as `eopnp_solve_batch`.
///
/// # Safety
/// `model`, `solver` NULL or live; `ransac` NULL or live; `image_ids` NULL or `count` ids;
/// `out`, `statuses` NULL or `count` writable elements each.
#[no_mangle]
pub unsafe extern "C" fn eopnp_model_register_batch(
    model: *const EopnpModel,
    image_ids: *const u32,
    count: usize,
    solver: *const EopnpSolver,
    ransac: *const EopnpRansac,
    threads: usize,
    out: *mut EopnpRegistration,
    statuses: *mut EopnpStatus,
) -> EopnpStatus {
    guard(|| {
        register_many(
            model,
            image_ids,
            count,
            solver,
            ransac,
            ptr::null(),
            threads,
            out,
            statuses,
        )
    })
}

/// Registers `count` images of the model, each as `eopnp_model_register_with` with the same
/// `intrinsics` (NULL: none), in parallel as `eopnp_model_register_batch` does. A range without
/// `unknown_focal` fails the whole call (`EOPNP_INVALID_ARGUMENT`, no status written); the
/// library's checks of the options (a bad range: `EOPNP_INVALID_OPTION`) are each image's.
///
/// # Safety
/// As `eopnp_model_register_batch`; `intrinsics` NULL or a readable `EopnpFreeIntrinsics`.
#[no_mangle]
pub unsafe extern "C" fn eopnp_model_register_batch_with(
    model: *const EopnpModel,
    image_ids: *const u32,
    count: usize,
    solver: *const EopnpSolver,
    ransac: *const EopnpRansac,
    intrinsics: *const EopnpFreeIntrinsics,
    threads: usize,
    out: *mut EopnpRegistration,
    statuses: *mut EopnpStatus,
) -> EopnpStatus {
    guard(|| {
        register_many(
            model, image_ids, count, solver, ransac, intrinsics, threads, out, statuses,
        )
    })
}

/// The ids of the model's frames (models with rigs: `rigs.txt`/`frames.txt` or their binary
/// forms; none otherwise), ascending, as `eopnp_model_image_ids` gives the images'.
///
/// # Safety
/// As `eopnp_model_image_ids`.
#[no_mangle]
pub unsafe extern "C" fn eopnp_model_frame_ids(
    model: *const EopnpModel,
    ids: *mut u32,
    capacity: usize,
    count: *mut usize,
) -> EopnpStatus {
    guard(|| {
        let model = &get(model, "model")?.model;
        let count = get_mut(count, "count")?;
        let ids: &mut [u32] = if capacity == 0 && ids.is_null() {
            &mut []
        } else {
            slice_mut(ids, capacity, "ids")?
        };
        *count = model.frames.len();
        for (o, id) in ids.iter_mut().zip(model.frames.keys()) {
            *o = *id;
        }
        if model.frames.len() > capacity {
            return Err(Failure::new(
                EopnpStatus::EOPNP_BUFFER_TOO_SMALL,
                format!("{} frames, room for {capacity}", model.frames.len()),
            ));
        }
        Ok(())
    })
}

fn frame_registration(r: &FrameRegistration) -> EopnpFrameRegistration {
    EopnpFrameRegistration {
        frame_id: r.frame_id,
        rig_id: r.rig_id,
        has_ransac: r.ransac.is_some(),
        images: r.image_ids.len() as u64,
        n: r.n as u64,
        inliers: r.inliers as u64,
        skipped: r.skipped as u64,
        // Registration solves through the model's cameras: no intrinsic is free.
        solution: EopnpSolution::of(&r.solution, false),
        ransac: r
            .ransac
            .as_ref()
            .map_or(EopnpRansacStats::ZERO, EopnpRansacStats::from),
        rotation_error_deg: r.rotation_error_deg,
        translation_error_pct: r.translation_error_pct,
        rmse_px: r.rmse_px,
        model_rmse_px: r.model_rmse_px,
        micros: r.micros,
    }
}

/// Registers frame `frame_id` of a model with rigs: the pose of the frame's rig from all its
/// images' correspondences, each through its own camera and that camera's pose in the rig (the
/// library's `colmap::register_frame`), with RANSAC when `ransac` is not NULL. Into `*out`. An
/// unknown frame or rig, a camera without a pose in the rig, an empty frame:
/// `EOPNP_REGISTER_ERROR`; a solver failure: its own status.
///
/// # Safety
/// `model`, `solver` NULL or live; `ransac` NULL or live; `out` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn eopnp_model_register_frame(
    model: *const EopnpModel,
    frame_id: u32,
    solver: *const EopnpSolver,
    ransac: *const EopnpRansac,
    out: *mut EopnpFrameRegistration,
) -> EopnpStatus {
    guard(|| {
        let model = &get(model, "model")?.model;
        let solver = &get(solver, "solver")?.solver;
        let ransac = if ransac.is_null() {
            None
        } else {
            Some(&get(ransac, "ransac")?.ransac)
        };
        let out = get_mut(out, "out")?;
        let r = colmap::register_frame(model, frame_id, solver, ransac)?;
        *out = frame_registration(&r);
        Ok(())
    })
}
