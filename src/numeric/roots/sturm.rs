//! The real roots of a polynomial above a value by its Sturm sequence: the number of distinct
//! real roots in an interval is the drop in the sequence's sign changes across it, so the
//! interval is split until each piece holds one root, which [`bracket`] then refines (as the
//! derivative-sequence method refines its brackets). No derivative's root is sought, and the
//! degree is a compile-time constant (every loop unrolled): on the P4Pf octic, whose interval
//! holds few roots, less work than [`super::isolate::solve_above`] (see [`super`] for where it
//! is used and why only there).
//!
//! The sequence is `p_0 = p`, `p_1 = p'`, `p_(k+1) = -rem(p_(k-1), p_k)`, each scaled to a
//! leading coefficient of magnitude 1 (a positive factor: the signs are those of the exact
//! sequence's), in the generic case where each remainder is one degree lower. The construction
//! is a chain of dependent steps; with that scale the quotients need no division, and each step
//! one, its scale's (with the largest coefficient scaled to 1 instead, three: P4Pf at 80 %
//! outliers, 1.50 -> 1.38 us a call). A remainder whose leading coefficient
//! is lost in the cancellation of its terms (a multiple or nearly multiple root, or a sequence
//! that is not generic), a root of `p` at a split point, counts that contradict each other, and
//! a cluster of roots that splitting cannot separate are refused (`None`): the caller falls
//! back to the derivative sequence.

use super::isolate::{bracket, split_above};
use super::{sgn, Poly, Roots, NC};

/// A remainder's leading coefficient counts as zero at or below this times the largest term
/// that entered it.
const GENERIC: f64 = 1e-9;
/// Splits of the interval before a cluster of roots is refused.
const MAX_SPLITS: usize = 120;

/// `c[0] + c[1] x + ... + c[d] x^d`.
#[inline(always)]
fn horner(c: &[f64; NC], d: usize, x: f64) -> f64 {
    let mut p = c[d];
    for i in (0..d).rev() {
        p = p * x + c[i];
    }
    p
}

/// The Sturm sequence `p_0 .. p_N` of a polynomial of degree `N` (`p_k` of degree `N - k`,
/// coefficients ascending in row `k`), each term evaluated by its own Horner chain (the
/// recurrence of the construction, cheaper, loses the signs of a few terms near their roots:
/// on the P4Pf octics of 20,000 noisy four-inlier samples, 31 fewer true solutions found).
struct Sturm<const N: usize> {
    c: [[f64; NC]; NC],
    /// The sign changes at `+infinity` (those of the leading coefficients).
    at_infinity: usize,
}

impl<const N: usize> Sturm<N> {
    /// The generic sequence of `p` (degree `N >= 1`), each term scaled to a leading coefficient
    /// of magnitude 1, or `None` (module docs).
    #[inline(always)]
    fn new(p: &Poly) -> Option<Self> {
        let mut c = [[0.0; NC]; NC];
        let s0 = 1.0 / p.c[N].abs();
        for (ci, pi) in c[0].iter_mut().zip(&p.c).take(N + 1) {
            *ci = pi * s0;
        }
        let s1 = s0 / N as f64;
        for i in 1..=N {
            c[1][i - 1] = p.c[i] * (i as f64 * s1);
        }
        let mut at_infinity = usize::from((c[0][N] < 0.0) != (c[1][N - 1] < 0.0));
        let mut generic = s0.is_finite();
        for k in 1..N {
            // p_(k-1) (degree m + 1) = (q1 x + q0) p_k (degree m) - p_(k+1) (degree m - 1); the
            // leading coefficients are +-1, their own reciprocals.
            let m = N - k;
            let (done, rest) = c.split_at_mut(k + 1);
            let (a, b) = (&done[k - 1], &done[k]);
            let q1 = a[m + 1] * b[m];
            let q0 = (a[m] - q1 * b[m - 1]) * b[m];
            let next = &mut rest[0];
            for i in 0..m {
                let below = if i >= 1 { b[i - 1] } else { 0.0 };
                next[i] = q1 * below + q0 * b[i] - a[i];
            }
            let below = if m >= 2 { b[m - 2] } else { 0.0 };
            let terms = a[m - 1]
                .abs()
                .max((q1 * below).abs())
                .max((q0 * b[m - 1]).abs());
            let lead = next[m - 1];
            let scale = 1.0 / lead.abs();
            generic &= lead.abs() > GENERIC * terms && scale.is_finite();
            for v in next.iter_mut().take(m) {
                *v *= scale;
            }
            at_infinity += usize::from((b[m] < 0.0) != (lead < 0.0));
        }
        let finite = c.iter().all(|row| row.iter().all(|v| v.is_finite()));
        (generic && finite).then_some(Sturm { c, at_infinity })
    }

