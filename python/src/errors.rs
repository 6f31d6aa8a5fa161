//! The exceptions of the package, created here with PyO3's `create_exception!` (one class per
//! family of `PnpError` variants, plus the camera and COLMAP families), and the Rust errors as
//! instances of them: the library's message (`str(e)`), the variant's name in `e.kind`, its
//! fields as attributes and in `e.details`.
//!
//! ```text
//! PnpError(Exception)                          base of every error of this package
//! ├── InvalidInputError(PnpError, ValueError)  TooFewPoints, LengthMismatch, WeightsLength,
//! │   │                                        NonFinite, InvalidWeight, CameraIndicesLength,
//! │   │                                        UnknownCamera, EmptyFrame; wrong array shapes
//! │   └── InputTypeError(InvalidInputError, TypeError)   arrays that are not real numbers
//! ├── DegenerateError(PnpError, ValueError)    Degenerate
//! ├── NoSolutionError(PnpError, RuntimeError)  NoSolution
//! ├── InvalidOptionError(PnpError, ValueError) InvalidOption; bad keyword values
//! ├── NoConsensusError(PnpError, RuntimeError) NoConsensus
//! ├── GravityMismatchError(PnpError, ValueError) GravityMismatch
//! ├── CameraError(PnpError, ValueError)        an invalid camera
//! ├── ModelError(PnpError)                     a COLMAP model that cannot be read
//! └── UnknownIdError(PnpError, LookupError)    no such image, camera, frame or rig in a
//!                                              COLMAP model; NoSensorPose
//! ```
//!
//! `create_exception!` takes one base class: each class is created with its base in this
//! package's hierarchy, and `add_to_module` gives the classes that also derive from a builtin
//! exception their second base (`__bases__`), once, when the module is initialised and before
//! any instance exists. Their method resolution order is then that of
//! `class InvalidInputError(PnpError, ValueError)`. Instances pickle by `BaseException`'s own
//! `__reduce__`: the class (by its name in `eopnp`), the message, and the attributes.

use eopnp::camera::CameraError as RustCameraError;
use eopnp::colmap::{Location, ModelError as RustModelError, RegisterError};
use eopnp::{DegenerateKind, InputKind, PnpError as RustPnpError};
use pyo3::create_exception;
use pyo3::exceptions::{PyException, PyLookupError, PyRuntimeError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyTuple, PyType};
use pyo3::PyTypeInfo;

