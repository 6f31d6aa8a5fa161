//! The camera distortion kernels (`distortion_*`): the hand-written maps they replace (the
//! formulas of the former `src/camera/distortion.rs`, COLMAP's `models.h` and OpenCV's
//! `calibration.cpp`), evaluated generically here over `f64`, complex numbers (complex step)
//! and truncated Taylor series (derivative bounds for the finite-difference checks).
//!
//! Three checks per kernel, each on seeded samples `(u, v)` uniform in `[-1.5, 1.5]^2` with
//! coefficients `N(0, 1) 10^U(-3, 0)`:
//!
//! - values: the kernel's values vs the hand-written map, relative to the absolute-value scale
//!   (the map evaluated at `|u|, |v|, |k|`: every term positive), `TOL_POLY`;
//! - derivatives vs the complex step of the hand-written map (no cancellation), relative to
//!   the absolute-value scale of the derivative, `TOL_POLY`;
//! - derivatives vs central differences of the kernel's own values, with a bound derived per
//!   sample: truncation `h^2 T3 / 6`, rounding `2 E / (2 h)` with `E = gamma_64 S` the
//!   kernel's rounding, and `|hp - hm| / 2 |f''|` for the actual steps (`crate::fd`), where
//!   `T3`, `f''` and `S` are bounded by the Taylor coefficients of the absolute-value map at
//!   `|x| + h` (a polynomial with non-negative coefficients is monotone there).

use crate::checks::{g64, TOL_POLY};
use crate::fd::{nodes, H_COMPLEX, H_REL};
use crate::report::{Measurement, Tracker};
use crate::strategies as st;
use eopnp::internals::kernels as k;
use num_complex::Complex64;
use rand::Rng;
use std::ops::{Add, Mul, Sub};

/// Arithmetic the reference maps need: a ring with real constants.
pub trait Ring: Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> {
    /// The constant `x`.
    fn c(x: f64) -> Self;
}

impl Ring for f64 {
    fn c(x: f64) -> Self {
        x
    }
}

impl Ring for Complex64 {
    fn c(x: f64) -> Self {
        Complex64::new(x, 0.0)
    }
}

/// A power series in `t` truncated after `t^3` (coefficients `[c0, c1, c2, c3]`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Taylor3(pub [f64; 4]);

impl Add for Taylor3 {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Taylor3(std::array::from_fn(|i| self.0[i] + o.0[i]))
    }
}

impl Sub for Taylor3 {
    type Output = Self;
    fn sub(self, o: Self) -> Self {
        Taylor3(std::array::from_fn(|i| self.0[i] - o.0[i]))
    }
}

impl Mul for Taylor3 {
    type Output = Self;
    fn mul(self, o: Self) -> Self {
        Taylor3(std::array::from_fn(|n| {
            (0..=n).map(|i| self.0[i] * o.0[n - i]).sum()
        }))
    }
}

impl Ring for Taylor3 {
    fn c(x: f64) -> Self {
        Taylor3([x, 0.0, 0.0, 0.0])
    }
}

/// One distortion kernel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Model {
    /// `distortion_simple_radial`.
    SimpleRadial,
    /// `distortion_radial`.
    Radial,
    /// `distortion_opencv`.
    OpenCv,
    /// `distortion_fisheye`.
    Fisheye,
    /// `distortion_full_opencv`.
    FullOpenCv,
    /// `distortion_thin_prism`.
    ThinPrism,
}

/// Every distortion kernel.
pub const MODELS: [Model; 6] = [
    Model::SimpleRadial,
    Model::Radial,
    Model::OpenCv,
    Model::Fisheye,
    Model::FullOpenCv,
    Model::ThinPrism,
];

