//! Real roots of real polynomials of degree at most [`MAX_DEGREE`].
//!
//! Coefficients are always given in **ascending** order: `c[0] + c[1] x + ... + c[n] x^n`.
//! Every function returns a [`Roots`] value (a fixed-capacity, allocation-free list of at most
//! [`MAX_DEGREE`] real roots, sorted ascending, each distinct root reported once). No function
//! panics, allocates, or loops without a hard iteration bound; non-finite input gives no roots.
//!
//! # Normalisation (docs/algorithm.md, constants and tolerances)
//!
//! The coefficients are divided by the largest `|c_i|`; leading coefficients whose normalised
//! magnitude is below `1e-14` are dropped (a polynomial whose leading coefficient is that small
//! relative to the others has a root beyond ~1e14 that the pose solver does not want). Any
//! non-finite coefficient, an all-zero polynomial (every `x` is a root: no meaningful answer) and a
//! nonzero constant give an empty result. Exact zero trailing coefficients are divided out
//! exactly (`x = 0` is then reported once).
//!
//! # Method of [`real_roots`]
//!
//! Real roots are isolated with the *derivative sequence* `p, p', p'', ..., p^(n-1)` instead of a
//! floating-point Sturm chain. Between two consecutive real roots of `p^(k+1)` the polynomial
//! `p^(k)` is monotone, so it has a root there iff its sign changes, and that root is then
//! bracketed; it is computed by safeguarded Halley steps (Newton's where Halley's denominator is
//! not safely positive; bisection whenever the step leaves the bracket
//! or converges slowly, geometric bisection across many binades). Working upward from the linear
//! `p^(n-1)` yields the real roots of every level, the last one being `p`; the outermost intervals
//! end at the Fujiwara root bound (by Gauss-Lucas it bounds the roots of every derivative too).
//!
//! Why not Sturm: both count *distinct* real roots exactly in exact arithmetic, but a Sturm chain
//! is built by repeated polynomial division whose remainders suffer catastrophic cancellation in
//! f64 (degree 8-9, roots spread over many magnitudes, or clustered roots), so its sign counts can
//! be wrong even for well-separated roots, and deciding when a remainder "is zero" (to stop the
//! chain at a non-constant gcd for multiple roots) needs an ad-hoc threshold. The derivative
//! sequence only ever *evaluates* polynomials, whose rounding error is bounded a priori by Horner's
//! bound `|fl(p(x)) - p(x)| <= gamma_2n sum |c_i| |x|^i` (`gamma_2n ~ n eps`); a misjudged sign
//! can therefore only move a root within its backward-error zone, never lose a well-conditioned
//! root. The same fixed `[[f64; 10]; 10]`-sized storage holds the sequence.
//!
//! Multiple roots: a multiple root of `p^(k)` is a simple root of some higher derivative, hence a
//! critical point `x*` of `p^(k)` that the level above has already found to rounding level. It is
//! reported when `|p^(k)(x*)| <= 2 n eps sum |c_i| |x*|^i` (twice the Horner error bound: the value
//! is indistinguishable from zero), and the two adjacent monotone intervals then contain no further
//! root. Double roots thus come out with (near) full relative precision, not the `sqrt(eps)` of a
//! companion-matrix eigenvalue solver.
//!
//! A cubic (the P3P solver's, once per triple of points) skips the two lowest levels: the
//! roots of its quadratic `p'` come in closed form (Kahan's discriminant; the vertex as a
//! double root where `p'` is negligible, which is what bracketing either side of it decides),
//! and `p` is bracketed between them with straight-line evaluations, from the inflection point
//! when `p` is monotone (259 -> 169 ns per call in `verify`'s timing test).
//!
//! Degrees 1-4 also go through this method in [`real_roots`]: every root ends bracketed, with a
//! value below Horner's error bound, a sub-ulp Newton step or a sign change between adjacent
//! floats, i.e. a backward error of at most a few `n eps` (the verification tests check
//! `|p(x)| <= 4 n eps sum |c_i| |x|^i`), whereas the closed forms ([`cubic_real_roots`],
//! [`quartic_real_roots`]) rely on Newton polishing to recover from cancellation and need a
//! placement check (with fallback to this method) to catch close real pairs they turn complex.
//! Measured, `real_roots` is also the faster of the two for degrees 3 and 4.
//!
//! # The Sturm sequence of [`real_roots_above`]
//!
//! One caller trades that guarantee for speed: P4Pf's octic (`numeric/p4pf.rs`), solved for
//! every RANSAC sample, whose roots above -1 are few and are polished afterwards by Newton's
//! method on the quadrics they come from. [`real_roots_above`] counts them by a Sturm chain
//! (the degree a compile-time constant, the chain's terms evaluated by Horner) and splits the
//! interval until each piece holds one, which the bracketing above then refines: 12.6 % less
//! time per P4Pf call on samples of four inliers, 15.4 % on random samples (`cargo bench
//! --bench minimal`, against the derivative sequence), with the checks of `verify` (the
//! solutions of the three quadrics against the companion matrix's count) passing for both. The
//! cancellation that makes a chain unreliable is tested for, not assumed away: a remainder
//! whose leading coefficient is at most `1e-9` times the largest term that cancelled into it
//! (a multiple
//! root, a close pair, a non-generic chain), a root at a split point or counts that contradict
//! each other make the chain refuse, and the derivative sequence answers instead. Where P4Pf
//! also wants the near-real roots ([`real_roots_near_above`]), the same chain isolates the
//! critical points, the roots of `p'`.
//!
//! # Near-real roots (docs/algorithm.md T8)
//!
//! [`real_roots_near`] additionally reports the real part of complex pairs whose imaginary part is
//! tiny (see its documentation), so that noise turning a double real root into a close complex
//! pair does not lose it.

