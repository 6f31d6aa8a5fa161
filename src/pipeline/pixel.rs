//! S10: Levenberg-Marquardt on the pixel residuals through the camera model.
//!
//! With a camera (pixel input), S1-S9 solve on undistorted points: S9 minimises the normalised
//! residuals weighted by the lens distortion's local scale, a first-order stand-in for the
//! pixel error. S10 then minimises the pixel error itself,
//! `E(R, t) = sum_i w_i rho(|u_i - K(pi(R P_i + t))|^2)`, with `u_i` the observed pixel, `K`
//! the camera's projection (distortion included, [`Projector`]), `pi(x, y, z) = (x/z, y/z)`,
//! `w_i` the caller's weight and `rho` the [`Loss`]: for the squared loss the
//! maximum-likelihood pose under isotropic Gaussian pixel noise, for any camera model. With a
//! robust loss the weights are iteratively reweighted (`rho'(r2)` per point), and the step is
//! accepted only if `E` itself decreases.
//!
//! It runs the same Levenberg-Marquardt iteration as S9
//! ([`super::reprojection::levenberg_marquardt`]: damping, depth-sign guard, reuse of
//! `J^T W J`, final step), in S1's working frame, from S7's minimum, in place of S9 (which
//! runs only if S10 cannot: a point at depth 0, a non-finite result). Starting S10 from S9's
//! first-order minimum instead saves about one S10 pass but costs S9's two or three passes
//! (on the bundled COLMAP model: 17 % more instructions per image, callgrind). Per point, the Jacobian row of residual `k` is
//! `[g_k x q, -g_k]` with `g_k = d K_k / d p = (J_k / z) [[1, 0, -x], [0, 1, -y]]`, `J` the
//! camera's 2 x 2 Jacobian at the normalised point `(x, y)` and `q` the rotated point.
//!
//! S10 does not run for a pinhole camera with the squared loss: S9 with the row weights
//! `(fx^2, fy^2)` already minimises exactly that cost. With normalised input and a robust loss,
//! S10 runs with the identity camera (residuals in normalised units).

use nalgebra::{Matrix3, Point2, Point3, Vector3};

use super::frame::{WorkingFrame, MIN_UNIT};
use super::options::Loss;
use super::reprojection::{
    levenberg_marquardt, Composed, Normal, ReprojOptions, ReprojOutcome, Residuals,
};
use crate::camera::{Project, ProjectionJob, Projector};
use crate::numeric::lanes::{lane_sum, Block, LANES};
use crate::numeric::mat3::pow2_scale;

/// What S10 needs beyond the solve's inputs: the observations in the camera's units.
#[derive(Clone, Copy)]
pub(crate) struct PixelInputs<'a> {
    /// The observed pixels, parallel to the solve's world points.
    pub pixels: &'a [Point2<f64>],
    /// The caller's weights, parallel (`None`: all 1).
    pub weights: Option<&'a [f64]>,
    /// The camera's projection.
    pub projector: Projector,
    /// The loss of the refinement.
    pub loss: Loss,
    /// Whether S10 runs; `false` when S9 already minimises this cost (a pinhole camera, the
    /// squared loss): the reported cost is then S9's, converted to pixels.
    pub refine: bool,
    /// Pixels per normalised unit of S9's residuals (`max(fx, fy)`; 1 for normalised input).
    pub scale: f64,
}

/// S10's result: the refinement and the sums the solution reports.
pub(crate) struct PixelOutcome {
    pub out: ReprojOutcome,
    /// The weight unit: `out.e * unit` is the caller's cost.
    pub unit: f64,
    /// `sum_i w_i |e_i|^2 / unit` at the returned pose (the plain squared error, also for a
    /// robust loss).
    pub squared: f64,
    /// `sum_i w_i / unit` over the points of non-zero weight.
    pub weight_sum: f64,
}

/// The residuals of S10 ([`Residuals`]) through the projection `P`.
struct PixelProblem<'a, P> {
    world: &'a [Point3<f64>],
    pixels: &'a [Point2<f64>],
    weights: Option<&'a [f64]>,
    /// `1 / unit`: the weights in a power-of-two unit (largest in `[1, 2)`).
    inv_weight: f64,
    c: Vector3<f64>,
    projection: P,
    loss: Loss,
}

