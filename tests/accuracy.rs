//! Statistical accuracy suites (docs/algorithm.md section 7 protocol). RELEASE MODE ONLY:
//!
//! ```sh
//! cargo test --release --test accuracy -- --nocapture     # prints the measured tables
//! ```
//!
//! In debug builds every test here is ignored (they run hundreds of thousands of solves).
//! Every trial is reproducible from the seed printed with it (`common::Problem::generate`).
//! `EOPNP_TEST_SEED` changes the suite seed. `EOPNP_ACCURACY_QUICK=1` divides every trial
//! count by 100 for a smoke run (it prints a warning; the tolerances do not change, and a
//! quick run is not a pass of this suite).
//!
//! 1. Noise-free: 10,000 trials per (N, scene, rotation kind), N = 4, 5, 6, 10, 100, 1000,
//!    scenes General / Planar / QuasiSingular, rotations Uniform / Near180 (the same at the
//!    CGR singularity of the solver's own frame: `tests/unit/pipeline/driver.rs`). Rotation
//!    error < 1e-6 deg and |t - t_gt| / |t_gt| < 1e-8. The same
//!    for algebraic mode (no `refine` stage) with 1,000 trials per configuration.
//! 2. Noisy (paper protocol, General, Uniform): N = 6..15 at sigma = 2 px and N = 10 at
//!    sigma = 0.5, 1, 2, 3, 5 px, 4,000 trials each: default mode mean and median rotation and
//!    translation errors within 1 % of the LM-from-ground-truth reference, algebraic mode within
//!    8 %; never a rotation error above 5 deg where the reference is below 1 deg.
//! 3. N = 4, 5 (4,000 trials each): `solve_all` contains the maximum-likelihood pose (LM from
//!    the ground truth, run to convergence) in >= 99 % of the trials: a candidate within 1e-5
//!    degrees and 1e-7 relative of it, or with a pixel reprojection cost at most its cost
//!    times (1 + 1e-9).

// `!(err <= tol)` is deliberate throughout: a NaN error must fail the check.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use eopnp_testkit as common;

use common::*;
use eopnp::{Refinement, Solver};

/// Noise-free suite: rotation error bound, degrees. The reference prototype's worst case over
/// 1000 trials per cell is 5.5e-10 deg (planar N = 4; typically 1e-13); 1e-6 deg is the
/// accuracy promised for noise-free input, and far above rounding, so a failure is an algorithmic miss.
const NOISE_FREE_ROT_DEG: f64 = 1e-6;
/// Noise-free suite: relative translation error bound |t - t_gt| / |t_gt| (the promised
/// "relative translation error < 1e-8"; the prototype's worst case is 1e-12 relative).
const NOISE_FREE_T_REL: f64 = 1e-8;
/// Trials per noise-free configuration.
const NOISE_FREE_TRIALS: u64 = 10_000;
/// Trials per noise-free configuration in algebraic mode (an extra check; see its test).
const NOISE_FREE_ALGEBRAIC_TRIALS: u64 = 1_000;
/// Trials per noisy configuration (at least 1,000). At 1,000 trials the sampling noise of a
/// *median* ratio is comparable to the gap between the algebraic mode's inherent bias (3-6 %,
/// docs/algorithm.md, `refine`) and the 8 % bound: measured, N = 13 sigma = 2 gave a median
/// rotation ratio of 1.084 with 1,000 trials and 1.061 with 4,000 (all other ratios 1.025-1.056).
/// More trials reduce the noise; the tolerance is unchanged.
const NOISY_TRIALS: u64 = 4_000;
/// `solve_all` suite: a candidate is the ML pose (LM from the ground truth, run to
/// convergence) when its rotation is within this many degrees of it (and its translation within
/// [`SOLVE_ALL_T_REL`]): two correct minimisers of the same cost agree to ~1e-9 degrees
/// (docs/algorithm.md, `refine`; the LM reference against scipy: at most 2.6e-7), distinct local
/// minima are degrees apart.
const SOLVE_ALL_ROT_DEG: f64 = 1e-5;
/// `solve_all` suite: translation tolerance relative to |t_LM| (see [`SOLVE_ALL_ROT_DEG`]).
const SOLVE_ALL_T_REL: f64 = 1e-7;
/// Point counts of the noise-free suite.
const NOISE_FREE_NS: [usize; 6] = [4, 5, 6, 10, 100, 1000];