//!
//! ```
//! use eopnp::internals::roots::{quartic_real_roots, real_roots};
//!
//! // (x - 1)(x - 2)(x + 3) = x^3 - 7x + 6, ascending coefficients.
//! let r = real_roots(&[6.0, -7.0, 0.0, 1.0]);
//! assert_eq!(r.len(), 3);
//! let s = r.as_slice();
//! assert!((s[0] + 3.0).abs() < 1e-14 && (s[1] - 1.0).abs() < 1e-14 && (s[2] - 2.0).abs() < 1e-14);
//! // x^4 + 1 has no real root.
//! assert!(quartic_real_roots(&[1.0, 0.0, 0.0, 0.0, 1.0]).is_empty());
//! ```

use crate::numeric::bounds::{Bound, Budget};

mod closed;
mod isolate;
mod sturm;

use isolate::solve_prepared;

/// Largest supported polynomial degree (the eopnp resultants have degree 8 and 9).
pub const MAX_DEGREE: usize = 9;

/// The imaginary-part tolerance of docs/algorithm.md's constants and tolerances ("keep roots
/// with |Im z| <= 1e-6 (1 + |z|)"), for use with [`real_roots_near`].
pub const DEFAULT_IMAG_TOL: f64 = 1e-6;

/// Number of coefficients of a polynomial of degree [`MAX_DEGREE`].
const NC: usize = MAX_DEGREE + 1;
/// Normalisation: normalised leading coefficients below this are dropped.
const DROP_TOL: f64 = 1e-14;
const EPS: f64 = f64::EPSILON;

/// A list of at most [`MAX_DEGREE`] real roots, sorted ascending, without duplicates.
///
/// Fixed capacity, no heap allocation; `Copy`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Roots {
    vals: [f64; MAX_DEGREE],
    len: usize,
}

impl Roots {
    /// Number of roots.
    #[inline]
    #[must_use]
    pub fn len(&self) -> usize {
        self.len
    }

    /// `true` if there are no roots.
    #[inline]
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The roots, ascending.
    #[inline]
    #[must_use]
    pub fn as_slice(&self) -> &[f64] {
        // len <= MAX_DEGREE is an invariant kept by `push`.
        &self.vals[..self.len.min(MAX_DEGREE)]
    }

    /// Iterator over the roots, ascending.
    #[inline]
    pub fn iter(&self) -> core::slice::Iter<'_, f64> {
        self.as_slice().iter()
    }

    /// Appends a finite root if there is room (silently ignores the rest).
    #[inline]
    fn push(&mut self, x: f64) {
        if self.len < MAX_DEGREE && x.is_finite() {
            self.vals[self.len] = x;
            self.len += 1;
        }
    }

    /// Sorts ascending (insertion sort, n <= 9) and removes exact duplicates.
    fn sort_dedup(&mut self) {
        let n = self.len.min(MAX_DEGREE);
        for i in 1..n {
            let mut j = i;
            while j > 0 && self.vals[j - 1] > self.vals[j] {
                self.vals.swap(j - 1, j);
                j -= 1;
            }
        }
        let mut m = 0;
        for i in 0..n {
            if m == 0 || self.vals[i] != self.vals[m - 1] {
                self.vals[m] = self.vals[i];
                m += 1;
            }
        }
        self.len = m;
    }
}

