//! `eopnp.SolverOptions`: the solver's eight options (`refinement`, `planar`, the iteration
//! limits, `exhaustive`, `loss`, `covariance`), validated once, at construction; and
//! `solver_arg`, which every function that solves calls on its `options=` and its keyword
//! arguments. `Keywords::validate` is the one place where options become an `eopnp::Solver`.

use std::collections::hash_map::DefaultHasher;
use std::hash::{Hash, Hasher};

use eopnp::covariance::NoiseModel;
use eopnp::{Loss, PlanarDetection, PnpError, Refinement, Solver};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyList, PyString, PyTuple};

use crate::errors::{option_error, pnp_error};

/// The keyword arguments of the solver options, in the order of `SolverOptions`'s signature.
pub(crate) const KEYWORDS: &[&str] = &[
    "refinement",
    "planar",
    "newton_iterations",
    "newton_step_tolerance",
    "reprojection_iterations",
    "exhaustive",
    "loss",
    "covariance",
];

/// The solver options `refine` takes as keyword arguments (it starts from the given pose:
/// `refinement`, `planar` and `exhaustive`, the options of the global search, are not its
/// keywords).
pub(crate) const REFINE_KEYWORDS: &[&str] = &[
    "newton_iterations",
    "newton_step_tolerance",
    "reprojection_iterations",
    "loss",
    "covariance",
];

/// `covariance=`: estimated from the residuals, or a given noise standard deviation.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Noise {
    Estimated,
    Sigma(f64),
}

/// The options of the solver (the Rust ``eopnp::Solver``), for ``options=`` of every function
/// that solves (``solve``, ``solve_all``, ``refine``, ``solve_ransac``, ``solve_batch``,
/// ``solve_ransac_batch``, ``solve_batch_arrays``, ``register_image``, ``register_images``, and
/// for rigs ``solve_generalized``, ``solve_generalized_ransac``, ``refine_generalized``,
/// ``solve_generalized_batch``, ``solve_generalized_ransac_batch``, ``register_frame``,
/// ``register_frames``).
/// Those functions also take each option as a keyword argument (not together with
/// ``options=``).
///
/// Every option is checked here: a value out of its range raises ``InvalidOptionError``
/// (``option``: its name) at construction, before anything is solved. Immutable (``replace``
/// returns a changed copy), hashable, picklable; ``==`` compares every attribute.
///
/// Args:
///     refinement: "ml" (default; alias "reprojection"): EOPnP then Levenberg-Marquardt on
///         the reprojection error, the maximum-likelihood pose; "algebraic": EOPnP alone.
///     planar: planar branch selection: "auto" (default), "planar" or "nonplanar".
///     newton_iterations: maximum damped-Newton iterations per candidate (None: the
///         library's default, 50).
///     newton_step_tolerance: Newton stops when the step falls to this (None: the library's
///         default, 1e-12); finite and >= 0.
///     reprojection_iterations: maximum Levenberg-Marquardt iterations (None: the library's
///         default, 200).
///     exhaustive: refine every start of every generator (default False: a start certified
///         globally optimal ends the search).
///     loss: the loss of the final refinement: None or "squared" (default; the
///         maximum-likelihood pose for Gaussian noise), ``("huber", s)`` (quadratic up to a
///         residual of ``s``, linear beyond: a few moderate outliers; ``s`` about 1-3 times
///         the noise) or ``("cauchy", s)`` (the influence of a residual decays beyond ``s``:
///         gross outliers hardly move the pose, when RANSAC is not run). ``s`` is in pixels
///         for pixel input (with a ``camera``), in normalised units otherwise; it must be
///         finite and > 0 (about 1e-154 < s < 1e154). ``Solution.cost`` is then the loss's
///         cost.
///     covariance: None (default: no covariance), "estimated" (the noise estimated from the
///         residuals, ``sigma^2 = sum of squared residuals / (2 n - 6)``) or the noise standard
///         deviation of each image coordinate (pixels for pixel input, normalised units
///         otherwise; pycolmap assumes 1 px): fills ``Solution.covariance``, the 6x6
///         covariance of ``[delta_q, delta_t]`` with ``R = Exp(2 delta_q) R_hat``,
///         ``t = t_hat + delta_t`` (pycolmap's convention), and ``Solution.sigma``.
///
/// Attributes:
///     The arguments, as given (``refinement`` "reprojection" reads "ml", ``loss`` None
///     reads "squared", a ``loss`` list reads as a tuple).
#[pyclass(frozen, module = "eopnp", name = "SolverOptions")]
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct PySolverOptions {
    refinement: &'static str,
    planar: &'static str,
    newton_iterations: Option<u32>,
    newton_step_tolerance: Option<f64>,
    reprojection_iterations: Option<u32>,
    exhaustive: bool,
    /// None: the squared loss.
    loss: Option<(&'static str, f64)>,
    covariance: Option<Noise>,
    /// The solver of these options.
    solver: Solver,
}

/// The solver options as given (keyword arguments, a dict, or `SolverOptions`' constructor),
/// not yet checked.
struct Keywords<'py> {
    refinement: String,
    planar: String,
    newton_iterations: Option<i64>,
    newton_step_tolerance: Option<f64>,
    reprojection_iterations: Option<i64>,
    exhaustive: bool,
    loss: Option<Bound<'py, PyAny>>,
    covariance: Option<Bound<'py, PyAny>>,
}

