//! The sampling and scoring machinery of [`super::Ransac`]: minimal samples, MSAC scores
//! (with the SPRT early exit), and the EOPnP fits on the inliers.

use nalgebra::{Matrix3, Point2, Point3, Vector3};
use rand_core::RngCore;
use rand_pcg::Pcg64;

use super::{MIN_FIT_POINTS, SAMPLE_ATTEMPTS, SPRT_A};
use crate::pipeline::PixelInputs;
use crate::{PnpError, Solution, Solver};

/// A hypothesis with its MSAC cost.
#[derive(Clone, Copy, Debug)]
pub(super) struct Scored {
    pub(super) r: Matrix3<f64>,
    pub(super) t: Vector3<f64>,
    pub(super) cost: f64,
    pub(super) inliers: usize,
}

/// The data of one problem: squared pixel error of a pose at each point.
pub(super) struct ScoringSet<'a> {
    pub(super) world: &'a [Point3<f64>],
    pub(super) image: &'a [Point2<f64>],
    pub(super) weights: Vec<f64>,
    pub(super) fx2: f64,
    pub(super) fy2: f64,
    pub(super) rows: (f64, f64),
    /// `refine_pixels`' observations of every point (pixel input, or a robust loss), gathered with
    /// the inliers of each fit.
    pub(super) pixel: Option<PixelInputs<'a>>,
}

impl ScoringSet<'_> {
    #[inline]
    pub(super) fn sq_err(&self, r: &Matrix3<f64>, t: &Vector3<f64>, i: usize) -> f64 {
        let p = r * self.world[i].coords + t;
        if !(p.z > 0.0) {
            return f64::INFINITY;
        }
        let iz = 1.0 / p.z;
        let dx = p.x * iz - self.image[i].x;
        let dy = p.y * iz - self.image[i].y;
        self.weights[i] * (self.fx2 * dx * dx + self.fy2 * dy * dy)
    }

    /// MSAC cost and inlier count, or `None` once the cost exceeds `bound`.
    pub(super) fn score(
        &self,
        r: &Matrix3<f64>,
        t: &Vector3<f64>,
        th2: f64,
        bound: f64,
    ) -> Option<Scored> {
        let (cost, inliers) = msac(
            (0..self.world.len()).map(|i| self.sq_err(r, t, i)),
            th2,
            bound,
        )?;
        Some(Scored {
            r: *r,
            t: *t,
            cost,
            inliers,
        })
    }

    /// As [`ScoringSet::score`] for a P3P hypothesis, with Wald's sequential probability ratio test
    /// (Chum and Matas 2008) on the points in the random order `order`: the hypothesis is
    /// rejected as soon as the likelihood ratio of "bad model" over "good model" exceeds
    /// [`SPRT_A`], `eps` the inlier ratio of a good model, `delta` the probability that a bad
    /// model is consistent with a point. Returns the score or `(consistent, scored)` counts
    /// of a rejected hypothesis.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn score_sprt(
        &self,
        r: &Matrix3<f64>,
        t: &Vector3<f64>,
        th2: f64,
        bound: f64,
        order: &[usize],
        eps: f64,
        delta: f64,
    ) -> Result<Scored, (usize, usize)> {
        let test = eps > 2.0 * delta && eps < 1.0;
        let (ln_good, ln_bad) = if test {
            ((delta / eps).ln(), ((1.0 - delta) / (1.0 - eps)).ln())
        } else {
            (0.0, 0.0)
        };
        let ln_a = SPRT_A.ln();
        let mut lambda = 0.0;
        let mut cost = 0.0;
        let mut inliers = 0;
        for (k, &i) in order.iter().enumerate() {
            let e = self.sq_err(r, t, i);
            if e < th2 {
                cost += e;
                inliers += 1;
                lambda += ln_good;
            } else {
                cost += th2;
                lambda += ln_bad;
            }
            if cost > bound || lambda > ln_a {
                return Err((inliers, k + 1));
            }
        }
        Ok(Scored {
            r: *r,
            t: *t,
            cost,
            inliers,
        })
    }

    /// EOPnP on the points with squared error below `th2` under `(r, t)`; writes the mask.
    pub(super) fn fit(
        &self,
        solver: &Solver,
        r: &Matrix3<f64>,
        t: &Vector3<f64>,
        th2: f64,
        mask: &mut [bool],
        buf: &mut FitBuffers,
    ) -> Option<Solution> {
        self.fit_result(solver, r, t, th2, mask, buf)?.ok()
    }

    /// [`ScoringSet::fit`] with the solve's error: `None` for too few inliers.
    pub(super) fn fit_result(
        &self,
        solver: &Solver,
        r: &Matrix3<f64>,
        t: &Vector3<f64>,
        th2: f64,
        mask: &mut [bool],
        buf: &mut FitBuffers,
    ) -> Option<Result<Solution, PnpError>> {
        buf.clear();
        for (i, m) in mask.iter_mut().enumerate() {
            *m = self.sq_err(r, t, i) < th2;
            if *m {
                buf.world.push(self.world[i]);
                buf.image.push(self.image[i]);
                buf.weights.push(self.weights[i]);
                if let Some(px) = &self.pixel {
                    buf.pixels.push(px.pixels[i]);
                    buf.user_weights.push(px.weights.map_or(1.0, |w| w[i]));
                }
            }
        }
        // At least MIN_FIT_POINTS inliers, or every point of a smaller problem (EOPnP needs 4;
        // a clean N = 4 or 5 problem is then fitted on all of its points).
        if buf.world.len() < MIN_FIT_POINTS.min(self.world.len()) {
            return None;
        }
        let px = self.pixel.map(|px| PixelInputs {
            pixels: &buf.pixels,
            weights: px.weights.map(|_| &buf.user_weights[..]),
            ..px
        });
        Some(solver.solve_with_row_weights(
            &buf.world,
            &buf.image,
            Some(&buf.weights),
            self.rows,
            px.as_ref(),
            None,
        ))
    }
}