/// Failure log: counts every failure, keeps the first few messages (each with its seed).
#[derive(Default)]
struct Failures {
    count: usize,
    shown: Vec<String>,
}

impl Failures {
    fn push(&mut self, msg: String) {
        self.count += 1;
        if self.shown.len() < 20 {
            self.shown.push(msg);
        }
    }

    fn extend(&mut self, other: Failures) {
        self.count += other.count;
        for m in other.shown {
            if self.shown.len() < 20 {
                self.shown.push(m);
            }
        }
    }

    fn assert_none(self) {
        assert!(
            self.count == 0,
            "{} failure(s); the first ones (reproduce with Problem::generate and the seed):\n{}",
            self.count,
            self.shown.join("\n")
        );
    }
}

/// Trial count after the optional smoke-run divisor.
fn trials(base: u64) -> u64 {
    if std::env::var("EOPNP_ACCURACY_QUICK").is_ok_and(|v| v != "0") {
        eprintln!(
            "WARNING: EOPNP_ACCURACY_QUICK set: {} instead of {base} trials (smoke run only)",
            base / 100
        );
        (base / 100).max(1)
    } else {
        base
    }
}

/// Runs the noise-free suite for one (scene, rotation kind, solver) over all N; returns the
/// failure messages (each with its seed).
fn noise_free(
    label: &str,
    scene: Scene,
    rotation: RotationKind,
    solver: &Solver,
    base_trials: u64,
) -> Failures {
    let mut failures = Failures::default();
    eprintln!(
        "noise-free {label:>10} {scene:>13?} {rotation:>7?}: {:>5} {:>7} {:>10} {:>10} {:>10} {:>6}",
        "N", "trials", "max deg", "median deg", "max t rel", "fails"
    );
    for n in NOISE_FREE_NS {
        let name = format!("accuracy/noise_free/{label}/{scene:?}/{rotation:?}/{n}");
        let count = trials(base_trials);
        let mut rot = Vec::with_capacity(count as usize);
        let mut trans = Vec::with_capacity(count as usize);
        let mut fails = 0usize;
        for trial in 0..count {
            let seed = trial_seed(&name, trial);
            let p = Problem::generate(&ProblemOptions {
                n,
                sigma_px: 0.0,
                scene,
                rotation,
                seed,
            });
            let msg = match solver.solve(&eopnp::Problem::normalised(&p.world, &p.image)) {
                Err(e) => {
                    rot.push(f64::NAN);
                    trans.push(f64::NAN);
                    Some(format!("error {e:?}"))
                }
                Ok(sol) => {
                    let (r, t) = pose_of(&sol);
                    let (er, et) = p.errors(&r, &t);
                    rot.push(er);
                    trans.push(et);
                    if !(er < NOISE_FREE_ROT_DEG && et < NOISE_FREE_T_REL) {
                        Some(format!("rotation {er:e} deg, translation {et:e} relative"))
                    } else if !sol.cheirality_ok {
                        // Every point is in front of the exact pose.
                        Some("cheirality_ok == false at the exact pose".to_owned())
                    } else {
                        None
                    }
                }
            };
            if let Some(m) = msg {
                fails += 1;
                failures.push(format!(
                    "[{label} {scene:?} {rotation:?} N={n} trial {trial} seed {seed:#x}] {m}"
                ));
            }
        }
        eprintln!(
            "noise-free {label:>10} {scene:>13?} {rotation:>7?}: {n:>5} {count:>7} {:>10.2e} {:>10.2e} {:>10.2e} {fails:>6}",
            max_of(&rot),
            median(&rot),
            max_of(&trans)
        );
    }
    failures
}

#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "release-mode suite: cargo test --release --test accuracy"
)]
fn noise_free_general_uniform() {
    noise_free(
        "default",
        Scene::General,
        RotationKind::Uniform,
        &Solver::default(),
        NOISE_FREE_TRIALS,
    )
    .assert_none();
}