impl Default for Keywords<'_> {
    /// `SolverOptions()`'s.
    fn default() -> Self {
        Keywords {
            refinement: "ml".into(),
            planar: "auto".into(),
            newton_iterations: None,
            newton_step_tolerance: None,
            reprojection_iterations: None,
            exhaustive: false,
            loss: None,
            covariance: None,
        }
    }
}

fn iterations(py: Python<'_>, name: &str, n: Option<i64>) -> PyResult<Option<u32>> {
    n.map(|n| {
        u32::try_from(n).map_err(|_| {
            option_error(
                py,
                name,
                format!("{name} must be an integer in [0, {}], got {n}", u32::MAX),
            )
        })
    })
    .transpose()
}

impl<'py> Keywords<'py> {
    /// The options of the entries of `d` (keyword arguments, or a dict given as `options=`),
    /// each extracted as `SolverOptions`' constructor extracts it: a key not in `allowed` is
    /// `unknown(key)`, a value of the wrong type a `TypeError` naming `what` and the key.
    fn from_dict(
        d: &Bound<'py, PyDict>,
        allowed: &[&str],
        what: &str,
        unknown: impl Fn(&str) -> PyErr,
    ) -> PyResult<Self> {
        let mut k = Keywords::default();
        for (key, value) in d.iter() {
            let key: String = key.extract()?;
            if !allowed.contains(&key.as_str()) {
                return Err(unknown(&key));
            }
            let bad = |e: PyErr| PyTypeError::new_err(format!("{what} argument '{key}': {e}"));
            match key.as_str() {
                "refinement" => k.refinement = value.extract().map_err(bad)?,
                "planar" => k.planar = value.extract().map_err(bad)?,
                "newton_iterations" => k.newton_iterations = value.extract().map_err(bad)?,
                "newton_step_tolerance" => {
                    k.newton_step_tolerance = value.extract().map_err(bad)?;
                }
                "reprojection_iterations" => {
                    k.reprojection_iterations = value.extract().map_err(bad)?;
                }
                "exhaustive" => k.exhaustive = value.extract().map_err(bad)?,
                "loss" => k.loss = Some(value),
                "covariance" => k.covariance = Some(value),
                _ => return Err(unknown(&key)),
            }
        }
        Ok(k)
    }

