//! The solvers under comparison, each behind one `solve` on a pre-converted problem.
//!
//! Every peer gets its inputs in its own format, converted once outside the timed loops:
//! - `sqpnp` 0.4 and `kornia-pnp` 0.1.10 take `f32` inputs: the world points are centred on
//!   their centroid in `f64` before the conversion (and the translation is mapped back,
//!   `t = t_c - R c`), which is the most favourable `f32` input we can give them;
//! - `lambda-twist` 0.7 is a P3P solver: it is run on the first three correspondences and its
//!   (up to four) poses are disambiguated by the total reprojection error of all four points
//!   (the usual P3P + 1 scheme), so it only runs for N = 4.

use crate::common::Problem;
use nalgebra::{Matrix3, Vector3};
use std::sync::mpsc;
use std::time::Duration;

/// A pose (world -> camera), `f64`.
pub type Pose = (Matrix3<f64>, Vector3<f64>);

/// Centroid of the world points.
fn centroid(p: &Problem) -> Vector3<f64> {
    p.world.iter().map(|x| x.coords).sum::<Vector3<f64>>() / p.world.len() as f64
}

// ---------------------------------------------------------------------------------------------
// sqpnp
// ---------------------------------------------------------------------------------------------

/// One problem in `sqpnp`'s input format.
pub struct SqpnpInput {
    c: Vector3<f64>,
    world: Vec<glam::Vec3>,
    image: Vec<glam::Vec2>,
}

/// Converts a problem for `sqpnp` (centred world, normalised image points, `f32`).
pub fn sqpnp_input(p: &Problem) -> SqpnpInput {
    let c = centroid(p);
    SqpnpInput {
        c,
        world: p
            .world
            .iter()
            .map(|x| {
                let d = x.coords - c;
                glam::Vec3::new(d.x as f32, d.y as f32, d.z as f32)
            })
            .collect(),
        image: p
            .image
            .iter()
            .map(|m| glam::Vec2::new(m.x as f32, m.y as f32))
            .collect(),
    }
}

/// `sqpnp` with its default parameters; the solver object is reused across problems.
pub struct Sqpnp(sqpnp::Solver<sqpnp::DefaultParameters>);

impl Sqpnp {
    /// A new solver.
    pub fn new() -> Self {
        Sqpnp(sqpnp::Solver::<sqpnp::DefaultParameters>::new())
    }

    /// The best pose, if any.
    pub fn solve(&mut self, q: &SqpnpInput) -> Option<Pose> {
        if !self.0.solve(&q.world, &q.image, None) {
            return None;
        }
        let s = self.0.best_solution()?;
        let r = s.rotation_matrix().to_cols_array();
        let r = Matrix3::from_column_slice(&r.map(f64::from));
        let t = s.translation();
        let t = Vector3::new(f64::from(t.x), f64::from(t.y), f64::from(t.z)) - r * q.c;
        Some((r, t))
    }
}

// ---------------------------------------------------------------------------------------------
// lambda-twist (P3P + disambiguation by the 4th point)
// ---------------------------------------------------------------------------------------------

use cv_core::nalgebra as na21;
use cv_core::sample_consensus::Estimator;
use cv_core::{FeatureWorldMatch, Projective, WorldPoint};

/// One N = 4 problem in `lambda-twist`'s input format.
pub struct LambdaInput {
    samples: [FeatureWorldMatch<na21::Unit<na21::Vector3<f64>>>; 3],
    world: [na21::Vector3<f64>; 4],
    image: [[f64; 2]; 4],
}

/// Converts an N >= 4 problem for `lambda-twist` (first three points for P3P, four for the
/// disambiguation).
pub fn lambda_input(p: &Problem) -> LambdaInput {
    let w = |i: usize| na21::Vector3::new(p.world[i].x, p.world[i].y, p.world[i].z);
    let b =
        |i: usize| na21::Unit::new_normalize(na21::Vector3::new(p.image[i].x, p.image[i].y, 1.0));
    let m = |i: usize| FeatureWorldMatch(b(i), WorldPoint::from_point(na21::Point3::from(w(i))));
    LambdaInput {
        samples: [m(0), m(1), m(2)],
        world: [w(0), w(1), w(2), w(3)],
        image: std::array::from_fn(|i| [p.image[i].x, p.image[i].y]),
    }
}

