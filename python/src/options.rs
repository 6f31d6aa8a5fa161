//! The solver's keyword options (`refinement=`, `planar=`, iteration limits, `exhaustive=`,
//! `loss=`, `covariance=`) as an `eopnp::Solver`: the one place where an entry point's keyword
//! arguments become a `Solver`. `None` keeps the library's default.

use eopnp::covariance::NoiseModel;
use eopnp::{Loss, PlanarDetection, PnpError, Refinement, Solver};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyList, PyString, PyTuple};

use crate::errors::{option_error, pnp_error};

/// The keyword options of every entry point that solves (`solve`, `solve_all`, `refine`,
/// `solve_ransac`, the batch functions, `register_image`). `covariance` stays `None` where the
/// entry point has no such keyword.
pub(crate) struct SolverOptions<'a, 'py> {
    pub refinement: &'a str,
    pub planar: &'a str,
    pub newton_iterations: Option<i64>,
    pub newton_step_tolerance: Option<f64>,
    pub reprojection_iterations: Option<i64>,
    pub exhaustive: bool,
    pub loss: Option<&'a Bound<'py, PyAny>>,
    pub covariance: Option<&'a Bound<'py, PyAny>>,
}

impl<'a> SolverOptions<'a, '_> {
    /// The library's defaults (the keyword defaults of the entry points).
    pub(crate) fn default_with(refinement: &'a str) -> Self {
        SolverOptions {
            refinement,
            planar: "auto",
            newton_iterations: None,
            newton_step_tolerance: None,
            reprojection_iterations: None,
            exhaustive: false,
            loss: None,
            covariance: None,
        }
    }
}

fn iterations(py: Python<'_>, name: &str, n: i64) -> PyResult<u32> {
    u32::try_from(n).map_err(|_| {
        option_error(
            py,
            name,
            format!("{name} must be an integer in [0, {}], got {n}", u32::MAX),
        )
    })
}

impl SolverOptions<'_, '_> {
    /// The `Solver` of these options; a bad option raises `InvalidOptionError` before anything
    /// is solved.
    pub(crate) fn solver(&self, py: Python<'_>) -> PyResult<Solver> {
        let refinement = match self.refinement {
            "ml" | "reprojection" => Refinement::Reprojection,
            "algebraic" => Refinement::Algebraic,
            other => {
                return Err(option_error(
                    py,
                    "refinement",
                    format!(
                        "refinement must be \"ml\" (alias \"reprojection\") or \"algebraic\", \
                         got {other:?}"
                    ),
                ))
            }
        };
        let planar = match self.planar {
            "auto" => PlanarDetection::Auto,
            "planar" => PlanarDetection::Planar,
            "nonplanar" => PlanarDetection::NonPlanar,
            other => {
                return Err(option_error(
                    py,
                    "planar",
                    format!("planar must be \"auto\", \"planar\" or \"nonplanar\", got {other:?}"),
                ))
            }
        };
        let mut s = Solver::default()
            .refinement(refinement)
            .planar_detection(planar)
            .exhaustive(self.exhaustive);
        if let Some(n) = self.newton_iterations {
            s = s.newton_iterations(iterations(py, "newton_iterations", n)?);
        }
        if let Some(n) = self.reprojection_iterations {
            s = s.reprojection_iterations(iterations(py, "reprojection_iterations", n)?);
        }
        if let Some(tol) = self.newton_step_tolerance {
            if !(tol.is_finite() && tol >= 0.0) {
                return Err(option_error(
                    py,
                    "newton_step_tolerance",
                    format!("newton_step_tolerance must be finite and >= 0, got {tol}"),
                ));
            }
            s = s.newton_step_tolerance(tol);
        }
        Ok(s.loss(loss_arg(py, self.loss)?)
            .covariance(covariance_arg(py, self.covariance)?))
    }
}

/// `loss=`: None or "squared" (the default), ("huber", s) or ("cauchy", s) with the scale `s`
/// in pixels for pixel input (through the camera), in normalised units otherwise. A scale the
/// library cannot use raises the library's `InvalidOption` ("loss") error here, before any
/// solve (so that a batch raises it rather than returning it for every problem).
fn loss_arg(py: Python<'_>, arg: Option<&Bound<'_, PyAny>>) -> PyResult<Loss> {
    let Some(a) = arg.filter(|a| !a.is_none()) else {
        return Ok(Loss::Squared);
    };
    let bad = || -> PyResult<PyErr> {
        Ok(option_error(
            py,
            "loss",
            format!(
                "loss must be None, \"squared\", (\"huber\", scale) or (\"cauchy\", scale), \
                 got {}",
                a.repr()?
            ),
        ))
    };
    if let Ok(s) = a.cast::<PyString>() {
        return match s.to_str()? {
            "squared" => Ok(Loss::Squared),
            _ => Err(bad()?),
        };
    }
    let parts: Vec<Bound<'_, PyAny>> = if let Ok(t) = a.cast::<PyTuple>() {
        t.iter().collect()
    } else if let Ok(l) = a.cast::<PyList>() {
        l.iter().collect()
    } else {
        return Err(bad()?);
    };
    let [name, scale] = parts.as_slice() else {
        return Err(bad()?);
    };
    let Ok(name) = name.cast::<PyString>() else {
        return Err(bad()?);
    };
    if scale.is_instance_of::<PyBool>() {
        return Err(bad()?);
    }
    let Ok(scale) = scale.extract::<f64>() else {
        return Err(bad()?);
    };
    let loss = match name.to_str()? {
        "huber" => Loss::Huber(scale),
        "cauchy" => Loss::Cauchy(scale),
        _ => return Err(bad()?),
    };
    if loss.is_valid() {
        Ok(loss)
    } else {
        Err(pnp_error(py, &PnpError::InvalidOption { option: "loss" }))
    }
}

/// `covariance=`: None (no covariance), "estimated" (the noise estimated from the residuals) or
/// a positive noise standard deviation in image units (pixels with a camera).
fn covariance_arg(py: Python<'_>, arg: Option<&Bound<'_, PyAny>>) -> PyResult<Option<NoiseModel>> {
    let Some(a) = arg else { return Ok(None) };
    if a.is_none() {
        return Ok(None);
    }
    if let Ok(s) = a.extract::<String>() {
        if s == "estimated" {
            return Ok(Some(NoiseModel::Estimated));
        }
    } else if !a.is_instance_of::<PyBool>() {
        if let Ok(sigma) = a.extract::<f64>() {
            if sigma.is_finite() && sigma > 0.0 {
                return Ok(Some(NoiseModel::Sigma(sigma)));
            }
        }
    }
    Err(option_error(
        py,
        "covariance",
        format!(
            "covariance must be None, \"estimated\" or a finite noise standard deviation > 0, \
             got {}",
            a.repr()?
        ),
    ))
}
