//! The upright two-point pose (up2p): the poses, with the vertical known in both frames, that
//! put two world points on two rays. The minimal solver of RANSAC with a known gravity
//! direction; rays with centres (a multi-camera rig) and rays through one centre (one camera)
//! alike.
//!
//! # Method
//!
//! In frames whose `y` axes are the vertical, the rotation is `R_y(theta)`. Each ray
//! `c_i + l v_i` gives two equations `a^T (R X_i + t) = a^T c_i`, `a` running over two unit
//! vectors orthogonal to `v_i`: four linear equations in `t`, consistent only where
//! `det [A | b(R) - e] = 0` (`A` the rows `a_k`, `b_k = a_k . R X_k`, `e_k = a_k . c_k`). The
//! generated kernel `up2p_quadratic` (`codegen/src/defs/up2p.rs`) expands that determinant in
//! the Cayley parameter `s = tan(theta / 2)`: a quadratic `c2 s^2 + c1 s + c0`. Its roots are
//! taken in the homogeneous form `(sin(theta / 2), cos(theta / 2))`, so the half-turn (`c2 = 0`)
//! is a root like any other; `t` is then the least-squares solution of the four equations
//! (exact at a root), and a pose is kept if both points are in front of their centres (positive
//! depth). World points are taken relative to the first one, so the coefficients do not grow
//! with the distance of the world's origin.
//!
//! Fixed-size, no heap allocation.

use arrayvec::ArrayVec;
use nalgebra::{Matrix3, Point3, Vector3};

use super::mat3::orthogonal_pair;
use super::p3p::P3pPose;
use crate::kernels::up2p_quadratic;

/// At most two poses (the quadratic's roots).
pub type Up2pSolutions = ArrayVec<P3pPose, 2>;

/// `R_y(theta)` from `(sin(theta / 2), cos(theta / 2))` up to a common positive or negative
/// scale.
fn rotation_y(sh: f64, ch: f64) -> Matrix3<f64> {
    let n = sh * sh + ch * ch;
    let (c, s) = ((ch * ch - sh * sh) / n, 2.0 * sh * ch / n);
    Matrix3::new(c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c)
}

/// The poses `x = R X + t` with `R = R_y(theta)` (a rotation about the `y` axis, the vertical
/// of both frames) that put `world[i]` on the ray from `centres[i]` along `directions[i]` (any
/// non-zero length), in front of its centre. For one camera the centres are the origin.
///
/// Returns no pose (never a NaN one) for degenerate input: parallel directions, a zero
/// direction, non-finite input, coefficients that all vanish (a one-parameter family of
/// poses).
#[must_use]
pub fn up2p(
    world: &[Point3<f64>; 2],
    centres: &[Point3<f64>; 2],
    directions: &[Vector3<f64>; 2],
) -> Up2pSolutions {
    let mut out = Up2pSolutions::new();
    let finite = |v: &Vector3<f64>| v.iter().all(|x| x.is_finite());
    if !(world.iter().all(|p| finite(&p.coords))
        && centres.iter().all(|p| finite(&p.coords))
        && directions.iter().all(finite))
    {
        return out;
    }
    let mut v = [Vector3::zeros(); 2];
    for (vi, d) in v.iter_mut().zip(directions) {
        let n = d.norm();
        if !(n > 0.0 && n.is_finite()) {
            return out;
        }
        *vi = d / n;
    }
    // Parallel rays leave `A` of rank 2: no unique translation.
    if v[0].cross(&v[1]).norm() <= 1e-12 {
        return out;
    }
    let (a0, a1) = orthogonal_pair(&v[0]);
    let (a2, a3) = orthogonal_pair(&v[1]);
    let rows = [a0, a1, a2, a3];
    let point = [0, 0, 1, 1];
    // World points relative to the first one.
    let x = [Vector3::zeros(), world[1].coords - world[0].coords];
    let a: [f64; 12] = std::array::from_fn(|i| rows[i / 3][i % 3]);
    let p = [x[0].x, x[0].y, x[0].z, x[1].x, x[1].y, x[1].z];
    let e: [f64; 4] = std::array::from_fn(|k| rows[k].dot(&centres[point[k]].coords));
    let [c0, c1, c2] = up2p_quadratic(&a, &p, &e);
    let scale = c0.abs().max(c1.abs()).max(c2.abs());
    if !(scale > 0.0 && scale.is_finite()) {
        return out;
    }
    let (c0, c1, c2) = (c0 / scale, c1 / scale, c2 / scale);
    // The roots of c2 sh^2 + c1 sh ch + c0 ch^2 = 0 as (sh, ch) pairs, by the stable formula.
    let disc = c1 * c1 - 4.0 * c0 * c2;
    if disc < 0.0 {
        return out;
    }
    let qq = -0.5 * (c1 + disc.sqrt().copysign(c1));
    let mut roots: ArrayVec<(f64, f64), 2> = ArrayVec::new();
    // (sh, ch) = (qq, c2) and (c0, qq): s = qq / c2 and s = c0 / qq (their product c0 / c2).
    if qq != 0.0 || c2 != 0.0 {
        roots.push((qq, c2));
    }
    if qq != 0.0 || c0 != 0.0 {
        roots.push((c0, qq));
    }
    // A^T A = sum a_k a_k^T = (I - v0 v0^T) + (I - v1 v1^T): invertible for non-parallel rays.
    let ata = Matrix3::identity() * 2.0 - v[0] * v[0].transpose() - v[1] * v[1].transpose();
    let Some(ata_inv) = ata.try_inverse() else {
        return out;
    };
    for (sh, ch) in roots {
        if !(sh.is_finite() && ch.is_finite()) || (sh == 0.0 && ch == 0.0) {
            continue;
        }
        let r = rotation_y(sh, ch);
        // A t = e - b(R): the least-squares t (exact at a root).
        let mut atb = Vector3::zeros();
        for k in 0..4 {
            atb += rows[k] * (e[k] - rows[k].dot(&(r * x[point[k]])));
        }
        let t_rel = ata_inv * atb;
        // Back to the caller's world frame: R (X - X0) + t_rel = R X + (t_rel - R X0).
        let translation = t_rel - r * world[0].coords;
        let in_front = (0..2)
            .all(|i| (r * world[i].coords + translation - centres[i].coords).dot(&v[i]) > 0.0);
        let finite_pose =
            r.iter().all(|z| z.is_finite()) && translation.iter().all(|z| z.is_finite());
        let duplicate = out.iter().any(|q| {
            (q.rotation - r).norm() <= 1e-12
                && (q.translation - translation).norm() <= 1e-12 * (1.0 + translation.norm())
        });
        if in_front && finite_pose && !duplicate {
            out.push(P3pPose {
                rotation: r,
                translation,
            });
        }
    }
    out
}

#[cfg(test)]
#[path = "../../tests/unit/numeric/up2p.rs"]
mod tests;
