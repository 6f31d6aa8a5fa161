//! The generalized three-point pose (gP3P): the rig poses that put three world points on three
//! rays, each ray with its own centre (a camera of a multi-camera rig, or any non-central
//! camera). The minimal solver of RANSAC on rigs.
//!
//! # Method
//!
//! With unit directions `v_i`, centres `c_i` and depths `l_i`, the points `c_i + l_i v_i` must
//! keep the distances of the world points:
//! `E_ij = l_i^2 + l_j^2 - 2 a_ij l_i l_j + 2 b_ij l_i + 2 c_ij l_j + d_ij = 0` for the three
//! pairs (`a_ij = v_i . v_j`, `b_ij = v_i . (c_i - c_j)`, `c_ij = v_j . (c_j - c_i)`,
//! `d_ij = |c_i - c_j|^2 - |X_i - X_j|^2`). The generated kernel `gp3p_elimination`
//! (`codegen/src/defs/gp3p.rs`) eliminates `l3` and then `l2` by resultants: its octic in `l1`
//! has the first depths as real roots (only the positive ones are sought), and `l2 = -r0(l1) / r1(l1)`,
//! `l3 = (q2 - q1) / (p1 - p2)` follow linearly (where those denominators vanish, from the
//! quadrics themselves). Each depth triple is polished by Gauss-Newton on the three quadrics and
//! kept only if it then solves them (to `1e-9` of their scale: the octic's coefficients are
//! rounded, and a root the finder reports far out, where evaluating them is all rounding, or
//! the real part of a near-real pair, solves nothing), and the pose is the rigid motion between
//! the orthonormal frames of the world triangle and of the triangle of the points on the rays. Lengths are scaled by the world triangle's
//! longest side and centres taken relative to their centroid first, so the kernel's
//! coefficients are O(1).
//!
//! With one centre the quadrics are Grunert's P3P system and the octic is even: the solutions
//! are those of [`super::p3p::p3p`].
//!
//! Everything is fixed-size (no heap allocation) and every loop is bounded.

use arrayvec::ArrayVec;
use nalgebra::{Matrix3, Point3, Vector3};

use super::p3p::{triangle_frame, P3pPose};
use super::roots::positive_real_roots;
use crate::kernels::gp3p_elimination;

/// Maximum number of gP3P solutions (the octic's degree).
pub const MAX_GP3P_SOLUTIONS: usize = 8;

/// Up to [`MAX_GP3P_SOLUTIONS`] poses (fixed capacity, no allocation).
pub type Gp3pSolutions = ArrayVec<P3pPose, MAX_GP3P_SOLUTIONS>;

/// Gauss-Newton iterations polishing each depth triple (a step is kept only if it lowers the
/// residual).
const GAUSS_NEWTON_ITERATIONS: usize = 5;

/// The three pairs, in the kernel's order.
const PAIRS: [(usize, usize); 3] = [(0, 1), (0, 2), (1, 2)];

