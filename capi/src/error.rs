//! Status codes, the per-thread last error, and the guard that every exported function runs its
//! body in (no panic crosses the C boundary).

use std::cell::RefCell;
use std::ffi::{c_char, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};

use eopnp::camera::CameraError;
use eopnp::colmap::{ModelError, RegisterError};
use eopnp::{DegenerateKind, InputKind, PnpError};

/// The result of every function of this interface that can fail. `EOPNP_OK` (0) is success;
/// any other value is a failure, whose message is then `eopnp_last_error_message()` and whose
/// details are `eopnp_last_error()` on the same thread.
///
/// The codes from `EOPNP_TOO_FEW_POINTS` to `EOPNP_NO_CONSENSUS`, and
/// `EOPNP_GRAVITY_MISMATCH` (added later, so numbered after the others), are the variants of
/// the Rust library's `PnpError`, one to one. The others are this interface's own (bad
/// pointers, bad arguments) or the camera, COLMAP model and registration errors of the library.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum EopnpStatus {
    /// Success.
    EOPNP_OK = 0,
    /// A pointer argument that must not be NULL is NULL (the message names it).
    EOPNP_NULL_POINTER = 1,
    /// An argument of this interface is out of range: a stride below the point size, an
    /// unknown enumeration value, a pointer not aligned for its type, a size that overflows, a
    /// non-UTF-8 string, a rotation matrix that is not a rotation, a camera and a rig given
    /// together. The message says which.
    EOPNP_INVALID_ARGUMENT = 2,
    /// `PnpError::TooFewPoints`: fewer than 4 correspondences (with weights: of weight > 0).
    EOPNP_TOO_FEW_POINTS = 3,
    /// `PnpError::LengthMismatch` (not produced through this interface, whose problems have
    /// one count `n` for every array; kept so that the codes mirror `PnpError`).
    EOPNP_LENGTH_MISMATCH = 4,
    /// `PnpError::WeightsLength` (as `EOPNP_LENGTH_MISMATCH`, one count for every array).
    EOPNP_WEIGHTS_LENGTH = 5,
    /// `PnpError::NonFinite`: a world point, an image point or a weight is NaN or infinite
    /// (`EopnpErrorInfo::index` and `input` say which).
    EOPNP_NON_FINITE = 6,
    /// `PnpError::CameraIndicesLength` (as `EOPNP_LENGTH_MISMATCH`).
    EOPNP_CAMERA_INDICES_LENGTH = 7,
    /// `PnpError::UnknownCamera`: a rig problem's camera index names no camera of the rig.
    EOPNP_UNKNOWN_CAMERA = 8,
    /// `PnpError::InvalidWeight`: a weight is negative.
    EOPNP_INVALID_WEIGHT = 9,
    /// `PnpError::Degenerate`: a degenerate configuration (`EopnpErrorInfo::degenerate`).
    EOPNP_DEGENERATE = 10,
    /// `PnpError::NoSolution`: numerical failure on every candidate.
    EOPNP_NO_SOLUTION = 11,
    /// `PnpError::InvalidOption`: an option out of its range (a RANSAC option, the loss scale,
    /// the focal lengths, a non-finite initial pose, an empty rig, ...; the message names it).
    EOPNP_INVALID_OPTION = 12,
    /// `PnpError::NoConsensus`: RANSAC found no consensus.
    EOPNP_NO_CONSENSUS = 13,
    /// A camera could not be built (unknown model name, wrong parameter count, non-finite or
    /// invalid parameters) or a point could not be projected or undistorted (`CameraError`).
    EOPNP_CAMERA_ERROR = 14,
    /// A COLMAP model could not be read (`ModelError`: missing file, parse error, limit).
    EOPNP_MODEL_ERROR = 15,
    /// A COLMAP image could not be registered for a reason other than the solver's: unknown
    /// image or camera id (`RegisterError`). A solver error is reported with its own code.
    EOPNP_REGISTER_ERROR = 16,
    /// A caller-provided output array is too small (e.g. for every local minimum); the count
    /// needed is written where the function documents it.
    EOPNP_BUFFER_TOO_SMALL = 17,
    /// A panic inside the library was caught at the boundary (a bug: please report it with
    /// the message). The outputs are unspecified; the handles stay valid.
    EOPNP_PANIC = 18,
    /// `PnpError::GravityMismatch`: the images contradict the known vertical
    /// (`EopnpProblem::gravity_camera`): the vertical of the images' own pose and the measured
    /// one differ by more than their combined uncertainties allow. The message gives the angle
    /// in degrees and the distance in standard deviations. The vertical, its frames or its
    /// sigma are wrong, or the correspondences are; solve without it to see the images' pose.
    EOPNP_GRAVITY_MISMATCH = 19,
}

