//! The derivative-sequence method of [`super::real_roots`]: the real roots of each derivative
//! bracket those of the one below, each root found by safeguarded Halley/Newton steps with
//! bisection (see the module documentation of [`super`]).

use super::closed::quadratic_closed;
use super::{sgn, Poly, Roots, EPS, MAX_DEGREE};
use crate::numeric::bounds::{Bound, Budget};

/// What the bracketing needs of a polynomial: its degree, leading coefficient and Horner
/// evaluations. [`Poly`] (any degree, loops over its coefficients) and [`Cubic`] (degree 3,
/// straight-line) implement it, so the cubic of the P3P solver runs the same method without
/// the loops.
pub(super) trait Horner {
    fn degree(&self) -> usize;
    fn lead(&self) -> f64;
    fn eval(&self, x: f64) -> f64;
    /// (p(x), p'(x), p''(x) / 2, sum |c_i| |x|^i).
    fn eval_d2_abs(&self, x: f64) -> (f64, f64, f64, f64);
    /// [`Poly::negligible_with`].
    #[inline]
    fn negligible_with(&self, f: f64, s: f64) -> bool {
        f.abs() <= 2.0 * self.degree() as f64 * EPS * s
    }
}

impl Horner for Poly {
    #[inline]
    fn degree(&self) -> usize {
        self.n
    }
    #[inline]
    fn lead(&self) -> f64 {
        self.c[self.n]
    }
    #[inline]
    fn eval(&self, x: f64) -> f64 {
        Poly::eval(self, x)
    }
    #[inline]
    fn eval_d2_abs(&self, x: f64) -> (f64, f64, f64, f64) {
        Poly::eval_d2_abs(self, x)
    }
}

/// A cubic `c[0] + c[1] x + c[2] x^2 + c[3] x^3` (`c[3] != 0`), evaluated in straight-line
/// code: the same Horner chains as [`Poly`]'s, in the same order, so the same values.
#[derive(Clone, Copy)]
struct Cubic([f64; 4]);

impl Horner for Cubic {
    #[inline]
    fn degree(&self) -> usize {
        3
    }
    #[inline]
    fn lead(&self) -> f64 {
        self.0[3]
    }
    #[inline]
    fn eval(&self, x: f64) -> f64 {
        let c = &self.0;
        ((c[3] * x + c[2]) * x + c[1]) * x + c[0]
    }
    #[inline]
    fn eval_d2_abs(&self, x: f64) -> (f64, f64, f64, f64) {
        let c = &self.0;
        let ax = x.abs();
        // Poly::eval_d2_abs unrolled for n = 3 (h starts at 0, d at 0).
        let p2 = c[3] * x + c[2];
        let d2 = c[3];
        let p1 = p2 * x + c[1];
        let d1 = d2 * x + p2;
        let h1 = d2;
        let p0 = p1 * x + c[0];
        let d0 = d1 * x + p1;
        let h0 = h1 * x + d1;
        let s = ((c[3].abs() * ax + c[2].abs()) * ax + c[1].abs()) * ax + c[0].abs();
        (p0, d0, h0, s)
    }
}

/// The next trial point strictly inside (lo, hi): 0 if the bracket straddles it, the geometric
/// mean if it spans more than a factor 2 on one side of 0, else the midpoint.
#[inline]
pub(super) fn split(lo: f64, hi: f64) -> f64 {
    if lo < 0.0 && hi > 0.0 {
        return 0.0;
    }
    if lo >= 0.0 {
        let l = lo.max(f64::MIN_POSITIVE);
        if hi > 2.0 * l {
            return (l.sqrt()) * (hi.sqrt());
        }
    } else {
        let h = (-hi).max(f64::MIN_POSITIVE);
        if -lo > 2.0 * h {
            return -((h.sqrt()) * ((-lo).sqrt()));
        }
    }
    lo + 0.5 * (hi - lo)
}

/// [`split`]'s geometric mean reaches from the smallest positive float: on a bracket from 0
/// (or to 0) it bisects the exponent, for roots of any magnitude. The Sturm sequence of
/// [`super::real_roots_above`] isolates P4Pf's depth ratios `mu > -1` (its first split is 0),
/// roots of order one, and there that cost about seven splits (1e-154, 1e-77, ..., 1e-4) before
/// one landed near them. This split floors the small end at [`SPLIT_ABOVE_FLOOR`] times the
/// other. On the focal RANSAC's samples at 80 % outliers (20,000 P4Pf calls, counted) the
/// sequence's splits fell from 67,514 to 25,974 and the bracketing's steps from 161,769 to
/// 131,945 (with a floor of `2^-10` or `2^-30`, or the midpoint: 132,000 to 139,000 steps). The
/// derivative sequence above -1 ([`solve_above`]) starts its brackets from quadratic models and
/// keeps [`split`]: this rule measured slower there.
#[inline]
pub(super) fn split_above(lo: f64, hi: f64) -> f64 {
    if lo < 0.0 && hi > 0.0 {
        return 0.0;
    }
    if lo >= 0.0 {
        let l = lo.max(hi * SPLIT_ABOVE_FLOOR);
        if hi > 2.0 * l {
            return l.sqrt() * hi.sqrt();
        }
    } else {
        let h = (-hi).max(-lo * SPLIT_ABOVE_FLOOR);
        if -lo > 2.0 * h {
            return -(h.sqrt() * (-lo).sqrt());
        }
    }
    lo + 0.5 * (hi - lo)
}

