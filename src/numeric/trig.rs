//! The arctangent of a non-negative number and the tangent of an angle in `[0, pi/2)`, in
//! straight-line arithmetic (no branch, no call), so that a loop over packed lanes that needs
//! them stays packed: the fisheye models' equidistant map `theta = atan(r)`, evaluated per
//! point in every pass of the pixel-space refinement, and its inverse `r = tan(theta)` in the
//! undistortion.
//!
//! [`atan_nonneg`]: `atan(x) = pi/2 - atan(1/x)` above 1; then, above `tan(pi/8)`, one
//! halving of the angle, `atan(y) = 2 atan(y / (1 + sqrt(1 + y^2)))`, which brings the
//! argument to at most `tan(pi/8) = 0.414`; there the Taylor series
//! `sum (-1)^n y^(2n+1) / (2n + 1)` (21 terms: the first omitted one is below `2^-56` of the
//! sum), summed mostly by Estrin's scheme ([`series_sum`]: seven levels of dependent
//! operations instead of Horner's 21, which the per-point loops of the fisheye models are
//! bound by). Every path is computed and the result selected. Accuracy: within 2.54 ulp of the
//! exact value over 60,000 log-uniform arguments from `1e-8` to `1e8` (these operations
//! transcribed to numpy, against mpmath at 120 bits; Horner's rule gave the same), and within
//! 4 ulp of `f64::atan` over 200,000 arguments from `1e-300` to `1e300` and the break points
//! (`tests/unit/numeric/trig.rs`).
//!
//! [`tan_quadrant`]: above `pi/4`, `tan(theta) = cos(a) / sin(a)` with `a = pi/2 - theta`
//! (exact in two doubles: `pi/2`'s high part minus `theta` is exact there); below,
//! `sin(a) / cos(a)` with `a = theta`; `sin` and `cos` of `a <= pi/4` by 10 terms each of
//! their Taylor series (the first omitted ones below `2^-60`), summed as the arctangent's.
//! Within 2.90 ulp of the exact value over 40,000 uniform angles (numpy against mpmath, as
//! Horner's rule) and within 4 ulp of `f64::tan` (tested).
//!
//! [`sinc_cos_small`]: `sin(a) / a` and `cos(a)` for `|a| <= 1/4`, from `a^2`, by 7 terms of
//! the same series, for the exponential map of the refinement's steps
//! (`numeric::rotation::exp_so3`).

/// `pi / 2` as the sum of two doubles (the nearest double, and the rest).
const PIO2_HI: f64 = core::f64::consts::FRAC_PI_2;
const PIO2_LO: f64 = 6.123_233_995_736_766e-17;
/// `tan(pi / 8)`: above it the angle is halved once.
const TAN_PI_8: f64 = 0.414_213_562_373_095_1;
/// The Taylor coefficients of `atan(y) / y` in `z = y^2`: `(-1)^n / (2n + 1)`, 21 terms.
const ATAN_COEFFS: [f64; 21] = series(1, false);

/// `atan(x)` for `x >= 0` (`+inf` gives `pi / 2`, NaN gives NaN); see the module documentation.
#[inline(always)]
pub(crate) fn atan_nonneg(x: f64) -> f64 {
    let big = x > 1.0;
    let y = if big { 1.0 / x } else { x };
    let halve = y > TAN_PI_8;
    let h = y / (1.0 + (1.0 + y * y).sqrt());
    let y = if halve { h } else { y };
    let z = y * y;
    let p = series_sum(&ATAN_COEFFS, z);
    let a = y * p;
    let a = if halve { 2.0 * a } else { a };
    if big {
        (PIO2_HI - a) + PIO2_LO
    } else {
        a
    }
}

/// The Taylor coefficients of `sin(a) / a` and `cos(a)` in `z = a^2`, 10 terms each:
/// `(-1)^k / (2k + 1)!` and `(-1)^k / (2k)!`.
const SIN_COEFFS: [f64; 10] = series(1, true);
const COS_COEFFS: [f64; 10] = series(0, true);

