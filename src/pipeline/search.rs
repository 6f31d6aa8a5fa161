//! The `search` stage of docs/algorithm.md: the small-N starts of the default mode. At N = 4 and 5
//! the null space of `M` is (nearly) 4- or 2-dimensional and the algebraic search says little about
//! where the minimum of the reprojection error lies; the poses that fit three of the points exactly
//! (P3P, [`crate::numeric::p3p`]) usually do: with the noise of the other points small, one of the
//! up to four poses of a triple lies in the basin of the maximum-likelihood pose.
//!
//! [`starts`] solves P3P on triples of the active points (all 4 at N = 4, 3 of the 10 at N = 5),
//! scores every pose by the number of points in front of it and its reprojection error over all
//! points ([`SmallProblem::score`], in `frame`'s weight unit and `refine`'s row weights), merges
//! the poses that lie within [`SAME_START`] of each other (keeping the better one) and returns them
//! best first. The driver runs `refine` from the best [`refined`] of them and keeps the best
//! refined pose.

use arrayvec::ArrayVec;
use nalgebra::{Matrix3, Point2, Point3, Vector3};

use super::frame::WorkingFrame;
use super::nullspace::CandidateSource;
use crate::numeric::p3p::{p3p_unpolished, MAX_P3P_SOLUTIONS};

/// The largest number of active points for which the small-N search runs.
pub(crate) const MAX_SMALL_N: usize = 5;
/// The triples of 4 points: all of them.
const TRIPLES_4: [[usize; 3]; 4] = [[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]];
/// The triples of 5 points: 3 of the 10, consecutive points (the middle point in all three,
/// the end points in one). Fewer starts, and fewer of them in the basins of higher minima: on
/// 206,000 seeded problems per scene type the search missed the global minimum in 0 general
/// (the best 3 starts refined) and 1 planar problem (the best 5), where with the 5 cyclically
/// consecutive triples (the best 2 refined, 5 in planar scenes) it missed 4 and 4, for 8 %
/// (general) and 5 % (planar) fewer instructions per solve (docs/algorithm.md, `search`, larger
/// sets).
const TRIPLES_5: [[usize; 3]; 3] = [[0, 1, 2], [1, 2, 3], [2, 3, 4]];
/// The most triples used (N = 4).
const MAX_TRIPLES: usize = TRIPLES_4.len();
/// Upper bound on the number of starts: every pose of every triple, and the driver's p1 start
/// in planar scenes ([`add`]).
pub(crate) const MAX_STARTS: usize = MAX_TRIPLES * MAX_P3P_SOLUTIONS + 1;
/// Two starts whose rotations differ by less than this (Frobenius norm, ~ radians; 0.05 is
/// about 2 degrees) and whose translations differ by less than this relative to `|t| + 1` are
/// one start: the poses of different triples near the same minimum differ by the noise.
const SAME_START: f64 = 0.05;

/// A scored start (working frame): `x_cam / d = R P + t`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Start {
    pub r: Matrix3<f64>,
    pub t: Vector3<f64>,
    /// Active points with a positive depth.
    pub in_front: usize,
    /// Weighted sum of squared reprojection residuals (`frame`'s weight unit, `refine`'s row
    /// weights); `+inf` if a depth is zero or the sum is not finite.
    pub cost: f64,
    /// Where the start came from: [`CandidateSource::P3p`], or the algebraic start the driver
    /// adds ([`add`]).
    pub source: CandidateSource,
    /// `newton` iterations that produced it (0 for a P3P pose).
    pub iterations: u32,
}

impl Start {
    /// The order of the starts (and of the refined poses): more points in front first, then
    /// the lower cost.
    pub(crate) fn better(&self, other: &Start) -> bool {
        self.in_front > other.in_front
            || (self.in_front == other.in_front && self.cost < other.cost)
    }
}

/// Radius (Frobenius norm of the rotation difference, and translation difference relative to
/// `|t| + 1`; 0.1 is about 4 degrees) of the neighbourhood of a refined pose taken to lie in
/// its basin: a start or a `refine` iterate that comes this close is taken to converge to it
/// (distinct minima of the reprojection error are many degrees apart; with this radius no
/// minimum was missed in the measurements of [`refined`]).
const IN_REFINED_BASIN: f64 = 0.1;

/// A start whose cost exceeds this multiple of the best refined pose's cost (with no more points in
/// front) is not refined. Measured (`examples/small_n.rs`, N = 4, sigma = 2 px, 18,000 general and
/// 18,000 planar problems): the largest ratio of a start that led to a lower minimum was about
/// 1,400 (with a cut at 1,000, 1 general problem in 6,000 missed its minimum; with 10,000 none of
/// the 18,000 per scene type, with 3,000 none of 12,000 of them), and the cut at 10,000 saves a
/// third of the instructions of general N = 4 solves: most of `refine`'s work went into long runs
/// from poor starts that end in a known basin. In planar scenes the cut is
/// [`MAX_COST_RATIO_PLANAR`].
const MAX_COST_RATIO: f64 = 1e4;

