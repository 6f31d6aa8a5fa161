//! Soak test: many seeded random problems across every configuration of the accuracy tests plus
//! a few percent of near-degenerate inputs. Asserts: no panic, no `Ok` with a non-finite pose,
//! every call bounded in time (a hang detector, not a speed check: the bound is generous);
//! reports the failure count (rotation error > 5 degrees) against LM from the ground truth.
//!
//! - `cargo test --release --test soak` runs `SOAK_CI` problems (part of the normal suite);
//!   with `-- --nocapture` it prints the headline counts in one block (`report`).
//! - `cargo test --release --test soak -- --ignored --nocapture` runs 1,000,000 problems
//!   (override with `EOPNP_SOAK=<count>`); under a minute on 2 cores.

use eopnp_testkit as common;

use common::*;
use eopnp::Solver;
use nalgebra::{Point2, Point3};
use rand::Rng;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::time::{Duration, Instant};

/// Problems in the CI-sized run.
const SOAK_CI: u64 = 20_000;
/// Problems in the full run.
const SOAK_FULL: u64 = 1_000_000;
/// A call taking longer than this is treated as a hang (normal solves take microseconds to a
/// millisecond; the bound only has to catch unbounded loops on a loaded machine).
const HANG: Duration = Duration::from_secs(2);

#[derive(Default)]
struct Tally {
    problems: u64,
    ok: u64,
    errors: u64,
    degenerate_inputs: u64,
    failures: u64,
    failures_small: u64,
    errors_nondegenerate: u64,
    lm_failures: u64,
    lm_compared: u64,
    max_call: Duration,
    max_call_n: usize,
}

/// A near-degenerate variant of a generated problem (a few percent of the trials).
fn degrade(p: &mut Problem, kind: u32, rng: &mut rand_pcg::Pcg64) {
    match kind {
        // almost collinear: squeeze the points towards a line through the first two
        0 => {
            let eps = 10f64.powf(rng.random_range(-9.0..-3.0));
            let a = p.world[0].coords;
            let d = (p.world[1].coords - a).normalize();
            for x in p.world.iter_mut() {
                let v = x.coords - a;
                let along = d * v.dot(&d);
                *x = Point3::from(a + along + (v - along) * eps);
            }
        }
        // almost coincident world points
        1 => {
            let eps = 10f64.powf(rng.random_range(-14.0..-6.0));
            let a = p.world[0].coords;
            for x in p.world.iter_mut() {
                *x = Point3::from(a + (x.coords - a) * eps);
            }
        }
        // tiny or huge world scale
        2 => {
            let s = if rng.random_bool(0.5) { 1e-150 } else { 1e150 };
            for x in p.world.iter_mut() {
                *x = Point3::from(x.coords * s);
            }
        }
        // almost coincident image points
        _ => {
            let eps = 10f64.powf(rng.random_range(-14.0..-8.0));
            let a = p.image[0].coords;
            for m in p.image.iter_mut() {
                *m = Point2::from(a + (m.coords - a) * eps);
            }
        }
    }
}

fn soak(count: u64) -> Tally {
    let solver = Solver::default();
    let mut t = Tally::default();
    for trial in 0..count {
        let seed = trial_seed("soak", trial);
        let mut rng = rng_from_seed(seed ^ 0x50A6);
        // N log-uniform in 4..1000, weighted towards small N where the search is hardest.
        let n = (4.0 * 250f64.powf(rng.random::<f64>().powi(2))).round() as usize;
        let scene = match rng.random_range(0..3) {
            0 => Scene::General,
            1 => Scene::Planar,
            _ => Scene::QuasiSingular,
        };
        let rotation = if rng.random_bool(0.2) {
            RotationKind::Near180
        } else {
            RotationKind::Uniform
        };
        let sigma_px = if rng.random_bool(0.1) {
            0.0
        } else {
            rng.random_range(0.0..10.0)
        };
        let mut p = Problem::generate(&ProblemOptions {
            n,
            sigma_px,
            scene,
            rotation,
            seed,
        });
        let degenerate = rng.random_bool(0.03);
        if degenerate {
            degrade(&mut p, rng.random_range(0..4), &mut rng);
            t.degenerate_inputs += 1;
        }
        let start = Instant::now();
        let result = catch_unwind(AssertUnwindSafe(|| {
            solver.solve(&eopnp::Problem::normalised(&p.world, &p.image))
        }));
        let took = start.elapsed();
        if took > t.max_call {
            t.max_call = took;
            t.max_call_n = n;
        }
        assert!(
            took < HANG,
            "call took {took:?} (seed {seed}, N = {n}, {scene:?})"
        );
        let result = result.unwrap_or_else(|_| panic!("solve panicked (seed {seed})"));
        t.problems += 1;
        match result {
            Ok(s) => {
                t.ok += 1;
                assert!(
                    s.rotation.iter().all(|x| x.is_finite())
                        && s.translation.iter().all(|x| x.is_finite()),
                    "Ok with a non-finite pose (seed {seed})"
                );
                if !degenerate {
                    let (er, _) = p.errors(&s.rotation, &s.translation);
                    if er > 5.0 {
                        t.failures += 1;
                        if n <= 20 {
                            t.failures_small += 1;
                        }
                    }
                    // The ML reference is costly at large N; compare on the small problems,
                    // where failures happen.
                    if n <= 20 {
                        let lm = p.lm_from_gt();
                        t.lm_compared += 1;
                        if p.errors(&lm.r, &lm.t).0 > 5.0 {
                            t.lm_failures += 1;
                        }
                    }
                }
            }
            Err(_) => {
                t.errors += 1;
                if !degenerate {
                    t.errors_nondegenerate += 1;
                }
            }
        }
    }
    report(&t);
    t
}

