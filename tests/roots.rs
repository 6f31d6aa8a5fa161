//! Unit-level tests of the public polynomial root finders (`eopnp::internals::roots`): known roots,
//! multiple roots, zero and degree-0 polynomials, leading zeros, non-finite and extreme
//! coefficients, near-real complex pairs, iteration. (Formerly `src/numeric/roots/tests.rs`.)

use eopnp::internals::roots::{
    cubic_real_roots, positive_real_roots, quartic_real_roots, real_roots, real_roots_above,
    real_roots_near, real_roots_near_above, Roots, DEFAULT_IMAG_TOL,
};
use eopnp_testkit::{
    assert_roots_above, poly_from_roots as from_roots, random_polynomial, uniform_stream as uniform,
};

fn close(a: &[f64], b: &[f64], tol: f64) -> bool {
    a.len() == b.len()
        && a.iter()
            .zip(b)
            .all(|(x, y)| (x - y).abs() <= tol * (1.0 + y.abs()))
}

#[test]
fn known_simple_roots() {
    let r = [-3.0, -1.0, 0.5, 2.0, 7.0];
    let c = from_roots(&r);
    assert!(close(real_roots(&c).as_slice(), &r, 1e-14));
    let c4 = from_roots(&r[..4]);
    let q = quartic_real_roots(&[c4[0], c4[1], c4[2], c4[3], c4[4]]);
    assert!(close(q.as_slice(), &r[..4], 1e-14), "{q:?}");
    let c3 = from_roots(&r[1..4]);
    let q = cubic_real_roots(&[c3[0], c3[1], c3[2], c3[3]]);
    assert!(close(q.as_slice(), &r[1..4], 1e-14), "{q:?}");
    // degree 9
    let r9 = [-4.0, -3.0, -2.0, -1.0, 0.25, 1.0, 2.0, 3.0, 4.0];
    assert!(close(real_roots(&from_roots(&r9)).as_slice(), &r9, 1e-12));
}

#[test]
fn double_and_triple_roots() {
    let c = from_roots(&[1.0, 1.0, 3.0]);
    let r = real_roots(&c);
    assert!(close(r.as_slice(), &[1.0, 3.0], 1e-14), "{r:?}");
    let r = cubic_real_roots(&[c[0], c[1], c[2], c[3]]);
    assert!(close(r.as_slice(), &[1.0, 3.0], 1e-14), "{r:?}");
    let c = from_roots(&[2.0, 2.0, 2.0, -1.0]);
    let r = real_roots(&c);
    assert!(close(r.as_slice(), &[-1.0, 2.0], 1e-14), "{r:?}");
    let c = from_roots(&[0.3, 0.3, -0.7, -0.7]);
    let r = quartic_real_roots(&[c[0], c[1], c[2], c[3], c[4]]);
    assert!(close(r.as_slice(), &[-0.7, 0.3], 1e-14), "{r:?}");
    assert!(close(real_roots(&c).as_slice(), &[-0.7, 0.3], 1e-14));
    // (x^2 + 1)^2 has no real roots
    assert!(real_roots(&[1.0, 0.0, 2.0, 0.0, 1.0]).is_empty());
    assert!(quartic_real_roots(&[1.0, 0.0, 2.0, 0.0, 1.0]).is_empty());
}

#[test]
fn zero_roots_and_degree_0() {
    assert!(close(real_roots(&[0.0, 0.0, 1.0]).as_slice(), &[0.0], 0.0));
    assert!(close(
        real_roots(&[0.0, -4.0, 0.0, 1.0]).as_slice(),
        &[-2.0, 0.0, 2.0],
        1e-15
    ));
    assert!(real_roots(&[5.0]).is_empty());
    assert!(real_roots(&[]).is_empty());
    assert!(real_roots(&[0.0, 0.0]).is_empty());
    assert!(cubic_real_roots(&[0.0; 4]).is_empty());
    assert!(close(
        cubic_real_roots(&[0.0, 0.0, 0.0, 2.0]).as_slice(),
        &[0.0],
        0.0
    ));
}

#[test]
fn leading_zeros_degrade() {
    // 1e-20 x^3 + x^2 - 1: leading coefficient dropped.
    let r = real_roots(&[-1.0, 0.0, 1.0, 1e-20]);
    assert!(close(r.as_slice(), &[-1.0, 1.0], 1e-15), "{r:?}");
    let r = cubic_real_roots(&[-1.0, 0.0, 1.0, 1e-20]);
    assert!(close(r.as_slice(), &[-1.0, 1.0], 1e-15), "{r:?}");
    let r = quartic_real_roots(&[-2.0, 1.0, 0.0, 0.0, 0.0]);
    assert!(close(r.as_slice(), &[2.0], 0.0), "{r:?}");
    // 1e-12 is kept: a far root near -1e12.
    let r = real_roots(&[-1.0, 0.0, 1.0, 1e-12]);
    assert_eq!(r.len(), 3);
    assert!((r.as_slice()[0] + 1e12).abs() < 1e-3 * 1e12);
}

