//! `eopnp.Solution`: a pose and how it was found (the Rust `Solution`'s fields, flattened to
//! plain numbers so that it pickles).

use eopnp::camera::{Camera, CameraModel};
use eopnp::{CandidateSource, Solution};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use crate::camera::PyCamera;
use crate::convert::{array1, array2};

/// A covariance: row-major 6 x 6, sigma, the focal length's standard deviation.
type Covariance = ([f64; 36], f64, Option<f64>);

/// A camera pose and how it was found (``x_cam = R @ X + t``, world to camera); from the
/// generalized functions (``solve_generalized``, ...), the rig's pose (``x_rig = R @ X + t``,
/// rig_from_world).
///
/// Attributes:
///     R: rotation matrix, shape (3, 3).
///     t: translation, shape (3,).
///     rvec: OpenCV's rotation vector (axis times angle, radians), shape (3,).
///     q: unit quaternion (w, x, y, z), COLMAP's order, shape (4,).
///     Rt: the 3x4 matrix [R | t].
///     cost: the minimised cost (refinement "ml"): the (weighted) sum of the loss of the
///         squared reprojection residuals, in pixels^2 for pixel input (through the camera),
///         in normalised units otherwise (the sum of squared residuals with the default
///         loss); or the algebraic cost (refinement "algebraic").
///     algebraic_cost: the paper's algebraic cost of the rotation.
///     reprojection_rmse: RMS normalised reprojection residual (multiply by the focal length
///         for pixels); inf if a point lies in the focal plane (algebraic mode only).
///     cheirality_ok: more than half of the points are in front of the camera.
///     degenerate: the configuration is close to degenerate; the pose may be ambiguous.
///     planar: the planar branch produced the starting candidate.
///     source: the candidate generator of the winning start ("case1", ..., "planar1",
///         "planar2", "extra_start", "p3p"; for a rig "generalized" or "gp3p"; "initial" for
///         ``refine`` and ``refine_generalized``).
///     newton_iterations: damped-Newton iterations of the winning candidate (0 when skipped:
///         an exact fit, whose start is already the minimum of the algebraic cost).
///     reprojection_iterations: Levenberg-Marquardt iterations of the refinement.
///     converged: the refinement stopped at a minimum (False when it ran out of iterations or
///         could not start; True in algebraic mode).
///     used: correspondences that entered the solve (weight > 0, undistorted).
///     skipped: correspondences left out because their pixel could not be undistorted.
///     covariance: the pose's 6x6 covariance (``covariance=`` of ``solve``), or None: of
///         ``[delta_q, delta_t]`` with ``R = Exp(2 delta_q) R_hat``, ``t = t_hat + delta_t``
///         (pycolmap's ``return_covariance=True`` convention).
///     sigma: the image noise standard deviation the covariance assumes (given or estimated;
///         pixels for pixel input, normalised units otherwise), or None.
///     camera: with estimated intrinsics (``estimate_focal``, ``refine_principal_point``,
///         ``refine_distortion``), the estimated ``Camera`` (the given one with those
///         intrinsics replaced); None otherwise.
///     focal: the estimated camera's focal lengths ``(fx, fy)`` in pixels, or None.
///     focal_sigma: with ``estimate_focal`` and a covariance, the estimated focal length's
///         standard deviation in pixels (the covariance is then the pose's marginal one);
///         None otherwise.
#[pyclass(frozen, module = "eopnp", name = "Solution")]
#[derive(Clone, Debug)]
pub(crate) struct PySolution {
    /// Row-major.
    r: [f64; 9],
    t: [f64; 3],
    /// (w, x, y, z).
    q: [f64; 4],
    rvec: [f64; 3],
    /// The minimised cost (refinement "ml"): the (weighted) sum of the loss of the squared
    /// reprojection residuals, in pixels^2 for pixel input (through the camera), in normalised
    /// units otherwise (the sum of squared residuals with the default loss); or the algebraic
    /// cost (refinement "algebraic").
    #[pyo3(get)]
    cost: f64,
    /// The paper's algebraic cost of the rotation.
    #[pyo3(get)]
    algebraic_cost: f64,
    /// RMS normalised reprojection residual (multiply by the focal length for pixels); inf if
    /// a point lies in the focal plane (algebraic mode only).
    #[pyo3(get)]
    reprojection_rmse: f64,
    /// More than half of the points are in front of the camera.
    #[pyo3(get)]
    cheirality_ok: bool,
    /// The configuration is close to degenerate; the pose may be ambiguous.
    #[pyo3(get)]
    degenerate: bool,
    /// The planar branch produced the starting candidate.
    #[pyo3(get)]
    planar: bool,
    /// The candidate generator of the winning start ("case1", ..., "planar1", "planar2",
    /// "extra_start", "p3p"; for a rig "generalized" or "gp3p"; "initial" for ``refine`` and
    /// ``refine_generalized``).
    #[pyo3(get)]
    source: &'static str,
    /// Damped-Newton iterations of the winning candidate (0 when skipped: an exact fit, whose
    /// start is already the minimum of the algebraic cost).
    #[pyo3(get)]
    newton_iterations: u32,
    /// Levenberg-Marquardt iterations of the refinement (0 in algebraic mode).
    #[pyo3(get)]
    reprojection_iterations: u32,
    /// The refinement stopped at a minimum (False when it ran out of iterations or could not
    /// start; True in algebraic mode).
    #[pyo3(get)]
    converged: bool,
    /// Correspondences that entered the solve (weight > 0, undistorted).
    #[pyo3(get)]
    used: usize,
    /// Correspondences left out because their pixel could not be undistorted.
    #[pyo3(get)]
    skipped: usize,
    /// Row-major covariance, sigma and the focal length's standard deviation (boxed: most
    /// solutions have none, and a batch moves every solution twice, into its list and into
    /// its Python object).
    cov: Option<Box<Covariance>>,
    /// The estimated camera with estimated intrinsics (boxed, as `cov`).
    cam: Option<Box<Camera>>,
}

