//! Exhaustive against default search, algebraic mode, for the README:
//! `cargo run --release --example exhaustive [-- TRIALS]` (default 2,000 trials per
//! combination).
//!
//! For every scene type (general, planar, quasi-singular), pixel noise sigma (0, 2, 5, 10 px)
//! and N (6, 8, 10, 15, 50), the same seeded problems (`eopnp-testkit`) are solved with
//! `Refinement::Algebraic`, once in the default mode (certified fast path, basin skipping)
//! and once with `exhaustive(true)` (every start refined to convergence). Two poses "differ"
//! when their rotations are more than 1e-4 degrees apart (two runs into the same minimum agree
//! to ~1e-9 degrees; distinct minima are degrees apart) or one of the two is an error. Prints
//! one Markdown row per combination: trials that differ, of those how many have a larger
//! rotation error (against the ground truth) in the default mode, and the largest rotation
//! difference; then the totals.

use eopnp_testkit as common;

use common::{rot_err_deg, trial_seed, Problem, ProblemOptions, RotationKind, Scene};
use eopnp::{Refinement, Solver};

/// Rotations further apart than this (degrees) are different minima.
const DIFFER_DEG: f64 = 1e-4;

fn main() {
    let trials: u64 = std::env::args()
        .nth(1)
        .map(|a| a.parse().expect("TRIALS must be a number"))
        .unwrap_or(2000);
    let default = Solver::default().refinement(Refinement::Algebraic);
    let exhaustive = default.exhaustive(true);
    println!(
        "Algebraic mode, default vs exhaustive search, {trials} trials per combination \
         (seeded; `cargo run --release --example exhaustive -- {trials}`)"
    );
    println!();
    println!("| scene | sigma (px) | N | trials that differ | default worse | largest rotation difference (deg) |");
    println!("|---|---|---|---|---|---|");
    let (mut total, mut total_differ, mut total_worse, mut max_per_combination) =
        (0u64, 0u64, 0u64, 0u64);
    let mut errors = 0u64;
    for (scene_name, scene) in [
        ("general", Scene::General),
        ("planar", Scene::Planar),
        ("quasi-singular", Scene::QuasiSingular),
    ] {
        for sigma in [0.0, 2.0, 5.0, 10.0] {
            for n in [6usize, 8, 10, 15, 50] {
                let (mut differ, mut worse) = (0u64, 0u64);
                let mut largest = 0.0f64;
                for trial in 0..trials {
                    let seed = trial_seed(
                        &format!("exhaustive-example {scene_name} {sigma} {n}"),
                        trial,
                    );
                    let p = Problem::generate(&ProblemOptions {
                        n,
                        sigma_px: sigma,
                        scene,
                        rotation: RotationKind::Uniform,
                        seed,
                    });
                    let a = default.solve(&eopnp::Problem::normalised(&p.world, &p.image));
                    let b = exhaustive.solve(&eopnp::Problem::normalised(&p.world, &p.image));
                    match (&a, &b) {
                        (Ok(a), Ok(b)) => {
                            let d = rot_err_deg(&a.rotation, &b.rotation);
                            largest = largest.max(d);
                            if d > DIFFER_DEG {
                                differ += 1;
                                if rot_err_deg(&a.rotation, &p.r_gt)
                                    > rot_err_deg(&b.rotation, &p.r_gt)
                                {
                                    worse += 1;
                                }
                            }
                        }
                        (Err(_), Err(_)) => errors += 2,
                        (Err(_), Ok(_)) => {
                            errors += 1;
                            differ += 1;
                            worse += 1;
                        }
                        (Ok(_), Err(_)) => {
                            errors += 1;
                            differ += 1;
                        }
                    }
                }
                println!("| {scene_name} | {sigma} | {n} | {differ} | {worse} | {largest:.2e} |");
                total += trials;
                total_differ += differ;
                total_worse += worse;
                max_per_combination = max_per_combination.max(differ);
            }
        }
    }
    println!();
    println!(
        "{total} trials in 60 combinations: {total_differ} differ (at most {max_per_combination} \
         in one combination), {total_worse} with a larger rotation error in the default mode; \
         {errors} errors"
    );
}