#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "release-mode suite: cargo test --release --test accuracy"
)]
fn noise_free_general_near180() {
    noise_free(
        "default",
        Scene::General,
        RotationKind::Near180,
        &Solver::default(),
        NOISE_FREE_TRIALS,
    )
    .assert_none();
}

#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "release-mode suite: cargo test --release --test accuracy"
)]
fn noise_free_planar_uniform() {
    noise_free(
        "default",
        Scene::Planar,
        RotationKind::Uniform,
        &Solver::default(),
        NOISE_FREE_TRIALS,
    )
    .assert_none();
}

#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "release-mode suite: cargo test --release --test accuracy"
)]
fn noise_free_planar_near180() {
    noise_free(
        "default",
        Scene::Planar,
        RotationKind::Near180,
        &Solver::default(),
        NOISE_FREE_TRIALS,
    )
    .assert_none();
}

#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "release-mode suite: cargo test --release --test accuracy"
)]
fn noise_free_quasi_singular_uniform() {
    noise_free(
        "default",
        Scene::QuasiSingular,
        RotationKind::Uniform,
        &Solver::default(),
        NOISE_FREE_TRIALS,
    )
    .assert_none();
}

#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "release-mode suite: cargo test --release --test accuracy"
)]
fn noise_free_quasi_singular_near180() {
    noise_free(
        "default",
        Scene::QuasiSingular,
        RotationKind::Near180,
        &Solver::default(),
        NOISE_FREE_TRIALS,
    )
    .assert_none();
}

#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "release-mode suite: cargo test --release --test accuracy"
)]
fn noise_free_algebraic_mode() {
    // The algebraic mode alone must also be exact on noise-free data (docs/algorithm.md section 7
    // measures exactly this mode). Same bounds, all scenes and rotation kinds, but 1,000 trials per
    // configuration (36,000 solves, to stay within the runtime budget of one test); the
    // 10,000-trial requirement is carried by the default-mode tests above.
    let solver = Solver::default().refinement(Refinement::Algebraic);
    let mut failures = Failures::default();
    for scene in [Scene::General, Scene::Planar, Scene::QuasiSingular] {
        for rotation in [RotationKind::Uniform, RotationKind::Near180] {
            failures.extend(noise_free(
                "algebraic",
                scene,
                rotation,
                &solver,
                NOISE_FREE_ALGEBRAIC_TRIALS,
            ));
        }
    }
    failures.assert_none();
}

/// Per-trial errors of one noisy configuration.
struct NoisyRun {
    default_rot: Vec<f64>,
    default_t: Vec<f64>,
    alg_rot: Vec<f64>,
    alg_t: Vec<f64>,
    lm_rot: Vec<f64>,
    lm_t: Vec<f64>,
    failures: Failures,
}

/// Paper protocol for one (N, sigma): default mode, algebraic mode and LM-from-GT on the same
/// trials. Translation errors in percent.
fn noisy_run(n: usize, sigma: f64) -> NoisyRun {
    let name = format!("accuracy/noisy/{n}/{sigma}");
    let default = Solver::default();
    let algebraic = Solver::default().refinement(Refinement::Algebraic);
    let count = trials(NOISY_TRIALS) as usize;
    let mut run = NoisyRun {
        default_rot: Vec::with_capacity(count),
        default_t: Vec::with_capacity(count),
        alg_rot: Vec::with_capacity(count),
        alg_t: Vec::with_capacity(count),
        lm_rot: Vec::with_capacity(count),
        lm_t: Vec::with_capacity(count),
        failures: Failures::default(),
    };
    for trial in 0..count as u64 {
        let seed = trial_seed(&name, trial);
        let p = Problem::generate(&ProblemOptions {
            n,
            sigma_px: sigma,
            scene: Scene::General,
            rotation: RotationKind::Uniform,
            seed,
        });
        let lm = p.lm_from_gt();
        let (lr, lt) = p.errors(&lm.r, &lm.t);
        run.lm_rot.push(lr);
        run.lm_t.push(100.0 * lt);
        for (mode, solver) in [("default", &default), ("algebraic", &algebraic)] {
            let (er, et) = match solver.solve(&eopnp::Problem::normalised(&p.world, &p.image)) {
                Ok(sol) => {
                    let (r, t) = pose_of(&sol);
                    let (er, et) = p.errors(&r, &t);
                    (er, 100.0 * et)
                }
                Err(e) => {
                    run.failures.push(format!(
                        "[N={n} sigma={sigma} {mode} seed {seed:#x}] error {e:?}"
                    ));
                    (f64::NAN, f64::NAN)
                }
            };
            // A gross failure where the maximum-likelihood estimate is good (N >= 6).
            if n >= 6 && lr < 1.0 && !(er <= 5.0) {
                run.failures.push(format!(
                    "[N={n} sigma={sigma} {mode} seed {seed:#x}] rotation error {er} deg, LM-from-GT {lr} deg"
                ));
            }
            if mode == "default" {
                run.default_rot.push(er);
                run.default_t.push(et);
            } else {
                run.alg_rot.push(er);
                run.alg_t.push(et);
            }
        }
    }
    run
}