const SOURCES: [&str; 12] = [
    "case1",
    "case2",
    "case3",
    "case4",
    "planar1",
    "planar2",
    "extra_start",
    "initial",
    "p3p",
    "generalized",
    "gp3p",
    "other",
];

fn source_name(s: CandidateSource) -> &'static str {
    match s {
        CandidateSource::Case1 => SOURCES[0],
        CandidateSource::Case2 => SOURCES[1],
        CandidateSource::Case3 => SOURCES[2],
        CandidateSource::Case4 => SOURCES[3],
        CandidateSource::Planar1 => SOURCES[4],
        CandidateSource::Planar2 => SOURCES[5],
        CandidateSource::ExtraStart => SOURCES[6],
        CandidateSource::Initial => SOURCES[7],
        CandidateSource::P3p => SOURCES[8],
        CandidateSource::Generalized => SOURCES[9],
        CandidateSource::Gp3p => SOURCES[10],
        _ => SOURCES[11],
    }
}

impl From<&Solution> for PySolution {
    fn from(s: &Solution) -> Self {
        let m = &s.rotation;
        let t = &s.translation;
        let q = *s.pose().rotation.quaternion();
        let rv = s.rvec();
        PySolution {
            r: [
                m[(0, 0)],
                m[(0, 1)],
                m[(0, 2)],
                m[(1, 0)],
                m[(1, 1)],
                m[(1, 2)],
                m[(2, 0)],
                m[(2, 1)],
                m[(2, 2)],
            ],
            t: [t.x, t.y, t.z],
            q: [q.w, q.i, q.j, q.k],
            rvec: [rv.x, rv.y, rv.z],
            cost: s.cost,
            algebraic_cost: s.algebraic_cost,
            reprojection_rmse: s.reprojection_rmse,
            cheirality_ok: s.cheirality_ok,
            degenerate: s.degenerate,
            planar: s.planar,
            source: source_name(s.source),
            newton_iterations: s.newton_iterations,
            reprojection_iterations: s.reprojection_iterations,
            converged: s.converged,
            used: s.used,
            skipped: s.skipped,
            cov: s.covariance.map(|c| {
                let mut m = [0.0; 36];
                for (k, v) in m.iter_mut().enumerate() {
                    *v = c.matrix[(k / 6, k % 6)];
                }
                Box::new((m, c.sigma, c.focal_sigma))
            }),
            cam: s.camera.map(Box::new),
        }
    }
}

/// The focal lengths `(fx, fy)` a solve with an unknown focal length estimated, or `None`: the
/// one place the package reads them from the library's `Solution`.
pub(crate) fn estimated_focal(s: &Solution) -> Option<(f64, f64)> {
    s.camera.map(|c| c.focal_lengths())
}

/// The covariance and the estimated camera of `s` as bits, for `__eq__`.
#[allow(clippy::type_complexity)]
fn intrinsics_bits(
    s: &PySolution,
) -> (
    Option<(Vec<u64>, u64, Option<u64>)>,
    Option<(CameraModel, u64, u64, Vec<u64>)>,
) {
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    (
        s.cov
            .as_deref()
            .map(|(m, sigma, f)| (bits(m), sigma.to_bits(), f.map(f64::to_bits))),
        s.cam
            .as_deref()
            .map(|c| (c.model(), c.width(), c.height(), bits(c.params()))),
    )
}