/// [`split_above`]'s floor: a bracket `(0, hi)` is split at `hi / sqrt(32)`.
const SPLIT_ABOVE_FLOOR: f64 = 1.0 / 32.0;

/// The root of `q` in the bracket (lo, hi), where q has (computed) sign `s_lo` at lo and the
/// opposite sign at hi, by safeguarded Halley/Newton steps started at `x0` (if inside). Halley's
/// step (cubic convergence) costs one more Horner chain than Newton's and saves about one
/// iteration per root from the usual quadratic-model start. Returns the iterate
/// with the smallest |q|. Stops when |q(x)| <= eps sum |c_i| |x|^i (below Horner's error bound:
/// further iterations only chase rounding noise), when a step is below half an ulp, or when
/// lo and hi are adjacent floats; with `xtol > 0`, also after a Halley or Newton step of at most
/// `xtol (1 + |x|)` (its result returned: the error left is of the order of the step cubed or
/// squared). Where a step leaves the bracket or stalls, the bracket is bisected by the rule
/// `split` ([`split`], or [`split_above`] above a finite lower end).
pub(super) fn bracket<P: Horner>(
    q: &P,
    mut lo: f64,
    mut hi: f64,
    s_lo: f64,
    x0: f64,
    xtol: f64,
    split: impl Fn(f64, f64) -> f64,
) -> f64 {
    let mut x = if x0 > lo && x0 < hi {
        x0
    } else {
        split(lo, hi)
    };
    let mut best_x = x;
    let mut best_f = f64::INFINITY;
    let mut step_old = f64::INFINITY;
    let mut step = f64::INFINITY;
    let mut iters = Budget::new(Bound::RootBracket);
    while iters.next() {
        let (f, d, h, s) = q.eval_d2_abs(x);
        if f.abs() < best_f {
            best_f = f.abs();
            best_x = x;
        }
        if f.abs() <= EPS * s {
            return x;
        }
        if sgn(f) == s_lo {
            lo = x;
        } else {
            hi = x;
        }
        // Halley's step (cubic convergence; h = q''/2): x - f d / (d^2 - f h), Newton's if the
        // denominator is not safely positive.
        let den = d * d - f * h;
        let xn = if den > 0.5 * d * d {
            x - f * d / den
        } else {
            x - f / d
        };
        let dx = (xn - x).abs();
        // The step is taken when it stays inside the bracket and either halves the step before
        // last (rtsafe's progress test) or is already tiny (quadratic regime: rounding noise in
        // f must not force bisection of a wide bracket).
        let newton_ok =
            xn.is_finite() && xn > lo && xn < hi && (dx < 0.5 * step_old || dx <= 1e-8 * x.abs());
        step_old = step;
        let next = if newton_ok {
            xn
        } else {
            let m = split(lo, hi);
            if !(m > lo && m < hi) {
                break; // lo and hi are adjacent floats
            }
            m
        };
        step = (next - x).abs();
        if next == x {
            break;
        }
        if newton_ok && step <= xtol * (1.0 + x.abs()) {
            return next;
        }
        // A (Halley or Newton) step below half an ulp of x: x is the correctly rounded root up to the
        // rounding of q; keep the better of x and its neighbour.
        if newton_ok && step <= 0.5 * EPS * x.abs() {
            let fnx = q.eval(next);
            if fnx.abs() < best_f {
                best_x = next;
            }
            break;
        }
        x = next;
    }
    best_x
}

/// Real roots of `q` given the sorted real roots `crit` of `q'` (all inside +-bound).
/// Returns the roots (ascending) and, for each critical point, nothing: callers that need to
/// know whether a critical point is a root test it again.
///
/// `start` (NaN for none) is the starting guess when `q'` has no real root: `q` is monotone
/// and has one root, found from there (else from the split of the root bound).
fn roots_between<P: Horner>(q: &P, crit: &[f64], bound: f64, start: f64) -> Roots {
    let lead = sgn(q.lead());
    let s_minf = if q.degree() & 1 == 0 { lead } else { -lead };
    roots_above(q, crit, (-bound, s_minf, false), bound, (start, 0.0), split)
}

