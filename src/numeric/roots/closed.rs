//! The closed forms behind [`super::cubic_real_roots`] and [`super::quartic_real_roots`]:
//! Kahan's quadratic, the trigonometric / Cardano cubic, Ferrari's quartic, each followed by
//! Newton polishing and a placement check against the critical points, with the fallback to
//! the derivative-sequence method of [`super::real_roots`].

use super::{sgn, solve_prepared, Poly, Roots, EPS, NC};
use crate::numeric::bounds::ROOT_POLISH_STEPS;

/// Real roots of `a x^2 + b x + c` (a != 0) in closed form (Kahan's accurate discriminant, the
/// cancellation-free pair `q/a`, `c/q`). A slightly negative discriminant whose vertex value is
/// negligible gives the double root.
pub(super) fn quadratic_closed(p: &Poly, out: &mut Roots) {
    let (c, b, a) = (p.c[0], p.c[1], p.c[2]);
    let bb = b * b;
    let bb_err = b.mul_add(b, -bb);
    let ac4 = 4.0 * a * c;
    let ac4_err = (4.0 * a).mul_add(c, -ac4);
    let disc = (bb - ac4) + (bb_err - ac4_err);
    if disc > 0.0 {
        let q = -0.5 * (b + sgn(b) * disc.sqrt());
        out.push(q / a);
        if q != 0.0 {
            out.push(c / q);
        }
    } else {
        let v = -b / (2.0 * a);
        if disc == 0.0 || p.negligible(v, p.eval(v)) {
            out.push(v);
        }
    }
}

/// Candidate double root near `x0` (the real part of a close complex pair): polish `x0` as a root
/// of p' (Newton, accepted only while |p'| decreases) and accept if p is negligible there.
fn double_candidate(p: &Poly, x0: f64, out: &mut Roots) {
    let mut x = x0;
    let (_, mut d, mut h) = p.eval_d2(x);
    for _ in 0..ROOT_POLISH_STEPS {
        if d == 0.0 || h == 0.0 {
            break;
        }
        let xn = x - d / h;
        if !xn.is_finite() || xn == x {
            break;
        }
        let (_, dn, hn) = p.eval_d2(xn);
        if dn.abs() >= d.abs() {
            break;
        }
        x = xn;
        d = dn;
        h = hn;
    }
    if p.negligible(x, p.eval(x)) {
        out.push(x);
    }
}

/// Real roots of a monic-izable cubic (`p.n == 3`) in closed form, unpolished.
fn cubic_closed(p: &Poly, out: &mut Roots) {
    let l = p.c[3];
    let (a, b, c) = (p.c[2] / l, p.c[1] / l, p.c[0] / l);
    let a3 = a / 3.0;
    let q = (a * a - 3.0 * b) / 9.0;
    let r = (2.0 * a * a * a - 9.0 * a * b + 27.0 * c) / 54.0;
    let r2 = r * r;
    let q3 = q * q * q;
    if r2 < q3 {
        // Three real roots (q > 0 here).
        let sq = q.sqrt();
        let cs = (r / (sq * sq * sq)).clamp(-1.0, 1.0);
        let th = cs.acos();
        // cos((th + 2 pi k) / 3), k = 0, 1, 2, from one sin_cos of phi = th / 3 in [0, pi/3]
        // by angle addition: cos(phi + 2 pi/3) = -c/2 - s sqrt(3)/2, cos(phi + 4 pi/3) =
        // -c/2 + s sqrt(3)/2; absolute error a few eps, as for cos of the rounded angle.
        let (sn, cn) = (th / 3.0).sin_cos();
        let h = 0.5 * 3f64.sqrt() * sn;
        let cosk = [cn, -0.5 * cn - h, -0.5 * cn + h];
        let mut x = cosk.map(|ck| -2.0 * sq * ck - a3);
        // The smallest-magnitude root suffers cancellation against a/3: recompute it from the
        // product of the roots (x0 x1 x2 = -c) when that is better.
        let mut im = 0;
        for k in 1..3 {
            if x[k].abs() < x[im].abs() {
                im = k;
            }
        }
        let prod = x[(im + 1) % 3] * x[(im + 2) % 3];
        if prod != 0.0 {
            let alt = -c / prod;
            if alt.is_finite() && p.eval(alt).abs() < p.eval(x[im]).abs() {
                x[im] = alt;
            }
        }
        for xk in x {
            out.push(xk);
        }
    } else {
        let big = -sgn(r) * (r.abs() + (r2 - q3).max(0.0).sqrt()).cbrt();
        let small = if big != 0.0 { q / big } else { 0.0 };
        out.push(big + small - a3);
        // The complex pair -(A+B)/2 - a/3 +- i sqrt(3)/2 (A - B): possibly a double root.
        double_candidate(p, -0.5 * (big + small) - a3, out);
    }
}

