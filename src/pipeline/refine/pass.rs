//! The O(N) pass of `refine` and `refine_pixels`, vectorised across points: cost, gradient and
//! (optionally) `J^T W J` at one pose, with the depth-sign test against a reference pose.
//!
//! Per point the residual enters through a [`Metric`]: at the normalised projection `(u, v)` of the
//! point it gives the point's cost, a symmetric 2 x 2 matrix `C` and a vector `e~` such that, to
//! first order in a change `d` of `(u, v)`, the cost changes by `-2 e~ . d + d^T C d`. `refine`'s
//! metric is `C = w diag(wx, wy)`, `e~ = C (m - (u, v))`; `refine_pixels`' is `C = w rho' J^T J`,
//! `e~ = w rho' J^T (pixel - K(u, v))`, `J` the camera's Jacobian. The normal equations follow from
//! `C` and `e~` alone (see [`lane`]).

use nalgebra::{Matrix3, Point2, Point3, Vector3};

use super::{Composed, Hessian, Normal};
use core::ops::ControlFlow;

use crate::numeric::lanes::{blocks, dispatched, lane_sum, Block, LANES};

/// Number of sums of one pass: `E` (1), `H_rr` (6, upper triangle, row-major), `H_rt = sum K`
/// (9, row-major, the third column negated), `H_tt` (`kx`, `ky`, `fx`, `fy`, `n22`: 5),
/// `sum [q]x b` (3), `sum b` (3, the third entry negated), and `kxy` (1, the off-diagonal of
/// `H_tt`; 0 for a diagonal metric). The two negations are undone in [`LaneSums::normal`]
/// (exactly: negation does not round).
const NSUMS: usize = 28;

/// What a residual contributes at the normalised projection of a point ([`Metric::at`]).
#[derive(Clone, Copy)]
pub(in crate::pipeline) struct LaneMetric {
    /// The point's cost (weight and loss applied).
    pub cost: f64,
    /// `C = [[c00, c01], [c01, c11]]`.
    pub c00: f64,
    pub c01: f64,
    pub c11: f64,
    /// `e~`.
    pub ex: f64,
    pub ey: f64,
}

/// How the residual of a point is measured (module documentation).
pub(in crate::pipeline) trait Metric {
    /// `c01` is always 0 (the cross terms are compiled out).
    const DIAGONAL: bool;
    /// The metric of a point with observation `m` and weight `w` (in the weight unit) at the
    /// normalised projection `(u, v)`.
    fn at(&self, m: [f64; 2], w: f64, u: f64, v: f64) -> LaneMetric;
}

/// `refine`'s metric: row weights `(wx, wy)` on the normalised residual.
pub(in crate::pipeline) struct RowWeights {
    pub wx: f64,
    pub wy: f64,
}

impl Metric for RowWeights {
    const DIAGONAL: bool = true;

    #[inline(always)]
    fn at(&self, m: [f64; 2], w: f64, u: f64, v: f64) -> LaneMetric {
        let (ex, ey) = (m[0] - u, m[1] - v);
        let sx = w * self.wx;
        let sy = w * self.wy;
        LaneMetric {
            cost: sx * ex * ex + sy * ey * ey,
            c00: sx,
            c01: 0.0,
            c11: sy,
            ex: sx * ex,
            ey: sy * ey,
        }
    }
}

/// What one pass needs of the problem and the poses, as plain scalars.
pub(in crate::pipeline) struct PassInputs {
    /// `A` of the pose, row-major.
    a: [[f64; 3]; 3],
    t: [f64; 3],
    /// Centroid `c` of the working frame.
    c: [f64; 3],
    /// Third row of `A` and `t_z` of the reference pose (zeros without one).
    ref_a: [f64; 3],
    ref_tz: f64,
    /// `1 / w_unit`: point weights in the weight unit.
    inv_weight: f64,
}