/// [`roots_between`] on `(lo, bound)`: `low` is `(lo, the sign of q at lo, whether q(lo) is
/// zero)`; critical points at or below `lo` are ignored, a root at `lo` is not reported.
/// `(start, xtol)`: the starting guess where `q` is monotone ([`roots_between`]'s) and
/// [`bracket`]'s `xtol`; `split`: the bisection rule.
fn roots_above<P: Horner>(
    q: &P,
    crit: &[f64],
    low: (f64, f64, bool),
    bound: f64,
    (start, xtol): (f64, f64),
    split: impl Fn(f64, f64) -> f64 + Copy,
) -> Roots {
    let mut out = Roots::default();
    let s_pinf = sgn(q.lead());
    let (mut prev_x, mut prev_s, mut prev_zero) = low;
    // Quadratic model at the previous critical point: q(x) ~ f + f2 (x - c)^2 / 2, whose root
    // c +- sqrt(2 |f / f2|) is the starting guess on either side (exact for a parabola).
    let mut prev_reach = f64::NAN;
    let mut prev_f = f64::INFINITY;
    for &x in crit {
        if !(x > prev_x && x < bound) {
            continue;
        }
        let (f, _, h, s) = q.eval_d2_abs(x);
        let f2 = 2.0 * h;
        let z = q.negligible_with(f, s);
        let reach = (2.0 * (f / f2).abs()).sqrt();
        if !prev_zero && !z && sgn(f) != prev_s {
            let x0 = if f.abs() <= prev_f.abs() || prev_reach.is_nan() {
                x - reach
            } else {
                prev_x + prev_reach
            };
            out.push(bracket(q, prev_x, x, prev_s, x0, xtol, split));
        }
        if z {
            out.push(x);
        }
        prev_x = x;
        prev_s = sgn(f);
        prev_zero = z;
        prev_reach = reach;
        prev_f = f;
    }
    if !prev_zero && s_pinf != prev_s {
        let x0 = if crit.is_empty() {
            start
        } else {
            prev_x + prev_reach
        };
        out.push(bracket(q, prev_x, bound, prev_s, x0, xtol, split));
    }
    out
}

/// The positive real roots of a prepared polynomial (ascending): the derivative sequence on
/// `(0, bound)` only, each level's roots bracketed between its derivative's positive roots.
pub(super) fn solve_positive(p: &Poly) -> Roots {
    let n = p.n;
    let mut cur = Roots::default();
    if n == 0 {
        return cur;
    }
    let bound = p.root_bound();
    let mut d = [*p; MAX_DEGREE];
    for k in 1..n {
        d[k] = d[k - 1].derivative();
    }
    let lin = &d[n - 1];
    let r = -lin.c[0] / lin.c[1];
    if r > 0.0 && r < bound {
        cur.push(r);
    }
    for k in (0..n - 1).rev() {
        let crit = cur;
        // q(0) is the constant coefficient, exactly.
        let c0 = d[k].c[0];
        cur = roots_above(
            &d[k],
            crit.as_slice(),
            (0.0, sgn(c0), c0 == 0.0),
            bound,
            (f64::NAN, 0.0),
            split,
        );
    }
    cur.sort_dedup();
    cur
}

/// The relative step at which [`solve_above`] stops refining the roots of the derivatives
/// `p', p'', ...` (they only bracket the roots of the level below: a root of `p^(k)` within
/// about the step's square or cube of such a bracket end is the only one its sign there can
/// misjudge); `p`'s own roots are refined to the rounding level.
const LEVEL_XTOL: f64 = 1e-7;

/// [`solve_prepared`] on `(lo, bound)` only: every level of the derivative sequence bracketed
/// between its derivative's roots above `lo` (the interval from `lo` to the first of them is
/// monotone), each level's sign at `lo` evaluated there; a root at `lo` itself is not reported.
/// Near-real roots (`imag_tol > 0`) come from the critical points above `lo`.
pub(super) fn solve_above(p: &Poly, zero_root: bool, imag_tol: f64, lo: f64) -> Roots {
    let n = p.n;
    let bound = p.root_bound();
    if !(lo > -bound) {
        return solve_prepared(p, zero_root, imag_tol);
    }
    let mut out = Roots::default();
    if n == 0 || !(lo < bound) {
        if zero_root && lo < 0.0 {
            out.push(0.0);
        }
        return out;
    }
    let mut d = [*p; MAX_DEGREE];
    for k in 1..n {
        d[k] = d[k - 1].derivative();
    }
    let lin = &d[n - 1];
    let mut cur = Roots::default();
    let r = -lin.c[0] / lin.c[1];
    if r > lo && r < bound {
        cur.push(r);
    }
    if n == 1 {
        out = cur;
        if zero_root && lo < 0.0 {
            out.push(0.0);
        }
        out.sort_dedup();
        return out;
    }
    // Each derivative's roots above `lo`, down to `p'`'s: the critical points.
    for k in (1..n - 1).rev() {
        let f = d[k].eval(lo);
        cur = roots_above(
            &d[k],
            cur.as_slice(),
            (lo, sgn(f), d[k].negligible(lo, f)),
            bound,
            (f64::NAN, LEVEL_XTOL),
            split,
        );
    }
    solve_above_at(p, bound, cur.as_slice(), zero_root, imag_tol, lo)
}

