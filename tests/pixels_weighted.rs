//! Weighted solves of pixels: all weights 1 is exactly the unweighted solve, a weight of 0 is
//! the same as dropping the point, and bad weights are reported with the correspondence's own
//! index, also when a pixel before it cannot be undistorted. A pixel that cannot be undistorted
//! is the same as the correspondence removed, for the solve and for RANSAC's inlier mask.

use eopnp::camera::Camera;
use eopnp::ransac::Ransac;
use eopnp::Problem;
use eopnp::{InputKind, PnpError, Solver};
use nalgebra::{Point2, Point3, Rotation3, Vector2, Vector3};

fn problem(cam: &Camera) -> (Vec<Point3<f64>>, Vec<Point2<f64>>) {
    let r = Rotation3::from_euler_angles(0.2, -0.1, 0.4);
    let t = Vector3::new(0.2, -0.1, 7.0);
    let world: Vec<Point3<f64>> = (0..12)
        .map(|i| {
            let a = f64::from(i);
            Point3::new((1.3 * a).sin(), (0.7 * a).cos(), 0.8 * (2.1 * a).sin())
        })
        .collect();
    let pixels = world
        .iter()
        .enumerate()
        .map(|(i, x)| {
            let p = r * x + t;
            let noise = 0.5 * (f64::from(i as u32) * 2.3).sin();
            cam.project(Point2::new(p.x / p.z, p.y / p.z)) + Vector2::new(noise, -noise)
        })
        .collect();
    (world, pixels)
}

fn camera() -> Camera {
    Camera::from_colmap(
        "OPENCV",
        640,
        480,
        vec![800.0, 790.0, 320.0, 240.0, -0.1, 0.02, 1e-3, -5e-4],
    )
    .unwrap()
}

#[test]
fn unit_weights_are_solve_pixels() {
    let cam = camera();
    let (world, pixels) = problem(&cam);
    let solver = Solver::default();
    let plain = solver
        .solve(&Problem::pixels(&world, &pixels, &cam))
        .unwrap();
    let ones = vec![1.0; world.len()];
    let weighted = solver
        .solve(&Problem::pixels(&world, &pixels, &cam).weights(&ones))
        .unwrap();
    assert_eq!(plain, weighted);
}

#[test]
fn zero_weight_drops_the_point() {
    let cam = camera();
    let (mut world, mut pixels) = problem(&cam);
    let solver = Solver::default();
    let reference = solver
        .solve(&Problem::pixels(&world, &pixels, &cam))
        .unwrap();
    world.insert(3, Point3::new(4.0, -3.0, 2.0));
    pixels.insert(3, Point2::new(12.0, 470.0));
    let mut weights = vec![1.0; world.len()];
    weights[3] = 0.0;
    let sol = solver
        .solve(&Problem::pixels(&world, &pixels, &cam).weights(&weights))
        .unwrap();
    assert_eq!((sol.used, sol.skipped), (12, 0));
    assert!((sol.rotation - reference.rotation).norm() < 1e-12);
    let dt = sol.translation - reference.translation;
    assert!(dt.norm() < 1e-11);
}

#[test]
fn bad_weights_keep_their_index() {
    let cam = camera();
    let (world, mut pixels) = problem(&cam);
    let solver = Solver::default();
    // Pixel 1 cannot be undistorted (skipped); the weight errors still name index 5.
    pixels[1] = Point2::new(f64::NAN, 0.0);
    let mut weights = vec![1.0; world.len()];
    weights[5] = -1.0;
    let err = solver.solve(&Problem::pixels(&world, &pixels, &cam).weights(&weights));
    assert_eq!(err, Err(PnpError::InvalidWeight { index: 5 }));
    weights[5] = f64::INFINITY;
    let err = solver.solve(&Problem::pixels(&world, &pixels, &cam).weights(&weights));
    assert_eq!(
        err,
        Err(PnpError::NonFinite {
            index: 5,
            input: InputKind::Weight
        })
    );
    let err = solver.solve(&Problem::pixels(&world, &pixels, &cam).weights(&weights[1..]));
    assert_eq!(
        err,
        Err(PnpError::WeightsLength {
            weights: 11,
            points: 12
        })
    );
    let err = solver.solve(&Problem::pixels(&world, &pixels[1..], &cam).weights(&weights));
    assert_eq!(
        err,
        Err(PnpError::LengthMismatch {
            world: 12,
            image: 11
        })
    );
    // Weight 1 everywhere: the NaN pixel is skipped, as in the unweighted solve.
    weights[5] = 1.0;
    let sol = solver
        .solve(&Problem::pixels(&world, &pixels, &cam).weights(&weights))
        .unwrap();
    assert_eq!((sol.used, sol.skipped), (11, 1));
}

/// `v` without its entries 3 and 8.
fn without_3_and_8<T: Copy>(v: &[T]) -> Vec<T> {
    v.iter()
        .enumerate()
        .filter(|(i, _)| *i != 3 && *i != 8)
        .map(|(_, x)| *x)
        .collect()
}

#[test]
fn pixels_left_out_are_the_correspondences_removed() {
    let cam = camera();
    let (world, pixels) = problem(&cam);
    let weights: Vec<f64> = (0..world.len()).map(|i| 0.5 + 0.1 * i as f64).collect();
    // Pixels 3 and 8 cannot be undistorted; the reference problem is the others.
    let (world_kept, pixels_kept, weights_kept) = (
        without_3_and_8(&world),
        without_3_and_8(&pixels),
        without_3_and_8(&weights),
    );
    let mut with_bad = pixels.clone();
    with_bad[3] = Point2::new(f64::NAN, 1.0);
    with_bad[8] = Point2::new(2.0, f64::INFINITY);

    let solver = Solver::default();
    let sol = solver
        .solve(&Problem::pixels(&world, &with_bad, &cam).weights(&weights))
        .unwrap();
    let reference = solver
        .solve(&Problem::pixels(&world_kept, &pixels_kept, &cam).weights(&weights_kept))
        .unwrap();
    assert_eq!((sol.used, sol.skipped), (10, 2));
    assert_eq!(sol.pose(), reference.pose());
    assert_eq!(sol.cost, reference.cost);

    let ransac = Ransac::default().seed(7);
    let est = ransac
        .estimate(&solver, &Problem::pixels(&world, &with_bad, &cam))
        .unwrap();
    let est_ref = ransac
        .estimate(&solver, &Problem::pixels(&world_kept, &pixels_kept, &cam))
        .unwrap();
    assert_eq!(est.solution.pose(), est_ref.solution.pose());
    assert_eq!(est.inliers.len(), 12);
    assert!(!est.inliers[3] && !est.inliers[8]);
    assert_eq!(without_3_and_8(&est.inliers), est_ref.inliers);
    assert_eq!(est.num_inliers, est_ref.num_inliers);
}