/// Number of sums: `E` (1), `J^T W J` (21, upper triangle row-major), `g` (6).
const NSUMS: usize = 28;

/// Lane-wise partial sums of one pass (lane `l` sums the points `l, l + LANES, ...` of the
/// sequence of active points), as in S9's pass.
#[repr(C, align(16))]
struct LaneSums {
    s: [[f64; LANES]; NSUMS],
    min_abs_z: [f64; LANES],
    max_abs_z: [f64; LANES],
    max_q2: [f64; LANES],
    flipped: [u64; LANES],
}

/// A pose and a reference pose as plain scalars.
struct PassPose {
    a: [[f64; 3]; 3],
    t: [f64; 3],
    c: [f64; 3],
    /// Third row of the reference `A` and its `t_z` (zeros without a reference).
    ref_a: [f64; 3],
    ref_tz: f64,
}

impl<P: Project> PixelProblem<'_, P> {
    // Index loops fill the blocks and the triangle of J^T W J by position.
    #[allow(clippy::needless_range_loop)]
    /// One pass at `pose` with `loss` (see [`Residuals::accumulate`]). `HESS`: form
    /// `J^T W J` (otherwise `h` is zero). The active points (weight > 0), in order, are
    /// gathered into blocks of [`LANES`]; per block the geometry and the camera run lane by
    /// lane, then the loss, then the sums, so that the compiler can use packed operations.
    fn pass<const HESS: bool>(
        &self,
        pose: &Composed,
        reference: Option<&Composed>,
        loss: Loss,
    ) -> Option<Normal> {
        let row = |m: &Matrix3<f64>, j: usize| [m[(j, 0)], m[(j, 1)], m[(j, 2)]];
        let (ref_a, ref_tz) = reference.map_or(([0.0; 3], 0.0), |rf| (row(&rf.a, 2), rf.t.z));
        let k = PassPose {
            a: [row(&pose.a, 0), row(&pose.a, 1), row(&pose.a, 2)],
            t: [pose.t.x, pose.t.y, pose.t.z],
            c: [self.c.x, self.c.y, self.c.z],
            ref_a,
            ref_tz,
        };
        let mut acc = LaneSums {
            s: [[0.0; LANES]; NSUMS],
            min_abs_z: [f64::INFINITY; LANES],
            max_abs_z: [0.0; LANES],
            max_q2: [0.0; LANES],
            flipped: [0; LANES],
        };
        let check = reference.is_some();
        let mut blk = Block::new();
        let mut filled = 0;
        for (i, (x, u)) in self.world.iter().zip(self.pixels).enumerate() {
            let w = match self.weights {
                Some(w) => w[i] * self.inv_weight,
                None => 1.0,
            };
            if w == 0.0 {
                continue;
            }
            blk.set(filled, x, u);
            blk.w[filled] = w;
            filled += 1;
            if filled == LANES {
                self.block::<HESS>(&k, &blk, LANES, loss, &mut acc);
                if check && acc.flipped.iter().any(|&f| f != 0) {
                    return None;
                }
                filled = 0;
            }
        }
        if filled > 0 {
            // The unused lanes repeat lane 0 (finite where it is), with no weight.
            for l in filled..LANES {
                let (x, m, _) = blk.point(0);
                for d in 0..3 {
                    blk.x[d][l] = x[d];
                }
                blk.m[0][l] = m[0];
                blk.m[1][l] = m[1];
            }
            self.block::<HESS>(&k, &blk, filled, loss, &mut acc);
            if check && acc.flipped.iter().any(|&f| f != 0) {
                return None;
            }
        }
        let s: [f64; NSUMS] = core::array::from_fn(|j| lane_sum(&acc.s[j]));
        let mut h = [[0.0f64; 6]; 6];
        if HESS {
            let mut idx = 1;
            for kk in 0..6 {
                for l in kk..6 {
                    h[kk][l] = s[idx];
                    h[l][kk] = s[idx];
                    idx += 1;
                }
            }
        }
        Some(Normal {
            h,
            g: core::array::from_fn(|j| s[22 + j]),
            e: s[0],
            min_abs_z: acc.min_abs_z.iter().fold(f64::INFINITY, |a, &z| a.min(z)),
            max_abs_z: acc.max_abs_z.iter().fold(0.0f64, |a, &z| a.max(z)),
            max_abs_q: if check {
                f64::NAN
            } else {
                acc.max_q2.iter().fold(0.0f64, |a, &q| a.max(q)).sqrt()
            },
        })
    }

    /// The first `n` lanes of `blk` into `acc` (the other lanes are left out).
    // Index loops fill the sums by position.
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    fn block<const HESS: bool>(
        &self,
        k: &PassPose,
        blk: &Block,
        n: usize,
        loss: Loss,
        acc: &mut LaneSums,
    ) {
        // Geometry and camera, lane by lane.
        let mut q = [[0.0f64; LANES]; 3];
        let mut g0 = [[0.0f64; LANES]; 3];
        let mut g1 = [[0.0f64; LANES]; 3];
        let mut e = [[0.0f64; LANES]; 2];
        let mut r2 = [0.0f64; LANES];
        let mut live = [0.0f64; LANES];
        for l in 0..LANES {
            let xc = [
                blk.x[0][l] - k.c[0],
                blk.x[1][l] - k.c[1],
                blk.x[2][l] - k.c[2],
            ];
            let dot = |r: &[f64; 3]| r[0] * xc[0] + r[1] * xc[1] + r[2] * xc[2];
            let (qx, qy, qz) = (dot(&k.a[0]), dot(&k.a[1]), dot(&k.a[2]));
            let (px, py, pz) = (qx + k.t[0], qy + k.t[1], qz + k.t[2]);
            let z_ref = dot(&k.ref_a) + k.ref_tz;
            let same_side = if z_ref > 0.0 { pz > 0.0 } else { pz < 0.0 };
            let on = l < n;
            acc.flipped[l] |= u64::from(on && !same_side);
            let q2 = if on { qx * qx + qy * qy + qz * qz } else { 0.0 };
            let mq = acc.max_q2[l];
            acc.max_q2[l] = if q2 > mq { q2 } else { mq };
            let az = if on { pz.abs() } else { f64::INFINITY };
            let mn = acc.min_abs_z[l];
            acc.min_abs_z[l] = if az < mn { az } else { mn };
            let az = if on { pz.abs() } else { 0.0 };
            let mx = acc.max_abs_z[l];
            acc.max_abs_z[l] = if az > mx { az } else { mx };
            let iz = 1.0 / pz;
            let (nx, ny) = (px * iz, py * iz);
            let ((ux, uy), j) = self.projection.project_with_jacobian(nx, ny);
            e[0][l] = blk.m[0][l] - ux;
            e[1][l] = blk.m[1][l] - uy;
            r2[l] = e[0][l] * e[0][l] + e[1][l] * e[1][l];
            // g_k = d K_k / d p = (J_k / z) [[1, 0, -x], [0, 1, -y]].
            g0[0][l] = j[0] * iz;
            g0[1][l] = j[1] * iz;
            g0[2][l] = -(j[0] * nx + j[1] * ny) * iz;
            g1[0][l] = j[2] * iz;
            g1[1][l] = j[3] * iz;
            g1[2][l] = -(j[2] * nx + j[3] * ny) * iz;
            q[0][l] = qx;
            q[1][l] = qy;
            q[2][l] = qz;
            live[l] = if on { blk.w[l] } else { 0.0 };
        }
        // The loss: rho and the IRLS weight rho' (1 for the squared loss).
        let mut rho = r2;
        let mut sw = live;
        if loss != Loss::Squared {
            for l in 0..n {
                let (r, d) = loss.eval(r2[l]);
                rho[l] = r;
                sw[l] = live[l] * d;
            }
        }
        // The sums. Residual rows [g_k x q, -g_k].
        let s = &mut acc.s;
        for l in 0..LANES {
            s[0][l] += live[l] * rho[l];
            let cross = |g: &[[f64; LANES]; 3]| {
                [
                    g[1][l] * q[2][l] - g[2][l] * q[1][l],
                    g[2][l] * q[0][l] - g[0][l] * q[2][l],
                    g[0][l] * q[1][l] - g[1][l] * q[0][l],
                ]
            };
            let c0 = cross(&g0);
            let c1 = cross(&g1);
            let r0 = [c0[0], c0[1], c0[2], -g0[0][l], -g0[1][l], -g0[2][l]];
            let r1 = [c1[0], c1[1], c1[2], -g1[0][l], -g1[1][l], -g1[2][l]];
            let (bx, by) = (sw[l] * e[0][l], sw[l] * e[1][l]);
            for m in 0..6 {
                s[22 + m][l] += bx * r0[m] + by * r1[m];
            }
            if HESS {
                let mut idx = 1;
                for a in 0..6 {
                    let (a0, a1) = (sw[l] * r0[a], sw[l] * r1[a]);
                    for b in a..6 {
                        s[idx][l] += a0 * r0[b] + a1 * r1[b];
                        idx += 1;
                    }
                }
            }
        }
    }
}