    /// The checked options and their `Solver`: the one place where options become a
    /// `Solver`. A bad option raises `InvalidOptionError`, before anything is solved.
    fn validate(&self, py: Python<'py>) -> PyResult<PySolverOptions> {
        let (refinement, r) = match self.refinement.as_str() {
            "ml" | "reprojection" => ("ml", Refinement::Reprojection),
            "algebraic" => ("algebraic", Refinement::Algebraic),
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
        let (planar, p) = match self.planar.as_str() {
            "auto" => ("auto", PlanarDetection::Auto),
            "planar" => ("planar", PlanarDetection::Planar),
            "nonplanar" => ("nonplanar", PlanarDetection::NonPlanar),
            other => {
                return Err(option_error(
                    py,
                    "planar",
                    format!("planar must be \"auto\", \"planar\" or \"nonplanar\", got {other:?}"),
                ))
            }
        };
        let newton_iterations = iterations(py, "newton_iterations", self.newton_iterations)?;
        let reprojection_iterations =
            iterations(py, "reprojection_iterations", self.reprojection_iterations)?;
        let newton_step_tolerance = match self.newton_step_tolerance {
            Some(tol) if !(tol.is_finite() && tol >= 0.0) => {
                return Err(option_error(
                    py,
                    "newton_step_tolerance",
                    format!("newton_step_tolerance must be finite and >= 0, got {tol}"),
                ))
            }
            // + 0.0: -0.0 reads (and hashes) as 0.0.
            tol => tol.map(|t| t + 0.0),
        };
        let loss = loss_arg(py, self.loss.as_ref())?;
        let covariance = covariance_arg(py, self.covariance.as_ref())?;

        let mut s = Solver::default()
            .refinement(r)
            .planar_detection(p)
            .exhaustive(self.exhaustive)
            .loss(match loss {
                None => Loss::Squared,
                Some(("huber", s)) => Loss::Huber(s),
                Some((_, s)) => Loss::Cauchy(s),
            })
            .covariance(covariance.map(|c| match c {
                Noise::Estimated => NoiseModel::Estimated,
                Noise::Sigma(s) => NoiseModel::Sigma(s),
            }));
        if let Some(n) = newton_iterations {
            s = s.newton_iterations(n);
        }
        if let Some(n) = reprojection_iterations {
            s = s.reprojection_iterations(n);
        }
        if let Some(tol) = newton_step_tolerance {
            s = s.newton_step_tolerance(tol);
        }
        Ok(PySolverOptions {
            refinement,
            planar,
            newton_iterations,
            newton_step_tolerance,
            reprojection_iterations,
            exhaustive: self.exhaustive,
            loss,
            covariance,
            solver: s,
        })
    }
}

/// `loss=`: None or "squared" (None here), ("huber", s) or ("cauchy", s). A scale the library
/// cannot use raises the library's `InvalidOption` ("loss") error.
fn loss_arg(
    py: Python<'_>,
    arg: Option<&Bound<'_, PyAny>>,
) -> PyResult<Option<(&'static str, f64)>> {
    let Some(a) = arg.filter(|a| !a.is_none()) else {
        return Ok(None);
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
            "squared" => Ok(None),
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
    let (name, loss) = match name.to_str()? {
        "huber" => ("huber", Loss::Huber(scale)),
        "cauchy" => ("cauchy", Loss::Cauchy(scale)),
        _ => return Err(bad()?),
    };
    if loss.is_valid() {
        Ok(Some((name, scale)))
    } else {
        Err(pnp_error(py, &PnpError::InvalidOption { option: "loss" }))
    }
}

/// `covariance=`: None (no covariance), "estimated" or a positive noise standard deviation.
fn covariance_arg(py: Python<'_>, arg: Option<&Bound<'_, PyAny>>) -> PyResult<Option<Noise>> {
    let Some(a) = arg.filter(|a| !a.is_none()) else {
        return Ok(None);
    };
    if let Ok(s) = a.cast::<PyString>() {
        if s.to_str()? == "estimated" {
            return Ok(Some(Noise::Estimated));
        }
    } else if !a.is_instance_of::<PyBool>() {
        if let Ok(sigma) = a.extract::<f64>() {
            if sigma.is_finite() && sigma > 0.0 {
                return Ok(Some(Noise::Sigma(sigma)));
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

impl Default for PySolverOptions {
    /// `SolverOptions()`: the library's `Solver::default()`.
    fn default() -> Self {
        PySolverOptions {
            refinement: "ml",
            planar: "auto",
            newton_iterations: None,
            newton_step_tolerance: None,
            reprojection_iterations: None,
            exhaustive: false,
            loss: None,
            covariance: None,
            solver: Solver::default(),
        }
    }
}

impl PySolverOptions {
    /// The solver of these options.
    pub(crate) fn solver(&self) -> Solver {
        self.solver
    }

    /// Whether these options ask for the pose covariance.
    pub(crate) fn wants_covariance(&self) -> bool {
        self.covariance.is_some()
    }
}

/// The solver of a function's options: `options` (a `SolverOptions`, a dict of its fields,
/// or None) or the keyword arguments `kwargs` (those named in `allowed`), not both. `func`
/// names the function in the messages.
pub(crate) fn solver_arg(
    py: Python<'_>,
    func: &str,
    options: Option<&Bound<'_, PyAny>>,
    kwargs: Option<&Bound<'_, PyDict>>,
    allowed: &[&str],
) -> PyResult<Solver> {
    options_arg(py, func, options, kwargs, allowed).map(|o| o.solver)
}

/// The options of `solver_arg`'s arguments.
pub(crate) fn options_arg(
    py: Python<'_>,
    func: &str,
    options: Option<&Bound<'_, PyAny>>,
    kwargs: Option<&Bound<'_, PyDict>>,
    allowed: &[&str],
) -> PyResult<PySolverOptions> {
    let options = options.filter(|o| !o.is_none());
    let keywords = match kwargs.filter(|k| !k.is_empty()) {
        None => None,
        Some(k) => Some(Keywords::from_dict(
            k,
            allowed,
            &format!("{func}()"),
            |key| {
                PyTypeError::new_err(format!(
                    "{func}() got an unexpected keyword argument '{key}'"
                ))
            },
        )?),
    };
    match (options, keywords) {
        (None, None) => Ok(PySolverOptions::default()),
        (None, Some(k)) => k.validate(py),
        (Some(_), Some(_)) => {
            let given: Vec<String> = kwargs
                .into_iter()
                .flat_map(|k| k.keys())
                .map(|k| k.to_string())
                .collect();
            Err(PyTypeError::new_err(format!(
                "{func}() got options= and the solver option keyword(s) {}: give the options \
                 either as options=SolverOptions(...) or as keyword arguments, not both",
                given.join(", ")
            )))
        }
        (Some(o), None) => {
            if let Ok(o) = o.cast::<PySolverOptions>() {
                Ok(o.get().clone())
            } else if let Ok(d) = o.cast::<PyDict>() {
                let k = Keywords::from_dict(d, KEYWORDS, "SolverOptions()", |key| {
                    option_error(
                        py,
                        key,
                        format!(
                            "unknown solver option {key:?} (known: {})",
                            KEYWORDS.join(", ")
                        ),
                    )
                })?;
                k.validate(py)
            } else {
                Err(option_error(
                    py,
                    "options",
                    format!(
                        "options must be a SolverOptions, a dict of its fields or None, got {}",
                        o.get_type().name()?
                    ),
                ))
            }
        }
    }
}

#[pymethods]
impl PySolverOptions {
    // One Rust parameter per option: this signature is the one place that lists the eight
    // options and their defaults (the functions that solve take them as `**kwargs`).
    #[allow(clippy::too_many_arguments)]
    #[new]
    #[pyo3(signature = (*, refinement = "ml", planar = "auto", newton_iterations = None,
        newton_step_tolerance = None, reprojection_iterations = None, exhaustive = false,
        loss = None, covariance = None))]
    fn new<'py>(
        py: Python<'py>,
        refinement: &str,
        planar: &str,
        newton_iterations: Option<i64>,
        newton_step_tolerance: Option<f64>,
        reprojection_iterations: Option<i64>,
        exhaustive: bool,
        loss: Option<Bound<'py, PyAny>>,
        covariance: Option<Bound<'py, PyAny>>,
    ) -> PyResult<Self> {
        Keywords {
            refinement: refinement.into(),
            planar: planar.into(),
            newton_iterations,
            newton_step_tolerance,
            reprojection_iterations,
            exhaustive,
            loss,
            covariance,
        }
        .validate(py)
    }

    /// "ml" or "algebraic".
    #[getter]
    fn refinement(&self) -> &'static str {
        self.refinement
    }

    /// "auto", "planar" or "nonplanar".
    #[getter]
    fn planar(&self) -> &'static str {
        self.planar
    }