/// [`MAX_COST_RATIO`] in planar scenes. Measured again (all starts refined, 12,000 problems
/// per N and scene type in two seed sets): the largest ratio of a start that led to a lower
/// minimum was 1,429 in general scenes, but 20,238 in one planar N = 4 problem of 12,000 (the
/// largest in the other seed set: 319), whose global minimum only that start reaches (32 `refine`
/// iterations): with 10,000 it was missed (cost 2.06x LM's from the ground truth). With
/// 100,000 it is found, for 7 % more instructions in planar N = 4 solves (in general ones the
/// same cut costs 40 %).
const MAX_COST_RATIO_PLANAR: f64 = 1e5;

/// A later run of `refine` is abandoned before a step when its cost `e` exceeds
/// [`UNREACHABLE_COST_RATIO`] times the best refined cost by more than [`UNREACHABLE_PRED_RATIO`]
/// times the decrease the damped Gauss-Newton model predicts for the step. Near a minimum LM
/// converges with a ratio well below 1, so the run's remaining decrease is a small multiple of
/// its next step's; far from one the model underestimates it, but by far less than these
/// margins. Measured (`examples/small_n.rs` with the runs' cost and prediction traced, sigma =
/// 2 px, N = 4 and 5, general and planar scenes, 56,000 problems each): of the 1,305 later
/// runs that ended below the best refined cost, the largest multiple of a prediction that
/// would have stopped one was 127 (the next ones 29 and 17, all others below 8), with the cost
/// ratio 2; with 1,000 none is stopped, and replayed on the traces the rule removes about
/// 31 % of `refine`'s iterations at general N = 4 (6.3 of 20.1 per solve), 30 % in planar N = 4,
/// 12 % in general and 40 % in planar N = 5: most of `refine`'s work went into long runs that end
/// in another, higher minimum.
const UNREACHABLE_PRED_RATIO: f64 = 1e3;
/// See [`UNREACHABLE_PRED_RATIO`]: two refinements of one flat minimum can end a few 1e-5
/// apart in cost, so a run is never stopped below twice the best cost.
const UNREACHABLE_COST_RATIO: f64 = 2.0;

/// Whether a later run of `refine` at cost `e`, whose next step is predicted to lower it by `pred`,
/// cannot end below `best` (see [`UNREACHABLE_PRED_RATIO`]).
pub(crate) fn cannot_reach(e: f64, pred: f64, best: f64) -> bool {
    e - UNREACHABLE_PRED_RATIO * pred > UNREACHABLE_COST_RATIO * best
}

impl Start {
    /// Whether this start is worth a `refine` run once `best` (a refined pose) is known: more
    /// points in front than `best`, or a cost at most [`MAX_COST_RATIO`] (in `planar` scenes
    /// [`MAX_COST_RATIO_PLANAR`]) times its cost.
    pub(crate) fn worth_refining(&self, best: &Start, planar: bool) -> bool {
        let ratio = if planar {
            MAX_COST_RATIO_PLANAR
        } else {
            MAX_COST_RATIO
        };
        self.in_front > best.in_front || self.cost <= ratio * best.cost
    }

    /// Whether `(r, t)` lies in the basin of this (refined) pose ([`IN_REFINED_BASIN`]).
    pub(crate) fn near(&self, r: &Matrix3<f64>, t: &Vector3<f64>) -> bool {
        (self.r - r).norm() <= IN_REFINED_BASIN
            && (self.t - t).norm() <= IN_REFINED_BASIN * (self.t.norm() + 1.0)
    }
}

/// How many of the best starts `refine` refines (measured with `examples/small_n.rs`, sigma = 2 px:
/// the fewest that never missed the minimum in 6,000 seeded problems per scene type, with
/// margin): every distinct start at N = 4 (with 4 starts, 2 of 6,000 general problems missed
/// it; with 6, 2 of 6,000 planar ones); at N = 5, measured on larger sets with the starts of
/// [`TRIPLES_5`] (docs/algorithm.md, `search`, larger sets), 3 in non-planar scenes (with 2, 3 of
/// 150,000 problems missed it) and 5 in planar ones (with 4, 4 of 150,000).
pub(crate) fn refined(sp: &SmallProblem, planar: bool) -> usize {
    match (sp.p.len(), planar) {
        (0..=4, _) => MAX_STARTS,
        (_, false) => 3,
        (_, true) => 5,
    }
}

/// Up to [`MAX_STARTS`] starts (fixed capacity, no allocation).
pub(crate) type Starts = ArrayVec<Start, MAX_STARTS>;