impl Model {
    /// The kernel's name.
    #[must_use]
    pub fn kernel(self) -> &'static str {
        match self {
            Model::SimpleRadial => "distortion_simple_radial",
            Model::Radial => "distortion_radial",
            Model::OpenCv => "distortion_opencv",
            Model::Fisheye => "distortion_fisheye",
            Model::FullOpenCv => "distortion_full_opencv",
            Model::ThinPrism => "distortion_thin_prism",
        }
    }

    /// Number of coefficients.
    #[must_use]
    pub fn ncoeffs(self) -> usize {
        match self {
            Model::SimpleRadial => 1,
            Model::Radial => 2,
            Model::OpenCv | Model::Fisheye => 4,
            Model::FullOpenCv => 8,
            Model::ThinPrism => 12,
        }
    }

    /// The kernel at `(u, v)`: `(values, d values / du, d values / dv)`, values in the order
    /// of [`Model::reference`].
    #[must_use]
    pub fn eval(self, u: f64, v: f64, c: &[f64]) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let x = [u, v];
        let poly = |o: [f64; 7]| (vec![o[0], o[1], o[6]], vec![o[2], o[4]], vec![o[3], o[5]]);
        // [n, d, n_u, n_v, d_u, d_v, tu, tv, t00, t01, t10, t11]
        let rational = |o: [f64; 12]| {
            (
                vec![o[0], o[1], o[6], o[7]],
                vec![o[2], o[4], o[8], o[10]],
                vec![o[3], o[5], o[9], o[11]],
            )
        };
        match self {
            Model::SimpleRadial => poly(k::distortion_simple_radial(&x, &[c[0]])),
            Model::Radial => poly(k::distortion_radial(&x, &[c[0], c[1]])),
            Model::OpenCv => poly(k::distortion_opencv(&x, &std::array::from_fn(|i| c[i]))),
            Model::Fisheye => poly(k::distortion_fisheye(&x, &std::array::from_fn(|i| c[i]))),
            Model::FullOpenCv => rational(k::distortion_full_opencv(
                &x,
                &std::array::from_fn(|i| c[i]),
            )),
            Model::ThinPrism => {
                rational(k::distortion_thin_prism(&x, &std::array::from_fn(|i| c[i])))
            }
        }
    }

    /// The number of differentiated values (the radial factor's derivatives are not output).
    #[must_use]
    pub fn ndiff(self) -> usize {
        match self {
            Model::SimpleRadial | Model::Radial | Model::OpenCv | Model::Fisheye => 2,
            Model::FullOpenCv | Model::ThinPrism => 4,
        }
    }

    /// The hand-written map (the formulas of the former `src/camera/distortion.rs`): for the
    /// polynomial models `[xd, yd, 1 + g]` with `(xd, yd) = (u, v) + D(u, v)`,
    /// `g = r2 (k1 + r2 (k2 + ...))`; for the rational models the pieces `[n, d, tu, tv]`.
    pub fn reference<T: Ring>(self, u: T, v: T, c: &[T]) -> Vec<T> {
        let two = T::c(2.0);
        let (u2, v2, uv) = (u * u, v * v, u * v);
        let r2 = u2 + v2;
        // Horner: r2 (c[0] + r2 (c[1] + ...)).
        let horner = |cs: &[T]| {
            let mut acc = T::c(0.0);
            for &ci in cs.iter().rev() {
                acc = (acc + ci) * r2;
            }
            acc
        };
        let tangential = |p1: T, p2: T| {
            (
                two * p1 * uv + p2 * (r2 + two * u2),
                two * p2 * uv + p1 * (r2 + two * v2),
            )
        };
        match self {
            Model::SimpleRadial | Model::Radial | Model::OpenCv | Model::Fisheye => {
                let nk = match self {
                    Model::SimpleRadial => 1,
                    Model::Fisheye => 4,
                    _ => 2,
                };
                let g = horner(&c[..nk]);
                let (mut du, mut dv) = (u * g, v * g);
                if self == Model::OpenCv {
                    let (tu, tv) = tangential(c[2], c[3]);
                    du = du + tu;
                    dv = dv + tv;
                }
                vec![u + du, v + dv, T::c(1.0) + g]
            }
            Model::FullOpenCv | Model::ThinPrism => {
                let one = T::c(1.0);
                let n = one + horner(&[c[0], c[1], c[4]]);
                let d = one + horner(&[c[5], c[6], c[7]]);
                let (mut tu, mut tv) = tangential(c[2], c[3]);
                if self == Model::ThinPrism {
                    tu = tu + horner(&[c[8], c[9]]);
                    tv = tv + horner(&[c[10], c[11]]);
                }
                vec![n, d, tu, tv]
            }
        }
    }
}

/// Samples `(u, v, coefficients)`.
fn sample(rng: &mut rand_pcg::Pcg64, model: Model) -> (f64, f64, Vec<f64>) {
    let u = rng.random_range(-1.5..1.5);
    let v = rng.random_range(-1.5..1.5);
    let c = (0..model.ncoeffs())
        .map(|_| st::normal(rng) * st::log_uniform(rng, -3.0, 0.0))
        .collect();
    (u, v, c)
}

fn abs_all(c: &[f64]) -> Vec<f64> {
    c.iter().map(|x| x.abs()).collect()
}

/// The reference along `(u, v) + t e_dir` as a Taylor series in `t` (absolute values if
/// `abs`, at `|u| + h`, `|v| + h`).
fn taylor(model: Model, u: f64, v: f64, c: &[f64], dir: usize, h: f64, abs: bool) -> Vec<Taylor3> {
    let (u, v, c) = if abs {
        (u.abs() + h, v.abs() + h, abs_all(c))
    } else {
        (u, v, c.to_vec())
    };
    let tu = Taylor3([u, if dir == 0 { 1.0 } else { 0.0 }, 0.0, 0.0]);
    let tv = Taylor3([v, if dir == 1 { 1.0 } else { 0.0 }, 0.0, 0.0]);
    let tc: Vec<Taylor3> = c.iter().map(|&x| Taylor3::c(x)).collect();
    model.reference(tu, tv, &tc)
}