/// Checks the mean / median ratios of one noisy configuration and prints its table row.
fn check_noisy(n: usize, sigma: f64, failures: &mut Failures) {
    let mut run = noisy_run(n, sigma);
    failures.extend(std::mem::take(&mut run.failures));
    let stats = |v: &[f64]| (mean(v), median(v));
    let (lr_mean, lr_med) = stats(&run.lm_rot);
    let (lt_mean, lt_med) = stats(&run.lm_t);
    let rows = [
        ("default", &run.default_rot, &run.default_t, 0.01),
        ("algebraic", &run.alg_rot, &run.alg_t, 0.08),
    ];
    for (mode, rot, trans, tol) in rows {
        let (r_mean, r_med) = stats(rot);
        let (t_mean, t_med) = stats(trans);
        let ratios = [
            ("mean rotation", r_mean / lr_mean),
            ("median rotation", r_med / lr_med),
            ("mean translation", t_mean / lt_mean),
            ("median translation", t_med / lt_med),
        ];
        eprintln!(
            "noisy N={n:>2} sigma={sigma:>3}: {mode:>9} rot mean {r_mean:.4} med {r_med:.4} | t% mean {t_mean:.4} med {t_med:.4} | ratios to LM-from-GT {:.4} {:.4} {:.4} {:.4}",
            ratios[0].1, ratios[1].1, ratios[2].1, ratios[3].1
        );
        for (what, ratio) in ratios {
            // Default mode: `refine` reaches the LM-from-GT minimum within 1e-6 deg in 1000/1000
            // trials for N >= 5 (docs/algorithm.md, `refine`), so the statistics coincide; 1 % is
            // the requirement. Algebraic mode: the stages up to `select` minimise f, whose
            // minimiser is 3-5 % worse (docs/algorithm.md, `refine`: ratio of means 1.030-1.049;
            // per-configuration ratios of means and medians of the reference prototype's noisy
            // runs: 0.995-1.065 for these configurations); 8 % is the requirement.
            if !((ratio - 1.0).abs() <= tol) {
                failures.push(format!(
                    "[N={n} sigma={sigma}] {mode} {what} / LM-from-GT = {ratio:.4} (allowed 1 +- {tol})"
                ));
            }
        }
    }
    eprintln!(
        "noisy N={n:>2} sigma={sigma:>3}: {:>9} rot mean {lr_mean:.4} med {lr_med:.4} | t% mean {lt_mean:.4} med {lt_med:.4}",
        "LM-GT"
    );
}

#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "release-mode suite: cargo test --release --test accuracy"
)]
fn noisy_point_count_sweep() {
    let mut failures = Failures::default();
    for n in 6..=15 {
        check_noisy(n, 2.0, &mut failures);
    }
    failures.assert_none();
}

