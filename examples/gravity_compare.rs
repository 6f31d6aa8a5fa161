//! RANSAC with a known vertical against RANSAC without it, on the same seeded problems: the
//! iterations each needs at the same confidence, the rotation errors, the time.
//!
//! ```sh
//! cargo run --release --example gravity_compare -- [--problems 200] [--n 100]
//!     [--outliers 0.8] [--sigmas 0.1,0.5,1] [--passes 3]
//! ```
//!
//! The problems: the synthetic generator of docs/algorithm.md section 7 (general scenes, a
//! Haar-uniform rotation, f = 800 px, 640 x 480), `--n` points with 1 px of noise, a fraction
//! `--outliers` of them made wrong matches (the pixel replaced by one uniform in the image).
//! The vertical: the world's down direction `(0.2, -0.3, -1)` (normalised), measured in the
//! camera with a Gaussian tilt of `sigma` degrees about each of the two axes across it, and
//! given with that `sigma`. Both runs: `Ransac::default()` (threshold 4 px, confidence 0.999,
//! the problem's seed) with `Solver::default()`, one thread; "P3P" without the vertical,
//! "up2p" with it. Iterations: the samples drawn (`RansacStats::iterations`). Rotation error:
//! the largest angle between corresponding axes, degrees, against the truth; a problem
//! without a pose (an error) counts as an infinite error. Time per problem: the median over
//! `--passes` passes of (one pass over the problems) / (number of problems).

use eopnp::camera::Camera;
use eopnp::ransac::{problem_seed, Ransac};
use eopnp::{Gravity, Problem, Solver};
use eopnp_testkit::{
    axis_angle, gauss, median, rng_from_seed, rot_err_deg, unit_vector, ProblemOptions,
    RotationKind, Scene,
};
use nalgebra::{Matrix3, Point2, Point3, Vector3};
use rand::Rng;
use std::time::Instant;

struct Case {
    world: Vec<Point3<f64>>,
    pixels: Vec<Point2<f64>>,
    r: Matrix3<f64>,
    gravity: Gravity,
}

fn down_world() -> Vector3<f64> {
    Vector3::new(0.2, -0.3, -1.0).normalize()
}

fn case(seed: u64, n: usize, outliers: f64, sigma_deg: f64) -> Case {
    let p = eopnp_testkit::Problem::generate(&ProblemOptions {
        n,
        sigma_px: 1.0,
        scene: Scene::General,
        rotation: RotationKind::Uniform,
        seed,
    });
    let mut rng = rng_from_seed(seed ^ 0x6a5);
    let mut pixels = p.pixels.clone();
    let wrong = (outliers * n as f64).round() as usize;
    let mut idx: Vec<usize> = (0..n).collect();
    for i in 0..n - 1 {
        let j = rng.random_range(i..n);
        idx.swap(i, j);
    }
    for &i in &idx[..wrong] {
        pixels[i] = Point2::new(rng.random_range(0.0..640.0), rng.random_range(0.0..480.0));
    }
    let g = p.r_gt * down_world();
    let a = g.cross(&unit_vector(&mut rng)).normalize();
    let b = g.cross(&a);
    let s = sigma_deg.to_radians();
    let w = a * (s * gauss(&mut rng)) + b * (s * gauss(&mut rng));
    let measured = axis_angle(&w.normalize(), w.norm()) * g;
    Case {
        world: p.world,
        pixels,
        r: p.r_gt,
        gravity: Gravity::new(measured, down_world(), sigma_deg).unwrap(),
    }
}

fn arg<T: std::str::FromStr>(args: &[String], name: &str, default: T) -> T {
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1))
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let problems: u64 = arg(&args, "--problems", 200);
    let n: usize = arg(&args, "--n", 100);
    let outliers: f64 = arg(&args, "--outliers", 0.8);
    let passes: usize = arg(&args, "--passes", 3);
    let sigmas: Vec<f64> = arg(&args, "--sigmas", "0.1,0.5,1".to_string())
        .split(',')
        .map(|s| s.parse().unwrap())
        .collect();
    let camera = Camera::pinhole(800.0, 800.0, 320.0, 240.0).unwrap();
    let solver = Solver::default();
    println!(
        "N = {n}, {:.0} % outliers, sigma 1 px, {problems} problems per row, median over problems:",
        outliers * 100.0
    );
    println!();
    println!("| gravity sigma | iterations P3P | iterations up2p | fewer | rotation error P3P | rotation error up2p | time P3P | time up2p | mismatch reports |");
    println!("|---|---|---|---|---|---|---|---|---|");
    for &sg in &sigmas {
        let cases: Vec<Case> = (0..problems)
            .map(|i| case(problem_seed(0x9a, i as usize), n, outliers, sg))
            .collect();
        let run = |with: bool| {
            let mut iters = Vec::new();
            let mut errs = Vec::new();
            let mut mismatches = 0;
            for (i, c) in cases.iter().enumerate() {
                let mut p = Problem::pixels(&c.world, &c.pixels, &camera);
                if with {
                    p = p.gravity(c.gravity);
                }
                let ransac = Ransac::default().seed(problem_seed(7, i));
                match ransac.estimate(&solver, &p) {
                    Ok(s) => {
                        iters.push(f64::from(s.stats.iterations));
                        errs.push(rot_err_deg(&s.solution.rotation, &c.r));
                    }
                    Err(eopnp::PnpError::GravityMismatch { .. }) => {
                        mismatches += 1;
                        errs.push(f64::INFINITY);
                    }
                    Err(_) => errs.push(f64::INFINITY),
                }
            }
            (iters, errs, mismatches)
        };
        let time = |with: bool| {
            let mut t = Vec::new();
            for _ in 0..passes {
                let start = Instant::now();
                std::hint::black_box(run(with));
                t.push(start.elapsed().as_secs_f64() * 1e6 / problems as f64);
            }
            median(&t)
        };
        let (ip, ep, _) = run(false);
        let (iu, eu, mu) = run(true);
        let (tp, tu) = (time(false), time(true));
        let (mip, miu) = (median(&ip), median(&iu));
        println!(
            "| {sg} deg | {mip:.0} | {miu:.0} | {:.2}x | {:.4} deg | {:.4} deg | {:.0} µs | {:.0} µs | {mu} of {problems} |",
            mip / miu,
            median(&ep),
            median(&eu),
            tp,
            tu
        );
    }
}
