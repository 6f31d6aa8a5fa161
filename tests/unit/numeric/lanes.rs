//! Unit tests of the dispatched passes (`src/numeric/lanes.rs`): the AVX2 + FMA build and the
//! baseline build give the same solutions, to the bit, through every pass they serve
//! (`frame`/`moments`' centred sums with and without weights and the axis rotation; `refine`'s and
//! `refine_pixels`' pass with and without the Hessian, the depth check, a robust loss, camera
//! models with distortion).

use super::wide;
use crate::camera::Camera;
use crate::Problem;
use crate::{Loss, PnpError, Refinement, Solution, Solver};
use nalgebra::{Point2, Point3, Vector3};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

/// A general scene (camera-frame points in `[-2, 2]^2 x [4, 8]`, or on a tilted plane),
/// normalised image points with noise, a world offset and rotation, and weights in (0, 2].
fn problem(seed: u64, n: usize, planar: bool) -> (Vec<Point3<f64>>, Vec<Point2<f64>>, Vec<f64>) {
    let mut rng = Pcg64::seed_from_u64(seed);
    let axis = Vector3::new(
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
    );
    let r = nalgebra::Rotation3::new(axis * 2.0);
    let t = Vector3::new(0.3, -0.2, 6.0);
    let mut world = Vec::new();
    let mut image = Vec::new();
    for _ in 0..n {
        let (x, y) = (rng.random_range(-2.0..2.0), rng.random_range(-2.0..2.0));
        let z = if planar {
            6.0 + 0.3 * x - 0.2 * y
        } else {
            rng.random_range(4.0..8.0)
        };
        let pc = Vector3::new(x, y, z);
        world.push(Point3::from(r.inverse() * (pc - t)));
        let m = Point2::new(
            pc.x / pc.z + rng.random_range(-2e-3..2e-3),
            pc.y / pc.z + rng.random_range(-2e-3..2e-3),
        );
        image.push(m);
    }
    let weights = (0..n).map(|_| rng.random_range(0.01..2.0)).collect();
    (world, image, weights)
}

/// The same call under both builds.
fn both(
    f: impl Fn() -> Result<Solution, PnpError>,
) -> (Result<Solution, PnpError>, Result<Solution, PnpError>) {
    (f(), super::with_baseline(&f))
}

#[test]
fn wide_and_baseline_builds_give_the_same_bits() {
    if !wide() {
        eprintln!("no AVX2 + FMA on this processor: only the baseline build exists here");
        return;
    }
    let cams = [
        Camera::from_colmap("SIMPLE_RADIAL", 640, 480, vec![800.0, 320.0, 240.0, -0.3]).unwrap(),
        Camera::from_colmap(
            "OPENCV_FISHEYE",
            640,
            480,
            vec![300.0, 300.0, 320.0, 240.0, 0.05, -0.01, 0.002, -0.0005],
        )
        .unwrap(),
    ];
    let mut compared = 0;
    for seed in 0..60u64 {
        let n = [4, 5, 6, 7, 10, 33, 100, 1001][seed as usize % 8];
        let planar = seed % 3 == 0;
        let (world, image, weights) = problem(seed, n, planar);
        for solver in [
            Solver::default(),
            Solver::default().refinement(Refinement::Algebraic),
            Solver::default().loss(Loss::Cauchy(1e-3)),
        ] {
            let (a, b) = both(|| solver.solve(&Problem::normalised(&world, &image)));
            assert_eq!(a, b, "seed {seed}, n {n}: solve");
            let (a, b) =
                both(|| solver.solve(&Problem::normalised(&world, &image).weights(&weights)));
            assert_eq!(a, b, "seed {seed}, n {n}: solve_weighted");
            compared += 2;
        }
        for cam in &cams {
            let pixels: Vec<Point2<f64>> = image.iter().map(|m| cam.project(*m)).collect();
            let (a, b) = both(|| Solver::default().solve(&Problem::pixels(&world, &pixels, cam)));
            assert_eq!(a, b, "seed {seed}, n {n}: solve_pixels");
            let loss = Solver::default().loss(Loss::Huber(1.0));
            let (a, b) =
                both(|| loss.solve(&Problem::pixels(&world, &pixels, cam).weights(&weights)));
            assert_eq!(a, b, "seed {seed}, n {n}: solve_pixels_weighted with Huber");
            compared += 2;
        }
    }
    assert_eq!(compared, 60 * 10);
}
