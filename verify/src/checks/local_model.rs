//! The checks of `so3_local_model`, the local model of `newton` on SO(3), and of
//! `so3_local_affine`, the same model of the generalized cost's affine part.

use crate::fd::{self, CHART_D1, CHART_D3, CHART_D4, EVAL_ROUNDING, H_REL};
use crate::reference as rf;
use crate::report::{Measurement, Tracker};
use crate::strategies as st;
use eopnp::internals::kernels as k;
use nalgebra::{Matrix3, Vector3};
use rf::{AffineChart, Chart, LocalModel, QuadraticChart, V9};

use super::{g64, sym3, TOL_POLY};

/// What the local model is compared with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LocalAgainst {
    /// `f` vs `vec(R)^T M vec(R)`.
    Value,
    /// `f, g, H_C` vs the explicit formulas with `M_k = D^T M D`.
    Explicit,
    /// `g` vs central differences of `F(s) = f(R(s) R)`.
    FdGradient,
    /// `H_C - 4 f I` vs second differences of `F` along 6 directions.
    FdHessian,
    /// `g` vs the complex step of `F`.
    CsGradient,
    /// `H_C - 4 f I` vs central differences of the complex-step derivative of `F` along 6
    /// directions.
    CsHessian,
}

/// The 6 unit directions `e_k` and `(e_k + e_l) / sqrt 2`: `u^T H u` on them determines `H`.
#[must_use]
pub fn hessian_directions() -> [Vector3<f64>; 6] {
    let r = std::f64::consts::FRAC_1_SQRT_2;
    [
        Vector3::new(1.0, 0.0, 0.0),
        Vector3::new(0.0, 1.0, 0.0),
        Vector3::new(0.0, 0.0, 1.0),
        Vector3::new(r, r, 0.0),
        Vector3::new(r, 0.0, r),
        Vector3::new(0.0, r, r),
    ]
}

/// Which kernel a local-model check evaluates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LocalKernel {
    /// `so3_local_model`: the quadratic cost `vec(R)^T M vec(R)`.
    Quadratic,
    /// `so3_local_affine`: the generalized cost's affine part `2 g^T vec(R) + k`.
    Affine,
}

/// One random sample: the kernel's outputs, the explicit model, the direct value and the chart.
enum Sample {
    Quadratic { m: Box<rf::M9>, r: Matrix3<f64> },
    Affine { g: V9, k: f64, r: Matrix3<f64> },
}

impl Sample {
    fn draw(kernel: LocalKernel, rng: &mut rand_pcg::Pcg64) -> Self {
        match kernel {
            LocalKernel::Quadratic => {
                let m = st::cost_matrix(rng);
                Sample::Quadratic {
                    m: Box::new(m),
                    r: st::rotation(rng),
                }
            }
            LocalKernel::Affine => {
                // Entries of mixed sign and magnitude (as `g` of a cost mixes them), `k` of
                // either sign.
                let g = V9::from_fn(|_, _| st::normal(rng) * st::log_uniform(rng, -3.0, 3.0));
                let k = st::normal(rng) * st::log_uniform(rng, -3.0, 3.0);
                Sample::Affine {
                    g,
                    k,
                    r: st::rotation(rng),
                }
            }
        }
    }
    fn r(&self) -> &Matrix3<f64> {
        match self {
            Sample::Quadratic { r, .. } | Sample::Affine { r, .. } => r,
        }
    }
    fn kernel(&self) -> [f64; 10] {
        let r = self.r();
        let r9: [f64; 9] = std::array::from_fn(|a| r[(a / 3, a % 3)]);
        match self {
            Sample::Quadratic { m, .. } => k::so3_local_model(&rf::m_upper45(m), &r9),
            Sample::Affine { g, k: kk, .. } => {
                k::so3_local_affine(&std::array::from_fn(|a| g[a]), *kk, &r9)
            }
        }
    }
    fn model(&self) -> LocalModel {
        match self {
            Sample::Quadratic { m, r } => rf::local_model(m, r),
            Sample::Affine { g, k, r } => rf::affine_model(g, *k, r),
        }
    }
    /// `f(R)` evaluated directly from its definition.
    fn direct(&self) -> f64 {
        let vr = rf::vec_r(self.r());
        match self {
            Sample::Quadratic { m, .. } => vr.dot(&(**m * vr)),
            Sample::Affine { g, k, .. } => 2.0 * g.dot(&vr) + k,
        }
    }
}