create_exception!(
    eopnp,
    PnpError,
    PyException,
    "Base class of every exception raised by eopnp.\n\
     \n\
     Attributes:\n    \
         kind: the name of the Rust ``PnpError`` variant (``\"TooFewPoints\"``,\n        \
             ``\"NonFinite\"``, ...) or of the package's check (``\"Shape\"``, ``\"DType\"``, ...).\n    \
         details: the variant's fields as a dict; each is also an attribute of the exception\n        \
             (e.g. ``e.index`` and ``e.input`` of a non-finite value).\n\
     \n\
     Exceptions raised by the package pickle with their ``kind`` and fields."
);
create_exception!(
    eopnp,
    InvalidInputError,
    PnpError,
    "Bad input (also a ``ValueError``): too few points (``got``, ``need``), mismatched lengths\n\
     (``world``, ``image``; ``weights``, ``points``), a NaN or infinite value (``index``,\n\
     ``input``: ``\"world\"``, ``\"image\"`` or ``\"weights\"``), a negative weight (``index``),\n\
     an array of the wrong shape (kind ``\"Shape\"``, ``argument``); for a rig, camera indices\n\
     not one per point (kind ``\"CameraIndicesLength\"``, ``indices``, ``points``) or naming a\n\
     camera the rig does not have (kind ``\"UnknownCamera\"``: correspondence ``index`` is in\n\
     ``camera``); a COLMAP frame without images (kind ``\"EmptyFrame\"``, ``id``)."
);
create_exception!(
    eopnp,
    InputTypeError,
    InvalidInputError,
    "An input that is not an array of real numbers (also a ``TypeError``; kind ``\"DType\"``,\n\
     ``argument``): complex, boolean, object or string data."
);
create_exception!(
    eopnp,
    DegenerateError,
    PnpError,
    "A degenerate configuration (also a ``ValueError``; kind ``\"Degenerate\"``);\n\
     ``degeneracy`` is one of ``\"coincident_world_points\"``, ``\"collinear_world_points\"``,\n\
     ``\"coincident_image_points\"``, ``\"scale_out_of_range\"``."
);
create_exception!(
    eopnp,
    NoSolutionError,
    PnpError,
    "No candidate pose survived (also a ``RuntimeError``): numerical failure on extremely\n\
     ill-conditioned input."
);
create_exception!(
    eopnp,
    InvalidOptionError,
    PnpError,
    "An option out of its range or of the wrong form (also a ``ValueError``; ``option``: its\n\
     name)."
);
create_exception!(
    eopnp,
    NoConsensusError,
    PnpError,
    "RANSAC found no consensus (also a ``RuntimeError``): no pose had enough inliers for a fit,\n\
     or the best pose's ``inliers`` are no more than a wrong pose reaches by chance\n\
     (``needed``: the least accepted; ``iterations``: samples drawn)."
);
create_exception!(
    eopnp,
    GravityMismatchError,
    PnpError,
    "The images contradict the known vertical given as ``gravity=`` (also a ``ValueError``; kind\n\
     ``\"GravityMismatch\"``): the vertical of the maximum-likelihood pose is ``angle_deg``\n\
     degrees off the measured one, ``sigmas`` standard deviations of their combined\n\
     uncertainty (a right vertical is reported with a probability of 0.27 %)."
);
create_exception!(
    eopnp,
    CameraError,
    PnpError,
    "An invalid camera (also a ``ValueError``): unsupported model, wrong number of parameters,\n\
     non-finite or non-positive focal lengths, a malformed ``K`` or distortion vector."
);
create_exception!(
    eopnp,
    ModelError,
    PnpError,
    "A COLMAP model that cannot be read: ``file``, ``line`` or ``offset`` (or None), and\n\
     ``reason``."
);
create_exception!(
    eopnp,
    UnknownIdError,
    PnpError,
    "No image (kind ``\"UnknownImage\"``), camera (``\"UnknownCamera\"``), frame\n\
     (``\"UnknownFrame\"``) or rig (``\"UnknownRig\"``) with this ``id`` in the model, or a\n\
     frame's camera without a known pose in its rig (``\"NoSensorPose\"``: ``rig_id``,\n\
     ``camera_id``, and ``id`` the camera's) (also a ``LookupError``)."
);