    /// The sign changes of the sequence at `x` (zeros skipped), and `p(x)`.
    #[inline(always)]
    fn variations(&self, x: f64) -> (usize, f64) {
        let mut v = [0.0; NC];
        for (k, vk) in v.iter_mut().enumerate().take(N + 1) {
            *vk = horner(&self.c[k], N - k, x);
        }
        let mut changes = 0;
        if v[..=N].iter().all(|x| *x != 0.0) {
            for k in 1..=N {
                changes += usize::from(v[k - 1].is_sign_negative() != v[k].is_sign_negative());
            }
        } else {
            let mut last = 0.0;
            for &vk in &v[..=N] {
                if vk != 0.0 {
                    changes += usize::from(last != 0.0 && (vk < 0.0) != (last < 0.0));
                    last = vk;
                }
            }
        }
        (changes, v[0])
    }
}

/// The distinct real roots of the prepared polynomial `p` (degree 1 to [`super::MAX_DEGREE`])
/// in `(lo, its root bound)`, ascending, each refined to the rounding level; `None` where the
/// sequence cannot decide (module docs).
pub(super) fn roots_above(p: &Poly, lo: f64) -> Option<Roots> {
    match p.n {
        1 => roots_above_n::<1>(p, lo),
        2 => roots_above_n::<2>(p, lo),
        3 => roots_above_n::<3>(p, lo),
        4 => roots_above_n::<4>(p, lo),
        5 => roots_above_n::<5>(p, lo),
        6 => roots_above_n::<6>(p, lo),
        7 => roots_above_n::<7>(p, lo),
        8 => roots_above_n::<8>(p, lo),
        9 => roots_above_n::<9>(p, lo),
        _ => None,
    }
}

/// [`roots_above`] at the degree `N`.
fn roots_above_n<const N: usize>(p: &Poly, lo: f64) -> Option<Roots> {
    let mut out = Roots::default();
    let bound = p.root_bound();
    if !(lo < bound) {
        return Some(out);
    }
    let sturm = Sturm::<N>::new(p)?;
    // No root above the bound: the changes there are those at infinity.
    let v_hi = sturm.at_infinity;
    let (v_lo, f_lo) = sturm.variations(lo);
    if f_lo == 0.0 || v_lo < v_hi {
        return None;
    }
    // Pieces (a, b) holding roots, with the changes at both ends and p(a); the leftmost on top.
    // Every piece on the stack holds a root: at most one piece per root.
    let mut stack = [(0.0, 0.0, 0usize, 0usize, 0.0); NC];
    let mut top = 0;
    if v_lo > v_hi {
        stack[0] = (lo, bound, v_lo, v_hi, f_lo);
        top = 1;
    }
    let mut splits = 0;
    while top > 0 {
        top -= 1;
        let (a, b, va, vb, fa) = stack[top];
        if va - vb == 1 {
            out.push(bracket(p, a, b, sgn(fa), f64::NAN, 0.0, split_above));
            continue;
        }
        let m = split_above(a, b);
        splits += 1;
        if !(m > a && m < b) || splits > MAX_SPLITS {
            return None;
        }
        let (vm, fm) = sturm.variations(m);
        if fm == 0.0 || vm < vb || va < vm || top + 2 > stack.len() {
            return None;
        }
        if vm > vb {
            stack[top] = (m, b, vm, vb, fm);
            top += 1;
        }
        if va > vm {
            stack[top] = (a, m, va, vm, fa);
            top += 1;
        }
    }
    Some(out)
}

#[cfg(test)]
#[path = "../../../tests/unit/numeric/roots/sturm.rs"]
mod tests;
