//! The consensus a wrong pose reaches by chance, and so the least consensus [`super::Ransac`]
//! accepts.
//!
//! Null hypothesis: the correspondences carry no information about the pose, so a pose's
//! projection of a point lands anywhere in the region of the image the observations cover,
//! uniformly. The chance that it lands within the final threshold `T` (pixels) of the
//! observation is `p = pi T^2 / A`, `A` the area of that region: the product of the widths of
//! the central 90 % of the observations in x and in y (stretched to the full width of a
//! uniform distribution; the extremes for a few points), so that a few far-away observations
//! among many do not inflate it.
//!
//! A consensus of `k` of the `N` points is accepted only if its number of false alarms
//!
//! ```text
//! NFA(k) = 4 (N - 3) C(N, k) C(k, 3) p^(k - 3)
//! ```
//!
//! is at most 1 (a contrario RANSAC: Moisan and Stival, IJCV 2004; Moisan, Moulon and
//! Monasse, IPOL 2012): the expected number, under the null hypothesis, of `k`-point sets (any
//! of the `C(N, k)`, with any of their `C(k, 3)` minimal samples and its up to 4 P3P poses, for
//! any of the `N - 3` sizes) whose other `k - 3` points all fall within `T`. It counts every
//! set a search could find, not only the hypotheses drawn, so the local optimisation's and the
//! final fit's pull towards chance inliers is covered: on pure noise a best-of-10,000 pose
//! with local optimisation gathers 8 of 100 points at 16 px, more than an independent count
//! of the drawn hypotheses allows. Four points are accepted when `16 p <= 1` (points spread
//! over more than about 60 x 60 px at the default 8 px final threshold).

use nalgebra::Point2;

/// Chance that a wrong hypothesis projects a point within `threshold_px` of its observation:
/// `pi T^2 / A`, `A` the observations' area in pixels (module documentation), at most 1.
pub(super) fn chance_inlier_rate(
    image: &[Point2<f64>],
    focal: (f64, f64),
    threshold_px: f64,
) -> f64 {
    let (fx, fy) = focal;
    // One buffer for both coordinates.
    let mut buf = Vec::with_capacity(image.len());
    let wx = spread(&mut buf, image.iter().map(|p| p.x));
    let wy = spread(&mut buf, image.iter().map(|p| p.y));
    let area = wx * fx * wy * fy;
    let disk = std::f64::consts::PI * threshold_px * threshold_px;
    if area.is_finite() && area > disk {
        disk / area
    } else {
        1.0
    }
}

/// The width of the central 90 % of the values (between the 5 % and 95 % quantiles),
/// stretched by `1 / 0.9` to the full width of a uniform distribution: the extremes for a few
/// values, and unmoved by a few far-away ones among many.
fn spread(v: &mut Vec<f64>, values: impl Iterator<Item = f64>) -> f64 {
    v.clear();
    v.extend(values);
    if v.len() < 2 {
        return 0.0;
    }
    let last = v.len() - 1;
    let lo_k = (0.05 * last as f64).floor() as usize;
    let hi_k = (0.95 * last as f64).ceil() as usize;
    let hi = *v.select_nth_unstable_by(hi_k, f64::total_cmp).1;
    let lo = *v[..=hi_k].select_nth_unstable_by(lo_k, f64::total_cmp).1;
    if lo_k == 0 && hi_k == last {
        hi - lo
    } else {
        (hi - lo) / 0.9
    }
}

/// The least consensus (inlier count) of `n` points whose number of false alarms is at most 1
/// at a chance inlier rate `p` (module documentation); `n + 1` (nothing is accepted) when
/// even all `n` points are within chance.
pub(super) fn least_consensus(n: usize, p: f64) -> usize {
    if n < 4 || !(p < 1.0) {
        return n + 1;
    }
    if !(p > 0.0) {
        return 4;
    }
    let nf = n as f64;
    // ln NFA(k) = ln(4 (n - 3)) + ln C(n, k) + ln C(k, 3) + (k - 3) ln p, C(n, k) by its
    // recurrence from C(n, 3).
    let base = (4.0 * (nf - 3.0)).ln();
    let mut ln_c_nk = (nf * (nf - 1.0) * (nf - 2.0) / 6.0).ln();
    let ln_p = p.ln();
    for k in 4..=n {
        let kf = k as f64;
        ln_c_nk += ((nf - kf + 1.0) / kf).ln();
        let ln_c_k3 = (kf * (kf - 1.0) * (kf - 2.0) / 6.0).ln();
        if base + ln_c_nk + ln_c_k3 + (kf - 3.0) * ln_p <= 0.0 {
            return k;
        }
    }
    n + 1
}

#[cfg(test)]
#[path = "../../../tests/unit/robust/ransac/chance.rs"]
mod tests;