/// Which input an `EOPNP_NON_FINITE` error refers to (`EopnpErrorInfo::input`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EopnpInput {
    /// Not an `EOPNP_NON_FINITE` error.
    EOPNP_INPUT_NONE = 0,
    /// A world point.
    EOPNP_INPUT_WORLD = 1,
    /// An image point (normalised or pixel).
    EOPNP_INPUT_IMAGE = 2,
    /// A weight.
    EOPNP_INPUT_WEIGHT = 3,
}

/// The kind of an `EOPNP_DEGENERATE` error (`EopnpErrorInfo::degenerate`), the library's
/// `DegenerateKind`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EopnpDegenerate {
    /// Not an `EOPNP_DEGENERATE` error.
    EOPNP_DEGENERATE_NONE = 0,
    /// All (positively weighted) world points are the same point.
    EOPNP_DEGENERATE_COINCIDENT_WORLD_POINTS = 1,
    /// The world points lie on a line.
    EOPNP_DEGENERATE_COLLINEAR_WORLD_POINTS = 2,
    /// All (positively weighted) image points are the same point.
    EOPNP_DEGENERATE_COINCIDENT_IMAGE_POINTS = 3,
    /// The world coordinates are outside the range f64 can normalise.
    EOPNP_DEGENERATE_SCALE_OUT_OF_RANGE = 4,
    /// A kind added to the library after this interface.
    EOPNP_DEGENERATE_OTHER = 5,
}

/// The details of the last failure on the calling thread (`eopnp_last_error`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EopnpErrorInfo {
    /// The failure's status (`EOPNP_OK` if no call of this thread has failed yet).
    pub status: EopnpStatus,
    /// `EOPNP_NON_FINITE`: which input holds the value; otherwise `EOPNP_INPUT_NONE`.
    pub input: EopnpInput,
    /// `EOPNP_DEGENERATE`: the kind; otherwise `EOPNP_DEGENERATE_NONE`.
    pub degenerate: EopnpDegenerate,
    /// The index of the offending correspondence (`EOPNP_NON_FINITE`, `EOPNP_INVALID_WEIGHT`,
    /// `EOPNP_UNKNOWN_CAMERA`), or of the offending problem of a batch; otherwise 0.
    pub index: u64,
    /// `EOPNP_TOO_FEW_POINTS`: the points given; `EOPNP_NO_CONSENSUS`: the inliers of the best
    /// pose; `EOPNP_UNKNOWN_CAMERA`: the camera index given; otherwise 0.
    pub got: u64,
    /// `EOPNP_TOO_FEW_POINTS`: the points needed; `EOPNP_NO_CONSENSUS`: the inliers needed;
    /// otherwise 0.
    pub need: u64,
}

impl EopnpErrorInfo {
    pub(crate) const fn of(status: EopnpStatus) -> Self {
        EopnpErrorInfo {
            status,
            input: EopnpInput::EOPNP_INPUT_NONE,
            degenerate: EopnpDegenerate::EOPNP_DEGENERATE_NONE,
            index: 0,
            got: 0,
            need: 0,
        }
    }
}

/// A failure: its details and its message.
#[derive(Clone, Debug)]
pub(crate) struct Failure {
    pub info: EopnpErrorInfo,
    pub message: String,
}

impl Failure {
    pub fn new(status: EopnpStatus, message: impl Into<String>) -> Self {
        Failure {
            info: EopnpErrorInfo::of(status),
            message: message.into(),
        }
    }

    pub fn null(name: &str) -> Self {
        Failure::new(EopnpStatus::EOPNP_NULL_POINTER, format!("`{name}` is NULL"))
    }

    pub fn invalid(message: impl Into<String>) -> Self {
        Failure::new(EopnpStatus::EOPNP_INVALID_ARGUMENT, message)
    }
}

fn to_u64(x: usize) -> u64 {
    u64::try_from(x).unwrap_or(u64::MAX)
}

