//! The measurement: every method on every row, its accuracy and its time per solve.

use crate::args::Args;
use crate::common::{self, Problem};
use crate::kornia::{kornia_accuracy, kornia_child, KorniaOutcome};
use crate::peers::{self, Pose};
use crate::rows::Row;
use crate::{FAIL_DEG, KORNIA_MAX_HANGS_PER_ROW};
use eopnp::{Refinement, Solver};
use std::hint::black_box;
use std::time::Instant;

/// The methods, in table order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    EopnpDefault,
    EopnpAlgebraic,
    Sqpnp,
    LambdaTwist,
    Kornia,
    LmGt,
}

pub const METHODS: [Method; 6] = [
    Method::EopnpDefault,
    Method::EopnpAlgebraic,
    Method::Sqpnp,
    Method::LambdaTwist,
    Method::Kornia,
    Method::LmGt,
];

impl Method {
    pub fn name(self) -> &'static str {
        match self {
            Method::EopnpDefault => "eopnp (default)",
            Method::EopnpAlgebraic => "eopnp (algebraic)",
            Method::Sqpnp => "sqpnp",
            Method::LambdaTwist => "lambda-twist (P3P+1)",
            Method::Kornia => "kornia-pnp (EPnP)",
            Method::LmGt => "LM from ground truth",
        }
    }
    pub fn color(self) -> &'static str {
        match self {
            Method::EopnpDefault => "#d62728",
            Method::EopnpAlgebraic => "#ff7f0e",
            Method::Sqpnp => "#1f77b4",
            Method::LambdaTwist => "#9467bd",
            Method::Kornia => "#2ca02c",
            Method::LmGt => "#555555",
        }
    }
}

/// Statistics of one method on one row.
#[derive(Clone, Debug)]
pub struct Stats {
    pub method: Method,
    pub trials: usize,
    pub failures: usize,
    pub med_rot: f64,
    pub mean_rot: f64,
    pub med_t: f64,
    pub mean_t: f64,
    /// Median microseconds per solve (None: not timed).
    pub us: Option<f64>,
    pub note: Option<String>,
}

fn stats(method: Method, problems: &[Problem], poses: &[Option<Pose>]) -> Stats {
    let mut rot = Vec::new();
    let mut tr = Vec::new();
    let mut failures = 0;
    for (p, pose) in problems.iter().zip(poses) {
        let ok = pose.and_then(|(r, t)| {
            let (er, et) = (
                common::rot_err_deg(&r, &p.r_gt),
                common::trans_err_pct(&t, &p.t_gt),
            );
            (er.is_finite() && et.is_finite() && er <= FAIL_DEG).then_some((er, et))
        });
        match ok {
            Some((er, et)) => {
                rot.push(er);
                tr.push(et);
            }
            None => failures += 1,
        }
    }
    Stats {
        method,
        trials: problems.len(),
        failures,
        med_rot: common::median(&rot),
        mean_rot: common::mean(&rot),
        med_t: common::median(&tr),
        mean_t: common::mean(&tr),
        us: None,
        note: None,
    }
}

/// Median over `passes` of (time of one pass over all inputs) / (number of inputs), in us.
fn time_per_solve<T, R>(inputs: &[T], passes: usize, mut f: impl FnMut(&T) -> R) -> Option<f64> {
    if inputs.is_empty() {
        return None;
    }
    let mut per: Vec<f64> = (0..passes)
        .map(|_| {
            let t0 = Instant::now();
            for x in inputs {
                black_box(f(black_box(x)));
            }
            t0.elapsed().as_secs_f64() * 1e6 / inputs.len() as f64
        })
        .collect();
    per.sort_by(f64::total_cmp);
    Some(per[per.len() / 2])
}

fn eopnp_pose(s: &eopnp::Solution) -> Pose {
    (s.rotation, s.translation)
}