impl<'a> IntoIterator for &'a Roots {
    type Item = &'a f64;
    type IntoIter = core::slice::Iter<'a, f64>;
    #[inline]
    fn into_iter(self) -> Self::IntoIter {
        self.iter()
    }
}

/// A polynomial of degree `n` (1..=9) with ascending coefficients `c[0..=n]`, `c[n] != 0`.
#[derive(Clone, Copy, Debug)]
struct Poly {
    c: [f64; NC],
    n: usize,
}

impl Poly {
    /// p(x) by Horner.
    #[inline]
    fn eval(&self, x: f64) -> f64 {
        let mut p = self.c[self.n];
        for i in (0..self.n).rev() {
            p = p * x + self.c[i];
        }
        p
    }

    /// (p(x), p'(x)) by Horner.
    #[inline]
    fn eval_d(&self, x: f64) -> (f64, f64) {
        let mut p = self.c[self.n];
        let mut d = 0.0;
        for i in (0..self.n).rev() {
            d = d * x + p;
            p = p * x + self.c[i];
        }
        (p, d)
    }

    /// (p(x), p'(x), p''(x)) by Horner.
    #[inline]
    fn eval_d2(&self, x: f64) -> (f64, f64, f64) {
        let mut p = self.c[self.n];
        let mut d = 0.0;
        let mut h = 0.0;
        for i in (0..self.n).rev() {
            h = h * x + d;
            d = d * x + p;
            p = p * x + self.c[i];
        }
        (p, d, 2.0 * h)
    }

    /// (p(x), p'(x), p''(x) / 2, sum |c_i| |x|^i) by Horner.
    #[inline]
    fn eval_d2_abs(&self, x: f64) -> (f64, f64, f64, f64) {
        let ax = x.abs();
        let mut p = self.c[self.n];
        let mut s = p.abs();
        let mut d = 0.0;
        let mut h = 0.0;
        for i in (0..self.n).rev() {
            h = h * x + d;
            d = d * x + p;
            p = p * x + self.c[i];
            s = s * ax + self.c[i].abs();
        }
        (p, d, h, s)
    }

    /// sum |c_i| |x|^i: the scale of Horner's rounding error at x.
    #[inline]
    fn abs_sum(&self, x: f64) -> f64 {
        let ax = x.abs();
        let mut s = self.c[self.n].abs();
        for i in (0..self.n).rev() {
            s = s * ax + self.c[i].abs();
        }
        s
    }

    /// Whether the computed value `f = p(x)` is indistinguishable from zero: `|f|` at most twice
    /// Horner's a-priori error bound `gamma_2n sum |c_i| |x|^i ~ n eps sum |c_i| |x|^i`.
    #[inline]
    fn negligible(&self, x: f64, f: f64) -> bool {
        self.negligible_with(f, self.abs_sum(x))
    }

    /// [`Poly::negligible`] with `s = sum |c_i| |x|^i` already computed.
    #[inline]
    fn negligible_with(&self, f: f64, s: f64) -> bool {
        f.abs() <= 2.0 * self.n as f64 * EPS * s
    }

    /// The derivative (degree n - 1; only called with n >= 2).
    fn derivative(&self) -> Poly {
        let mut c = [0.0; NC];
        for i in 1..=self.n {
            c[i - 1] = self.c[i] * i as f64;
        }
        Poly { c, n: self.n - 1 }
    }

    /// Fujiwara's bound on |z| over all complex roots, enlarged by 1 % against rounding.
    fn root_bound(&self) -> f64 {
        let n = self.n;
        let lead = self.c[n].abs();
        let mut b: f64 = 0.0;
        for k in 1..=n {
            let mut r = self.c[n - k].abs() / lead;
            if k == n {
                r *= 0.5;
            }
            if k > 1 {
                // r^(1/k) < b when r < b^k: then the term cannot raise the maximum, and the
                // powf is skipped. The margin 1e-12 exceeds the rounding of b^k (k eps) and of
                // powf with the inexact exponent 1/k (|ln r| eps), so the result is the same.
                let mut bk = b;
                for _ in 1..k {
                    bk *= b;
                }
                if r < bk * (1.0 - 1e-12) {
                    continue;
                }
            }
            let t = if k == 1 { r } else { r.powf(1.0 / k as f64) };
            if t > b {
                b = t;
            }
        }
        let b = 2.0 * b * 1.01;
        if b.is_finite() && b > 0.0 {
            b
        } else {
            f64::MAX
        }
    }

    /// Newton polishing: at most `ROOT_POLISH_STEPS` steps, each accepted only if it reduces |p|.
    fn polish(&self, x0: f64) -> f64 {
        self.polish_f(x0).0
    }

