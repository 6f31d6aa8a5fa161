//! The lens distortion maps of the camera models and their Jacobians with respect to the
//! normalised point they distort (COLMAP's `src/colmap/sensor/models.h`, OpenCV's
//! `calib3d/src/calibration.cpp`).
//!
//! Each model's map `(u, v) -> (u, v) + D(u, v)` is written once here as a polynomial in
//! `(u, v)` and its coefficients, with `r2 = u^2 + v^2` and the radial factor (a polynomial in
//! `r2`) as named intermediates; the Jacobian is derived from it by the chain rule through
//! those intermediates (forward-mode differentiation over exact polynomials: every
//! intermediate carries its partial derivatives in `u` and `v`). Nothing is typed in by hand
//! but the maps themselves.
//!
//! The rational model (`FULL_OPENCV`, and with the thin-prism terms OpenCV's 12- and
//! 14-coefficient models) is a quotient: the kernels give its polynomial pieces (numerator and
//! denominator of the radial factor, the tangential and thin-prism terms) and their
//! derivatives, and the division is left to the caller. The equidistant fisheye map
//! `theta = atan r` and OpenCV's projective tilt are not polynomial and stay hand-written in
//! `src/camera/`.

use crate::poly::{q, Poly, Var};
use crate::program::Kernel;
use std::collections::BTreeMap;

const DEF: &str = "codegen/src/defs/camera.rs";

/// A quantity and its partial derivatives in `(u, v)`, polynomials in the kernel's inputs and
/// intermediates.
#[derive(Clone)]
struct Dual {
    value: Poly,
    d: [Poly; 2],
}

/// The symbols of one distortion kernel: the point, and the partial derivatives of every
/// intermediate defined so far.
struct Ctx {
    u: Poly,
    v: Poly,
    /// For each variable with a non-zero derivative: `(d/du, d/dv)`.
    deriv: BTreeMap<Var, [Poly; 2]>,
}

impl Ctx {
    /// The partial derivative of `p` in `u` (`wrt = 0`) or `v` (`wrt = 1`), by the chain rule
    /// through the intermediates of `self.deriv`; every other symbol is a constant.
    fn partial(&self, p: &Poly, wrt: usize) -> Poly {
        let mut out = Poly::zero();
        for (&var, d) in &self.deriv {
            let dp = p.derivative(var);
            if !dp.is_zero() && !d[wrt].is_zero() {
                out = out.add(&dp.mul(&d[wrt]));
            }
        }
        out
    }

    fn dual(&self, p: Poly) -> Dual {
        let d = [self.partial(&p, 0), self.partial(&p, 1)];
        Dual { value: p, d }
    }

    /// Names `p` as an intermediate of `k` and records its derivatives.
    fn define(&mut self, k: &mut Kernel, name: &str, p: &Poly) -> Poly {
        let d = [self.partial(p, 0), self.partial(p, 1)];
        let x = k.define(name, p.clone());
        let var = x.as_var().expect("a defined intermediate is a variable");
        self.deriv.insert(var, d);
        x
    }
}

/// Starts a distortion kernel: the inputs `x = [u, v]` and `k = coefficients`, and `r2`.
fn start(name: &str, coeffs: &[&str], coeff_doc: &str) -> (Kernel, Ctx, Vec<Poly>, Poly) {
    let mut k = Kernel::new(name, DEF);
    let x = k.input_array(
        "x",
        &["u".into(), "v".into()],
        "the normalised point `(u, v)` the distortion applies to",
    );
    let c = k.input_array(
        "k",
        &coeffs.iter().map(|s| (*s).to_string()).collect::<Vec<_>>(),
        coeff_doc,
    );
    let (u, v) = (x[0].clone(), x[1].clone());
    let mut deriv = BTreeMap::new();
    deriv.insert(u.as_var().expect("var"), [Poly::int(1), Poly::zero()]);
    deriv.insert(v.as_var().expect("var"), [Poly::zero(), Poly::int(1)]);
    let mut ctx = Ctx { u, v, deriv };
    let r2 = ctx.u.mul(&ctx.u).add(&ctx.v.mul(&ctx.v));
    let r2 = ctx.define(&mut k, "r2", &r2);
    (k, ctx, c, r2)
}

/// `c0 + c[0] r2 + c[1] r2^2 + ...` (Horner order does not matter: exact polynomials).
fn poly_in_r2(c0: i128, c: &[Poly], r2: &Poly) -> Poly {
    let mut out = Poly::int(c0);
    let mut pw = Poly::int(1);
    for ci in c {
        pw = pw.mul(r2);
        out = out.add(&ci.mul(&pw));
    }
    out
}