    /// Maximum damped-Newton iterations per candidate, or None (the library's default, 50).
    #[getter]
    fn newton_iterations(&self) -> Option<u32> {
        self.newton_iterations
    }

    /// Newton's step tolerance, or None (the library's default, 1e-12).
    #[getter]
    fn newton_step_tolerance(&self) -> Option<f64> {
        self.newton_step_tolerance
    }

    /// Maximum Levenberg-Marquardt iterations, or None (the library's default, 200).
    #[getter]
    fn reprojection_iterations(&self) -> Option<u32> {
        self.reprojection_iterations
    }

    /// Refine every start of every generator.
    #[getter]
    fn exhaustive(&self) -> bool {
        self.exhaustive
    }

    /// "squared", ``("huber", s)`` or ``("cauchy", s)``.
    #[getter]
    fn loss<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        Ok(match self.loss {
            None => "squared".into_pyobject(py)?.into_any(),
            Some((name, s)) => (name, s).into_pyobject(py)?.into_any(),
        })
    }

    /// None, "estimated" or the noise standard deviation.
    #[getter]
    fn covariance<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        Ok(match self.covariance {
            None => py.None().into_bound(py),
            Some(Noise::Estimated) => "estimated".into_pyobject(py)?.into_any(),
            Some(Noise::Sigma(s)) => s.into_pyobject(py)?.into_any(),
        })
    }

    /// The options as a dict (``SolverOptions(**d)`` gives them back).
    fn as_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        d.set_item("refinement", self.refinement)?;
        d.set_item("planar", self.planar)?;
        d.set_item("newton_iterations", self.newton_iterations)?;
        d.set_item("newton_step_tolerance", self.newton_step_tolerance)?;
        d.set_item("reprojection_iterations", self.reprojection_iterations)?;
        d.set_item("exhaustive", self.exhaustive)?;
        d.set_item("loss", self.loss(py)?)?;
        d.set_item("covariance", self.covariance(py)?)?;
        Ok(d)
    }

    /// A copy with the given options changed: ``options.replace(loss=("huber", 2.0))``.
    #[pyo3(signature = (**changes))]
    fn replace<'py>(
        slf: &Bound<'py, Self>,
        changes: Option<&Bound<'py, PyDict>>,
    ) -> PyResult<Bound<'py, Self>> {
        let py = slf.py();
        let d = slf.get().as_dict(py)?;
        if let Some(c) = changes {
            d.update(c.as_mapping())?;
        }
        Ok(py
            .get_type::<PySolverOptions>()
            .call((), Some(&d))?
            .cast_into::<PySolverOptions>()?)
    }

    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        let d = self.as_dict(py)?;
        let mut parts = Vec::with_capacity(KEYWORDS.len());
        for (k, v) in d.iter() {
            parts.push(format!("{}={}", k.str()?, v.repr()?));
        }
        Ok(format!("SolverOptions({})", parts.join(", ")))
    }

    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        other
            .cast::<PySolverOptions>()
            .is_ok_and(|o| o.get() == self)
    }

    fn __hash__(&self) -> u64 {
        let mut h = DefaultHasher::new();
        (self.refinement, self.planar).hash(&mut h);
        (self.newton_iterations, self.reprojection_iterations).hash(&mut h);
        self.newton_step_tolerance.map(f64::to_bits).hash(&mut h);
        self.exhaustive.hash(&mut h);
        self.loss.map(|(n, s)| (n, s.to_bits())).hash(&mut h);
        match self.covariance {
            None => 0u64.hash(&mut h),
            Some(Noise::Estimated) => 1u64.hash(&mut h),
            Some(Noise::Sigma(s)) => (2u64, s.to_bits()).hash(&mut h),
        }
        h.finish()
    }

    /// Pickling: ``SolverOptions(**as_dict())``.
    fn __getnewargs_ex__<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(Bound<'py, PyTuple>, Bound<'py, PyDict>)> {
        Ok((PyTuple::empty(py), self.as_dict(py)?))
    }
}