impl Chart for Sample {
    fn value<T: nalgebra::ComplexField<RealField = f64> + Copy>(&self, s: &[T; 3]) -> T {
        match self {
            Sample::Quadratic { m, r } => QuadraticChart { m, r }.value(s),
            Sample::Affine { g, k, r } => AffineChart { g, k: *k, r }.value(s),
        }
    }
    fn amplitude(&self, u: &Vector3<f64>) -> f64 {
        match self {
            Sample::Quadratic { m, r } => QuadraticChart { m, r }.amplitude(u),
            Sample::Affine { g, k, r } => AffineChart { g, k: *k, r }.amplitude(u),
        }
    }
}

/// Check 3: `so3_local_model`.
///
/// - Value / Explicit: `1e-12` relative to the absolute-value scales (`reference::local_model`),
///   max over the 10 outputs of `|d out| / scale`.
/// - FdGradient: `h = u^(1/3)`, `|dg_k| <= h^2/6 * 73 A + 64 u A / h + gamma_64 S_g,k`
///   (`A = A_{e_k}`, `fd::CHART_D3`).
/// - FdHessian: second differences, `h = 2e-4` (balances `h^2/12 * 386 A` against
///   `4 * 64 u A / h^2`): `|u^T dH u| <= h^2/12 * 386 A_u + 4 * 64 u A_u / h^2 + gamma_64 (u^T S_H u + 4 S_f)`.
/// - CsGradient: `1e-12` relative to `|S_g|_inf`.
/// - CsHessian: `delta = u^(1/3)`, `|u^T dH u| <= delta^2/6 * 386 A_u + 64 u * 4 A_u / delta + gamma_64 (...)`.
///
/// Norm reported: error relative to the absolute-value scale (`S_f`, `|S_g|_inf`,
/// `|S_H|_max + 4 S_f`).
#[must_use]
pub fn local_model(against: LocalAgainst, n: usize) -> Measurement {
    run(LocalKernel::Quadratic, against, n)
}

/// Check 3b: `so3_local_affine`, the same six comparisons as [`local_model`] with the affine
/// part `2 g^T vec(R) + k` in place of the quadratic form (`reference::affine_model`,
/// `reference::affine_amplitude`; the chart bounds hold because the affine part is a
/// trigonometric polynomial of degree 1 along every line of the chart).
#[must_use]
pub fn local_affine(against: LocalAgainst, n: usize) -> Measurement {
    run(LocalKernel::Affine, against, n)
}