/// `lambda-twist` with its default parameters.
pub fn lambda_twist(q: &LambdaInput) -> Option<Pose> {
    let poses = lambda_twist::LambdaTwist::new().estimate(q.samples.iter().cloned());
    let mut best: Option<(f64, Pose)> = None;
    for pose in &poses {
        let iso = pose.0;
        let r = iso.rotation.matrix();
        let t = iso.translation.vector;
        let mut e = 0.0;
        for (x, m) in q.world.iter().zip(&q.image) {
            let c = r * x + t;
            e += if c.z > 0.0 {
                (c.x / c.z - m[0]).powi(2) + (c.y / c.z - m[1]).powi(2)
            } else {
                f64::INFINITY
            };
        }
        if best.as_ref().is_none_or(|(b, _)| e < *b) {
            let r = Matrix3::from_fn(|i, j| r[(i, j)]);
            let t = Vector3::new(t.x, t.y, t.z);
            best = Some((e, (r, t)));
        }
    }
    best.map(|(_, p)| p)
}

// ---------------------------------------------------------------------------------------------
// kornia-pnp (EPnP), with a watchdog
// ---------------------------------------------------------------------------------------------

/// One problem in `kornia-pnp`'s input format (centred world, pixels, K; `f32`).
#[derive(Clone)]
pub struct KorniaInput {
    c: Vector3<f64>,
    world: Vec<[f32; 3]>,
    pixels: Vec<[f32; 2]>,
    k: [[f32; 3]; 3],
}

/// Converts a problem for `kornia-pnp`.
pub fn kornia_input(p: &Problem) -> KorniaInput {
    use crate::common::{CX, CY, F};
    let c = centroid(p);
    KorniaInput {
        c,
        world: p
            .world
            .iter()
            .map(|x| {
                let d = x.coords - c;
                [d.x as f32, d.y as f32, d.z as f32]
            })
            .collect(),
        pixels: p.pixels.iter().map(|m| [m.x as f32, m.y as f32]).collect(),
        k: [
            [F as f32, 0.0, CX as f32],
            [0.0, F as f32, CY as f32],
            [0.0, 0.0, 1.0],
        ],
    }
}

/// `kornia_pnp::solve_pnp` with `EPnPDefault`, called directly (only for inputs known to return:
/// see [`kornia_guarded`]).
pub fn kornia(q: &KorniaInput) -> Option<Pose> {
    let r = kornia_pnp::solve_pnp(
        &q.world,
        &q.pixels,
        &q.k,
        None,
        kornia_pnp::PnPMethod::EPnPDefault,
    )
    .ok()?;
    let rot = Matrix3::from_fn(|i, j| f64::from(r.rotation[i][j]));
    let t = Vector3::new(
        f64::from(r.translation[0]),
        f64::from(r.translation[1]),
        f64::from(r.translation[2]),
    ) - rot * q.c;
    Some((rot, t))
}

/// Outcome of a guarded `kornia-pnp` call.
pub enum Guarded {
    /// The call returned (with or without a pose).
    Returned(Option<Pose>),
    /// The call panicked (the worker's channel closed without a result).
    Panicked,
    /// No answer within the timeout; the worker thread was left detached.
    TimedOut,
}

/// Runs [`kornia`] on a dedicated worker thread and waits at most `timeout` for it. On a
/// timeout the thread is left detached (it cannot be cancelled); the caller caps how many.
pub fn kornia_guarded(q: &KorniaInput, timeout: Duration) -> Guarded {
    let (tx, rx) = mpsc::channel();
    let q = q.clone();
    let spawned = std::thread::Builder::new()
        .name("kornia-worker".into())
        .spawn(move || {
            let _ = tx.send(kornia(&q));
        });
    if spawned.is_err() {
        return Guarded::Panicked;
    }
    match rx.recv_timeout(timeout) {
        Ok(r) => Guarded::Returned(r),
        Err(mpsc::RecvTimeoutError::Disconnected) => Guarded::Panicked,
        Err(mpsc::RecvTimeoutError::Timeout) => Guarded::TimedOut,
    }
}