/// [`solve_above`]'s last level, given `p`'s root bound and its critical points `crit` (the real
/// roots of `p'` above `lo`, ascending; of degree 2 or more): `p`'s roots bracketed between them and
/// refined to the rounding level, the exact zero root (`zero_root`, reported if above `lo`),
/// and the near-real roots (`imag_tol > 0`) from the critical points.
pub(super) fn solve_above_at(
    p: &Poly,
    bound: f64,
    crit: &[f64],
    zero_root: bool,
    imag_tol: f64,
    lo: f64,
) -> Roots {
    let f = p.eval(lo);
    let mut out = roots_above(
        p,
        crit,
        (lo, sgn(f), p.negligible(lo, f)),
        bound,
        (f64::NAN, 0.0),
        split,
    );
    // The exact zero root first, so that the capacity can only ever cut near-real extras.
    if zero_root && lo < 0.0 {
        out.push(0.0);
    }
    if imag_tol > 0.0 {
        near_real(p, crit, imag_tol, &mut out);
    }
    out.sort_dedup();
    out
}

/// Adds to `out` the critical points `crit` of `p` next to a near-real complex pair
/// ([`super::real_roots_near`]).
fn near_real(p: &Poly, crit: &[f64], imag_tol: f64, out: &mut Roots) {
    let found = *out;
    for &x in crit {
        let tol = imag_tol * (1.0 + x.abs());
        let (f, _, h, s) = p.eval_d2_abs(x);
        let f2 = 2.0 * h;
        if p.negligible_with(f, s) || found.iter().any(|&r| (r - x).abs() <= tol) {
            continue; // already a root
        }
        // Same signs of p and p'': a complex pair x +- i b (opposite signs: a real pair,
        // already found by the bracketing).
        if f == 0.0 || f2 == 0.0 || (f > 0.0) != (f2 > 0.0) {
            continue;
        }
        let b = (2.0 * (f / f2)).sqrt();
        if b <= tol {
            out.push(x);
        }
    }
}

/// The full solver on a prepared polynomial. `imag_tol > 0` adds near-real roots.
pub(super) fn solve_prepared(p: &Poly, zero_root: bool, imag_tol: f64) -> Roots {
    let mut out = Roots::default();
    if p.n == 0 {
        if zero_root {
            out.push(0.0);
        }
        return out;
    }
    let n = p.n;
    let bound = p.root_bound();
    let mut crit = Roots::default(); // roots of p'
    if n == 3 {
        // The cubic (P3P's, once per triple of points): the roots of the quadratic p' in
        // closed form (Kahan's discriminant; the vertex, a double root, when p' is negligible
        // there: what bracketing either side of it decides, to a few ulps), then p's roots
        // bracketed between them by straight-line evaluations.
        quadratic_closed(&p.derivative(), &mut crit);
        crit.sort_dedup();
        // Without critical points the cubic is monotone: Halley's iteration from its
        // inflection point (the root of p'') converges without bisecting from 0.
        let inflection = -p.c[2] / (3.0 * p.c[3]);
        let cubic = Cubic([p.c[0], p.c[1], p.c[2], p.c[3]]);
        out = roots_between(&cubic, crit.as_slice(), bound, inflection);
    } else {
        // Derivative sequence d[k] = p^(k), k = 0..n-1 (d[n-1] is linear).
        let mut d = [*p; MAX_DEGREE];
        for k in 1..n {
            d[k] = d[k - 1].derivative();
        }
        // Roots of the linear level.
        let lin = &d[n - 1];
        let mut cur = Roots::default();
        cur.push(-lin.c[0] / lin.c[1]);
        for k in (0..n - 1).rev() {
            crit = cur;
            cur = roots_between(&d[k], crit.as_slice(), bound, f64::NAN);
        }
        out = cur;
        if n == 1 {
            crit = Roots::default();
        }
    }
    // The exact zero root first, so that the capacity can only ever cut near-real extras.
    if zero_root {
        out.push(0.0);
    }
    // Near-real roots from the critical points of p (T8).
    if imag_tol > 0.0 && n >= 2 {
        near_real(p, crit.as_slice(), imag_tol, &mut out);
    }
    out.sort_dedup();
    out
}
