//! S7 of docs/algorithm.md: the refined local minima and the choice among them. The pose with the
//! smallest algebraic cost `f` among the minima with more than half of the points in front of
//! the camera; without any such minimum, the smallest `f`.

use nalgebra::{Matrix3, Point3, Vector3};

use super::frame::WorkingFrame;
use super::nullspace::CandidateSource;

/// A refined local minimum of f (working frame).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Minimum {
    pub r: Matrix3<f64>,
    pub t: Vector3<f64>,
    pub f: f64,
    pub source: CandidateSource,
    pub planar: bool,
    pub iterations: u32,
    /// Whether more than half of the points are in front (`None` until it is counted).
    pub cheirality: Option<bool>,
}

/// Whether more than half of the active points have positive depth (working-frame pose),
/// computed from the world points: `z_i = a . (X_i - c) + t_z`, `a = (R Rw)_3 / d`.
pub(crate) fn in_front(
    world: &[Point3<f64>],
    weights: Option<&[f64]>,
    fr: &WorkingFrame,
    r: &Matrix3<f64>,
    t: &Vector3<f64>,
) -> bool {
    let a = (r * fr.rw).row(2).transpose() / fr.d;
    let mut pos = 0usize;
    for (i, x) in world.iter().enumerate() {
        if weights.is_some_and(|w| w[i] == 0.0) {
            continue;
        }
        if a.dot(&(x.coords - fr.c)) + t.z > 0.0 {
            pos += 1;
        }
    }
    2 * pos > fr.n_active
}

/// S7: sorts `minima` by `f` and returns the index of the first one with more than half of the
/// points in front (0 if none is); depths are counted lazily, in order of `f`, until one
/// passes, and recorded in each minimum's `cheirality`.
pub(crate) fn pick(
    minima: &mut [Minimum],
    world: &[Point3<f64>],
    weights: Option<&[f64]>,
    fr: &WorkingFrame,
) -> usize {
    minima.sort_by(|a, b| a.f.total_cmp(&b.f));
    for (i, m) in minima.iter_mut().enumerate() {
        let ok = in_front(world, weights, fr, &m.r, &m.t);
        m.cheirality = Some(ok);
        if ok {
            return i;
        }
    }
    0
}

/// Counts the cheirality of every minimum (for `solve_all`, which returns them all).
pub(crate) fn count_all(
    minima: &mut [Minimum],
    world: &[Point3<f64>],
    weights: Option<&[f64]>,
    fr: &WorkingFrame,
) {
    for m in minima.iter_mut() {
        m.cheirality = Some(in_front(world, weights, fr, &m.r, &m.t));
    }
}