/// Six decimals, or six significant digits in exponent form for very large or small values.
fn num(x: f64) -> String {
    if x == 0.0 || (1e-4..1e6).contains(&x.abs()) {
        format!("{x:.6}")
    } else {
        format!("{x:.6e}")
    }
}

impl PySolution {
    /// Row-major rotation.
    pub(crate) fn rotation(&self) -> &[f64; 9] {
        &self.r
    }

    pub(crate) fn translation(&self) -> &[f64; 3] {
        &self.t
    }

    /// The library's unit quaternion (w, x, y, z).
    pub(crate) fn quaternion(&self) -> &[f64; 4] {
        &self.q
    }
}

#[pymethods]
impl PySolution {
    /// Rotation matrix, shape (3, 3) (a new array on each access).
    #[getter(R)]
    fn r<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        array2(py, 3, 3, &self.r).into_any()
    }

    /// Translation, shape (3,).
    #[getter]
    fn t<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        array1(py, &self.t).into_any()
    }

    /// OpenCV's rotation vector (``cv2.Rodrigues``), shape (3,).
    #[getter]
    fn rvec<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        array1(py, &self.rvec).into_any()
    }

    /// Unit quaternion (w, x, y, z), shape (4,).
    #[getter]
    fn q<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        array1(py, &self.q).into_any()
    }

    /// The 3x4 matrix [R | t].
    #[getter(Rt)]
    fn rt<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        let r = &self.r;
        let t = &self.t;
        let m = [
            r[0], r[1], r[2], t[0], r[3], r[4], r[5], t[1], r[6], r[7], r[8], t[2],
        ];
        array2(py, 3, 4, &m).into_any()
    }

    /// The pose's 6x6 covariance of ``[delta_q, delta_t]`` (pycolmap's convention), or None
    /// when not asked for (``covariance=``) or not defined (degenerate normal equations).
    #[getter]
    fn covariance<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyAny>> {
        self.cov
            .as_deref()
            .map(|(m, _, _)| array2(py, 6, 6, m).into_any())
    }

    /// The image noise standard deviation the covariance assumes, or None.
    #[getter]
    fn sigma(&self) -> Option<f64> {
        self.cov.as_ref().map(|c| c.1)
    }

    /// The estimated camera with ``estimate_focal``, ``refine_principal_point`` or
    /// ``refine_distortion`` (the given camera with those intrinsics replaced), or None.
    #[getter]
    fn camera(&self) -> Option<PyCamera> {
        self.cam.as_deref().map(|c| PyCamera { inner: *c })
    }

    /// The estimated camera's focal lengths ``(fx, fy)`` in pixels, or None.
    #[getter]
    fn focal(&self) -> Option<(f64, f64)> {
        self.cam.as_deref().map(|c| c.focal_lengths())
    }

    /// The estimated focal length's standard deviation in pixels (``estimate_focal`` with a
    /// covariance), or None.
    #[getter]
    fn focal_sigma(&self) -> Option<f64> {
        self.cov.as_deref().and_then(|c| c.2)
    }

    /// Every field as a dict (arrays for R, t, rvec, q, covariance).
    fn as_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        d.set_item("R", self.r(py))?;
        d.set_item("t", self.t(py))?;
        d.set_item("rvec", self.rvec(py))?;
        d.set_item("q", self.q(py))?;
        d.set_item("cost", self.cost)?;
        d.set_item("algebraic_cost", self.algebraic_cost)?;
        d.set_item("reprojection_rmse", self.reprojection_rmse)?;
        d.set_item("cheirality_ok", self.cheirality_ok)?;
        d.set_item("degenerate", self.degenerate)?;
        d.set_item("planar", self.planar)?;
        d.set_item("source", self.source)?;
        d.set_item("newton_iterations", self.newton_iterations)?;
        d.set_item("reprojection_iterations", self.reprojection_iterations)?;
        d.set_item("converged", self.converged)?;
        d.set_item("used", self.used)?;
        d.set_item("skipped", self.skipped)?;
        d.set_item("covariance", self.covariance(py))?;
        d.set_item("sigma", self.sigma())?;
        d.set_item("camera", self.camera())?;
        d.set_item("focal", self.focal())?;
        d.set_item("focal_sigma", self.focal_sigma())?;
        Ok(d)
    }

    fn __repr__(&self) -> String {
        let v = |a: &[f64]| a.iter().map(|x| num(*x)).collect::<Vec<_>>().join(", ");
        format!(
            "Solution(rvec=[{}], t=[{}], cost={:.3e}, cheirality_ok={}, degenerate={}, \
             converged={}, used={}, skipped={})",
            v(&self.rvec),
            v(&self.t),
            self.cost,
            if self.cheirality_ok { "True" } else { "False" },
            if self.degenerate { "True" } else { "False" },
            if self.converged { "True" } else { "False" },
            self.used,
            self.skipped
        )
    }

    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        match other.cast::<PySolution>() {
            Ok(o) => {
                let o = o.get();
                self.r == o.r
                    && self.t == o.t
                    && self.cost.to_bits() == o.cost.to_bits()
                    && self.algebraic_cost.to_bits() == o.algebraic_cost.to_bits()
                    && self.reprojection_rmse.to_bits() == o.reprojection_rmse.to_bits()
                    && (self.cheirality_ok, self.degenerate, self.planar)
                        == (o.cheirality_ok, o.degenerate, o.planar)
                    && self.source == o.source
                    && (
                        self.newton_iterations,
                        self.reprojection_iterations,
                        self.converged,
                    ) == (o.newton_iterations, o.reprojection_iterations, o.converged)
                    && (self.used, self.skipped) == (o.used, o.skipped)
                    && intrinsics_bits(self) == intrinsics_bits(o)
            }
            Err(_) => false,
        }
    }

    /// Pickling: the fields as a tuple of plain numbers.
    fn __reduce__<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        let rebuild = py.import("eopnp._eopnp")?.getattr("_solution_from_state")?;
        let state = (
            self.r.to_vec(),
            self.t.to_vec(),
            self.q.to_vec(),
            self.rvec.to_vec(),
            (self.cost, self.algebraic_cost, self.reprojection_rmse),
            (self.cheirality_ok, self.degenerate, self.planar),
            self.source,
            (
                self.newton_iterations,
                self.reprojection_iterations,
                self.converged,
            ),
            (self.used, self.skipped),
            self.cov.as_deref().map(|(m, s, f)| (m.to_vec(), *s, *f)),
            self.cam
                .as_deref()
                .map(|c| (c.model().name(), c.width(), c.height(), c.params().to_vec())),
        );
        Ok((rebuild, PyTuple::new(py, [state.into_pyobject(py)?])?))
    }
}