#[test]
fn non_finite_and_extreme() {
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        assert!(real_roots(&[1.0, bad, 1.0]).is_empty());
        assert!(cubic_real_roots(&[1.0, bad, 1.0, 1.0]).is_empty());
        assert!(quartic_real_roots(&[bad, 0.0, 1.0, 1.0, 1.0]).is_empty());
        assert!(real_roots_near(&[1.0, 0.0, bad], 1e-6).is_empty());
    }
    let r = real_roots(&[-1e300, 0.0, 1e300]);
    assert!(close(r.as_slice(), &[-1.0, 1.0], 1e-15));
    let r = real_roots(&[-5e-324, 0.0, 5e-324]);
    assert!(close(r.as_slice(), &[-1.0, 1.0], 1e-15));
    let r = real_roots(&[-f64::MAX, f64::MAX]);
    assert!(close(r.as_slice(), &[1.0], 1e-15));
    // Too long but negligible high part: fine; genuinely degree 10: empty.
    let mut c = [0.0; 12];
    c[0] = -1.0;
    c[1] = 1.0;
    c[11] = 1e-20;
    assert!(close(real_roots(&c).as_slice(), &[1.0], 1e-15));
    c[11] = 1.0;
    assert!(real_roots(&c).is_empty());
}

#[test]
fn near_real_pairs() {
    // (x - 1)^2 + 1e-14: complex pair 1 +- 1e-7 i.
    let c = [1.0 + 1e-14, -2.0, 1.0];
    assert!(real_roots(&c).is_empty());
    let r = real_roots_near(&c, DEFAULT_IMAG_TOL);
    assert!(close(r.as_slice(), &[1.0], 1e-15), "{r:?}");
    // (x - 1)^2 + 1e-4: Im = 1e-2: not near-real.
    assert!(real_roots_near(&[1.0 + 1e-4, -2.0, 1.0], DEFAULT_IMAG_TOL).is_empty());
    // Real roots unaffected, no duplicates.
    let c = from_roots(&[1.0, 1.0 + 1e-9, 3.0]);
    let r = real_roots_near(&c, DEFAULT_IMAG_TOL);
    assert!(!r.is_empty() && r.len() <= 3);
    assert!((r.as_slice()[r.len() - 1] - 3.0).abs() < 1e-14);
    assert!(real_roots_near(&c, f64::NAN).len() == real_roots(&c).len());
}

#[test]
fn iterators() {
    let r = real_roots(&[-1.0, 0.0, 1.0]);
    let v: Vec<f64> = (&r).into_iter().copied().collect();
    assert_eq!(v, r.iter().copied().collect::<Vec<_>>());
    assert_eq!(Roots::default().len(), 0);
}

/// `positive_real_roots` finds the positive roots `real_roots` finds (to a few ulps): known
/// roots of both signs, double roots, a root at 0 (not positive), and 20,000 random polynomials
/// of degree 1 to 9 (random roots and random coefficients), whose positive roots are also
/// checked against the polynomial (a sign change across each one).
#[test]
fn positive_roots_are_the_positive_real_roots() {
    let r = [-3.0, -1.0, 0.5, 2.0, 7.0];
    assert!(close(
        positive_real_roots(&from_roots(&r)).as_slice(),
        &[0.5, 2.0, 7.0],
        1e-14
    ));
    let c = from_roots(&[2.0, 2.0, -1.0, 0.0]);
    assert!(close(positive_real_roots(&c).as_slice(), &[2.0], 1e-14));
    assert!(positive_real_roots(&from_roots(&[-1.0, -2.0, -5.0])).is_empty());
    assert!(positive_real_roots(&[1.0, 0.0, 1.0]).is_empty());
    let mut next = uniform(0x9e37_79b9_7f4a_7c15_u64);
    let (mut compared, mut found) = (0, 0);
    for k in 0..20_000 {
        let c = random_polynomial(k, &mut next);
        let all: Vec<f64> = real_roots(&c)
            .iter()
            .copied()
            .filter(|&x| x > 0.0)
            .collect();
        let pos = positive_real_roots(&c);
        assert_eq!(pos.len(), all.len(), "{c:?}: {pos:?} vs {all:?}");
        for (&a, &b) in pos.iter().zip(&all) {
            assert!((a - b).abs() <= 1e-9 * (1.0 + b.abs()), "{c:?}: {a} vs {b}");
        }
        compared += 1;
        found += pos.len();
    }
    assert_eq!(compared, 20_000);
    assert!(found > 20_000, "{found} positive roots");
}