/// Adds the exception classes to the module, each with its builtin second base (see the
/// module's documentation).
pub(crate) fn add_to_module(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    let mixed: [(Bound<'_, PyType>, Bound<'_, PyType>, Bound<'_, PyType>); 9] = [
        (
            InvalidInputError::type_object(py),
            PnpError::type_object(py),
            PyValueError::type_object(py),
        ),
        (
            InputTypeError::type_object(py),
            InvalidInputError::type_object(py),
            PyTypeError::type_object(py),
        ),
        (
            DegenerateError::type_object(py),
            PnpError::type_object(py),
            PyValueError::type_object(py),
        ),
        (
            NoSolutionError::type_object(py),
            PnpError::type_object(py),
            PyRuntimeError::type_object(py),
        ),
        (
            InvalidOptionError::type_object(py),
            PnpError::type_object(py),
            PyValueError::type_object(py),
        ),
        (
            NoConsensusError::type_object(py),
            PnpError::type_object(py),
            PyRuntimeError::type_object(py),
        ),
        (
            GravityMismatchError::type_object(py),
            PnpError::type_object(py),
            PyValueError::type_object(py),
        ),
        (
            CameraError::type_object(py),
            PnpError::type_object(py),
            PyValueError::type_object(py),
        ),
        (
            UnknownIdError::type_object(py),
            PnpError::type_object(py),
            PyLookupError::type_object(py),
        ),
    ];
    for (class, base, builtin) in mixed {
        // Idempotent: the same two bases whenever the module is initialised.
        class.setattr("__bases__", PyTuple::new(py, [base, builtin])?)?;
    }
    m.add("PnpError", PnpError::type_object(py))?;
    m.add("InvalidInputError", InvalidInputError::type_object(py))?;
    m.add("InputTypeError", InputTypeError::type_object(py))?;
    m.add("DegenerateError", DegenerateError::type_object(py))?;
    m.add("NoSolutionError", NoSolutionError::type_object(py))?;
    m.add("InvalidOptionError", InvalidOptionError::type_object(py))?;
    m.add(
        "GravityMismatchError",
        GravityMismatchError::type_object(py),
    )?;
    m.add("NoConsensusError", NoConsensusError::type_object(py))?;
    m.add("CameraError", CameraError::type_object(py))?;
    m.add("ModelError", ModelError::type_object(py))?;
    m.add("UnknownIdError", UnknownIdError::type_object(py))?;
    Ok(())
}

/// A value of an exception's field.
pub(crate) enum Field {
    Int(u64),
    /// A signed value (a camera index as given, which may be negative).
    Signed(i64),
    Str(String),
    Float(f64),
    None,
}

impl From<usize> for Field {
    fn from(v: usize) -> Self {
        Field::Int(v as u64)
    }
}

impl From<u32> for Field {
    fn from(v: u32) -> Self {
        Field::Int(u64::from(v))
    }
}

impl From<i64> for Field {
    fn from(v: i64) -> Self {
        Field::Signed(v)
    }
}

impl From<&str> for Field {
    fn from(v: &str) -> Self {
        Field::Str(v.to_string())
    }
}

impl From<String> for Field {
    fn from(v: String) -> Self {
        Field::Str(v)
    }
}

/// An instance of `class(message)` with `kind`, `details` and the fields set, as a `PyErr`.
fn instance(
    class: &Bound<'_, PyType>,
    kind: &str,
    message: String,
    fields: Vec<(&'static str, Field)>,
) -> PyErr {
    let py = class.py();
    let build = || -> PyResult<PyErr> {
        let exc = class.call1((message,))?;
        let details = PyDict::new(py);
        for (key, value) in fields {
            let value = match value {
                Field::Int(v) => v.into_pyobject(py)?.into_any(),
                Field::Signed(v) => v.into_pyobject(py)?.into_any(),
                Field::Str(v) => v.into_pyobject(py)?.into_any(),
                Field::Float(v) => v.into_pyobject(py)?.into_any(),
                Field::None => py.None().into_bound(py),
            };
            details.set_item(key, &value)?;
            exc.setattr(key, value)?;
        }
        exc.setattr("kind", kind)?;
        exc.setattr("details", details)?;
        Ok(PyErr::from_value(exc))
    };
    build().unwrap_or_else(|e| e)
}

/// An instance of the exception class `T` with `kind` and `fields`, as a `PyErr`.
pub(crate) fn error<T: PyTypeInfo>(
    py: Python<'_>,
    kind: &str,
    message: impl Into<String>,
    fields: Vec<(&'static str, Field)>,
) -> PyErr {
    instance(&T::type_object(py), kind, message.into(), fields)
}

/// `InvalidInputError` for an array of the wrong shape.
pub(crate) fn shape_error(py: Python<'_>, argument: &str, message: String) -> PyErr {
    error::<InvalidInputError>(py, "Shape", message, vec![("argument", argument.into())])
}

/// `InputTypeError` for an array that is not of real numbers.
pub(crate) fn dtype_error(py: Python<'_>, argument: &str, message: String) -> PyErr {
    error::<InputTypeError>(py, "DType", message, vec![("argument", argument.into())])
}

/// `InvalidOptionError` for an option of the bindings out of its range.
pub(crate) fn option_error(py: Python<'_>, option: &str, message: String) -> PyErr {
    error::<InvalidOptionError>(
        py,
        "InvalidOption",
        message,
        vec![("option", option.into())],
    )
}

fn input_name(input: InputKind) -> &'static str {
    match input {
        InputKind::World => "world",
        InputKind::Image => "image",
        InputKind::Weight => "weights",
    }
}

fn degeneracy(kind: DegenerateKind) -> &'static str {
    match kind {
        DegenerateKind::CoincidentWorldPoints => "coincident_world_points",
        DegenerateKind::CollinearWorldPoints => "collinear_world_points",
        DegenerateKind::CoincidentImagePoints => "coincident_image_points",
        DegenerateKind::ScaleOutOfRange => "scale_out_of_range",
        _ => "other",
    }
}

/// The exception of a solver error, with the library's message.
pub(crate) fn pnp_error(py: Python<'_>, e: &RustPnpError) -> PyErr {
    let msg = e.to_string();
    let (class, kind, fields): (Bound<'_, PyType>, &str, Vec<(&'static str, Field)>) = match *e {
        RustPnpError::TooFewPoints { got, need } => (
            InvalidInputError::type_object(py),
            "TooFewPoints",
            vec![("got", got.into()), ("need", need.into())],
        ),
        RustPnpError::LengthMismatch { world, image } => (
            InvalidInputError::type_object(py),
            "LengthMismatch",
            vec![("world", world.into()), ("image", image.into())],
        ),
        RustPnpError::WeightsLength { weights, points } => (
            InvalidInputError::type_object(py),
            "WeightsLength",
            vec![("weights", weights.into()), ("points", points.into())],
        ),
        RustPnpError::NonFinite { index, input } => (
            InvalidInputError::type_object(py),
            "NonFinite",
            vec![("index", index.into()), ("input", input_name(input).into())],
        ),
        RustPnpError::InvalidWeight { index } => (
            InvalidInputError::type_object(py),
            "InvalidWeight",
            vec![("index", index.into())],
        ),
        RustPnpError::CameraIndicesLength { indices, points } => (
            InvalidInputError::type_object(py),
            "CameraIndicesLength",
            vec![("indices", indices.into()), ("points", points.into())],
        ),
        RustPnpError::UnknownCamera { index, camera } => {
            return unknown_camera(py, index, i64::from(camera));
        }
        RustPnpError::Degenerate(kind) => (
            DegenerateError::type_object(py),
            "Degenerate",
            vec![("degeneracy", degeneracy(kind).into())],
        ),
        RustPnpError::NoSolution => (NoSolutionError::type_object(py), "NoSolution", vec![]),
        RustPnpError::InvalidOption { option } => (
            InvalidOptionError::type_object(py),
            "InvalidOption",
            vec![("option", option.into())],
        ),
        RustPnpError::NoConsensus {
            iterations,
            inliers,
            needed,
        } => (
            NoConsensusError::type_object(py),
            "NoConsensus",
            vec![
                ("iterations", iterations.into()),
                ("inliers", inliers.into()),
                ("needed", needed.into()),
            ],
        ),
        RustPnpError::GravityMismatch { angle_deg, sigmas } => (
            GravityMismatchError::type_object(py),
            "GravityMismatch",
            vec![
                ("angle_deg", Field::Float(angle_deg)),
                ("sigmas", Field::Float(sigmas)),
            ],
        ),
        _ => (PnpError::type_object(py), "Other", vec![]),
    };
    instance(&class, kind, msg, fields)
}