    /// [`Poly::polish`], also returning p at the result (the value `eval` would give).
    fn polish_f(&self, x0: f64) -> (f64, f64) {
        let mut x = x0;
        let (mut f, mut d) = self.eval_d(x);
        let mut steps = Budget::new(Bound::RootPolish);
        while steps.next() {
            if f == 0.0 || d == 0.0 {
                break;
            }
            let xn = x - f / d;
            if !xn.is_finite() || xn == x {
                break;
            }
            let (fn_, dn) = self.eval_d(xn);
            if fn_.abs() >= f.abs() {
                break;
            }
            x = xn;
            f = fn_;
            d = dn;
        }
        (x, f)
    }
}

/// The normalisation (module docs). Returns the normalised polynomial with exact zero roots divided
/// out, and whether x = 0 is a root; `None` if there is nothing to solve (see the module docs).
fn prepare(c: &[f64]) -> Option<(Poly, bool)> {
    let mut mx: f64 = 0.0;
    for &v in c {
        if !v.is_finite() {
            return None;
        }
        mx = mx.max(v.abs());
    }
    if mx == 0.0 || c.is_empty() {
        return None;
    }
    let mut n = c.len() - 1;
    while n > 0 && (c[n] / mx).abs() < DROP_TOL {
        n -= 1;
    }
    if n == 0 || n > MAX_DEGREE {
        return None;
    }
    // Exact zero roots: c[0] = ... = c[k-1] = 0 (k < n because c[n] != 0).
    let mut k = 0;
    while k < n && c[k] == 0.0 {
        k += 1;
    }
    let mut p = Poly {
        c: [0.0; NC],
        n: n - k,
    };
    for i in 0..=(n - k) {
        p.c[i] = c[i + k] / mx;
    }
    if p.n == 0 {
        // Only possible as c = a x^k: the single root 0.
        return Some((p, true));
    }
    Some((p, k > 0))
}

/// Sign as +-1.0 (0 counts as +).
#[inline]
fn sgn(x: f64) -> f64 {
    if x < 0.0 {
        -1.0
    } else {
        1.0
    }
}

/// All distinct real roots of the polynomial `c[0] + c[1] x + ... + c[n] x^n` (ascending
/// coefficients), sorted ascending.
///
/// Implements the normalisation exactly (divide by the largest `|c_i|`, drop leading
/// coefficients below `1e-14` after that; non-finite input gives no roots). After dropping, the
/// degree must be at most [`MAX_DEGREE`]: `c` may be longer than 10 only if the extra leading
/// coefficients are negligible; a genuinely higher degree gives an empty result (documented
/// refusal rather than a wrong answer). Roots are isolated with the derivative sequence and
/// refined by safeguarded Halley/Newton steps to the rounding level (backward error a few `n eps`); multiple
/// roots are reported once, to (near) full precision. See the module documentation for the method and why it is used for every degree.
#[must_use]
pub fn real_roots(c: &[f64]) -> Roots {
    match prepare(c) {
        Some((p, z)) => solve_prepared(&p, z, 0.0),
        None => Roots::default(),
    }
}

/// The real roots of [`real_roots`] that are positive, found on `(0, bound)` only (about half
/// the work when only positive roots matter, as for depths): the same normalisation and method.
#[must_use]
pub fn positive_real_roots(c: &[f64]) -> Roots {
    match prepare(c) {
        Some((p, _)) => isolate::solve_positive(&p),
        None => Roots::default(),
    }
}

/// [`real_roots`] plus the real parts of *near-real* complex pairs (docs/algorithm.md T8), e.g.
/// `real_roots_near(c, DEFAULT_IMAG_TOL)` reproduces the prototype's rule
/// `|Im z| <= 1e-6 (1 + |z|)`.
///
/// A complex pair `x* +- i b` with small `b` sits next to a real critical point `x*` of `p`
/// (`p'(x*) = 0`, since p is nearly `(x - x*)^2 + b^2` times a factor there). Expanding around
/// `x*`, `p(x) ~ p(x*) + p''(x*) (x - x*)^2 / 2`, whose roots are `x* +- sqrt(-2 p(x*) / p''(x*))`:
/// imaginary when `p(x*)` and `p''(x*)` have the same sign, with `b = sqrt(2 |p(x*) / p''(x*)|)`.
/// Every real root `x*` of `p'` that is not already a root of `p` (value negligible, or a found
/// root within `imag_tol (1 + |x*|)`) is therefore added when `b <= imag_tol (1 + |x*|)`.
/// (If the signs differ, `b` is the half-distance of a real pair, which the bracketing already
/// finds, so nothing is added.) `imag_tol <= 0` or NaN adds nothing. At most [`MAX_DEGREE`] roots, deduplicated.
#[must_use]
pub fn real_roots_near(c: &[f64], imag_tol: f64) -> Roots {
    match prepare(c) {
        Some((p, z)) => solve_prepared(&p, z, if imag_tol > 0.0 { imag_tol } else { 0.0 }),
        None => Roots::default(),
    }
}