/// `tan(theta)` for `0 <= theta < pi/2` (the caller checks the range; see the module
/// documentation).
#[inline(always)]
pub(crate) fn tan_quadrant(theta: f64) -> f64 {
    let big = theta > core::f64::consts::FRAC_PI_4;
    let a = if big {
        (PIO2_HI - theta) + PIO2_LO
    } else {
        theta
    };
    let z = a * a;
    // sin(a) and cos(a) by their series in z = a^2.
    let s = a * series_sum(&SIN_COEFFS, z);
    let c = series_sum(&COS_COEFFS, z);
    if big {
        c / s
    } else {
        s / c
    }
}

/// `sum_k c[k] z^k`: the first two terms by Horner's rule around the rest, which Estrin's
/// scheme sums (adjacent coefficients paired as `c[2k] + c[2k+1] z`, then those pairs with
/// `z^2`, and so on), so that the chain of dependent operations is about `2 + log2(N)` levels
/// deep instead of Horner's `N`. The two leading terms, the largest, are added last, as
/// Horner's rule adds them, which keeps Horner's accuracy: transcribed to numpy against
/// mpmath, the arctangent's worst error stayed 2.54 ulp (60,000 arguments; Estrin's scheme
/// alone: 2.95) and the tangent's 2.90 ulp (40,000; alone: 4.21).
#[inline(always)]
fn series_sum<const N: usize>(c: &[f64; N], z: f64) -> f64 {
    let mut v = [0.0; N];
    let mut n = N - 2;
    v[..n].copy_from_slice(&c[2..]);
    let mut zp = z;
    while n > 1 {
        let m = n.div_ceil(2);
        for k in 0..m {
            // Reads at 2k and 2k + 1 >= k: not yet overwritten in this level.
            v[k] = if 2 * k + 1 < n {
                v[2 * k] + v[2 * k + 1] * zp
            } else {
                v[2 * k]
            };
        }
        n = m;
        zp *= zp;
    }
    c[0] + z * (c[1] + z * v[0])
}

/// Below this angle [`sinc_cos_small`] applies (the first omitted terms of its series are
/// below `2^-64` of the sums).
pub(crate) const SMALL_ANGLE: f64 = 0.25;

/// `(sin(a) / a, cos(a))` for `|a| <= SMALL_ANGLE`, from `z = a^2` (both are even: the angle
/// itself, a square root away, is not needed), by the first 7 terms of each Taylor series (Horner's
/// rule in `z`): the half-angle functions of the exponential map of `refine`'s and `refine_pixels`'
/// steps, without two calls of libm. Within 1 ulp of `f64::sin(a) / a` and `f64::cos` (tested).
#[inline(always)]
pub(crate) fn sinc_cos_small(z: f64) -> (f64, f64) {
    let s = SIN_COEFFS[..7].iter().rev().fold(0.0, |p, &k| p * z + k);
    let c = COS_COEFFS[..7].iter().rev().fold(0.0, |p, &k| p * z + k);
    (s, c)
}

/// `(-1)^n / d(n)` for `n = 0..N`, with `d(n) = 2n + odd`, or its factorial: evaluated at
/// compile time.
const fn series<const N: usize>(odd: usize, factorial_of: bool) -> [f64; N] {
    let mut out = [0.0; N];
    let mut n = 0;
    while n < N {
        let d = 2 * n + odd;
        let d = if factorial_of { factorial(d) } else { d as f64 };
        out[n] = if n % 2 == 0 { 1.0 / d } else { -1.0 / d };
        n += 1;
    }
    out
}

/// `n!` as a double (exact up to `22!`).
const fn factorial(n: usize) -> f64 {
    let mut f = 1.0;
    let mut k = 2;
    while k <= n {
        f *= k as f64;
        k += 1;
    }
    f
}

#[cfg(test)]
#[path = "../../tests/unit/numeric/trig.rs"]
mod tests;