impl<P: Project> Residuals for PixelProblem<'_, P> {
    fn accumulate(&self, pose: &Composed, reference: Option<&Composed>) -> Option<Normal> {
        self.pass::<true>(pose, reference, self.loss)
    }

    fn accumulate_gradient(
        &self,
        pose: &Composed,
        reference: &Composed,
        h_prev: &[[f64; 6]; 6],
    ) -> Option<Normal> {
        self.pass::<false>(pose, Some(reference), self.loss)
            .map(|mut nrm| {
                nrm.h = *h_prev;
                nrm
            })
    }
}

/// S10 with the camera's model fixed at compile time: the refinement, and the plain squared
/// error at its pose.
struct Job<'a> {
    world: &'a [Point3<f64>],
    px: &'a PixelInputs<'a>,
    fr: &'a WorkingFrame,
    r_work: &'a Matrix3<f64>,
    t_work: &'a Vector3<f64>,
    opts: &'a ReprojOptions,
    inv_weight: f64,
}

impl ProjectionJob for Job<'_> {
    type Output = (ReprojOutcome, f64);

    fn run<P: Project>(self, projection: P) -> (ReprojOutcome, f64) {
        let (px, fr) = (self.px, self.fr);
        let prob = PixelProblem {
            world: self.world,
            pixels: px.pixels,
            weights: px.weights,
            inv_weight: self.inv_weight,
            c: fr.c,
            projection,
            loss: px.loss,
        };
        let out = levenberg_marquardt(&prob, fr, self.r_work, self.t_work, self.opts);
        let squared = if px.loss == Loss::Squared {
            out.e
        } else {
            let pose = Composed::new(&out.r, &fr.rw, fr.d, &out.t);
            prob.pass::<false>(&pose, None, Loss::Squared)
                .map_or(f64::NAN, |n| n.e)
        };
        (out, squared)
    }
}

