//! Polynomials for the root finders' tests: from their roots, random ones from a seeded stream,
//! and the test of a root to the rounding level.

/// The ascending coefficients of `prod (x - r_i)`.
#[must_use]
pub fn poly_from_roots(r: &[f64]) -> Vec<f64> {
    let mut c = vec![1.0];
    for &ri in r {
        let mut n = vec![0.0; c.len() + 1];
        for (i, &ci) in c.iter().enumerate() {
            n[i + 1] += ci;
            n[i] -= ri * ci;
        }
        c = n;
    }
    c
}

/// A deterministic stream of uniform draws in [0, 1) from `seed` (SplitMix64), so that a
/// failure reproduces.
pub fn uniform_stream(mut state: u64) -> impl FnMut() -> f64 {
    move || {
        let z = crate::splitmix64(state);
        state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        (z >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// The `k`-th polynomial of a random family of degree `1 + k % 9`: for even `k` the product of
/// random roots in [-10, 10], for odd `k` random coefficients in [-1, 1] (ascending), drawn from
/// `next`.
pub fn random_polynomial(k: usize, next: &mut impl FnMut() -> f64) -> Vec<f64> {
    let degree = 1 + k % 9;
    if k.is_multiple_of(2) {
        let roots: Vec<f64> = (0..degree).map(|_| 20.0 * next() - 10.0).collect();
        poly_from_roots(&roots)
    } else {
        (0..=degree).map(|_| 2.0 * next() - 1.0).collect()
    }
}

/// Whether `x` is a root of `c` (ascending) to the rounding level: `|p(x)|` at most 64 eps
/// times the sum of its terms' absolute values (Horner's error bound, with room).
#[must_use]
pub fn is_root_to_rounding(c: &[f64], x: f64) -> bool {
    let (value, terms) = c.iter().rev().fold((0.0, 0.0), |(v, s), &ci| {
        (v * x + ci, s * x.abs() + ci.abs())
    });
    value.abs() <= 64.0 * f64::EPSILON * terms
}

/// Checks the roots `got` of `c` above `lo` against `reference` (the roots of another method,
/// filtered to those above `lo` here), those within 1e-6 (relative) of `lo` left out of both: as
/// many, and each within 1e-9 (relative) of its counterpart or, with `rounding`, a root to the
/// rounding level ([`is_root_to_rounding`]: in a cluster of roots two methods stop at different
/// points of the rounding's band). Returns the number compared; panics with the polynomial.
pub fn assert_roots_above(
    c: &[f64],
    lo: f64,
    got: &[f64],
    reference: &[f64],
    rounding: bool,
) -> usize {
    let away = |x: &f64| (x - lo).abs() > 1e-6 * (1.0 + lo.abs());
    let want: Vec<f64> = reference
        .iter()
        .copied()
        .filter(|&x| x > lo && away(&x))
        .collect();
    let got: Vec<f64> = got.iter().copied().filter(away).collect();
    assert_eq!(
        got.len(),
        want.len(),
        "{c:?} above {lo}: {got:?} vs {want:?}"
    );
    for (&a, &b) in got.iter().zip(&want) {
        assert!(
            (a - b).abs() <= 1e-9 * (1.0 + b.abs()) || (rounding && is_root_to_rounding(c, a)),
            "{c:?}: {a} vs {b}"
        );
    }
    got.len()
}