/// `n` with thousands separators (1,249).
fn thousands(n: u64) -> String {
    let digits = n.to_string();
    let mut out = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

/// Prints the headline counts in one block (the README and the comments quote it from
/// `cargo test --release --test soak -- --nocapture`). Panics and non-finite `Ok` poses stop
/// the run where they happen, so a finished run has 0 of each.
fn report(t: &Tally) {
    let row = |what: &str, value: String| println!("  {what:<52} {value:>9}");
    println!("soak: {} problems", thousands(t.problems));
    row("panics", "0".into());
    row("Ok with a non-finite pose", "0".into());
    row(
        &format!(
            "typed errors, near-degenerate inputs (of {})",
            thousands(t.degenerate_inputs)
        ),
        thousands(t.errors - t.errors_nondegenerate),
    );
    row(
        "typed errors, non-degenerate inputs",
        thousands(t.errors_nondegenerate),
    );
    row(
        "rotation error > 5 deg, non-degenerate, all N: eopnp",
        thousands(t.failures),
    );
    println!(
        "  rotation error > 5 deg on the {} non-degenerate problems with N <= 20:",
        thousands(t.lm_compared)
    );
    row("  eopnp", thousands(t.failures_small));
    row("  LM from the ground truth", thousands(t.lm_failures));
    row(
        "  eopnp / LM - 1",
        format!(
            "{:+.1} %",
            100.0 * (t.failures_small as f64 / t.lm_failures as f64 - 1.0)
        ),
    );
    row(
        &format!("longest call (N = {})", t.max_call_n),
        format!("{:.1} ms", t.max_call.as_secs_f64() * 1e3),
    );
}

#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "release-mode suite: cargo test --release --test soak"
)]
fn soak_ci_size() {
    let t = soak(SOAK_CI);
    assert_eq!(t.problems, SOAK_CI);
    assert_headline(&t);
}

/// The headline counts the README states (panics and non-finite `Ok` poses fail inside
/// [`soak`] at once): no typed error on a non-degenerate input, and on the problems with
/// N <= 20, where failures happen, no more than 10 % more rotation errors above 5 degrees than
/// LM started at the ground truth. Measured (the block [`report`] prints, at the commit that
/// added it): `cargo test --release --test soak -- --nocapture`, 20,000 problems: 1,233 vs
/// 1,171 on the 10,580 non-degenerate problems with N <= 20 (+5.3 %), 0 typed errors on
/// non-degenerate inputs, 110 on the 615 near-degenerate ones; with `-- --ignored`,
/// 1,000,000 problems: 63,563 vs 60,519 on 527,100 (+5.0 %), 0 and 5,075 of 30,210.
fn assert_headline(t: &Tally) {
    assert_eq!(
        t.errors_nondegenerate, 0,
        "typed errors on non-degenerate inputs"
    );
    assert!(t.lm_compared > 0);
    assert!(
        t.failures_small as f64 <= 1.10 * t.lm_failures as f64,
        "{} failures with N <= 20 against {} for LM from the ground truth",
        t.failures_small,
        t.lm_failures
    );
}

#[test]
#[ignore = "1,000,000 problems: cargo test --release --test soak -- --ignored --nocapture"]
fn soak_full() {
    let count = std::env::var("EOPNP_SOAK")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(SOAK_FULL);
    let t = soak(count);
    assert_eq!(t.problems, count);
    assert_headline(&t);
}
