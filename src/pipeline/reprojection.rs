//! S9 of ALGORITHM.md: Levenberg-Marquardt refinement of the reprojection error.
//!
//! Minimises `E(R, t) = sum_i w_i (wx e_ix^2 + wy e_iy^2)`, `e_i = m_i - pi(R P_i + t)`,
//! `pi(x, y, z) = (x / z, y / z)`, over the working-frame pose `(R, t)` with the update
//! `R := Exp(w) R`, `t := t + tau`. Nielsen's damping rule; a step is accepted only if it lowers
//! `E` and keeps the sign of every depth, so `E` never increases and no point crosses `z = 0`
//! (a tiny final step is accepted on proof of both instead of evaluation, see below).
//! Reference: `shared/reference/reproj_refine.py`, function `refine`.
//!
//! The working-frame points `P_i = Rw (X_i - c) / d` (S1) are never materialised: every pass
//! composes the frame into the pose, `p_i = A (X_i - c) + t` with `A = R Rw / d`, and
//! `q_i = R P_i = A (X_i - c)` is the lever arm of the rotation Jacobian. Each pass is O(N)
//! and allocation-free; the 6 x 6 normal equations keep their 21 unique entries.
//!
//! `J^T W J` is reused while the pose stays close to where it was computed: a candidate pose
//! within `HESSIAN_REUSE_REL (|t| + 1)` (sum of the step norms since) is evaluated by a pass
//! that sums only the cost, the gradient and the depths (7 sums per point instead of 27), and
//! the step is solved with the earlier `J^T W J`. The gradient is always exact, so the
//! stationary point and the stopping tests are those of plain LM; only the step's matrix is
//! off, by about the relative distance moved (at most 1e-3), which changes the linear
//! convergence rate of Gauss-Newton on a non-zero residual (about sigma / f) by as much. From
//! the algebraic start usually only the first pass forms `J^T W J` (callgrind probe, general
//! scenes, sigma = 2 px: 370 later passes did in 2,000 solves at N = 10, none at N = 100 and
//! N = 1000).
//!
//! The final step is taken unverified when it is tiny and the run has converged to the point
//! where the next step would be negligible anyway: a step `delta` with
//! - `|delta| <= FINAL_STEP_REL (|t| + 1)` (`FINAL_STEP_REL = 1e-7`),
//! - `|delta|^2 / |delta_prev| <= xtol (|t| + 1)`, where `delta_prev` is the step accepted in
//!   the iteration just before (none after a rejected step or a failed factorisation): near the
//!   minimum LM converges linearly with the ratio `|delta| / |delta_prev|`, so the left side
//!   is the predicted size of the next step, the one that would end the run by the `xtol` test,
//! - `|delta| (max_i |q_i| + 1) < min_i |z_i| / 2`,
//!
//! is applied without the O(N) pass that would evaluate it, and the refinement stops
//! ([`ReprojStop::FinalStep`], converged). It saves the last of the (typically four) passes:
//! that pass would only confirm the step and compute a next step below `xtol`. Why this is safe:
//! - Depths keep their signs. With `delta = (w, tau)`, a depth moves by
//!   `|z_i' - z_i| <= |Exp(w) q_i - q_i| + |tau| <= |w| |q_i| + |tau| <= |delta| (|q_i| + 1)`,
//!   less than half the smallest `|z_i|`; the other half is the margin for rounding. `|q_i| =
//!   |X_i - c| / d` does not depend on the pose: it is measured once, in the first pass.
//! - The cost does not go up. The predicted decrease `pred = -(2 g.delta + delta.H.delta)` of
//!   the damped Gauss-Newton model is positive, and the true decrease differs from it by the
//!   residual-curvature term, a fraction of `pred` of the order of the linear convergence
//!   ratio (below 1 here: the second condition with `|delta| > xtol (|t| + 1)` gives
//!   `|delta| / |delta_prev| < 1`), plus `O(|delta|^3)`. The returned cost is the prediction,
//!   `E - pred` clamped to `[0, E]`, so the reported `e` still never exceeds `e0`.
//! - The accuracy is that of the `xtol` stop: that stop leaves the last (unapplied) step, at
//!   most `xtol (|t| + 1)`, as the distance to the minimum; this one leaves the predicted next
//!   step, bounded alike.

use nalgebra::{Matrix3, Point2, Point3, Vector3};