/// OpenCV's tangential terms `(2 p1 u v + p2 (r2 + 2 u^2), 2 p2 u v + p1 (r2 + 2 v^2))`.
fn tangential(ctx: &Ctx, p1: &Poly, p2: &Poly, r2: &Poly) -> [Poly; 2] {
    let (u, v) = (&ctx.u, &ctx.v);
    let uv2 = u.mul(v).scale(&q(2));
    [
        p1.mul(&uv2).add(&p2.mul(&r2.add(&u.mul(u).scale(&q(2))))),
        p2.mul(&uv2).add(&p1.mul(&r2.add(&v.mul(v).scale(&q(2))))),
    ]
}

/// Which polynomial model.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Polynomial {
    /// `SIMPLE_RADIAL` (and `SIMPLE_RADIAL_FISHEYE` after the equidistant map): `k`.
    SimpleRadial,
    /// `RADIAL` (and `RADIAL_FISHEYE`): `k1, k2`.
    Radial,
    /// `OPENCV`: `k1, k2, p1, p2`.
    OpenCv,
    /// `OPENCV_FISHEYE`'s polynomial in `theta^2` (applied to the equidistant point):
    /// `k1, k2, k3, k4`.
    Fisheye,
}

/// A polynomial distortion kernel: `[xd, yd, j00, j01, j10, j11, radial]`.
pub fn polynomial(model: Polynomial) -> Kernel {
    let (name, coeffs, what, cdoc): (_, &[&str], _, _) = match model {
        Polynomial::SimpleRadial => (
            "distortion_simple_radial",
            &["k1"],
            "COLMAP's `SIMPLE_RADIAL` (and `SIMPLE_RADIAL_FISHEYE`, applied to the equidistant \
             point): `(u, v) (1 + k r2)`",
            "`[k]` (the camera parameter after `f, cx, cy`)",
        ),
        Polynomial::Radial => (
            "distortion_radial",
            &["k1", "k2"],
            "COLMAP's `RADIAL` (and `RADIAL_FISHEYE`, applied to the equidistant point): \
             `(u, v) (1 + k1 r2 + k2 r2^2)`",
            "`[k1, k2]` (the camera parameters after `f, cx, cy`)",
        ),
        Polynomial::OpenCv => (
            "distortion_opencv",
            &["k1", "k2", "p1", "p2"],
            "COLMAP's and OpenCV's `OPENCV`: `(u, v) (1 + k1 r2 + k2 r2^2)` plus the \
             tangential terms `(2 p1 u v + p2 (r2 + 2 u^2), 2 p2 u v + p1 (r2 + 2 v^2))`",
            "`[k1, k2, p1, p2]` (the camera parameters after `fx, fy, cx, cy`)",
        ),
        Polynomial::Fisheye => (
            "distortion_fisheye",
            &["k1", "k2", "k3", "k4"],
            "`OPENCV_FISHEYE`'s polynomial part, applied to the equidistant point \
             `(u, v) = theta / r (x, y)` (`theta = atan r`, so `r2 = theta^2` here): \
             `(u, v) (1 + k1 theta^2 + k2 theta^4 + k3 theta^6 + k4 theta^8)`",
            "`[k1, k2, k3, k4]` (the camera parameters after `fx, fy, cx, cy`)",
        ),
    };
    let (mut k, mut ctx, c, r2) = start(name, coeffs, cdoc);
    k.doc(&format!(
        "The lens distortion of {what}, `r2 = u^2 + v^2`, and its Jacobian with respect to \
         `(u, v)`."
    ));
    k.doc(
        "Defined in `codegen/src/defs/camera.rs`; the Jacobian is derived symbolically by the \
         chain rule through `r2` and the radial factor.",
    );
    let nradial = match model {
        Polynomial::SimpleRadial => 1,
        Polynomial::Radial | Polynomial::OpenCv => 2,
        Polynomial::Fisheye => 4,
    };
    // The radial factor and its derivative in r2, named so the Jacobian shares them.
    let radial = poly_in_r2(1, &c[..nradial], &r2);
    let r2v = r2.as_var().expect("r2 is an intermediate");
    let dradial = k.define("dradial", radial.derivative(r2v));
    let radial = {
        let x = k.define("radial", radial);
        let var = x.as_var().expect("var");
        let two_u = ctx.u.scale(&q(2));
        let two_v = ctx.v.scale(&q(2));
        ctx.deriv
            .insert(var, [dradial.mul(&two_u), dradial.mul(&two_v)]);
        x
    };
    let mut xd = ctx.u.mul(&radial);
    let mut yd = ctx.v.mul(&radial);
    if model == Polynomial::OpenCv {
        let [tu, tv] = tangential(&ctx, &c[2], &c[3], &r2);
        xd = xd.add(&tu);
        yd = yd.add(&tv);
    }
    let (x, y) = (ctx.dual(xd), ctx.dual(yd));
    outputs(&mut k, &x, &y, ["xd", "yd", "j00", "j01", "j10", "j11"]);
    k.output("radial_factor", radial);
    k.output_doc = "`[xd, yd, j00, j01, j10, j11, radial]`: the distorted point `(xd, yd)`, the \
                    Jacobian `[[dxd/du, dxd/dv], [dyd/du, dyd/dv]]` row-major, and the radial \
                    factor `1 + k1 r2 + ...` (positive where the point is not mirrored through \
                    the principal point)."
        .to_string();
    k
}

