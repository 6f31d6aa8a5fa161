//! Pixel input through a camera model: `Solver::solve` of a `Problem::pixels` (undistortion + solve) against
//! `Solver::solve` on the same points already undistorted (the normalised points computed once,
//! outside the timed closure), N = 100, 1,000, 10,000, general scenes, sigma = 1 px, seeded.
//!
//! Cameras: `PINHOLE`, `RADIAL` (`k1 = -0.3`, `k2 = 0.1`, points up to 40 degrees off axis)
//! and `OPENCV_FISHEYE` (points up to 75 degrees off axis, a 150-degree field of view).

use criterion::{black_box, criterion_group, criterion_main, BenchmarkId, Criterion};
use eopnp::camera::Camera;
use eopnp::Solver;
use eopnp_testkit as common;
use nalgebra::{Point2, Point3, Vector3};
use rand::Rng;
use std::time::Duration;

/// Seed of every problem set of this bench.
const SEED: u64 = 0x5049_5845_4C53;
const NS: [usize; 3] = [100, 1000, 10_000];

/// One problem: world points, their noisy pixels and those pixels undistorted.
struct PixelProblem {
    world: Vec<Point3<f64>>,
    pixels: Vec<Point2<f64>>,
    normalised: Vec<Point2<f64>>,
}

/// Problems per set (the timed closure cycles through them).
fn set_size(n: usize) -> usize {
    match n {
        0..=100 => 32,
        101..=1000 => 16,
        _ => 4,
    }
}

/// A general scene seen by `camera`: camera-frame directions uniform in the cone of half-angle
/// `max_deg` about the axis, depths in [4, 8], a Haar-uniform rotation, the world origin at
/// the centroid; pixel noise sigma = 1 px.
fn problem(camera: &Camera, max_deg: f64, n: usize, seed: u64) -> PixelProblem {
    let mut rng = common::rng_from_seed(seed);
    let r = common::haar_rotation(&mut rng);
    let cos_max = max_deg.to_radians().cos();
    let cam: Vec<Vector3<f64>> = (0..n)
        .map(|_| {
            // Uniform on the spherical cap, then scaled to a depth in [4, 8].
            let z: f64 = rng.random_range(cos_max..1.0);
            let phi: f64 = rng.random_range(0.0..std::f64::consts::TAU);
            let s = (1.0 - z * z).sqrt();
            let d = Vector3::new(s * phi.cos(), s * phi.sin(), z);
            d * (rng.random_range(4.0..8.0) / z)
        })
        .collect();
    let t = cam.iter().sum::<Vector3<f64>>() / n as f64;
    let world = cam
        .iter()
        .map(|p| Point3::from(r.transpose() * (p - t)))
        .collect();
    let mut gauss = || {
        // Box-Muller.
        let (u1, u2): (f64, f64) = (rng.random_range(f64::EPSILON..1.0), rng.random());
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    };
    let pixels: Vec<Point2<f64>> = cam
        .iter()
        .map(|p| {
            let px = camera.project(Point2::new(p.x / p.z, p.y / p.z));
            Point2::new(px.x + gauss(), px.y + gauss())
        })
        .collect();
    let normalised = pixels
        .iter()
        .map(|px| camera.undistort(*px).expect("bench pixels undistort"))
        .collect();
    PixelProblem {
        world,
        pixels,
        normalised,
    }
}

fn cameras() -> Vec<(&'static str, Camera, f64)> {
    vec![
        (
            "pinhole",
            Camera::from_colmap("PINHOLE", 1280, 960, vec![800.0, 810.0, 640.0, 480.0]).unwrap(),
            40.0,
        ),
        (
            "radial",
            Camera::from_colmap("RADIAL", 1280, 960, vec![800.0, 640.0, 480.0, -0.3, 0.1]).unwrap(),
            40.0,
        ),
        (
            "fisheye",
            Camera::from_colmap(
                "OPENCV_FISHEYE",
                1280,
                960,
                vec![400.0, 401.0, 640.0, 480.0, 0.02, -0.01, 0.003, -0.001],
            )
            .unwrap(),
            75.0,
        ),
    ]
}

fn pixels(c: &mut Criterion) {
    let solver = Solver::default();
    for (name, camera, max_deg) in cameras() {
        let sets: Vec<(usize, Vec<PixelProblem>)> = NS
            .iter()
            .map(|&n| {
                let set = (0..set_size(n) as u64)
                    .map(|i| {
                        let seed = common::splitmix64(SEED ^ (n as u64) << 20 ^ i);
                        problem(&camera, max_deg, n, seed)
                    })
                    .collect();
                (n, set)
            })
            .collect();
        let mut group = c.benchmark_group(format!("pixels/{name}/undistort+solve"));
        for (n, set) in &sets {
            group.bench_with_input(BenchmarkId::from_parameter(n), set, |b, set| {
                let mut i = 0usize;
                b.iter(|| {
                    let p = &set[i % set.len()];
                    i = i.wrapping_add(1);
                    black_box(solver.solve(&eopnp::Problem::pixels(
                        black_box(&p.world),
                        black_box(&p.pixels),
                        &camera,
                    )))
                });
            });
        }
        group.finish();
        let mut group = c.benchmark_group(format!("pixels/{name}/solve"));
        for (n, set) in &sets {
            group.bench_with_input(BenchmarkId::from_parameter(n), set, |b, set| {
                let mut i = 0usize;
                b.iter(|| {
                    let p = &set[i % set.len()];
                    i = i.wrapping_add(1);
                    black_box(solver.solve(&eopnp::Problem::normalised(
                        black_box(&p.world),
                        black_box(&p.normalised),
                    )))
                });
            });
        }
        group.finish();
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(30)
        .measurement_time(Duration::from_secs(2))
        .warm_up_time(Duration::from_secs(1));
    targets = pixels
}
criterion_main!(benches);