/// The rig poses `x_rig = R X + t` that put `world[i]` on the ray from `centres[i]` along
/// `directions[i]` (both in the rig frame; any non-zero direction, normalised here), in front
/// of its centre (positive depth).
///
/// Returns no pose (never a NaN one) for degenerate input: coincident or collinear world
/// points, a zero direction, non-finite input. Solutions closer than `1e-9` (relative) to a
/// previous one are reported once.
#[must_use]
pub fn gp3p(
    world: &[Point3<f64>; 3],
    centres: &[Point3<f64>; 3],
    directions: &[Vector3<f64>; 3],
) -> Gp3pSolutions {
    let mut out = Gp3pSolutions::new();
    let finite = |v: &Vector3<f64>| v.iter().all(|x| x.is_finite());
    if !(world.iter().all(|p| finite(&p.coords))
        && centres.iter().all(|p| finite(&p.coords))
        && directions.iter().all(finite))
    {
        return out;
    }
    let mut v = [Vector3::zeros(); 3];
    for (vi, d) in v.iter_mut().zip(directions) {
        let n = d.norm();
        if !(n > 0.0 && n.is_finite()) {
            return out;
        }
        *vi = d / n;
    }
    let x = [world[0].coords, world[1].coords, world[2].coords];
    let dist2 = PAIRS.map(|(i, j)| (x[i] - x[j]).norm_squared());
    let amax = dist2[0].max(dist2[1]).max(dist2[2]);
    let (d12, d13) = (x[0] - x[1], x[0] - x[2]);
    if !(amax > 0.0 && amax.is_finite())
        || d12.cross(&d13).norm_squared() <= 1e-20 * dist2[0] * dist2[1]
    {
        return out;
    }
    // Scaled units: the longest side of the world triangle is 1, the centres relative to
    // their centroid.
    let s = amax.sqrt();
    let c_mean = (centres[0].coords + centres[1].coords + centres[2].coords) / 3.0;
    let c = centres.map(|p| (p.coords - c_mean) / s);
    let mut e = [0.0; 12];
    for (k, (i, j)) in PAIRS.into_iter().enumerate() {
        let dc = c[i] - c[j];
        e[4 * k] = v[i].dot(&v[j]);
        e[4 * k + 1] = v[i].dot(&dc);
        e[4 * k + 2] = -v[j].dot(&dc);
        e[4 * k + 3] = dc.norm_squared() - dist2[k] / amax;
    }
    let k = gp3p_elimination(&e);
    let (f, r1, r0) = (&k[0..9], &k[9..13], &k[13..18]);
    let Some(fw) = triangle_frame(&x) else {
        return out;
    };
    let xw = (x[0] + x[1] + x[2]) / 3.0;
    for &l1 in positive_real_roots(f).iter() {
        let Some(l) = depths(&e, l1, horner(r1, l1), horner(r0, l1)) else {
            continue;
        };
        let l = gauss_newton(l, &e);
        if !l.iter().all(|d| d.is_finite() && *d > 0.0) || !solves(&l, &e) {
            continue;
        }
        // The points on the rays, back in the caller's units.
        let ps = [0, 1, 2].map(|i| centres[i].coords + v[i] * (l[i] * s));
        let Some(fc) = triangle_frame(&ps) else {
            continue;
        };
        let rotation = fc * fw.transpose();
        let translation = (ps[0] + ps[1] + ps[2]) / 3.0 - rotation * xw;
        let finite_pose =
            rotation.iter().all(|v| v.is_finite()) && translation.iter().all(|v| v.is_finite());
        let scale = 1.0 + translation.norm();
        let duplicate = out.iter().any(|q| {
            (q.rotation - rotation).norm() <= 1e-9
                && (q.translation - translation).norm() <= 1e-9 * scale
        });
        if finite_pose && !duplicate && !out.is_full() {
            out.push(P3pPose {
                rotation,
                translation,
            });
        }
    }
    out
}

/// `c[0] + c[1] x + ...` at `x`.
fn horner(c: &[f64], x: f64) -> f64 {
    c.iter().rev().fold(0.0, |acc, &ci| acc * x + ci)
}

/// `E_ij` (pair `k` of [`PAIRS`]) at depths `li`, `lj`.
fn quadric(e: &[f64; 12], k: usize, li: f64, lj: f64) -> f64 {
    let (a, b, c, d) = (e[4 * k], e[4 * k + 1], e[4 * k + 2], e[4 * k + 3]);
    li * li + lj * lj - 2.0 * a * li * lj + 2.0 * b * li + 2.0 * c * lj + d
}

/// The roots (0, 1 or 2, real parts of a pair whose discriminant is negative by rounding) of
/// `E_ij` (pair `k`) as a quadratic in its second depth, the first being `li`.
fn second_depths(e: &[f64; 12], k: usize, li: f64) -> [f64; 2] {
    let (a, b, c, d) = (e[4 * k], e[4 * k + 1], e[4 * k + 2], e[4 * k + 3]);
    // lj^2 + p lj + q = 0.
    let p = 2.0 * c - 2.0 * a * li;
    let q = li * li + 2.0 * b * li + d;
    let disc = (0.25 * p * p - q).max(0.0).sqrt();
    // The larger root first, the other from the product (no cancellation).
    let big = -0.5 * p + if p <= 0.0 { disc } else { -disc };
    let other = if big != 0.0 { q / big } else { big };
    [big, other]
}