/// Real roots of a quartic (`p.n == 4`) by Ferrari's method, unpolished.
fn quartic_closed(p: &Poly, out: &mut Roots) {
    let l = p.c[4];
    let (a, b, c, d) = (p.c[3] / l, p.c[2] / l, p.c[1] / l, p.c[0] / l);
    let a4 = a / 4.0;
    let aa = a * a;
    // Depressed quartic y^4 + pp y^2 + qq y + rr, x = y - a/4.
    let pp = b - 3.0 * aa / 8.0;
    let qq = c - a * b / 2.0 + aa * a / 8.0;
    let rr = d - a * c / 4.0 + aa * b / 16.0 - 3.0 * aa * aa / 256.0;
    let scale = pp.abs().max(qq.abs().powf(2.0 / 3.0)).max(rr.abs().sqrt());
    let push_quad = |s: f64, t: f64, out: &mut Roots| {
        // y^2 + s y + t = 0, x = y - a/4
        let mut qp = Poly { c: [0.0; NC], n: 2 };
        qp.c[0] = t;
        qp.c[1] = s;
        qp.c[2] = 1.0;
        let mut ys = Roots::default();
        quadratic_closed(&qp, &mut ys);
        let pushed = ys.len();
        for &y in &ys {
            out.push(y - a4);
        }
        if pushed == 0 {
            double_candidate(p, -0.5 * s - a4, out);
        }
    };
    if qq.abs() <= 16.0 * EPS * scale.max(f64::MIN_POSITIVE).powf(1.5) || scale == 0.0 {
        // Biquadratic: z = y^2, z^2 + pp z + rr = 0.
        let mut zp = Poly { c: [0.0; NC], n: 2 };
        zp.c[0] = rr;
        zp.c[1] = pp;
        zp.c[2] = 1.0;
        let mut zs = Roots::default();
        quadratic_closed(&zp, &mut zs);
        for &z in &zs {
            if z >= 0.0 {
                let y = z.sqrt();
                out.push(y - a4);
                out.push(-y - a4);
            } else {
                double_candidate(p, -a4, out);
            }
        }
        if zs.is_empty() {
            double_candidate(p, -a4, out);
        }
        return;
    }
    // Resolvent cubic 8 m^3 + 8 pp m^2 + (2 pp^2 - 8 rr) m - qq^2 = 0: take its largest root (> 0).
    let mut rc = Poly { c: [0.0; NC], n: 3 };
    rc.c[0] = -qq * qq;
    rc.c[1] = 2.0 * pp * pp - 8.0 * rr;
    rc.c[2] = 8.0 * pp;
    rc.c[3] = 8.0;
    let mut ms = Roots::default();
    cubic_closed(&rc, &mut ms);
    let mut m: f64 = 0.0;
    for &mi in &ms {
        let mi = rc.polish(mi);
        if mi > m {
            m = mi;
        }
    }
    if m <= 0.0 {
        return;
    }
    let s = (2.0 * m).sqrt();
    let h = qq / (2.0 * s);
    push_quad(s, 0.5 * pp + m - h, out);
    push_quad(-s, 0.5 * pp + m + h, out);
}

/// Whether the sorted roots `r` of `q` are placed exactly as the sign pattern of `q` at the
/// sorted real roots `crit` of `q'` demands: one root strictly inside each interval between
/// consecutive critical points (or +-infinity) where `q` changes sign, none elsewhere. A
/// critical point where `q` is negligible (a multiple or nearly multiple root) fails the check,
/// leaving that case to the bracketing method.
fn placement_ok(q: &Poly, crit: &Roots, r: &Roots) -> bool {
    let r = r.as_slice();
    let lead = sgn(q.c[q.n]);
    let mut prev_s = if q.n & 1 == 0 { lead } else { -lead };
    let mut lo = f64::NEG_INFINITY;
    let mut k = 0;
    for &x in crit.iter().chain(core::iter::once(&f64::INFINITY)) {
        let s = if x == f64::INFINITY {
            lead
        } else {
            let f = q.eval(x);
            if q.negligible(x, f) {
                return false;
            }
            sgn(f)
        };
        let mut cnt = 0;
        while k < r.len() && r[k] < x {
            if r[k] <= lo {
                return false;
            }
            cnt += 1;
            k += 1;
        }
        if cnt != usize::from(s != prev_s) {
            return false;
        }
        prev_s = s;
        lo = x;
    }
    k == r.len()
}

/// Polishes the closed-form candidates and checks them: every polished root must be a root within
/// the backward-error criterion, and for degrees 3 and 4 they must sit one in each interval
/// between critical points of p where p changes sign (`placement_ok`; the critical points come
/// from the closed form of one degree less, itself checked the same way). The closed forms can lose a close real pair to
/// cancellation (the discriminant comes out with the wrong sign); on any mismatch the whole
/// polynomial is solved by the bracketing method instead.
fn finish_closed(p: &Poly, zero_root: bool, cand: &Roots) -> Roots {
    let mut out = Roots::default();
    for &x in cand {
        let (x, f) = p.polish_f(x);
        if !p.negligible(x, f) {
            return solve_prepared(p, zero_root, 0.0);
        }
        out.push(x);
    }
    out.sort_dedup();
    if p.n >= 3 {
        let crit = if p.n == 3 {
            // The critical points only serve placement_ok. The stable quadratic formula gives
            // them to a few ulps without polishing; that decides the same placement (a root
            // within ulps of a critical point makes p negligible there, failing the check).
            let mut c = Roots::default();
            quadratic_closed(&p.derivative(), &mut c);
            c.sort_dedup();
            c
        } else {
            closed_prepared(&p.derivative(), false)
        };
        if !placement_ok(p, &crit, &out) {
            return solve_prepared(p, zero_root, 0.0);
        }
    }
    if zero_root {
        out.push(0.0);
        out.sort_dedup();
    }
    out
}

/// Closed-form solution for prepared polynomials of degree <= 4 (recursion depth <= 2: each
/// check calls this on the derivative, one degree lower).
pub(super) fn closed_prepared(p: &Poly, zero_root: bool) -> Roots {
    let mut cand = Roots::default();
    match p.n {
        0 => {}
        1 => cand.push(-p.c[0] / p.c[1]),
        2 => quadratic_closed(p, &mut cand),
        3 => cubic_closed(p, &mut cand),
        4 => quartic_closed(p, &mut cand),
        _ => return solve_prepared(p, zero_root, 0.0),
    }
    finish_closed(p, zero_root, &cand)
}