use crate::numeric::lanes::{lane_sum, Block, LANES};
use crate::numeric::rotation::exp_so3;

/// Options of the reprojection refinement (S9). The defaults are ALGORITHM.md's values.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct ReprojOptions {
    /// Hard cap on LM iterations (rejected steps and failed factorisations count). Default 50.
    pub max_iterations: u32,
    /// Initial damping relative to the largest diagonal entry of `J^T J`. Default `1e-6`.
    pub tau: f64,
    /// Stop when `|delta| <= xtol (|t| + 1)`. Default `1e-10`.
    pub xtol: f64,
    /// Stop when `max_k |g_k| <= gtol sqrt(trace(J^T J) E)`. Default `1e-13`.
    pub gtol: f64,
    /// Weights of the x and y residual rows, e.g. `(fx^2, fy^2)` to minimise the pixel error
    /// for anisotropic intrinsics. Default `(1, 1)`.
    pub row_weights: (f64, f64),
}

impl Default for ReprojOptions {
    fn default() -> Self {
        Self {
            max_iterations: 50,
            tau: 1e-6,
            xtol: 1e-10,
            gtol: 1e-13,
            row_weights: (1.0, 1.0),
        }
    }
}

/// Why the refinement stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum ReprojStop {
    /// The gradient test passed (converged).
    Gradient,
    /// The step became negligible (converged).
    Step,
    /// A tiny final step was applied without evaluating it (converged; see the module docs).
    FinalStep,
    /// The damping grew beyond `1e16 max_k H_kk` without an acceptable step.
    Damping,
    /// The iteration cap was reached.
    MaxIterations,
    /// Some starting depth is zero (`|z_i| <= 1e-12 max |z|`): nothing was done.
    SkippedZeroDepth,
}

/// Result of [`refine_reprojection`]: the working-frame pose and diagnostics.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ReprojOutcome {
    /// Refined working-frame rotation.
    pub r: Matrix3<f64>,
    /// Refined working-frame translation.
    pub t: Vector3<f64>,
    /// Cost `E` at the start (NaN when skipped).
    #[cfg_attr(not(test), allow(dead_code))]
    pub e0: f64,
    /// Cost `E` at the returned pose (NaN when skipped); never above `e0`. After
    /// [`ReprojStop::FinalStep`], the linear model's prediction of it.
    pub e: f64,
    /// Iterations performed (0 when skipped).
    pub iterations: u32,
    /// Stop reason.
    pub stop: ReprojStop,
}

/// Relative depth below which a starting depth counts as zero.
const ZERO_DEPTH_REL: f64 = 1e-12;
/// Give up once the damping exceeds this multiple of the largest diagonal entry of `J^T J`.
const DAMPING_LIMIT_REL: f64 = 1e16;
/// Reuse of `J^T W J` (module docs): a pass evaluates only the cost and the gradient while
/// the candidate pose is within `HESSIAN_REUSE_REL (|t| + 1)` (sum of step norms) of the pose
/// where `J^T W J` was last computed.
const HESSIAN_REUSE_REL: f64 = 1e-3;
/// Bound on a step taken without evaluating it: `|delta| <= FINAL_STEP_REL (|t| + 1)` (one of
/// the three conditions of the module docs).
const FINAL_STEP_REL: f64 = 1e-7;

/// A pose with the working frame composed in: `p_i = a (X_i - c) + t`.
#[derive(Clone, Copy)]
struct Composed {
    a: Matrix3<f64>,
    t: Vector3<f64>,
}

impl Composed {
    fn new(r: &Matrix3<f64>, rw: &Matrix3<f64>, d: f64, t: &Vector3<f64>) -> Self {
        Self {
            a: (r * rw) / d,
            t: *t,
        }
    }
}

/// Normal equations at one pose: `h = J^T W J` (upper triangle filled, then mirrored),
/// `g = J^T W e`, `e = E`, the extreme absolute depths and the largest lever arm `|q_i|`.
struct Normal {
    h: [[f64; 6]; 6],
    g: [f64; 6],
    e: f64,
    min_abs_z: f64,
    max_abs_z: f64,
    /// `max_i |q_i|` over the active points. Only the pass without reference pose computes it
    /// (NaN otherwise): `|q_i| = |X_i - c| / d` does not depend on the pose.
    max_abs_q: f64,
}

impl Normal {
    fn max_diag(&self) -> f64 {
        (0..6).fold(f64::NEG_INFINITY, |acc, k| acc.max(self.h[k][k]))
    }

