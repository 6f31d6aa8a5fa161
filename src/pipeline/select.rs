//! The `select` stage of docs/algorithm.md: the refined local minima and the choice among them. The
//! pose with the smallest algebraic cost `f` among the minima with more than half of the points in
//! front of the camera; without any such minimum, the smallest `f`.

use nalgebra::{Matrix3, Point3, Vector3};

use super::frame::WorkingFrame;
use super::nullspace::CandidateSource;
use crate::numeric::lanes::dispatched;

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
    /// An exact fit: the start itself, certified at the rounding level of `f` (`newton` skipped);
    /// `refine` (or `refine_pixels`) then applies the step of its `xtol` stop
    /// ([`super::refine::ReprojOptions::exact_start`]).
    pub exact: bool,
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
    fr.most_in_front(count_in_front(world, weights, &a, &fr.c, t.z))
}

dispatched! {
    /// The number of active points with `a . (X_i - c) + t_z > 0`: a count, so the same in
    /// every build; branch-free, so that the compiler vectorises it.
    pub(crate) fn count_in_front[][](
        world: &[Point3<f64>],
        weights: Option<&[f64]>,
        a: &Vector3<f64>,
        c: &Vector3<f64>,
        tz: f64,
    ) -> usize = count_in_front_body;
}

#[inline(always)]
fn count_in_front_body(
    world: &[Point3<f64>],
    weights: Option<&[f64]>,
    a: &Vector3<f64>,
    c: &Vector3<f64>,
    tz: f64,
) -> usize {
    let front = |x: &Point3<f64>| a.dot(&(x.coords - c)) + tz > 0.0;
    match weights {
        None => world.iter().map(|x| usize::from(front(x))).sum(),
        Some(w) => world
            .iter()
            .zip(w)
            .map(|(x, &w)| usize::from((w != 0.0) & front(x)))
            .sum(),
    }
}

/// `select`: sorts `minima` by `f` and returns the index of the first one with more than half of
/// the points in front (0 if none is); depths are counted lazily, in order of `f`, until one
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