/// `real_roots_near_above` finds the roots `real_roots_near` finds above the bound: known roots,
/// a double root, a near-real pair, and 20,000 random polynomials of degree 1 to 9 (random roots
/// and random coefficients) with random bounds and imaginary tolerances (roots within 1e-6 of
/// the bound left out of the comparison; each root within 1e-9 of its counterpart or a root to
/// the rounding level, as for `real_roots_above`: the two isolate the critical points
/// differently, by the Sturm sequence of `p'` and by the derivative sequence, and where
/// cancellation makes a root's rounding band wide, stop at different points of it, e.g. the
/// root 6.7839567132 of a random octic with coefficients up to 1.8e6, 6.78395661621 and
/// 6.78395667749, both at `|p|` within Horner's error bound).
#[test]
fn roots_above_are_the_real_roots_above() {
    let r = [-3.0, -1.0, 0.5, 2.0, 7.0];
    let got = real_roots_near_above(&from_roots(&r), 0.0, -2.0);
    assert!(
        close(got.as_slice(), &[-1.0, 0.5, 2.0, 7.0], 1e-14),
        "{got:?}"
    );
    let c = from_roots(&[2.0, 2.0, -3.0, 0.0]);
    assert!(close(
        real_roots_near_above(&c, 0.0, -2.0).as_slice(),
        &[0.0, 2.0],
        1e-14
    ));
    // ((x - 1)^2 + 1e-8) (x + 3), a pair 1 +- 1e-4 i: found with the tolerance (above -2, not
    // -3).
    let c = [3.0 + 3e-8, -5.0 + 1e-8, 1.0, 1.0];
    let near = real_roots_near_above(&c, 1e-3, -2.0);
    assert!(close(near.as_slice(), &[1.0], 1e-8), "{near:?}");
    let none = real_roots_near_above(&c, 0.0, -2.0);
    assert!(none.is_empty(), "{none:?}");
    // Everywhere when the bound is below every root.
    assert_eq!(
        real_roots_near_above(&from_roots(&r), 0.0, f64::NEG_INFINITY).as_slice(),
        real_roots(&from_roots(&r)).as_slice()
    );
    let mut next = uniform(0x2545_f491_4f6c_dd1d_u64);
    let mut found = 0;
    for k in 0..20_000 {
        let c = random_polynomial(k, &mut next);
        let lo = 10.0 * next() - 5.0;
        let tol = [0.0, DEFAULT_IMAG_TOL, 1e-2][k % 3];
        found += assert_roots_above(
            &c,
            lo,
            real_roots_near_above(&c, tol, lo).as_slice(),
            real_roots_near(&c, tol).as_slice(),
            true,
        );
    }
    assert!(found > 20_000, "{found} roots");
}

/// `real_roots_above` (the Sturm sequence, the derivative sequence where it refuses): the roots
/// of `real_roots` above the value, for known roots, a double root (refused by the Sturm
/// sequence: the fallback's answer), a close pair, an exact zero root, a non-finite value, and
/// 20,000 random polynomials of degree 1 to 9 (roots within 1e-6 of the value left out; each
/// root within 1e-9 of its counterpart or a root to the rounding level).
#[test]
fn sturm_roots_above_are_the_real_roots_above() {
    let r = [-3.0, -1.0, 0.5, 2.0, 7.0];
    let got = real_roots_above(&from_roots(&r), -2.0);
    assert!(
        close(got.as_slice(), &[-1.0, 0.5, 2.0, 7.0], 1e-14),
        "{got:?}"
    );
    // A double root: the Sturm chain refuses, the derivative sequence's answer.
    let c = from_roots(&[2.0, 2.0, -1.0]);
    assert_eq!(
        real_roots_above(&c, 0.5),
        real_roots_near_above(&c, 0.0, 0.5)
    );
    assert!(close(real_roots_above(&c, 0.5).as_slice(), &[2.0], 1e-7));
    // A pair 1e-6 apart, found by either method to well within the pair's distance.
    let pair = [1.0, 1.0 + 1e-6, 3.0];
    for lo in [0.0, 0.5] {
        let got = real_roots_above(&from_roots(&pair), lo);
        assert!(close(got.as_slice(), &pair, 1e-9), "{got:?}");
    }
    let c = from_roots(&[0.0, 2.0, -3.0]);
    assert!(close(
        real_roots_above(&c, -1.0).as_slice(),
        &[0.0, 2.0],
        1e-14
    ));
    assert_eq!(
        real_roots_above(&from_roots(&r), f64::NEG_INFINITY).as_slice(),
        real_roots(&from_roots(&r)).as_slice()
    );
    let mut next = uniform(0x3c6e_f372_fe94_f82b_u64);
    let mut found = 0;
    for k in 0..20_000 {
        let c = random_polynomial(k, &mut next);
        let lo = 10.0 * next() - 5.0;
        found += assert_roots_above(
            &c,
            lo,
            real_roots_above(&c, lo).as_slice(),
            real_roots(&c).as_slice(),
            true,
        );
    }
    assert!(found > 20_000, "{found} roots");
}