type State = (
    Vec<f64>,
    Vec<f64>,
    Vec<f64>,
    Vec<f64>,
    (f64, f64, f64),
    (bool, bool, bool),
    String,
    (u32, u32, bool),
    (usize, usize),
    Option<(Vec<f64>, f64, Option<f64>)>,
    Option<(String, u64, u64, Vec<f64>)>,
);

/// Rebuilds a `Solution` from `__reduce__`'s state (private; for pickle).
#[pyfunction]
pub(crate) fn _solution_from_state(state: State) -> PyResult<PySolution> {
    let (r, t, q, rvec, costs, flags, source, iters, counts, cov, cam) = state;
    let arr = |v: Vec<f64>, n: usize| -> PyResult<Vec<f64>> {
        if v.len() == n {
            Ok(v)
        } else {
            Err(pyo3::exceptions::PyValueError::new_err(
                "bad Solution state",
            ))
        }
    };
    let (r, t, q, rvec) = (arr(r, 9)?, arr(t, 3)?, arr(q, 4)?, arr(rvec, 3)?);
    let cov = match cov {
        Some((m, s, f)) => Some(Box::new((arr(m, 36)?.try_into().expect("checked"), s, f))),
        None => None,
    };
    let cam = match cam {
        Some((model, w, h, params)) => {
            let c = CameraModel::from_name(&model)
                .and_then(|m| Camera::new(m, w, h, params))
                .map_err(|_| pyo3::exceptions::PyValueError::new_err("bad Solution state"))?;
            Some(Box::new(c))
        }
        None => None,
    };
    let source = SOURCES
        .iter()
        .find(|s| **s == source)
        .copied()
        .unwrap_or(SOURCES[11]);
    Ok(PySolution {
        r: r.try_into().expect("checked"),
        t: t.try_into().expect("checked"),
        q: q.try_into().expect("checked"),
        rvec: rvec.try_into().expect("checked"),
        cost: costs.0,
        algebraic_cost: costs.1,
        reprojection_rmse: costs.2,
        cheirality_ok: flags.0,
        degenerate: flags.1,
        planar: flags.2,
        source,
        newton_iterations: iters.0,
        reprojection_iterations: iters.1,
        converged: iters.2,
        used: counts.0,
        skipped: counts.1,
        cov,
        cam,
    })
}