fn run(kernel: LocalKernel, against: LocalAgainst, n: usize) -> Measurement {
    let (seed, name, value_check) = match kernel {
        LocalKernel::Quadratic => (
            71 + against as u64,
            "so3_local_model",
            "f vs vec(R)^T M vec(R)",
        ),
        LocalKernel::Affine => (
            171 + against as u64,
            "so3_local_affine",
            "f vs 2 g^T vec(R) + k",
        ),
    };
    let explicit = match kernel {
        LocalKernel::Quadratic => "f, g, H_C vs M_k = D^T M D formulas",
        LocalKernel::Affine => "f, g, H_C vs g_k = D^T g formulas",
    };
    let mut rng = st::rng(seed);
    let (check, norm, bound) = match against {
        LocalAgainst::Value => (value_check, "|df| / S_f", format!("{TOL_POLY:.0e}")),
        LocalAgainst::Explicit => (explicit, "max |d out| / scale", format!("{TOL_POLY:.0e}")),
        LocalAgainst::FdGradient => (
            "g vs central differences of f(R(s) R)",
            "|dg|_inf / |S_g|_inf",
            "derived per sample".into(),
        ),
        LocalAgainst::FdHessian => (
            "H_C - 4 f I vs second differences of f(R(s) R)",
            "|u^T dH u| / (|S_H| + 4 S_f)",
            "derived per sample".into(),
        ),
        LocalAgainst::CsGradient => (
            "g vs complex step of f(R(s) R)",
            "|dg|_inf / |S_g|_inf",
            format!("{TOL_POLY:.0e}"),
        ),
        LocalAgainst::CsHessian => (
            "H_C - 4 f I vs central diff. of complex-step derivative",
            "|u^T dH u| / (|S_H| + 4 S_f)",
            "derived per sample".into(),
        ),
    };
    let mut t = Tracker::new(name, check, norm, bound);
    for i in 0..n {
        let sample = Sample::draw(kernel, &mut rng);
        let r9: [f64; 9] = std::array::from_fn(|a| sample.r()[(a / 3, a % 3)]);
        let out = sample.kernel();
        let f = out[0];
        let g = Vector3::new(out[1], out[2], out[3]);
        let hc = sym3(&[out[4], out[5], out[6], out[7], out[8], out[9]]);
        let lm = sample.model();
        let h_exact = hc - 4.0 * f * Matrix3::identity();
        let sh_tot = lm.sh.amax() + 4.0 * lm.sf;
        let input = || format!("seed {seed} sample {i} R = {:?}", r9);
        match against {
            LocalAgainst::Value => {
                let err = (f - sample.direct()).abs() / lm.sf;
                t.record(err, TOL_POLY, input);
            }
            LocalAgainst::Explicit => {
                let mut err = (f - lm.f).abs() / lm.sf;
                for a in 0..3 {
                    err = err.max((g[a] - lm.g[a]).abs() / lm.sg[a]);
                    for b in a..3 {
                        err = err.max((hc[(a, b)] - lm.hc[(a, b)]).abs() / lm.sh[(a, b)]);
                    }
                }
                t.record(err, TOL_POLY, input);
            }
            LocalAgainst::FdGradient => {
                let h = H_REL;
                let (mut wr, mut we) = (0.0f64, 0.0f64);
                for a in 0..3 {
                    let u = Vector3::ith(a, 1.0);
                    let amp = sample.amplitude(&u);
                    let fdv = fd::chart_central(&sample, &u, h);
                    let bound =
                        h * h / 6.0 * CHART_D3 * amp + EVAL_ROUNDING * amp / h + g64() * lm.sg[a];
                    let err = (g[a] - fdv).abs();
                    wr = wr.max(err / bound);
                    we = we.max(err / lm.sg.amax());
                }
                t.record(we, we / wr.max(f64::MIN_POSITIVE), input);
            }
            LocalAgainst::CsGradient => {
                let mut err = 0.0f64;
                for a in 0..3 {
                    let u = Vector3::ith(a, 1.0);
                    err = err.max((g[a] - fd::chart_complex_step(&sample, &u, 0.0)).abs());
                }
                t.record(err / lm.sg.amax(), TOL_POLY, input);
            }
            LocalAgainst::FdHessian | LocalAgainst::CsHessian => {
                let (mut wr, mut we) = (0.0f64, 0.0f64);
                for u in hessian_directions() {
                    let amp = sample.amplitude(&u);
                    let model = u.dot(&(h_exact * u));
                    let kernel_err = g64() * (u.dot(&(lm.sh * u)) + 4.0 * lm.sf * u.norm_squared());
                    let (est, bound) = if against == LocalAgainst::FdHessian {
                        let h = 2e-4;
                        (
                            fd::chart_second(&sample, &u, h),
                            h * h / 12.0 * CHART_D4 * amp
                                + 4.0 * EVAL_ROUNDING * amp / (h * h)
                                + kernel_err,
                        )
                    } else {
                        let d = H_REL;
                        let est = (fd::chart_complex_step(&sample, &u, d)
                            - fd::chart_complex_step(&sample, &u, -d))
                            / (2.0 * d);
                        (
                            est,
                            d * d / 6.0 * CHART_D4 * amp
                                + EVAL_ROUNDING * CHART_D1 * amp / d
                                + kernel_err,
                        )
                    };
                    let err = (model - est).abs();
                    wr = wr.max(err / bound);
                    we = we.max(err / sh_tot);
                }
                t.record(we, we / wr.max(f64::MIN_POSITIVE), input);
            }
        }
    }
    t.finish()
}