impl PassInputs {
    /// The pose (and reference), the working frame's centroid `c` and `1 / w_unit`.
    pub(in crate::pipeline) fn new(
        c: &Vector3<f64>,
        inv_weight: f64,
        pose: &Composed,
        reference: Option<&Composed>,
    ) -> Self {
        let row = |m: &Matrix3<f64>, j: usize| [m[(j, 0)], m[(j, 1)], m[(j, 2)]];
        let (ref_a, ref_tz) = reference.map_or(([0.0; 3], 0.0), |rf| (row(&rf.a, 2), rf.t.z));
        Self {
            a: [row(&pose.a, 0), row(&pose.a, 1), row(&pose.a, 2)],
            t: [pose.t.x, pose.t.y, pose.t.z],
            c: [c.x, c.y, c.z],
            ref_a,
            ref_tz,
            inv_weight,
        }
    }
}

/// Lane-wise partial sums of one pass: lane `l` sums the points `l, l + LANES, ...` of the
/// sequence of active points. Aligned (every field is a multiple of 32 bytes) so that SSE2
/// and AVX2 can use the sums as operands in place.
#[repr(C, align(32))]
struct LaneSums {
    /// The [`NSUMS`] sums, in the order of [`NSUMS`]'s documentation.
    s: [[f64; LANES]; NSUMS],
    min_abs_z: [f64; LANES],
    max_abs_z: [f64; LANES],
    /// Largest `|q_i|^2` of the lane (pass without reference pose only).
    max_q2: [f64; LANES],
    /// Some depth of the lane differs in sign from its depth under the reference pose.
    flipped: [u64; LANES],
    /// Points of the lane with positive depth (pass without reference pose only).
    front: [u64; LANES],
}

impl LaneSums {
    /// Adds the lanes ((0 + 1) + (2 + 3)) and assembles the normal equations (with `HESS`,
    /// `J^T W J` into `h`; without, its sums are neither added nor read). `CHECK`: the pass
    /// had a reference pose (and so no `max_abs_q`).
    // Index loops fill the blocks of H by position.
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    fn normal<const CHECK: bool, const HESS: bool>(&self, h: Option<&mut Hessian>) -> Normal {
        let s: [f64; NSUMS] = core::array::from_fn(|j| lane_sum(&self.s[j]));
        let (e, hrr, hrt, htt, gq, gb) = (
            s[0],
            &s[1..7],
            &s[7..16],
            &s[16..21],
            &s[21..24],
            &s[24..27],
        );
        if let Some(h) = h.filter(|_| HESS) {
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
            h[3][4] = s[27];
            h[3][5] = -htt[2];
            h[4][4] = htt[1];
            h[4][5] = -htt[3];
            h[5][5] = htt[4];
            for k in 0..6 {
                for l in 0..k {
                    h[k][l] = h[l][k];
                }
            }
        }
        Normal {
            g: [-gq[0], -gq[1], -gq[2], -gb[0], -gb[1], gb[2]],
            e,
            min_abs_z: self.min_abs_z.iter().fold(f64::INFINITY, |a, &z| a.min(z)),
            max_abs_z: self.max_abs_z.iter().fold(0.0f64, |a, &z| a.max(z)),
            max_abs_q: if CHECK {
                f64::NAN
            } else {
                self.max_q2.iter().fold(0.0f64, |a, &q| a.max(q)).sqrt()
            },
            in_front: if CHECK {
                None
            } else {
                Some(self.front.iter().sum::<u64>() as usize)
            },
        }
    }
}

dispatched! {
/// One pass over the points: gathers the active points into blocks (without weights, every
/// point, straight from the slices) and runs [`lane`] on each lane. `CHECK`: compare depth
/// signs with the reference pose of `k`; `None` after the first block with a flipped sign.
/// `HESS`: the sums of `J^T W J`, written into `h` (which is then `Some`).
///
/// Built for the processor ([`crate::numeric::lanes::dispatched`]).
pub(in crate::pipeline) fn pass[const CHECK: bool, const HESS: bool, M: Metric][CHECK, HESS, M](
        k: &PassInputs,
        metric: &M,
        world: &[Point3<f64>],
        image: &[Point2<f64>],
        weights: Option<&[f64]>,
        h: Option<&mut Hessian>,
    ) -> Option<Normal> = pass_body;
}

