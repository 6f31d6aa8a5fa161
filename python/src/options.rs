//! The solver's keyword options (`refinement=`, `planar=`, iteration limits, `exhaustive=`) as
//! an `eopnp::Solver`. `None` keeps the library's default.

use eopnp::covariance::NoiseModel;
use eopnp::{PlanarDetection, Refinement, Solver};
use pyo3::prelude::*;

use crate::errors::option_error;

/// The keyword options shared by `solve`, `solve_all`, `solve_ransac` and `register_image`.
pub(crate) struct SolverOptions<'a> {
    pub refinement: &'a str,
    pub planar: &'a str,
    pub newton_iterations: Option<i64>,
    pub newton_step_tolerance: Option<f64>,
    pub reprojection_iterations: Option<i64>,
    pub exhaustive: bool,
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

impl SolverOptions<'_> {
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
        Ok(s)
    }
}

/// `covariance=`: None (no covariance), "estimated" (the noise estimated from the residuals) or
/// a positive noise standard deviation in image units (pixels with a camera).
pub(crate) fn covariance_arg(
    py: Python<'_>,
    arg: Option<&Bound<'_, PyAny>>,
) -> PyResult<Option<NoiseModel>> {
    let Some(a) = arg else { return Ok(None) };
    if a.is_none() {
        return Ok(None);
    }
    if let Ok(s) = a.extract::<String>() {
        if s == "estimated" {
            return Ok(Some(NoiseModel::Estimated));
        }
    } else if !a.is_instance_of::<pyo3::types::PyBool>() {
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
