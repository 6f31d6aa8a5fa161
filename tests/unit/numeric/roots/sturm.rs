//! The Sturm-sequence isolation itself (not through `real_roots_above`, whose fallback would
//! hide a failure): it decides (`Some`) on generic polynomials, finds the real roots above the
//! value that the derivative sequence finds, and refuses (`None`) a double root.

use super::super::{prepare, real_roots, Roots};
use super::roots_above;
use eopnp_testkit::{
    assert_roots_above, poly_from_roots as from_roots, random_polynomial, uniform_stream,
};

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
    let mut next = uniform_stream(0x5851_f42d_4c95_7f2d_u64);
    let (mut decided, mut found) = (0, 0);
    for k in 0..20_000 {
        let c = random_polynomial(k, &mut next);
        let lo = 10.0 * next() - 5.0;
        let Some(got) = sturm(&c, lo) else {
            continue;
        };
        decided += 1;
        found += assert_roots_above(&c, lo, got.as_slice(), real_roots(&c).as_slice(), true);
    }
    println!("decided {decided} of 20000, {found} roots");
    assert!(decided >= 19_900, "decided on {decided} of 20000");
    assert!(found > 20_000, "{found} roots");
}