/// Outputs `[x, y, dx/du, dx/dv, dy/du, dy/dv]` under the given names.
fn outputs(k: &mut Kernel, x: &Dual, y: &Dual, names: [&str; 6]) {
    let values = [&x.value, &y.value, &x.d[0], &x.d[1], &y.d[0], &y.d[1]];
    for (name, p) in names.into_iter().zip(values) {
        k.output(name, p.clone());
    }
}

/// The polynomial pieces of OpenCV's rational model (`FULL_OPENCV`; with `prism`, OpenCV's
/// 12- and 14-coefficient models before the tilt): the radial numerator `n` and denominator
/// `d`, the additive terms `t` (tangential, and thin prism) and their derivatives.
pub fn rational(prism: bool) -> Kernel {
    let (name, coeffs, cdoc): (_, &[&str], _) = if prism {
        (
            "distortion_thin_prism",
            &[
                "k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6", "s1", "s2", "s3", "s4",
            ],
            "`[k1, k2, p1, p2, k3, k4, k5, k6, s1, s2, s3, s4]` (OpenCV's order: the camera \
             parameters after `fx, fy, cx, cy`, without the tilt)",
        )
    } else {
        (
            "distortion_full_opencv",
            &["k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6"],
            "`[k1, k2, p1, p2, k3, k4, k5, k6]` (COLMAP's and OpenCV's order: the camera \
             parameters after `fx, fy, cx, cy`)",
        )
    };
    let (mut k, ctx, c, r2) = start(name, coeffs, cdoc);
    if prism {
        k.doc(
            "The polynomial pieces of OpenCV's rational distortion with thin-prism terms (the \
             12- and 14-coefficient models, before the tilt): the distorted point is \
             `(u, v) n / d + t` with `n = 1 + k1 r2 + k2 r2^2 + k3 r2^3`, \
             `d = 1 + k4 r2 + k5 r2^2 + k6 r2^3`, `r2 = u^2 + v^2`, and `t` the tangential \
             terms `(2 p1 u v + p2 (r2 + 2 u^2), 2 p2 u v + p1 (r2 + 2 v^2))` plus the thin \
             prism `(s1 r2 + s2 r2^2, s3 r2 + s4 r2^2)`.",
        );
    } else {
        k.doc(
            "The polynomial pieces of the rational distortion of `FULL_OPENCV`: the distorted \
             point is `(u, v) n / d + t` with `n = 1 + k1 r2 + k2 r2^2 + k3 r2^3`, \
             `d = 1 + k4 r2 + k5 r2^2 + k6 r2^3`, `r2 = u^2 + v^2`, and `t` the tangential \
             terms `(2 p1 u v + p2 (r2 + 2 u^2), 2 p2 u v + p1 (r2 + 2 v^2))`.",
        );
    }
    k.doc(
        "The quotient is the caller's (`src/camera/distortion.rs`); the derivatives of `n`, \
         `d` and `t` are derived symbolically here by the chain rule through `r2`.",
    );
    let num = poly_in_r2(1, &[c[0].clone(), c[1].clone(), c[4].clone()], &r2);
    let den = poly_in_r2(1, &[c[5].clone(), c[6].clone(), c[7].clone()], &r2);
    let r2v = r2.as_var().expect("r2 is an intermediate");
    // dn/du = n'(r2) 2u: name n'(r2) and d'(r2) once.
    let dnum = k.define("dnum", num.derivative(r2v));
    let dden = k.define("dden", den.derivative(r2v));
    let [mut tu, mut tv] = tangential(&ctx, &c[2], &c[3], &r2);
    if prism {
        tu = tu.add(&poly_in_r2(0, &[c[8].clone(), c[9].clone()], &r2));
        tv = tv.add(&poly_in_r2(0, &[c[10].clone(), c[11].clone()], &r2));
    }
    let two_u = ctx.u.scale(&q(2));
    let two_v = ctx.v.scale(&q(2));
    let (t, s) = (ctx.dual(tu), ctx.dual(tv));
    k.output("num", num);
    k.output("den", den);
    k.output("num_u", dnum.mul(&two_u));
    k.output("num_v", dnum.mul(&two_v));
    k.output("den_u", dden.mul(&two_u));
    k.output("den_v", dden.mul(&two_v));
    outputs(&mut k, &t, &s, ["tu", "tv", "t00", "t01", "t10", "t11"]);
    k.output_doc = "`[n, d, dn/du, dn/dv, dd/du, dd/dv, tu, tv, dtu/du, dtu/dv, dtv/du, dtv/dv]`: \
                    the radial numerator and denominator and their gradients, the additive \
                    terms `t` and their Jacobian, row-major."
        .to_string();
    k
}