    fn trace(&self) -> f64 {
        (0..6).map(|k| self.h[k][k]).sum()
    }
}

/// The inputs of one refinement, borrowed from the caller.
struct Problem<'a> {
    world: &'a [Point3<f64>],
    image: &'a [Point2<f64>],
    weights: Option<&'a [f64]>,
    c: Vector3<f64>,
    n: usize,
    row_weights: (f64, f64),
}

impl Problem<'_> {
    /// One O(N) pass at `pose`: cost, normal equations and depth range. With `reference`,
    /// returns `None` as soon as a depth differs in sign from its depth under `reference`.
    /// Points of weight 0 are skipped entirely (bit-identical to dropping them).
    ///
    /// Uses the structure of the Jacobian rows `r = [a x q; -a]` (`a` = `A_p`'s row, `q` the
    /// rotated point, see [`point_terms`]): with `N = sum_rows s a a^T` per point (5 distinct
    /// entries: `a_x = (1/z)(1, 0, -u)`, `a_y = (1/z)(0, 1, -v)`) and `K = [q]x N`,
    /// `H = sum [[K [q]x^T, K], [K^T, N]]` and, with `b = sum_rows s e a`,
    /// `g = -sum [[q]x b; b]`. `K` and `K [q]x^T` are formed from the two vectors
    /// `q x (1, 0, -u)` and `q x (0, 1, -v)` (see [`lane`]): about 60 % of the multiply-adds of
    /// the 21-entry outer products.
    ///
    /// Vectorised across points, without `unsafe` or target features: the active points
    /// (non-zero weight), in order, are gathered into blocks of [`LANES`] transposed values
    /// ([`Block`]); lane `l` of the block goes into its own partial sums ([`Partial`]), so the
    /// compiler runs the per-point code ([`lane`]) on packed registers. The lanes are added
    /// once at the end. The sequence of active points, and so the result to the bit, does not
    /// depend on the points of weight 0; the depth-sign test is the scalar one, lane by lane.
    fn accumulate(&self, pose: &Composed, reference: Option<&Composed>) -> Option<Normal> {
        let k = PassConsts::new(self, pose, reference);
        let world = &self.world[..self.n];
        let image = &self.image[..self.n];
        let weights = self.weights.map(|w| &w[..self.n]);
        if reference.is_some() {
            pass::<true, true>(&k, world, image, weights)
        } else {
            pass::<false, true>(&k, world, image, weights)
        }
    }

    /// As [`Problem::accumulate`] with a reference pose, but without `J^T W J`: cost, gradient
    /// and depth range only (7 sums per point instead of 27). The returned `h` is `h_prev`,
    /// the caller's `J^T W J` from a nearby pose (see [`HESSIAN_REUSE_REL`]).
    fn accumulate_gradient(
        &self,
        pose: &Composed,
        reference: &Composed,
        h_prev: &[[f64; 6]; 6],
    ) -> Option<Normal> {
        let k = PassConsts::new(self, pose, Some(reference));
        let world = &self.world[..self.n];
        let image = &self.image[..self.n];
        let weights = self.weights.map(|w| &w[..self.n]);
        pass::<true, false>(&k, world, image, weights).map(|mut nrm| {
            nrm.h = *h_prev;
            nrm
        })
    }
}

/// Number of sums of one pass: `E` (1), `H_rr` (6, upper triangle, row-major), `H_rt = sum K`
/// (9, row-major, the third column negated), `H_tt` (`kx`, `ky`, `fx`, `fy`, `n22`: 5),
/// `sum [q]x b` (3), `sum b` (3, the third entry negated). The two negations are undone in
/// [`Partial::normal`] (exactly: negation does not round).
const NSUMS: usize = 27;

/// What one pass needs of the problem and the poses, as plain scalars.
struct PassConsts {
    /// `A` of the pose, row-major.
    a: [[f64; 3]; 3],
    t: [f64; 3],
    /// Centroid `c` of the working frame.
    c: [f64; 3],
    /// Third row of `A` and `t_z` of the reference pose (zeros without one).
    ref_a: [f64; 3],
    ref_tz: f64,
    wx: f64,
    wy: f64,
}

