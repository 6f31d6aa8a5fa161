//! Rust errors as the Python exceptions of `eopnp/_errors.py` (one class per family of
//! `PnpError` variants; the variant's name in `kind`, its fields as attributes).

use eopnp::camera::CameraError;
use eopnp::colmap::{Location, ModelError, RegisterError};
use eopnp::{DegenerateKind, InputKind, PnpError};
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::{PyDict, PyModule};

static ERRORS: PyOnceLock<Py<PyModule>> = PyOnceLock::new();

/// A value of an exception's field.
pub(crate) enum Field {
    Int(u64),
    Str(String),
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

/// An instance of `eopnp.<class>(message, kind, **fields)` as a `PyErr`.
pub(crate) fn error(
    py: Python<'_>,
    class: &str,
    kind: &str,
    message: impl Into<String>,
    fields: Vec<(&'static str, Field)>,
) -> PyErr {
    let message = message.into();
    let build = || -> PyResult<PyErr> {
        let module = ERRORS.get_or_try_init(py, || {
            PyModule::import(py, "eopnp._errors").map(Bound::unbind)
        })?;
        let class = module.bind(py).getattr(class)?;
        let kwargs = PyDict::new(py);
        for (key, value) in fields {
            match value {
                Field::Int(v) => kwargs.set_item(key, v)?,
                Field::Str(v) => kwargs.set_item(key, v)?,
                Field::None => kwargs.set_item(key, py.None())?,
            }
        }
        let exc = class.call((message.as_str(), kind), Some(&kwargs))?;
        Ok(PyErr::from_value(exc))
    };
    build().unwrap_or_else(|e| e)
}

/// `InvalidInputError` for an array of the wrong shape.
pub(crate) fn shape_error(py: Python<'_>, argument: &str, message: String) -> PyErr {
    error(
        py,
        "InvalidInputError",
        "Shape",
        message,
        vec![("argument", argument.into())],
    )
}

/// `InputTypeError` for an array that is not of real numbers.
pub(crate) fn dtype_error(py: Python<'_>, argument: &str, message: String) -> PyErr {
    error(
        py,
        "InputTypeError",
        "DType",
        message,
        vec![("argument", argument.into())],
    )
}

/// `InvalidOptionError` for an option of the bindings out of its range.
pub(crate) fn option_error(py: Python<'_>, option: &str, message: String) -> PyErr {
    error(
        py,
        "InvalidOptionError",
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
pub(crate) fn pnp_error(py: Python<'_>, e: &PnpError) -> PyErr {
    let msg = e.to_string();
    let (class, kind, fields): (&str, &str, Vec<(&'static str, Field)>) = match *e {
        PnpError::TooFewPoints { got, need } => (
            "InvalidInputError",
            "TooFewPoints",
            vec![("got", got.into()), ("need", need.into())],
        ),
        PnpError::LengthMismatch { world, image } => (
            "InvalidInputError",
            "LengthMismatch",
            vec![("world", world.into()), ("image", image.into())],
        ),
        PnpError::WeightsLength { weights, points } => (
            "InvalidInputError",
            "WeightsLength",
            vec![("weights", weights.into()), ("points", points.into())],
        ),
        PnpError::NonFinite { index, input } => (
            "InvalidInputError",
            "NonFinite",
            vec![("index", index.into()), ("input", input_name(input).into())],
        ),
        PnpError::InvalidWeight { index } => (
            "InvalidInputError",
            "InvalidWeight",
            vec![("index", index.into())],
        ),
        PnpError::Degenerate(kind) => (
            "DegenerateError",
            "Degenerate",
            vec![("degeneracy", degeneracy(kind).into())],
        ),
        PnpError::NoSolution => ("NoSolutionError", "NoSolution", vec![]),
        PnpError::InvalidOption { option } => (
            "InvalidOptionError",
            "InvalidOption",
            vec![("option", option.into())],
        ),
        PnpError::NoConsensus {
            iterations,
            inliers,
            needed,
        } => (
            "NoConsensusError",
            "NoConsensus",
            vec![
                ("iterations", iterations.into()),
                ("inliers", inliers.into()),
                ("needed", needed.into()),
            ],
        ),
        _ => ("PnpError", "Other", vec![]),
    };
    error(py, class, kind, msg, fields)
}

/// The exception of a camera error.
pub(crate) fn camera_error(py: Python<'_>, e: &CameraError) -> PyErr {
    let kind = match e {
        CameraError::UnsupportedModel(_) => "UnsupportedModel",
        CameraError::ParamCount { .. } => "ParamCount",
        CameraError::InvalidParams(_) => "InvalidParams",
        CameraError::NonFinite => "NonFinite",
        CameraError::NoConvergence { .. } => "NoConvergence",
        CameraError::BeyondHemisphere { .. } => "BeyondHemisphere",
        CameraError::OutOfRange { .. } => "OutOfRange",
        _ => "Other",
    };
    error(py, "CameraError", kind, e.to_string(), vec![])
}

/// The exception of a COLMAP reading error.
pub(crate) fn model_error(py: Python<'_>, e: &ModelError) -> PyErr {
    let (line, offset) = match e.location {
        Location::Line(l) => (Field::from(l), Field::None),
        Location::Offset(o) => (Field::None, Field::Int(o)),
        Location::File => (Field::None, Field::None),
    };
    error(
        py,
        "ModelError",
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
pub(crate) fn register_error(py: Python<'_>, e: &RegisterError) -> PyErr {
    match e {
        RegisterError::Solver(e) => pnp_error(py, e),
        RegisterError::UnknownImage(id) => error(
            py,
            "UnknownIdError",
            "UnknownImage",
            e.to_string(),
            vec![("id", (*id).into())],
        ),
        RegisterError::UnknownCamera(id) => error(
            py,
            "UnknownIdError",
            "UnknownCamera",
            e.to_string(),
            vec![("id", (*id).into())],
        ),
        _ => error(py, "PnpError", "Other", e.to_string(), vec![]),
    }
}