/// The roots of [`real_roots_near`] above `lo`, found on `(lo, bound)` only (less work when only
/// the roots above a known value matter, as for the P4Pf octic's depth ratios); `lo` at or below
/// the root bound's negative (or NaN) searches everywhere. A root at `lo` itself is not
/// reported; near-real roots come from the critical points above `lo`, the real roots of `p'`
/// there, which the Sturm sequence of `p'` isolates ([`real_roots_above`]'s; where it refuses,
/// every level of the derivative sequence is searched above `lo`, its roots refined to a relative
/// Halley step of 1e-7). The polynomial's roots are bracketed between the critical points and
/// refined to the rounding level, as [`real_roots`]'s. On the focal RANSAC's P4Pf calls whose
/// points are close to coplanar (18 % of the samples at 80 % outliers), this took 9,380
/// instructions a call where the derivative sequence took 12,780 (callgrind; the sequence
/// refused on 99 of 20,502).
#[must_use]
pub fn real_roots_near_above(c: &[f64], imag_tol: f64, lo: f64) -> Roots {
    match prepare(c) {
        Some((p, z)) => {
            let imag_tol = if imag_tol > 0.0 { imag_tol } else { 0.0 };
            let bound = p.root_bound();
            let crit = if p.n >= 2 && !z && lo > -bound && lo < bound {
                sturm::roots_above(&p.derivative(), lo)
            } else {
                None
            };
            match crit {
                Some(crit) => isolate::solve_above_at(&p, bound, crit.as_slice(), z, imag_tol, lo),
                None => isolate::solve_above(&p, z, imag_tol, lo),
            }
        }
        None => Roots::default(),
    }
}

/// The distinct real roots of `c` above `lo` (ascending, to the rounding level), isolated by
/// the Sturm sequence (module docs): the same normalisation as [`real_roots`], no near-real
/// roots; where the sequence cannot decide (a multiple or nearly multiple root, a root at a
/// split point), or `lo` is not finite, or `x = 0` is an exact root, the roots of
/// [`real_roots_near_above`] without near-real ones.
#[must_use]
pub fn real_roots_above(c: &[f64], lo: f64) -> Roots {
    match prepare(c) {
        Some((p, z)) => {
            let found = if p.n >= 1 && lo.is_finite() && !z {
                sturm::roots_above(&p, lo)
            } else {
                None
            };
            found.unwrap_or_else(|| isolate::solve_above(&p, z, 0.0, lo))
        }
        None => Roots::default(),
    }
}

/// Real roots of the cubic `c[0] + c[1] x + c[2] x^2 + c[3] x^3`, sorted ascending, in closed form
/// (trigonometric form for three real roots, Cardano with the cancellation-free `A + Q/A`
/// otherwise, the smallest root recomputed from the product of the roots), then Newton polishing
/// (at most 4 steps, each accepted only if it reduces |p|).
///
/// Same normalisation as [`real_roots`]: a (near-)zero leading coefficient degrades to the
/// quadratic / linear case. A double root is reported once. The result is checked: if a polished
/// root still has a residual above the rounding level, or the roots do not sit one in each
/// interval between critical points where p changes sign (cancellation can turn a close real pair
/// complex), the cubic is solved by [`real_roots`]'s method instead. [`real_roots`] itself is at
/// least as accurate and, with these checks, measured slightly faster; the closed forms are kept
/// as an independent implementation.
#[must_use]
pub fn cubic_real_roots(c: &[f64; 4]) -> Roots {
    match prepare(c) {
        Some((p, z)) => closed::closed_prepared(&p, z),
        None => Roots::default(),
    }
}

/// Real roots of the quartic `c[0] + c[1] x + ... + c[4] x^4`, sorted ascending, by Ferrari's
/// method (depressed quartic, largest root of the resolvent cubic, two quadratics solved without
/// cancellation), then Newton polishing as in [`cubic_real_roots`], with the same degradation
/// rules and the same fallback to [`real_roots`]'s method.
#[must_use]
pub fn quartic_real_roots(c: &[f64; 5]) -> Roots {
    match prepare(c) {
        Some((p, z)) => closed::closed_prepared(&p, z),
        None => Roots::default(),
    }
}