impl PassConsts {
    fn new(prob: &Problem<'_>, pose: &Composed, reference: Option<&Composed>) -> Self {
        let row = |m: &Matrix3<f64>, j: usize| [m[(j, 0)], m[(j, 1)], m[(j, 2)]];
        let (ref_a, ref_tz) = reference.map_or(([0.0; 3], 0.0), |rf| (row(&rf.a, 2), rf.t.z));
        Self {
            a: [row(&pose.a, 0), row(&pose.a, 1), row(&pose.a, 2)],
            t: [pose.t.x, pose.t.y, pose.t.z],
            c: [prob.c.x, prob.c.y, prob.c.z],
            ref_a,
            ref_tz,
            wx: prob.row_weights.0,
            wy: prob.row_weights.1,
        }
    }
}

/// Lane-wise partial sums of one pass: lane `l` sums the points `l, l + LANES, ...` of the
/// sequence of active points. Aligned (every field is a multiple of 16 bytes) so that SSE2
/// can use the sums as operands in place.
#[repr(C, align(16))]
struct Partial {
    /// The [`NSUMS`] sums, in the order of [`NSUMS`]'s documentation.
    s: [[f64; LANES]; NSUMS],
    min_abs_z: [f64; LANES],
    max_abs_z: [f64; LANES],
    /// Largest `|q_i|^2` of the lane (pass without reference pose only).
    max_q2: [f64; LANES],
    /// Some depth of the lane differs in sign from its depth under the reference pose.
    flipped: [u64; LANES],
}

impl Partial {
    /// Adds the lanes ((0 + 1) + (2 + 3)) and assembles the normal equations. `CHECK`: the
    /// pass had a reference pose (and so no `max_abs_q`).
    // Index loops fill the blocks of H by position.
    #[allow(clippy::needless_range_loop)]
    fn normal<const CHECK: bool>(&self) -> Normal {
        let s: [f64; NSUMS] = core::array::from_fn(|j| lane_sum(&self.s[j]));
        let (e, hrr, hrt, htt, gq, gb) = (
            s[0],
            &s[1..7],
            &s[7..16],
            &s[16..21],
            &s[21..24],
            &s[24..27],
        );
        let mut h = [[0.0f64; 6]; 6];
        let mut idx = 0;
        for j in 0..3 {
            for l in j..3 {
                h[j][l] = hrr[idx];
                idx += 1;
            }
            h[j][3] = hrt[3 * j];
            h[j][4] = hrt[3 * j + 1];
            h[j][5] = -hrt[3 * j + 2];
        }
        h[3][3] = htt[0];
        h[3][4] = 0.0;
        h[3][5] = -htt[2];
        h[4][4] = htt[1];
        h[4][5] = -htt[3];
        h[5][5] = htt[4];
        for k in 0..6 {
            for l in 0..k {
                h[k][l] = h[l][k];
            }
        }
        Normal {
            h,
            g: [-gq[0], -gq[1], -gq[2], -gb[0], -gb[1], gb[2]],
            e,
            min_abs_z: self.min_abs_z.iter().fold(f64::INFINITY, |a, &z| a.min(z)),
            max_abs_z: self.max_abs_z.iter().fold(0.0f64, |a, &z| a.max(z)),
            max_abs_q: if CHECK {
                f64::NAN
            } else {
                self.max_q2.iter().fold(0.0f64, |a, &q| a.max(q)).sqrt()
            },
        }
    }
}