/// Runs one method on one row (accuracy pass, then timed passes).
fn run_method(
    method: Method,
    row_index: usize,
    row: &Row,
    problems: &[Problem],
    args: &Args,
    kornia_hangs_total: &mut usize,
) -> Option<Stats> {
    let passes = args.passes;
    match method {
        Method::EopnpDefault | Method::EopnpAlgebraic => {
            let solver = if method == Method::EopnpDefault {
                Solver::default()
            } else {
                Solver::default().refinement(Refinement::Algebraic)
            };
            let poses: Vec<_> = problems
                .iter()
                .map(|p| {
                    solver
                        .solve(&eopnp::Problem::normalised(&p.world, &p.image))
                        .ok()
                        .map(|s| eopnp_pose(&s))
                })
                .collect();
            let mut s = stats(method, problems, &poses);
            s.us = time_per_solve(problems, passes, |p| {
                solver.solve(&eopnp::Problem::normalised(&p.world, &p.image))
            });
            Some(s)
        }
        Method::Sqpnp => {
            let inputs: Vec<_> = problems.iter().map(peers::sqpnp_input).collect();
            let mut solver = peers::Sqpnp::new();
            let poses: Vec<_> = inputs.iter().map(|q| solver.solve(q)).collect();
            let mut s = stats(method, problems, &poses);
            s.us = time_per_solve(&inputs, passes, |q| solver.solve(q));
            Some(s)
        }
        Method::LambdaTwist => {
            if row.n != 4 {
                return None;
            }
            let inputs: Vec<_> = problems.iter().map(peers::lambda_input).collect();
            let poses: Vec<_> = inputs.iter().map(peers::lambda_twist).collect();
            let mut s = stats(method, problems, &poses);
            s.us = time_per_solve(&inputs, passes, peers::lambda_twist);
            Some(s)
        }
        Method::Kornia => {
            let inputs: Vec<_> = problems.iter().map(peers::kornia_input).collect();
            // The guarded accuracy pass runs in a child process (this program with
            // `--kornia-row`), so that the threads of hung calls, which keep a core busy,
            // die with it instead of disturbing the timings here; in-process if that fails.
            let outcomes = kornia_child(row_index, args)
                .filter(|o| o.len() == inputs.len())
                .unwrap_or_else(|| kornia_accuracy(&inputs, args));
            let mut poses = Vec::with_capacity(inputs.len());
            // Inputs whose call returned within the timeout: only these are timed (directly,
            // without the watchdog thread, whose spawn would dominate the time).
            let mut safe = Vec::with_capacity(inputs.len());
            let (mut hangs, mut panics, mut skipped) = (0usize, 0usize, 0usize);
            for (q, o) in inputs.iter().zip(outcomes) {
                match o {
                    KorniaOutcome::Returned(r) => {
                        safe.push(q.clone());
                        poses.push(r);
                    }
                    KorniaOutcome::Panicked => panics += 1,
                    KorniaOutcome::TimedOut => hangs += 1,
                    KorniaOutcome::Skipped => skipped += 1,
                }
                if !matches!(o, KorniaOutcome::Returned(_)) {
                    poses.push(None);
                }
            }
            *kornia_hangs_total += hangs;
            let mut s = stats(method, problems, &poses);
            s.us = time_per_solve(&safe, passes, peers::kornia);
            let mut notes = Vec::new();
            if hangs > 0 {
                notes.push(format!(
                    "{hangs} call(s) did not return within {} ms (counted as failures)",
                    args.kornia_timeout.as_millis()
                ));
            }
            if panics > 0 {
                notes.push(format!("{panics} call(s) panicked (counted as failures)"));
            }
            if skipped > 0 {
                notes.push(format!(
                    "{skipped} trial(s) not run after {KORNIA_MAX_HANGS_PER_ROW} hangs (counted \
                     as failures)"
                ));
            }
            if hangs + skipped + panics > 0 {
                notes.push(format!("time over the {} returning calls", safe.len()));
            }
            if !notes.is_empty() {
                s.note = Some(notes.join("; "));
            }
            Some(s)
        }
        Method::LmGt => {
            let poses: Vec<_> = problems
                .iter()
                .map(|p| {
                    let r = p.lm_from_gt();
                    Some((r.r, r.t))
                })
                .collect();
            Some(stats(method, problems, &poses))
        }
    }
}

/// One run of the measurement: every method on every row (kornia-pnp last: a hung kornia call
/// leaves a busy detached thread behind, which must not disturb the timings of the other
/// methods). Per row, the methods' statistics in table order; and the number of hung kornia
/// calls.
pub fn measure(all: &[(Row, Vec<Problem>)], args: &Args) -> (Vec<Vec<Stats>>, usize) {
    let mut results: Vec<Vec<Stats>> = vec![Vec::new(); all.len()];
    let mut kornia_hangs = 0usize;
    for phase_kornia in [false, true] {
        for (i, (row, probs)) in all.iter().enumerate() {
            for m in METHODS {
                if (m == Method::Kornia) != phase_kornia {
                    continue;
                }
                if let Some(s) = run_method(m, i, row, probs, args, &mut kornia_hangs) {
                    results[i].push(s);
                }
            }
            eprint!(".");
        }
    }
    eprintln!();
    for r in &mut results {
        r.sort_by_key(|s| METHODS.iter().position(|&m| m == s.method));
    }
    (results, kornia_hangs)
}