/// Reused gather buffers of the EOPnP fits.
#[derive(Default)]
pub(super) struct FitBuffers {
    pub(super) world: Vec<Point3<f64>>,
    pub(super) image: Vec<Point2<f64>>,
    pub(super) weights: Vec<f64>,
    pub(super) pixels: Vec<Point2<f64>>,
    pub(super) user_weights: Vec<f64>,
}

impl FitBuffers {
    pub(super) fn clear(&mut self) {
        self.world.clear();
        self.image.clear();
        self.weights.clear();
        self.pixels.clear();
        self.user_weights.clear();
    }
}

/// Uniform index in `0..n` (Lemire's multiply-shift; the bias, below `n / 2^64`, is
/// irrelevant here and the mapping is the same on every platform).
#[inline]
pub(crate) fn index(rng: &mut Pcg64, n: usize) -> usize {
    ((u128::from(rng.next_u64()) * n as u128) >> 64) as usize
}

/// The MSAC cost `sum min(e2, th2)` of the squared errors `errors` and the number below `th2`,
/// or `None` as soon as the cost exceeds `bound` (the hypothesis cannot beat the best one).
pub(super) fn msac(
    errors: impl Iterator<Item = f64>,
    th2: f64,
    bound: f64,
) -> Option<(f64, usize)> {
    let (mut cost, mut inliers) = (0.0, 0);
    for e2 in errors {
        if e2 < th2 {
            cost += e2;
            inliers += 1;
        } else {
            cost += th2;
        }
        if cost > bound {
            return None;
        }
    }
    Some((cost, inliers))
}

/// Two distinct indices in `0..n`, or `None` (n < 2, or the bounded attempts ran out).
pub(super) fn sample2(rng: &mut Pcg64, n: usize) -> Option<[usize; 2]> {
    if n < 2 {
        return None;
    }
    let a = index(rng, n);
    let mut b = index(rng, n);
    for _ in 0..SAMPLE_ATTEMPTS {
        if b != a {
            break;
        }
        b = index(rng, n);
    }
    (a != b).then_some([a, b])
}

/// Three distinct indices in `0..n`, or `None` (n < 3, or the bounded attempts ran out).
pub(super) fn sample3(rng: &mut Pcg64, n: usize) -> Option<[usize; 3]> {
    if n < 3 {
        return None;
    }
    let a = index(rng, n);
    let mut b = index(rng, n);
    let mut c = index(rng, n);
    for _ in 0..SAMPLE_ATTEMPTS {
        if b != a {
            break;
        }
        b = index(rng, n);
    }
    for _ in 0..SAMPLE_ATTEMPTS {
        if c != a && c != b {
            break;
        }
        c = index(rng, n);
    }
    (a != b && a != c && b != c).then_some([a, b, c])
}