/// One pass over the points: gathers the active points into blocks (without weights, every
/// point, straight from the slices) and runs [`lane`] on each lane. `CHECK`: compare depth
/// signs with the reference pose of `k`; `None` after the first block with a flipped sign.
#[inline(always)]
fn pass<const CHECK: bool, const HESS: bool>(
    k: &PassConsts,
    world: &[Point3<f64>],
    image: &[Point2<f64>],
    weights: Option<&[f64]>,
) -> Option<Normal> {
    let mut acc = Partial {
        s: [[0.0; LANES]; NSUMS],
        min_abs_z: [f64::INFINITY; LANES],
        max_abs_z: [0.0; LANES],
        max_q2: [0.0; LANES],
        flipped: [0; LANES],
    };
    let flipped = |acc: &Partial| CHECK && acc.flipped.iter().any(|&f| f != 0);
    let mut blk = Block::new();
    let mut filled = 0;
    match weights {
        None => {
            let mut cw = world.chunks_exact(LANES);
            let mut cm = image.chunks_exact(LANES);
            for (xs, ms) in (&mut cw).zip(&mut cm) {
                blk.x = [
                    core::array::from_fn(|l| xs[l].x),
                    core::array::from_fn(|l| xs[l].y),
                    core::array::from_fn(|l| xs[l].z),
                ];
                blk.m = [
                    core::array::from_fn(|l| ms[l].x),
                    core::array::from_fn(|l| ms[l].y),
                ];
                for l in 0..LANES {
                    lane::<CHECK, HESS>(k, &blk, l, &mut acc);
                }
                if flipped(&acc) {
                    return None;
                }
            }
            for (l, (x, m)) in cw.remainder().iter().zip(cm.remainder()).enumerate() {
                blk.set(l, x, m);
                filled = l + 1;
            }
        }
        Some(weights) => {
            for ((x, m), &w) in world.iter().zip(image).zip(weights) {
                if w == 0.0 {
                    continue;
                }
                let l = filled % LANES;
                blk.set(l, x, m);
                blk.w[l] = w;
                filled = l + 1;
                if filled == LANES {
                    for l in 0..LANES {
                        lane::<CHECK, HESS>(k, &blk, l, &mut acc);
                    }
                    if flipped(&acc) {
                        return None;
                    }
                    filled = 0;
                }
            }
        }
    }
    for l in 0..filled.min(LANES) {
        lane::<CHECK, HESS>(k, &blk, l, &mut acc);
    }
    if flipped(&acc) {
        return None;
    }
    Some(acc.normal::<CHECK>())
}

/// Adds point `l` of `blk` to lane `l` of `acc` (see [`Problem::accumulate`]).
#[inline(always)]
fn lane<const CHECK: bool, const HESS: bool>(
    k: &PassConsts,
    blk: &Block,
    l: usize,
    acc: &mut Partial,
) {
    let xc = [
        blk.x[0][l] - k.c[0],
        blk.x[1][l] - k.c[1],
        blk.x[2][l] - k.c[2],
    ];
    let dot = |r: &[f64; 3]| r[0] * xc[0] + r[1] * xc[1] + r[2] * xc[2];
    let (qx, qy, qz) = (dot(&k.a[0]), dot(&k.a[1]), dot(&k.a[2]));
    let (px, py, pz) = (qx + k.t[0], qy + k.t[1], qz + k.t[2]);
    if CHECK {
        let z_ref = dot(&k.ref_a) + k.ref_tz;
        let same_side = if z_ref > 0.0 { pz > 0.0 } else { pz < 0.0 };
        acc.flipped[l] |= u64::from(!same_side);
    } else {
        let q2 = qx * qx + qy * qy + qz * qz;
        let mq = acc.max_q2[l];
        acc.max_q2[l] = if q2 > mq { q2 } else { mq };
    }
    // `if a < b { a } else { b }` (not f64::min): one packed instruction; a NaN depth is
    // ignored as by f64::min, the partial extremes never being NaN.
    let az = pz.abs();
    let mn = acc.min_abs_z[l];
    acc.min_abs_z[l] = if az < mn { az } else { mn };
    let mx = acc.max_abs_z[l];
    acc.max_abs_z[l] = if az > mx { az } else { mx };
    let iz = 1.0 / pz;
    let pu = px * iz;
    let pv = py * iz;
    let (ex, ey) = (blk.m[0][l] - pu, blk.m[1][l] - pv);
    let wi = blk.w[l];
    let sx = wi * k.wx;
    let sy = wi * k.wy;
    // N = sx a_x a_x^T + sy a_y a_y^T = [[kx, 0, -fx], [0, ky, -fy], [-fx, -fy, n22]] with
    // a_x = iz (1, 0, -u), a_y = iz (0, 1, -v); b = sx ex a_x + sy ey a_y = (bx, by, -bz).
    let iz2 = iz * iz;
    let kx = sx * iz2;
    let ky = sy * iz2;
    let fx = kx * pu;
    let fy = ky * pv;
    let bx = sx * ex * iz;
    let by = sy * ey * iz;
    let s = &mut acc.s;
    s[0][l] += sx * ex * ex + sy * ey * ey;
    if HESS {
        s[16][l] += kx;
        s[17][l] += ky;
        s[18][l] += fx;
        s[19][l] += fy;
        s[20][l] += fx * pu + fy * pv;
    }
    s[24][l] += bx;
    s[25][l] += by;
    s[26][l] += bx * pu + by * pv;
    // With c1 = q x (1, 0, -u) and c2 = q x (0, 1, -v): [q]x N = kx c1 (1, 0, -u)^T +
    // ky c2 (0, 1, -v)^T, so H_rt row j = (k1, k2, -(k1 u + k2 v)) with k1 = kx c1_j,
    // k2 = ky c2_j; H_rr = [q]x N [q]x^T = kx c1 c1^T + ky c2 c2^T; [q]x b = bx c1 + by c2.
    let c1 = [-pu * qy, qz + pu * qx, -qy];
    let c2 = [-(pv * qy + qz), pv * qx, qx];
    let mut idx = 1;
    for j in 0..3 {
        if HESS {
            let k1 = kx * c1[j];
            let k2 = ky * c2[j];
            s[7 + 3 * j][l] += k1;
            s[8 + 3 * j][l] += k2;
            s[9 + 3 * j][l] += k1 * pu + k2 * pv;
            for m in j..3 {
                s[idx][l] += k1 * c1[m] + k2 * c2[m];
                idx += 1;
            }
        }
        s[21 + j][l] += bx * c1[j] + by * c2[j];
    }
}

