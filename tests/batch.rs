//! The batch API (feature `rayon`): every result equals the one-problem call, whatever the
//! thread count, for plain and RANSAC solves, normalised and pixel input, with and without
//! weights, and for bad problems (the same typed error).
use eopnp::camera::Camera;
use eopnp::ransac::problem_seed;
use eopnp::ransac::Ransac;
use eopnp::Problem;
use eopnp::Solver;
use eopnp_testkit::{self as common, Problem as Synth, ProblemOptions, RotationKind, Scene};
use nalgebra::Point2;

struct Owned {
    p: Synth,
    pixels: Vec<Point2<f64>>,
    weights: Vec<f64>,
}

fn owned(k: u64) -> Owned {
    let mut p = Synth::generate(&ProblemOptions {
        n: 10 + (k % 40) as usize,
        sigma_px: 1.0,
        scene: if k.is_multiple_of(5) {
            Scene::Planar
        } else {
            Scene::General
        },
        rotation: RotationKind::Uniform,
        seed: common::trial_seed("batch", k),
    });
    // Every seventh problem is bad: a NaN image point.
    if k % 7 == 3 {
        p.image[2].x = f64::NAN;
        p.pixels[2].x = f64::NAN;
    }
    // A few wrong correspondences for RANSAC.
    for m in p.pixels.iter_mut().take(2) {
        m.x += 60.0;
    }
    let pixels = p.pixels.clone();
    let weights = (0..p.world.len()).map(|i| 0.5 + (i % 3) as f64).collect();
    Owned { p, pixels, weights }
}

fn problems<'a>(data: &'a [Owned], cam: &'a Camera) -> Vec<Problem<'a>> {
    data.iter()
        .enumerate()
        .map(|(k, o)| match k % 4 {
            0 => Problem::normalised(&o.p.world, &o.p.image).focal(800.0, 800.0),
            1 => Problem::normalised(&o.p.world, &o.p.image)
                .focal(800.0, 800.0)
                .weights(&o.weights),
            2 => Problem::pixels(&o.p.world, &o.pixels, cam),
            _ => Problem::pixels(&o.p.world, &o.pixels, cam).weights(&o.weights),
        })
        .collect()
}

#[test]
fn batch_equals_one_by_one_on_any_thread_count() {
    let cam = Camera::pinhole(800.0, 800.0, 320.0, 240.0).unwrap();
    let data: Vec<Owned> = (0..200).map(owned).collect();
    let batch = problems(&data, &cam);
    let solver = Solver::default();
    let ransac = Ransac::default().seed(11);
    // One by one, through the one-problem entry points.
    let serial: Vec<_> = data
        .iter()
        .enumerate()
        .map(|(k, o)| match k % 4 {
            0 => solver.solve(&Problem::normalised(&o.p.world, &o.p.image)),
            1 => solver.solve(&Problem::normalised(&o.p.world, &o.p.image).weights(&o.weights)),
            2 => solver.solve(&Problem::pixels(&o.p.world, &o.pixels, &cam)),
            _ => solver.solve(&Problem::pixels(&o.p.world, &o.pixels, &cam).weights(&o.weights)),
        })
        .collect();
    let serial_ransac: Vec<_> = data
        .iter()
        .enumerate()
        .map(|(k, o)| {
            let r = ransac.seed(problem_seed(11, k));
            match k % 4 {
                0 => r.estimate(
                    &solver,
                    &Problem::normalised(&o.p.world, &o.p.image).focal(800.0, 800.0),
                ),
                1 => r.estimate(
                    &solver,
                    &Problem::normalised(&o.p.world, &o.p.image)
                        .focal(800.0, 800.0)
                        .weights(&o.weights),
                ),
                2 => r.estimate(&solver, &Problem::pixels(&o.p.world, &o.pixels, &cam)),
                _ => r.estimate(
                    &solver,
                    &Problem::pixels(&o.p.world, &o.pixels, &cam).weights(&o.weights),
                ),
            }
        })
        .collect();
    // (A NaN pixel is left out by undistortion, a NaN normalised point is an error.)
    assert!(serial.iter().filter(|r| r.is_err()).count() >= 10);
    for threads in [1, 2, 3] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let (plain, robust) = pool.install(|| {
            (
                solver.solve_batch(&batch),
                ransac.estimate_batch(&solver, &batch),
            )
        });
        assert_eq!(plain.len(), serial.len());
        for (k, (a, b)) in plain.iter().zip(&serial).enumerate() {
            match (a, b) {
                (Ok(a), Ok(b)) => {
                    assert_eq!(a.pose(), b.pose(), "{threads} threads, problem {k}");
                    assert_eq!(a.cost, b.cost, "{threads} threads, problem {k}");
                }
                (Err(a), Err(b)) => assert_eq!(a, b, "{threads} threads, problem {k}"),
                _ => panic!("{threads} threads, problem {k}: {a:?} vs {b:?}"),
            }
        }
        for (k, (a, b)) in robust.iter().zip(&serial_ransac).enumerate() {
            match (a, b) {
                (Ok(a), Ok(b)) => {
                    assert_eq!(
                        a.solution.pose(),
                        b.solution.pose(),
                        "{threads} threads, problem {k}"
                    );
                    assert_eq!(a.inliers, b.inliers, "{threads} threads, problem {k}");
                    assert_eq!(a.stats.iterations, b.stats.iterations);
                }
                (Err(a), Err(b)) => assert_eq!(a, b, "{threads} threads, problem {k}"),
                _ => panic!("{threads} threads, problem {k}: {a:?} vs {b:?}"),
            }
        }
    }
}

#[test]
fn problem_seeds_differ() {
    let mut seeds: Vec<u64> = (0..10_000).map(|i| problem_seed(0, i)).collect();
    seeds.extend((0..10_000).map(|i| problem_seed(1, i)));
    seeds.sort_unstable();
    seeds.dedup();
    assert_eq!(seeds.len(), 20_000);
}
