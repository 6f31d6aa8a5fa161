//! Issue 14, weights: multiplying every weight by one positive constant, anywhere in the
//! positive finite f64 range, leaves the pose unchanged and multiplies the cost by the
//! constant; weights that leave fewer than 4 points above f64 resolution of the largest are
//! `TooFewPoints`, not a degeneracy of the points.
use common::{Problem, ProblemOptions, RotationKind, Scene};
use eopnp::{PnpError, Solution, Solver};
use eopnp_testkit as common;
use rand::Rng;

const TRIALS: u64 = 50;

fn problem(trial: u64, scene: Scene) -> (Problem, Vec<f64>) {
    let p = Problem::generate(&ProblemOptions {
        n: 12,
        sigma_px: 1.0,
        scene,
        rotation: RotationKind::Uniform,
        seed: common::trial_seed("weight_scale", trial),
    });
    let mut rng = common::rng_from_seed(common::trial_seed("weight_scale_w", trial));
    let w = (0..p.world.len())
        .map(|_| rng.random_range(0.5..2.0))
        .collect();
    (p, w)
}

/// `2^k` for any k whose result is representable (`powi` alone underflows below 2^-1022).
fn pow2(k: i32) -> f64 {
    2f64.powi(k / 2) * 2f64.powi(k - k / 2)
}

fn rot_diff_deg(a: &Solution, b: &Solution) -> f64 {
    common::rot_err_deg(&a.rotation, &b.rotation)
}

fn solve(p: &Problem, w: &[f64]) -> Solution {
    Solver::default()
        .solve(&eopnp::Problem::normalised(&p.world, &p.image).weights(w))
        .unwrap_or_else(|e| panic!("seed {:#x}: {e}", p.opts.seed))
}

/// Exact scalings (powers of two, from the smallest subnormal weights to weights near
/// f64::MAX): the same pose to the bit, the cost scaled exactly.
#[test]
fn power_of_two_scale_gives_the_same_pose() {
    for scene in [Scene::General, Scene::Planar] {
        for trial in 0..TRIALS {
            let (p, w) = problem(trial, scene);
            let base = solve(&p, &w);
            // 2^k * w stays exact while it is a normal number; for k < -1022 the weights are
            // first rounded to subnormals, so the reference is the pose at the rounded weights.
            for k in [
                -1070, -1060, -1030, -1000, -600, -100, -1, 1, 100, 600, 1000, 1022,
            ] {
                let c = pow2(k);
                let wc: Vec<f64> = w.iter().map(|x| x * c).collect();
                let exact = wc.iter().zip(&w).all(|(a, b)| a / c == *b);
                let reference = if exact {
                    base
                } else {
                    // Bring the rounded weights back to the normal range exactly.
                    let back: Vec<f64> = wc.iter().map(|x| x * pow2(530) * pow2(530)).collect();
                    solve(&p, &back)
                };
                let s = solve(&p, &wc);
                let seed = p.opts.seed;
                if k >= -1000 {
                    // Normal weights: `frame`'s weight unit undoes the scale exactly.
                    assert_eq!(s.rotation, reference.rotation, "seed {seed:#x} 2^{k}");
                    assert_eq!(s.translation, reference.translation, "seed {seed:#x} 2^{k}");
                    assert_eq!(s.reprojection_rmse, reference.reprojection_rmse);
                } else {
                    // Weights below 2^-1000 are taken in the unit 2^-1000 (whose reciprocal is
                    // finite), not near the largest weight: the same pose up to rounding.
                    let dr = rot_diff_deg(&s, &reference);
                    let dt = (s.translation - reference.translation).norm();
                    assert!(
                        dr <= 1e-10,
                        "seed {seed:#x} 2^{k}: rotation moved {dr:e} deg"
                    );
                    assert!(dt <= 1e-10 * reference.translation.norm());
                }
                let scale = if exact { c } else { pow2(-530) * pow2(-530) };
                // The cost is the caller's, so it is rounded to f64 like any result: below the
                // normal range only to the subnormal spacing (5e-324).
                let expected = reference.cost * scale;
                let ok = if expected >= f64::MIN_POSITIVE {
                    (s.cost / expected - 1.0).abs() <= 1e-12
                } else {
                    (s.cost - expected).abs() <= 2e-323
                };
                assert!(
                    ok,
                    "seed {seed:#x} 2^{k}: cost {:e}, expected {expected:e}",
                    s.cost
                );
            }
        }
    }
}

/// Any common constant over the normal range: the pose moves only by the rounding of the
/// scaled weights (a relative 1e-16 per weight).
#[test]
fn any_scale_gives_the_same_pose() {
    for trial in 0..TRIALS {
        let (p, w) = problem(trial, Scene::General);
        let base = solve(&p, &w);
        for c in [3e-300, 1e-200, 1e-100, 0.3, 7.0, 1e100, 1e200, 1e300, 1e306] {
            let wc: Vec<f64> = w.iter().map(|x| x * c).collect();
            let s = solve(&p, &wc);
            let seed = p.opts.seed;
            let dr = rot_diff_deg(&s, &base);
            let dt = (s.translation - base.translation).norm();
            assert!(
                dr <= 1e-10,
                "seed {seed:#x} c {c:e}: rotation moved {dr:e} deg"
            );
            assert!(
                dt <= 1e-10 * base.translation.norm(),
                "seed {seed:#x} c {c:e}: translation moved {dt:e}"
            );
            let ratio = s.cost / (base.cost * c);
            assert!(
                (ratio - 1.0).abs() <= 1e-9,
                "seed {seed:#x} c {c:e}: cost ratio {ratio}"
            );
        }
    }
}

/// Weights whose sum overflows f64 (each finite): still the same pose.
#[test]
fn weights_whose_sum_overflows() {
    let (p, w) = problem(0, Scene::General);
    let base = solve(&p, &w);
    let wc: Vec<f64> = w.iter().map(|x| x / 2.0 * f64::MAX).collect();
    assert!(wc.iter().all(|x| x.is_finite()) && !wc.iter().sum::<f64>().is_finite());
    let s = solve(&p, &wc);
    assert!(rot_diff_deg(&s, &base) <= 1e-10);
}

/// One weight 1e300 times the others: the other points are below f64 resolution of the
/// weighted sums, so the problem has one point (a typed `TooFewPoints`, not a claim that the
/// image points coincide). At a ratio of 1e12 the other points still count.
#[test]
fn one_dominant_weight() {
    for trial in 0..TRIALS {
        let (p, mut w) = problem(trial, Scene::General);
        w[3] = 1e300;
        let err = Solver::default()
            .solve(&eopnp::Problem::normalised(&p.world, &p.image).weights(&w))
            .unwrap_err();
        assert_eq!(err, PnpError::TooFewPoints { got: 1, need: 4 });
        w[3] = 1e12;
        let s = solve(&p, &w);
        assert!(s.cost.is_finite());
    }
}
