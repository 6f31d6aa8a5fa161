use super::*;

/// Distance in units in the last place between two finite doubles of the same sign.
fn ulps(a: f64, b: f64) -> u64 {
    (a.to_bits() as i64 - b.to_bits() as i64).unsigned_abs()
}

/// Uniform numbers in `[0, 1)` from a seeded xorshift generator.
fn uniform(mut s: u64) -> impl FnMut() -> f64 {
    move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64
    }
}

#[test]
fn atan_is_within_four_ulp_of_std() {
    // Log-uniform from 1e-300 to 1e300, uniform in [0, 4], and the break points.
    let mut next = uniform(0x9E37_79B9_7F4A_7C15);
    let mut worst = 0;
    let mut args: Vec<f64> = (0..200_000)
        .map(|k| {
            if k % 2 == 0 {
                10f64.powf(600.0 * next() - 300.0)
            } else {
                4.0 * next()
            }
        })
        .collect();
    for b in [TAN_PI_8, 1.0] {
        let mut x = b;
        for _ in 0..8 {
            args.extend([x, -x]);
            x = f64::from_bits(x.to_bits() + 1);
        }
        let mut x = b;
        for _ in 0..8 {
            x = f64::from_bits(x.to_bits() - 1);
            args.push(x);
        }
    }
    for x in args.into_iter().filter(|x| *x >= 0.0) {
        let (a, b) = (atan_nonneg(x), x.atan());
        let u = ulps(a, b);
        assert!(u <= 4, "atan({x:e}) = {a:e}, std {b:e}: {u} ulp");
        worst = worst.max(u);
    }
    // Not the identity of std's (else the bound above is vacuous): it differs somewhere.
    assert!(worst >= 1, "{worst}");
}

#[test]
fn atan_special_values() {
    assert_eq!(atan_nonneg(0.0), 0.0);
    assert_eq!(atan_nonneg(1e-300), 1e-300);
    assert_eq!(atan_nonneg(f64::INFINITY), core::f64::consts::FRAC_PI_2);
    assert!(ulps(atan_nonneg(1e300), core::f64::consts::FRAC_PI_2) <= 1);
    assert!(ulps(atan_nonneg(1.0), core::f64::consts::FRAC_PI_4) <= 1);
    assert!(atan_nonneg(f64::NAN).is_nan());
}

#[test]
fn tan_is_within_four_ulp_of_std() {
    let mut next = uniform(0x2545_F491_4F6C_DD1D);
    let half_pi = core::f64::consts::FRAC_PI_2;
    let mut args: Vec<f64> = (0..200_000)
        .map(|k| match k % 3 {
            0 => half_pi * next(),
            // Near pi/2 (large tangents) and near 0.
            1 => half_pi - 10f64.powf(-16.0 * next()),
            _ => 10f64.powf(-300.0 * next()),
        })
        .filter(|t| (0.0..half_pi).contains(t))
        .collect();
    let mut t = core::f64::consts::FRAC_PI_4;
    for _ in 0..8 {
        args.push(t);
        t = f64::from_bits(t.to_bits() + 1);
    }
    args.extend([0.0, f64::from_bits(half_pi.to_bits() - 1)]);
    let mut worst = 0;
    for x in args {
        let (a, b) = (tan_quadrant(x), x.tan());
        let u = ulps(a, b);
        assert!(u <= 4, "tan({x:e}) = {a:e}, std {b:e}: {u} ulp");
        worst = worst.max(u);
    }
    assert!(worst >= 1, "{worst}");
}

#[test]
fn sinc_cos_small_is_within_one_ulp_of_std() {
    let mut next = uniform(0x2545_F491_4F6C_DD1D);
    let mut args: Vec<f64> = (0..100_000).map(|_| SMALL_ANGLE * next()).collect();
    // Tiny angles, and the ends of the range.
    args.extend((1..40).map(|k| 10f64.powi(-k)));
    args.extend([0.0, SMALL_ANGLE, f64::from_bits(SMALL_ANGLE.to_bits() - 1)]);
    let (mut worst_s, mut worst_c) = (0, 0);
    for a in args {
        for a in [a, -a] {
            let (s, c) = sinc_cos_small(a * a);
            let s_std = if a == 0.0 { 1.0 } else { a.sin() / a };
            let (us, uc) = (ulps(s, s_std), ulps(c, a.cos()));
            assert!(
                us <= 1 && uc <= 1,
                "a = {a:e}: sin(a)/a {s:e} vs {s_std:e}, cos {c:e} vs {:e}",
                a.cos()
            );
            worst_s = worst_s.max(us);
            worst_c = worst_c.max(uc);
        }
    }
    assert!(worst_s + worst_c >= 1, "not the identity of std's");
}