/// `InvalidInputError` (kind `"UnknownCamera"`): correspondence `index` of a rig problem names
/// camera `camera` (as given: possibly negative), which the rig does not have. The library's
/// `PnpError::UnknownCamera` and the package's own check of camera indices (which also sees
/// negative ones) give the same exception, with the library's message.
pub(crate) fn unknown_camera(py: Python<'_>, index: usize, camera: i64) -> PyErr {
    error::<InvalidInputError>(
        py,
        "UnknownCamera",
        format!("correspondence {index} is in camera {camera}, which the rig does not have"),
        vec![("index", index.into()), ("camera", camera.into())],
    )
}

/// The exception of a camera error.
pub(crate) fn camera_error(py: Python<'_>, e: &RustCameraError) -> PyErr {
    let kind = match e {
        RustCameraError::UnsupportedModel(_) => "UnsupportedModel",
        RustCameraError::ParamCount { .. } => "ParamCount",
        RustCameraError::InvalidParams(_) => "InvalidParams",
        RustCameraError::NonFinite => "NonFinite",
        RustCameraError::NoConvergence { .. } => "NoConvergence",
        RustCameraError::BeyondHemisphere { .. } => "BeyondHemisphere",
        RustCameraError::OutOfRange { .. } => "OutOfRange",
        _ => "Other",
    };
    error::<CameraError>(py, kind, e.to_string(), vec![])
}