#[inline(always)]
fn pass_body<const CHECK: bool, const HESS: bool, M: Metric>(
    k: &PassInputs,
    metric: &M,
    world: &[Point3<f64>],
    image: &[Point2<f64>],
    weights: Option<&[f64]>,
    h: Option<&mut Hessian>,
) -> Option<Normal> {
    let mut acc = LaneSums {
        s: [[0.0; LANES]; NSUMS],
        min_abs_z: [f64::INFINITY; LANES],
        max_abs_z: [0.0; LANES],
        max_q2: [0.0; LANES],
        flipped: [0; LANES],
        front: [0; LANES],
    };
    let flipped = |acc: &LaneSums| CHECK && acc.flipped.iter().any(|&f| f != 0);
    let rest = blocks(
        world,
        image,
        weights,
        k.inv_weight,
        #[inline(always)]
        |full| {
            for l in 0..LANES {
                lane::<CHECK, HESS, M>(k, metric, full, l, &mut acc);
            }
            if flipped(&acc) {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        },
    );
    let ControlFlow::Continue((blk, filled)) = rest else {
        return None;
    };
    for l in 0..filled.min(LANES) {
        lane::<CHECK, HESS, M>(k, metric, &blk, l, &mut acc);
    }
    if flipped(&acc) {
        return None;
    }
    Some(acc.normal::<CHECK, HESS>(h))
}

/// Adds point `l` of `blk` to lane `l` of `acc` (see [`Problem::accumulate`]).
#[inline(always)]
fn lane<const CHECK: bool, const HESS: bool, M: Metric>(
    k: &PassInputs,
    metric: &M,
    blk: &Block,
    l: usize,
    acc: &mut LaneSums,
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
        // `select`'s depth test at this pose, `a . (X - c) + t_z > 0` (`select::in_front`: the
        // same operations in the same order, so the same count).
        acc.front[l] += u64::from(pz > 0.0);
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
    let lm = metric.at([blk.m[0][l], blk.m[1][l]], blk.w[l], pu, pv);
    // N = sum_ab C_ab a_a a_b^T with a_x = iz (1, 0, -u), a_y = iz (0, 1, -v):
    // [[kx, kxy, -fx], [kxy, ky, -fy], [-fx, -fy, n22]] with (kx, kxy, ky) = iz^2 C,
    // fx = kx u + kxy v, fy = kxy u + ky v, n22 = fx u + fy v; b = e~x a_x + e~y a_y =
    // (bx, by, -bz).
    let iz2 = iz * iz;
    let kx = lm.c00 * iz2;
    let ky = lm.c11 * iz2;
    let kxy = if M::DIAGONAL { 0.0 } else { lm.c01 * iz2 };
    let (fx, fy) = if M::DIAGONAL {
        (kx * pu, ky * pv)
    } else {
        (kx * pu + kxy * pv, kxy * pu + ky * pv)
    };
    let bx = lm.ex * iz;
    let by = lm.ey * iz;
    let s = &mut acc.s;
    s[0][l] += lm.cost;
    if HESS {
        s[16][l] += kx;
        s[17][l] += ky;
        s[18][l] += fx;
        s[19][l] += fy;
        s[20][l] += fx * pu + fy * pv;
        if !M::DIAGONAL {
            s[27][l] += kxy;
        }
    }
    s[24][l] += bx;
    s[25][l] += by;
    s[26][l] += bx * pu + by * pv;
    // With c1 = q x (1, 0, -u) and c2 = q x (0, 1, -v): [q]x N = (kx c1 + kxy c2)
    // (1, 0, -u)^T + (kxy c1 + ky c2) (0, 1, -v)^T, so H_rt row j = (k1, k2, -(k1 u + k2 v))
    // with k1 = kx c1_j + kxy c2_j, k2 = kxy c1_j + ky c2_j; H_rr = [q]x N [q]x^T has
    // entries k1_j c1_m + k2_j c2_m; [q]x b = bx c1 + by c2.
    let c1 = [-pu * qy, qz + pu * qx, -qy];
    let c2 = [-(pv * qy + qz), pv * qx, qx];
    let mut idx = 1;
    for j in 0..3 {
        if HESS {
            let (k1, k2) = if M::DIAGONAL {
                (kx * c1[j], ky * c2[j])
            } else {
                (kx * c1[j] + kxy * c2[j], kxy * c1[j] + ky * c2[j])
            };
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