/// The active points (weight > 0) in the working frame with their image points and weights in
/// `frame`'s unit.
pub(crate) struct SmallProblem {
    p: ArrayVec<Vector3<f64>, MAX_SMALL_N>,
    m: ArrayVec<Point2<f64>, MAX_SMALL_N>,
    w: ArrayVec<f64, MAX_SMALL_N>,
    row_weights: (f64, f64),
}

impl SmallProblem {
    /// The problem of the active points, or `None` unless there are 4 or 5 of them.
    pub(crate) fn new(
        world: &[Point3<f64>],
        image: &[Point2<f64>],
        weights: Option<&[f64]>,
        fr: &WorkingFrame,
        row_weights: (f64, f64),
    ) -> Option<Self> {
        if !(4..=MAX_SMALL_N).contains(&fr.n_active) {
            return None;
        }
        let inv_weight = 1.0 / fr.weight_unit;
        let mut sp = SmallProblem {
            p: ArrayVec::new(),
            m: ArrayVec::new(),
            w: ArrayVec::new(),
            row_weights,
        };
        for (i, (x, m)) in world.iter().zip(image).enumerate() {
            let w = weights.map_or(1.0, |w| w[i]);
            if w == 0.0 {
                continue;
            }
            if sp.p.is_full() {
                return None;
            }
            sp.p.push(fr.to_working(x));
            sp.m.push(*m);
            sp.w.push(w * inv_weight);
        }
        (sp.p.len() >= 4).then_some(sp)
    }

    /// Points in front of `(r, t)` and the weighted reprojection error over the active points.
    pub(crate) fn score(&self, r: &Matrix3<f64>, t: &Vector3<f64>) -> (usize, f64) {
        let (wx, wy) = self.row_weights;
        let mut in_front = 0;
        let mut e = 0.0;
        for ((p, m), w) in self.p.iter().zip(&self.m).zip(&self.w) {
            let c = r * p + t;
            if c.z > 0.0 {
                in_front += 1;
            }
            let (du, dv) = (m.x - c.x / c.z, m.y - c.y / c.z);
            e += w * (wx * du * du + wy * dv * dv);
        }
        (in_front, if e.is_finite() { e } else { f64::INFINITY })
    }
}

/// `search`: the P3P poses of the triples of the active points ([`TRIPLES_4`], [`TRIPLES_5`]),
/// scored, merged within [`SAME_START`] and sorted best first ([`Start::better`]) into `out`.
/// Degenerate triples (collinear or coincident points, parallel rays) give no pose.
pub(crate) fn starts(sp: &SmallProblem, out: &mut Starts) {
    let triples: &[[usize; 3]] = if sp.p.len() == 4 {
        &TRIPLES_4
    } else {
        &TRIPLES_5
    };
    for &[i, j, k] in triples {
        let world = [sp.p[i], sp.p[j], sp.p[k]].map(Point3::from);
        let bearing = [i, j, k].map(|l| Vector3::new(sp.m[l].x, sp.m[l].y, 1.0));
        for pose in p3p_unpolished(&world, &bearing) {
            let (in_front, cost) = sp.score(&pose.rotation, &pose.translation);
            let s = Start {
                r: pose.rotation,
                t: pose.translation,
                in_front,
                cost,
                source: CandidateSource::P3p,
                iterations: 0,
            };
            insert(out, s);
        }
    }
    sort(out);
}

/// Adds the pose `(r, t)` from `source` to `out`, scored and merged as the P3P starts are,
/// and sorts `out` again.
pub(crate) fn add(
    sp: &SmallProblem,
    r: &Matrix3<f64>,
    t: &Vector3<f64>,
    (source, iterations): (CandidateSource, u32),
    out: &mut Starts,
) {
    let (in_front, cost) = sp.score(r, t);
    insert(
        out,
        Start {
            r: *r,
            t: *t,
            in_front,
            cost,
            source,
            iterations,
        },
    );
    sort(out);
}

/// Best first ([`Start::better`]).
fn sort(out: &mut Starts) {
    out.sort_by(|a, b| b.in_front.cmp(&a.in_front).then(a.cost.total_cmp(&b.cost)));
}

/// Adds `s` to `out`, or replaces the start it duplicates if `s` is better.
fn insert(out: &mut Starts, s: Start) {
    let scale = s.t.norm() + 1.0;
    // The translations first: three differences tell most distinct starts apart.
    if let Some(o) = out
        .iter_mut()
        .find(|o| (o.t - s.t).norm() <= SAME_START * scale && (o.r - s.r).norm() <= SAME_START)
    {
        if s.better(o) {
            *o = s;
        }
        return;
    }
    if !out.is_full() {
        out.push(s);
    }
}