/// Solves `(H + lam I) delta = -g` by a 6 x 6 Cholesky factorisation; `None` if `H + lam I`
/// is not (numerically) positive definite, including NaN entries.
// Index loops mirror the textbook factorisation; `!(s > 0.0)` deliberately rejects NaN.
#[allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]
fn solve_damped(h: &[[f64; 6]; 6], lam: f64, g: &[f64; 6]) -> Option<[f64; 6]> {
    let mut l = [[0.0; 6]; 6];
    for j in 0..6 {
        let mut s = h[j][j] + lam;
        for k in 0..j {
            s -= l[j][k] * l[j][k];
        }
        if !(s > 0.0) {
            return None;
        }
        let ljj = s.sqrt();
        l[j][j] = ljj;
        for i in (j + 1)..6 {
            let mut s = h[i][j];
            for k in 0..j {
                s -= l[i][k] * l[j][k];
            }
            l[i][j] = s / ljj;
        }
    }
    // L y = -g, then L^T delta = y.
    let mut y = [0.0; 6];
    for i in 0..6 {
        let mut s = -g[i];
        for k in 0..i {
            s -= l[i][k] * y[k];
        }
        y[i] = s / l[i][i];
    }
    let mut delta = [0.0; 6];
    for i in (0..6).rev() {
        let mut s = y[i];
        for k in (i + 1)..6 {
            s -= l[k][i] * delta[k];
        }
        delta[i] = s / l[i][i];
    }
    Some(delta)
}