/// S10 from the working-frame pose `(r_work, t_work)` (S9's result). `world` are the solve's
/// world points, `px` their observations; `fr` is S1's working frame. No allocation.
pub(crate) fn refine_pixels(
    world: &[Point3<f64>],
    px: &PixelInputs<'_>,
    fr: &WorkingFrame,
    r_work: &Matrix3<f64>,
    t_work: &Vector3<f64>,
    opts: &ReprojOptions,
) -> PixelOutcome {
    debug_assert_eq!(world.len(), px.pixels.len());
    // The caller's weights in a power-of-two unit, so that no sum overflows or underflows.
    let unit = px.weights.map_or(1.0, |w| {
        let wmax = w.iter().fold(0.0f64, |m, &x| m.max(x));
        if wmax > 0.0 {
            pow2_scale(wmax).max(MIN_UNIT)
        } else {
            1.0
        }
    });
    let weight_sum = px.weights.map_or(world.len() as f64, |w| {
        w.iter().map(|&x| x / unit).sum::<f64>()
    });
    let job = Job {
        world,
        px,
        fr,
        r_work,
        t_work,
        opts,
        inv_weight: 1.0 / unit,
    };
    let (out, squared) = px.projector.with_projection(job);
    PixelOutcome {
        out,
        unit,
        squared,
        weight_sum,
    }
}
