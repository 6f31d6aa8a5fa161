//! The Sturm-sequence isolation itself (not through `real_roots_above`, whose fallback would
//! hide a failure): it decides (`Some`) on generic polynomials, finds the real roots above the
//! value that the derivative sequence finds, and refuses (`None`) a double root.
//!
//! Unit tests run in the published package too, without the workspace's `eopnp-testkit`: the
//! polynomials are made here (`tests/roots.rs` checks `real_roots_above` with testkit's).

use super::super::{prepare, real_roots, Roots};
use super::roots_above;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

/// The ascending coefficients of `prod (x - r_i)`.
fn from_roots(r: &[f64]) -> Vec<f64> {
    r.iter().fold(vec![1.0], |c, &ri| {
        let mut n = vec![0.0; c.len() + 1];
        for (i, &ci) in c.iter().enumerate() {
            n[i + 1] += ci;
            n[i] -= ri * ci;
        }
        n
    })
}

fn sturm(c: &[f64], lo: f64) -> Option<Roots> {
    let (p, zero) = prepare(c).expect("a polynomial");
    assert!(!zero);
    roots_above(&p, lo)
}

#[test]
fn known_roots_above_a_value() {
    let r = [-3.0, -1.0, 0.5, 2.0, 7.0];
    let got = sturm(&from_roots(&r), -2.0).expect("decided");
    assert_eq!(got.len(), 4);
    for (a, b) in got.iter().zip([-1.0, 0.5, 2.0, 7.0]) {
        assert!((a - b).abs() <= 1e-14 * (1.0 + b.abs()), "{got:?}");
    }
    // No root above the value, and a value above the root bound.
    assert!(sturm(&from_roots(&r), 7.5).expect("decided").is_empty());
    assert!(sturm(&from_roots(&r), 1e6).expect("decided").is_empty());
    // Close simple roots are separated by splitting.
    let close = [1.0, 1.0 + 1e-3, 3.0];
    let got = sturm(&from_roots(&close), 0.0).expect("decided");
    assert_eq!(got.len(), 3, "{got:?}");
    for (a, b) in got.iter().zip(close) {
        assert!((a - b).abs() <= 1e-12, "{got:?}");
    }
    // A double root, and a pair 1e-6 apart: the last remainder (about the square of the
    // pair's distance) is lost in the cancellation of its terms, the sequence refuses (the
    // caller falls back to the derivative sequence).
    assert!(sturm(&from_roots(&[2.0, 2.0, -1.0]), -5.0).is_none());
    assert!(sturm(&from_roots(&[1.0, 1.0 + 1e-6, 3.0]), 0.0).is_none());
}

/// 20,000 random polynomials of degree 1 to 9 (random roots in [-10, 10] and random
/// coefficients) with random values `lo`: the sequence decides on all but a few, and then
/// gives as many roots above `lo` as `real_roots` (roots within 1e-6 of `lo` left out), each
/// within 1e-9 of its counterpart or a root to the rounding level (`|p(x)|` at most 64 eps
/// times its terms' sum: in a cluster of roots the two methods stop at different points of
/// the rounding's band, 1.1e-6 apart in one of these polynomials).
#[test]
fn decides_and_agrees_with_the_derivative_sequence() {
    let mut rng = Pcg64::seed_from_u64(0x5851_f42d_4c95_7f2d);
    let (mut decided, mut found) = (0, 0);
    for k in 0..20_000 {
        let degree = 1 + k % 9;
        let c: Vec<f64> = if k % 2 == 0 {
            let roots: Vec<f64> = (0..degree).map(|_| rng.random_range(-10.0..10.0)).collect();
            from_roots(&roots)
        } else {
            (0..=degree).map(|_| rng.random_range(-1.0..1.0)).collect()
        };
        let lo = rng.random_range(-5.0..5.0);
        let Some(got) = sturm(&c, lo) else {
            continue;
        };
        decided += 1;
        let away = |x: &f64| (x - lo).abs() > 1e-6 * (1.0 + f64::abs(lo));
        let want: Vec<f64> = real_roots(&c)
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
            let (value, terms) = c.iter().rev().fold((0.0, 0.0), |(v, s), &ci| {
                (v * a + ci, s * a.abs() + ci.abs())
            });
            let root = value.abs() <= 64.0 * f64::EPSILON * terms;
            assert!(
                (a - b).abs() <= 1e-9 * (1.0 + b.abs()) || root,
                "{c:?}: {a} vs {b}"
            );
        }
        found += got.len();
    }
    println!("decided {decided} of 20000, {found} roots");
    assert!(decided >= 19_900, "decided on {decided} of 20000");
    assert!(found > 20_000, "{found} roots");
}