/// Which comparison.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CameraAgainst {
    /// Values vs the hand-written map.
    Values,
    /// Derivatives vs the complex step of the hand-written map.
    ComplexStep,
    /// Derivatives vs central differences of the kernel's values.
    FiniteDifference,
}

/// Samples per camera check.
pub const N_CAMERA: usize = 10_000;

/// One check of one distortion kernel (module documentation).
#[must_use]
pub fn distortion(model: Model, against: CameraAgainst, n: usize) -> Measurement {
    let seed = 301 + 10 * model as u64 + against as u64;
    let mut rng = st::rng(seed);
    let (check, norm, bound) = match against {
        CameraAgainst::Values => (
            "values vs the hand-written map",
            "max |d value| / S_value",
            format!("{TOL_POLY:.0e}"),
        ),
        CameraAgainst::ComplexStep => (
            "derivatives vs complex step of the hand-written map",
            "max |d deriv| / S_deriv",
            format!("{TOL_POLY:.0e}"),
        ),
        CameraAgainst::FiniteDifference => (
            "derivatives vs central differences of the kernel",
            "max |d deriv| / S_deriv",
            "derived per sample".to_string(),
        ),
    };
    let mut t = Tracker::new(model.kernel(), check, norm, bound);
    for i in 0..n {
        let (u, v, c) = sample(&mut rng, model);
        let (vals, du, dv) = model.eval(u, v, &c);
        let input = || format!("seed {seed} sample {i} (u, v) = ({u:e}, {v:e}) k = {c:?}");
        match against {
            CameraAgainst::Values => {
                let want = model.reference(u, v, &c);
                let scale = model.reference(u.abs(), v.abs(), &abs_all(&c));
                let err = vals
                    .iter()
                    .zip(&want)
                    .zip(&scale)
                    .map(|((a, b), s)| (a - b).abs() / s)
                    .fold(0.0, f64::max);
                t.record(err, TOL_POLY, input);
            }
            CameraAgainst::ComplexStep => {
                let cc: Vec<Complex64> = c.iter().map(|&x| Complex64::c(x)).collect();
                let mut err = 0.0f64;
                for (dir, got) in [(0, &du), (1, &dv)] {
                    let h = Complex64::new(0.0, H_COMPLEX);
                    let (zu, zv) = if dir == 0 {
                        (Complex64::c(u) + h, Complex64::c(v))
                    } else {
                        (Complex64::c(u), Complex64::c(v) + h)
                    };
                    let want = model.reference(zu, zv, &cc);
                    let scale = taylor(model, u, v, &c, dir, 0.0, true);
                    for j in 0..model.ndiff() {
                        let d = (got[j] - want[j].im / H_COMPLEX).abs();
                        if d > 0.0 {
                            err = err.max(d / scale[j].0[1]);
                        }
                    }
                }
                t.record(err, TOL_POLY, input);
            }
            CameraAgainst::FiniteDifference => {
                // (max error / derivative scale, max error / bound) over outputs and directions.
                let (mut err_n, mut ratio) = (0.0f64, 0.0f64);
                for (dir, got) in [(0, &du), (1, &dv)] {
                    let x = [u, v, 0.0];
                    let h = H_REL * x[dir].abs().max(1.0);
                    let (xp, xm, hp, hm) = nodes(&x, dir, h);
                    let (fp, _, _) = model.eval(xp[0], xp[1], &c);
                    let (fm, _, _) = model.eval(xm[0], xm[1], &c);
                    // Bounds on the stencil from the absolute-value map at |x| + max(hp, hm).
                    let big = taylor(model, u, v, &c, dir, hp.max(hm), true);
                    let at = taylor(model, u, v, &c, dir, 0.0, true);
                    for j in 0..model.ndiff() {
                        let fd = (fp[j] - fm[j]) / (hp + hm);
                        let [s0, _, c2, c3] = big[j].0;
                        let rounding = 2.0 * g64() * s0 / (hp + hm);
                        let hmax = hp.max(hm);
                        let trunc = hmax * hmax * c3; // h^2 T3 / 6 with T3 <= 6 c3
                        let steps = (hp - hm).abs() / 2.0 * 2.0 * c2;
                        let bound = rounding + trunc + steps + g64() * at[j].0[1];
                        let err = (got[j] - fd).abs();
                        if err > 0.0 {
                            err_n = err_n.max(err / at[j].0[1]);
                            ratio = ratio.max(err / bound);
                        }
                    }
                }
                t.record_ratio(err_n, ratio, input);
            }
        }
    }
    t.finish()
}

/// Every camera check.
#[must_use]
pub fn all(n: usize) -> Vec<Measurement> {
    let mut out = Vec::new();
    for m in MODELS {
        for a in [
            CameraAgainst::Values,
            CameraAgainst::ComplexStep,
            CameraAgainst::FiniteDifference,
        ] {
            out.push(distortion(m, a, n));
        }
    }
    out
}