#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "release-mode suite: cargo test --release --test accuracy"
)]
fn noisy_noise_level_sweep() {
    let mut failures = Failures::default();
    for sigma in [0.5, 1.0, 3.0, 5.0] {
        // sigma = 2 at N = 10 is part of noisy_point_count_sweep.
        check_noisy(10, sigma, &mut failures);
    }
    failures.assert_none();
}

#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "release-mode suite: cargo test --release --test accuracy"
)]
fn solve_all_contains_ml_pose_n4_n5() {
    let solver = Solver::default();
    let mut failures = Failures::default();
    for n in [4usize, 5] {
        let name = format!("accuracy/solve_all/{n}");
        let count = trials(NOISY_TRIALS);
        let (mut hits, mut by_pose, mut by_cost, mut lm_unconverged) = (0u64, 0u64, 0u64, 0u64);
        let mut misses = Vec::new();
        let (mut best_rot, mut lm_rot) = (Vec::new(), Vec::new());
        let mut closest = Vec::new();
        for trial in 0..count {
            let seed = trial_seed(&name, trial);
            let p = Problem::generate(&ProblemOptions {
                n,
                sigma_px: 2.0,
                scene: Scene::General,
                rotation: RotationKind::Uniform,
                seed,
            });
            // The ML pose: LM from the ground truth, run to convergence.
            let lm = p.lm_from_gt();
            lm_unconverged += u64::from(!lm.converged);
            lm_rot.push(p.errors(&lm.r, &lm.t).0);
            let all = match solver.solve_all(&eopnp::Problem::normalised(&p.world, &p.image)) {
                Ok(all) => all,
                Err(e) => {
                    misses.push(format!("seed {seed:#x}: error {e:?}"));
                    continue;
                }
            };
            if let Some(best) = all.iter().next() {
                let (r, t) = pose_of(best);
                best_rot.push(p.errors(&r, &t).0);
            }
            let (mut pose_match, mut cost_match) = (false, false);
            let mut nearest = f64::INFINITY;
            for s in all.iter() {
                let (r, t) = pose_of(s);
                let (dr, dt) = (rot_err_deg(&r, &lm.r), trans_err_rel(&t, &lm.t));
                nearest = nearest.min(dr);
                pose_match |= dr <= SOLVE_ALL_ROT_DEG && dt <= SOLVE_ALL_T_REL;
                let cost = reprojection_cost(&p.world, &p.pixels, &r, &t, PIXEL_CAMERA);
                cost_match |= cost <= lm.cost * (1.0 + 1e-9);
            }
            closest.push(nearest);
            by_pose += u64::from(pose_match);
            by_cost += u64::from(cost_match);
            if pose_match || cost_match {
                hits += 1;
            } else if misses.len() < 10 {
                misses.push(format!(
                    "seed {seed:#x}: the ML pose is not among the {} candidates (closest {nearest:.3e} deg away; LM-from-GT {} deg off the truth)",
                    all.len(),
                    p.errors(&lm.r, &lm.t).0
                ));
            }
        }
        let rate = hits as f64 / count as f64;
        closest.sort_by(f64::total_cmp);
        eprintln!(
            "solve_all N={n}: {hits}/{count} trials contain the ML pose ({:.2} %): {by_pose} by pose \
             (<= {SOLVE_ALL_ROT_DEG:e} deg, <= {SOLVE_ALL_T_REL:e} relative), {by_cost} by cost \
             (<= LM-from-GT's x (1 + 1e-9)); LM not converged in {lm_unconverged}; closest \
             candidate to the ML pose: median {:.2e} deg, 99th percentile {:.2e} deg; ranked-first \
             mean rot {:.4} deg (median {:.4}), LM-from-GT mean {:.4} (median {:.4})",
            100.0 * rate,
            closest[closest.len() / 2],
            closest[closest.len() * 99 / 100],
            mean(&best_rot),
            median(&best_rot),
            mean(&lm_rot),
            median(&lm_rot)
        );
        // Requirement: >= 99 % of the trials.
        if rate < 0.99 {
            failures.push(format!(
                "N={n}: only {:.2} % of the trials; e.g.\n{}",
                100.0 * rate,
                misses.join("\n")
            ));
        }
    }
    failures.assert_none();
}