impl From<PnpError> for Failure {
    fn from(e: PnpError) -> Self {
        use EopnpStatus as S;
        let message = e.to_string();
        let mut info = EopnpErrorInfo::of(S::EOPNP_NO_SOLUTION);
        info.status = match e {
            PnpError::TooFewPoints { got, need } => {
                info.got = to_u64(got);
                info.need = to_u64(need);
                S::EOPNP_TOO_FEW_POINTS
            }
            PnpError::LengthMismatch { .. } => S::EOPNP_LENGTH_MISMATCH,
            PnpError::WeightsLength { .. } => S::EOPNP_WEIGHTS_LENGTH,
            PnpError::NonFinite { index, input } => {
                info.index = to_u64(index);
                info.input = match input {
                    InputKind::World => EopnpInput::EOPNP_INPUT_WORLD,
                    InputKind::Image => EopnpInput::EOPNP_INPUT_IMAGE,
                    InputKind::Weight => EopnpInput::EOPNP_INPUT_WEIGHT,
                };
                S::EOPNP_NON_FINITE
            }
            PnpError::CameraIndicesLength { .. } => S::EOPNP_CAMERA_INDICES_LENGTH,
            PnpError::UnknownCamera { index, camera } => {
                info.index = to_u64(index);
                info.got = u64::from(camera);
                S::EOPNP_UNKNOWN_CAMERA
            }
            PnpError::InvalidWeight { index } => {
                info.index = to_u64(index);
                S::EOPNP_INVALID_WEIGHT
            }
            PnpError::Degenerate(kind) => {
                info.degenerate = match kind {
                    DegenerateKind::CoincidentWorldPoints => {
                        EopnpDegenerate::EOPNP_DEGENERATE_COINCIDENT_WORLD_POINTS
                    }
                    DegenerateKind::CollinearWorldPoints => {
                        EopnpDegenerate::EOPNP_DEGENERATE_COLLINEAR_WORLD_POINTS
                    }
                    DegenerateKind::CoincidentImagePoints => {
                        EopnpDegenerate::EOPNP_DEGENERATE_COINCIDENT_IMAGE_POINTS
                    }
                    DegenerateKind::ScaleOutOfRange => {
                        EopnpDegenerate::EOPNP_DEGENERATE_SCALE_OUT_OF_RANGE
                    }
                    _ => EopnpDegenerate::EOPNP_DEGENERATE_OTHER,
                };
                S::EOPNP_DEGENERATE
            }
            PnpError::NoSolution => S::EOPNP_NO_SOLUTION,
            PnpError::InvalidOption { .. } => S::EOPNP_INVALID_OPTION,
            PnpError::NoConsensus {
                inliers, needed, ..
            } => {
                info.got = to_u64(inliers);
                info.need = to_u64(needed);
                S::EOPNP_NO_CONSENSUS
            }
            PnpError::GravityMismatch { .. } => S::EOPNP_GRAVITY_MISMATCH,
            // A variant added to the library after this interface: the nearest general code.
            // Every variant known when this was written has its arm above (the unit test
            // `every_known_pnp_error_has_its_own_status` lists them).
            _ => S::EOPNP_NO_SOLUTION,
        };
        Failure { info, message }
    }
}

impl From<CameraError> for Failure {
    fn from(e: CameraError) -> Self {
        Failure::new(EopnpStatus::EOPNP_CAMERA_ERROR, e.to_string())
    }
}

impl From<ModelError> for Failure {
    fn from(e: ModelError) -> Self {
        Failure::new(EopnpStatus::EOPNP_MODEL_ERROR, e.to_string())
    }
}

impl From<RegisterError> for Failure {
    fn from(e: RegisterError) -> Self {
        match e {
            RegisterError::Solver(e) => Failure::from(e),
            other => Failure::new(EopnpStatus::EOPNP_REGISTER_ERROR, other.to_string()),
        }
    }
}

struct LastError {
    info: EopnpErrorInfo,
    message: CString,
}

thread_local! {
    static LAST: RefCell<LastError> = RefCell::new(LastError {
        info: EopnpErrorInfo::of(EopnpStatus::EOPNP_OK),
        message: CString::default(),
    });
}

/// Records `failure` as the calling thread's last error.
pub(crate) fn record(failure: &Failure) {
    // An interior NUL (a model path, say) cannot cross as a C string: cut it there.
    let bytes: Vec<u8> = failure.message.bytes().take_while(|b| *b != 0).collect();
    let message = CString::new(bytes).unwrap_or_default();
    // `try_with`: a call during the thread's teardown, after the slot is gone, just loses it.
    let _ = LAST.try_with(|l| {
        if let Ok(mut l) = l.try_borrow_mut() {
            *l = LastError {
                info: failure.info,
                message,
            };
        }
    });
}

/// The calling thread's last error's message, valid until the thread's next failing call.
pub(crate) fn last_message() -> *const c_char {
    static EMPTY: &[u8] = b"\0";
    LAST.try_with(|l| l.borrow().message.as_ptr())
        .unwrap_or(EMPTY.as_ptr().cast())
}

pub(crate) fn last_info() -> EopnpErrorInfo {
    LAST.try_with(|l| l.borrow().info)
        .unwrap_or(EopnpErrorInfo::of(EopnpStatus::EOPNP_OK))
}

/// Runs `body`, catching any panic: the status of every exported function that can fail.
/// A failure (or a panic, as `EOPNP_PANIC`) is recorded as the thread's last error.
pub(crate) fn guard(body: impl FnOnce() -> Result<(), Failure>) -> EopnpStatus {
    match catch_unwind(AssertUnwindSafe(body)) {
        Ok(Ok(())) => EopnpStatus::EOPNP_OK,
        Ok(Err(failure)) => {
            record(&failure);
            failure.info.status
        }
        Err(payload) => {
            let what = payload
                .downcast_ref::<&str>()
                .map(|s| (*s).to_owned())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "(no message)".to_owned());
            let failure = Failure::new(
                EopnpStatus::EOPNP_PANIC,
                format!("internal error (a panic caught at the C boundary): {what}"),
            );
            record(&failure);
            EopnpStatus::EOPNP_PANIC
        }
    }
}

#[cfg(test)]
#[path = "../tests/unit/error.rs"]
mod tests;