/// The depths `(l1, l2, l3)` for a root `l1` of the octic: `l2 = -r0 / r1`, and `l3` from
/// `E13 - E23` (linear in `l3`); where either denominator vanishes, the candidate of the
/// quadrics that fits the third best.
fn depths(e: &[f64; 12], l1: f64, r1: f64, r0: f64) -> Option<Vector3<f64>> {
    let scale_r = r0.abs().max(r1.abs() * (1.0 + l1.abs()));
    let l2_candidates: ArrayVec<f64, 2> = if r1.abs() > 1e-10 * scale_r {
        [-r0 / r1].into_iter().collect()
    } else {
        second_depths(e, 0, l1).into_iter().collect()
    };
    let mut best: Option<(f64, Vector3<f64>)> = None;
    for l2 in l2_candidates {
        // E13 - E23 = (p1 - p2) l3 + (q1 - q2), p, q the coefficients in l3.
        let (a13, b13, c13, d13) = (e[4], e[5], e[6], e[7]);
        let (a23, b23, c23, d23) = (e[8], e[9], e[10], e[11]);
        let dp = (2.0 * c13 - 2.0 * a13 * l1) - (2.0 * c23 - 2.0 * a23 * l2);
        let dq = (l1 * l1 + 2.0 * b13 * l1 + d13) - (l2 * l2 + 2.0 * b23 * l2 + d23);
        let scale_q = dq.abs().max(1e-300);
        let l3_candidates: ArrayVec<f64, 2> = if dp.abs() > 1e-10 * scale_q.max(dp.abs()) {
            [-dq / dp].into_iter().collect()
        } else {
            second_depths(e, 1, l1).into_iter().collect()
        };
        for l3 in l3_candidates {
            let l = Vector3::new(l1, l2, l3);
            let r = residuals(&l, e).norm();
            if r.is_finite() && best.is_none_or(|(b, _)| r < b) {
                best = Some((r, l));
            }
        }
    }
    best.map(|(_, l)| l)
}

/// Relative residual a depth triple must reach to be a solution: a root of the octic gives,
/// after the polish, the quadrics to a few `u` of their scale; a spurious root (the real part of
/// a complex pair, or a root of the rounded octic far out where its evaluation is all rounding
/// error) leaves them far from 0 and gives no pose.
const SOLVED: f64 = 1e-9;

/// Whether `l` solves the three quadrics to [`SOLVED`] relative to the sum of the absolute
/// values of each quadric's terms.
fn solves(l: &Vector3<f64>, e: &[f64; 12]) -> bool {
    let r = residuals(l, e);
    PAIRS.into_iter().enumerate().all(|(k, (i, j))| {
        let (a, b, c, d) = (e[4 * k], e[4 * k + 1], e[4 * k + 2], e[4 * k + 3]);
        let (li, lj) = (l[i], l[j]);
        let scale = li * li
            + lj * lj
            + 2.0 * (a * li * lj).abs()
            + 2.0 * (b * li).abs()
            + 2.0 * (c * lj).abs()
            + d.abs();
        r[k].abs() <= SOLVED * scale
    })
}

/// The three quadrics at `l`.
fn residuals(l: &Vector3<f64>, e: &[f64; 12]) -> Vector3<f64> {
    Vector3::new(
        quadric(e, 0, l[0], l[1]),
        quadric(e, 1, l[0], l[2]),
        quadric(e, 2, l[1], l[2]),
    )
}

/// Gauss-Newton on the three quadrics; a step is kept only if it lowers the residual norm.
fn gauss_newton(mut l: Vector3<f64>, e: &[f64; 12]) -> Vector3<f64> {
    let mut r = residuals(&l, e);
    // d E_ij / d li = 2 li - 2 a lj + 2 b, d E_ij / d lj = 2 lj - 2 a li + 2 c.
    let grad = |k: usize, li: f64, lj: f64| {
        let (a, b, c) = (e[4 * k], e[4 * k + 1], e[4 * k + 2]);
        (2.0 * (li - a * lj + b), 2.0 * (lj - a * li + c))
    };
    for _ in 0..GAUSS_NEWTON_ITERATIONS {
        let rn = r.norm();
        if rn == 0.0 {
            break;
        }
        let (g12i, g12j) = grad(0, l[0], l[1]);
        let (g13i, g13j) = grad(1, l[0], l[2]);
        let (g23i, g23j) = grad(2, l[1], l[2]);
        let j = Matrix3::new(g12i, g12j, 0.0, g13i, 0.0, g13j, 0.0, g23i, g23j);
        let Some(ji) = j.try_inverse() else {
            break;
        };
        let cand = l - ji * r;
        let rc = residuals(&cand, e);
        if !(rc.norm() < rn) {
            break;
        }
        l = cand;
        r = rc;
    }
    l
}

#[cfg(test)]
#[path = "../../tests/unit/numeric/gp3p.rs"]
mod tests;