/// S9: refines the working-frame pose `(r_work, t_work)` by Levenberg-Marquardt on the
/// (weighted) reprojection error of the caller's world points.
///
/// `world`, `image` (normalised coordinates) and `weights` (optional, one per point, >= 0) are
/// the caller's inputs as validated by S1; `c`, `d`, `rw` are S1's working frame
/// (`P_i = rw (X_i - c) / d`). The pose is the working-frame pose in and out (S8 maps it to the
/// world frame). A point of weight 0 contributes nothing and gives bit-identical results to
/// dropping it. If some starting depth is (relatively) zero the pose is returned unchanged with
/// [`ReprojStop::SkippedZeroDepth`]. At most `opts.max_iterations` iterations; no allocation.
#[allow(clippy::too_many_arguments)]
pub(crate) fn refine_reprojection(
    world: &[Point3<f64>],
    image: &[Point2<f64>],
    weights: Option<&[f64]>,
    c: &Vector3<f64>,
    d: f64,
    rw: &Matrix3<f64>,
    r_work: &Matrix3<f64>,
    t_work: &Vector3<f64>,
    opts: &ReprojOptions,
) -> ReprojOutcome {
    debug_assert_eq!(world.len(), image.len());
    debug_assert!(weights.is_none_or(|w| w.len() == world.len()));
    let n = world
        .len()
        .min(image.len())
        .min(weights.map_or(usize::MAX, <[f64]>::len));
    let prob = Problem {
        world,
        image,
        weights,
        c: *c,
        n,
        row_weights: opts.row_weights,
    };

    let mut r = *r_work;
    let mut t = *t_work;
    let mut cur = Composed::new(&r, rw, d, &t);
    let skipped = ReprojOutcome {
        r,
        t,
        e0: f64::NAN,
        e: f64::NAN,
        iterations: 0,
        stop: ReprojStop::SkippedZeroDepth,
    };
    let Some(mut nrm) = prob.accumulate(&cur, None) else {
        return skipped; // unreachable: no reference pose
    };
    if nrm.min_abs_z <= ZERO_DEPTH_REL * nrm.max_abs_z {
        return skipped;
    }

    let e0 = nrm.e;
    // Pose-independent (see Normal::max_abs_q): measured by this first pass only.
    let max_abs_q = nrm.max_abs_q;
    let mut e_final = None;
    // Norm of the step accepted in the previous iteration (None after anything else).
    let mut prev_step: Option<f64> = None;
    // Distance (sum of accepted step norms) from the pose where `nrm.h` was computed.
    let mut h_dist = 0.0;
    let mut lam = opts.tau * nrm.max_diag();
    let mut nu = 2.0;
    let mut stop = ReprojStop::MaxIterations;
    let mut iterations = 0;
    for it in 1..=opts.max_iterations {
        iterations = it;
        let gmax = nrm.g.iter().fold(0.0_f64, |acc, gk| acc.max(gk.abs()));
        if gmax <= opts.gtol * (nrm.trace() * nrm.e).sqrt() {
            stop = ReprojStop::Gradient;
            break;
        }
        let Some(delta) = solve_damped(&nrm.h, lam, &nrm.g) else {
            lam *= nu;
            nu *= 2.0;
            prev_step = None;
            continue;
        };
        let step_norm = delta.iter().map(|x| x * x).sum::<f64>().sqrt();
        let scale = t.norm() + 1.0;
        if step_norm <= opts.xtol * scale {
            stop = ReprojStop::Step;
            break;
        }
        let w = Vector3::new(delta[0], delta[1], delta[2]);
        let r_new = exp_so3(&w) * r;
        let t_new = t + Vector3::new(delta[3], delta[4], delta[5]);
        let cand = Composed::new(&r_new, rw, d, &t_new);

        // Predicted decrease of the linear model: -(2 g.delta + delta.H.delta).
        let mut g_d = 0.0;
        let mut d_h_d = 0.0;
        for k in 0..6 {
            g_d += nrm.g[k] * delta[k];
            for l in 0..6 {
                d_h_d += delta[k] * nrm.h[k][l] * delta[l];
            }
        }
        let pred = -(2.0 * g_d + d_h_d);

        // A tiny step after which the next one would be below xtol, and that cannot flip a
        // depth sign, ends the run unverified (module docs).
        if step_norm <= FINAL_STEP_REL * scale
            && prev_step.is_some_and(|sp| step_norm * step_norm <= opts.xtol * scale * sp)
            && step_norm * (max_abs_q + 1.0) < 0.5 * nrm.min_abs_z
        {
            r = r_new;
            t = t_new;
            // E - pred clamped to [0, E]; E itself if the prediction is not a decrease (or NaN).
            e_final = Some(if pred > 0.0 {
                (nrm.e - pred).max(0.0)
            } else {
                nrm.e
            });
            stop = ReprojStop::FinalStep;
            break;
        }

        // J^T W J changes by O(distance) relative: within HESSIAN_REUSE_REL (|t| + 1) of the
        // pose where it was computed, the pass only evaluates cost and gradient and keeps it.
        let reuse = h_dist + step_norm <= HESSIAN_REUSE_REL * scale;
        let next = if reuse {
            prob.accumulate_gradient(&cand, &cur, &nrm.h)
        } else {
            prob.accumulate(&cand, Some(&cur))
        };
        match next {
            Some(next) if next.e < nrm.e => {
                h_dist = if reuse { h_dist + step_norm } else { 0.0 };
                let rho = if pred > 0.0 {
                    (nrm.e - next.e) / pred
                } else {
                    0.0
                };
                r = r_new;
                t = t_new;
                cur = cand;
                nrm = next;
                lam *= (1.0_f64 / 3.0).max(1.0 - (2.0 * rho - 1.0).powi(3));
                nu = 2.0;
                prev_step = Some(step_norm);
            }
            _ => {
                lam *= nu;
                nu *= 2.0;
                prev_step = None;
                if lam > DAMPING_LIMIT_REL * nrm.max_diag() {
                    stop = ReprojStop::Damping;
                    break;
                }
            }
        }
    }
    ReprojOutcome {
        r,
        t,
        e0,
        e: e_final.unwrap_or(nrm.e),
        iterations,
        stop,
    }
}

#[cfg(test)]
mod tests;