/// The exception of a COLMAP reading error.
pub(crate) fn model_error(py: Python<'_>, e: &RustModelError) -> PyErr {
    let (line, offset) = match e.location {
        Location::Line(l) => (Field::from(l), Field::None),
        Location::Offset(o) => (Field::None, Field::Int(o)),
        Location::File => (Field::None, Field::None),
    };
    error::<ModelError>(
        py,
        "Model",
        e.to_string(),
        vec![
            ("file", e.file.display().to_string().into()),
            ("line", line),
            ("offset", offset),
            ("reason", e.reason.clone().into()),
        ],
    )
}

/// The exception of a registration error.
/// A batch's option error, raised: an option out of range (`InvalidOption`) fails every problem
/// of a batch alike, since it does not depend on the problem, so the batch raises it as one call
/// would, rather than returning it once per problem. `errors` are the problems' errors.
pub(crate) fn raise_option_error<'a>(
    py: Python<'_>,
    errors: impl IntoIterator<Item = &'a RustPnpError>,
) -> PyResult<()> {
    match errors
        .into_iter()
        .find(|e| matches!(e, RustPnpError::InvalidOption { .. }))
    {
        Some(e) => Err(pnp_error(py, e)),
        None => Ok(()),
    }
}

/// A batch of registrations as the list `register_images` and `register_frames` return: each
/// result converted by `to_py`, or its error as an exception instance (not raised); an option
/// error raised instead ([`raise_option_error`]).
pub(crate) fn registrations<'py, T, U: IntoPyObject<'py>>(
    py: Python<'py>,
    results: Vec<Result<T, RegisterError>>,
    mut to_py: impl FnMut(T) -> PyResult<U>,
) -> PyResult<Bound<'py, PyList>> {
    raise_option_error(
        py,
        results.iter().filter_map(|r| match r {
            Err(RegisterError::Solver(e)) => Some(e),
            _ => None,
        }),
    )?;
    let out = PyList::empty(py);
    for r in results {
        match r {
            Ok(reg) => out.append(to_py(reg)?)?,
            Err(e) => out.append(register_error(py, &e).into_value(py))?,
        }
    }
    Ok(out)
}

pub(crate) fn register_error(py: Python<'_>, e: &RegisterError) -> PyErr {
    match e {
        RegisterError::Solver(e) => pnp_error(py, e),
        RegisterError::UnknownImage(id) => error::<UnknownIdError>(
            py,
            "UnknownImage",
            e.to_string(),
            vec![("id", (*id).into())],
        ),
        RegisterError::UnknownCamera(id) => error::<UnknownIdError>(
            py,
            "UnknownCamera",
            e.to_string(),
            vec![("id", (*id).into())],
        ),
        RegisterError::UnknownFrame(id) => error::<UnknownIdError>(
            py,
            "UnknownFrame",
            e.to_string(),
            vec![("id", (*id).into())],
        ),
        RegisterError::UnknownRig(id) => {
            error::<UnknownIdError>(py, "UnknownRig", e.to_string(), vec![("id", (*id).into())])
        }
        RegisterError::NoSensorPose { rig_id, camera_id } => error::<UnknownIdError>(
            py,
            "NoSensorPose",
            e.to_string(),
            vec![
                ("id", (*camera_id).into()),
                ("rig_id", (*rig_id).into()),
                ("camera_id", (*camera_id).into()),
            ],
        ),
        RegisterError::EmptyFrame(id) => {
            error::<InvalidInputError>(py, "EmptyFrame", e.to_string(), vec![("id", (*id).into())])
        }
        _ => error::<PnpError>(py, "Other", e.to_string(), vec![]),
    }
}
