//! `refine_intrinsics` on seeded noise-free problems: from a start a few degrees and 20 % of the
//! focal length off (and, when free, a principal point and distortion off), the true pose and
//! intrinsics, through a pinhole and distorting cameras (the covariance against the spread of
//! the estimates: `tests/covariance.rs`).

use super::*;
use crate::numeric::rotation::rotation_error_deg;
use crate::pipeline::Loss;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

/// World points, their pixels, the rotation and the translation.
type Seeded = (
    Vec<Point3<f64>>,
    Vec<Point2<f64>>,
    Matrix3<f64>,
    Vector3<f64>,
);

/// A seeded problem through `camera`: `n` points 3 to 8 units in front filling most of the
/// field of view, its pose `(r, t)`, pixel noise `sigma`.
fn problem(rng: &mut Pcg64, camera: &Camera, n: usize, sigma: f64) -> Seeded {
    let r = nalgebra::Rotation3::from_euler_angles(
        rng.random_range(-3.0..3.0),
        rng.random_range(-1.5..1.5),
        rng.random_range(-3.0..3.0),
    )
    .into_inner();
    let t = Vector3::new(0.2, -0.1, 5.0);
    let (mut world, mut pixels) = (Vec::new(), Vec::new());
    for _ in 0..n {
        let z = rng.random_range(3.0..8.0);
        let cam = Vector3::new(
            rng.random_range(-0.3..0.3) * z,
            rng.random_range(-0.25..0.25) * z,
            z,
        );
        world.push(Point3::from(r.transpose() * (cam - t)));
        let px = camera.project(Point2::new(cam.x / cam.z, cam.y / cam.z));
        let (a, b) = (
            rng.random_range(-1.0..1.0f64),
            rng.random_range(-1.0..1.0f64),
        );
        // Uniform noise of standard deviation sigma per coordinate.
        pixels.push(Point2::new(
            px.x + a * sigma * 3f64.sqrt(),
            px.y + b * sigma * 3f64.sqrt(),
        ));
    }
    (world, pixels, r, t)
}

const FOCAL: Free = Free {
    focal: true,
    principal_point: false,
    distortion: false,
};
const ALL: Free = Free {
    focal: true,
    principal_point: true,
    distortion: true,
};

#[test]
fn noise_free_problems_give_the_true_focal_length() {
    let mut rng = Pcg64::seed_from_u64(5);
    let cams = [
        Camera::pinhole(900.0, 900.0, 320.0, 240.0).unwrap(),
        Camera::from_colmap("SIMPLE_RADIAL", 640, 480, vec![900.0, 320.0, 240.0, -0.1]).unwrap(),
    ];
    for trial in 0..40 {
        let camera = &cams[trial % 2];
        let (world, pixels, r, t) = problem(&mut rng, camera, 20, 0.0);
        // The camera given with a focal length 20 % off, the start 2 degrees off.
        let guess = camera.with_focal_scale(1.2);
        let r0 = exp_so3(&Vector3::new(0.02, -0.03, 0.01)) * r;
        let inp = IntrinsicsInputs {
            world: &world,
            pixels: &pixels,
            weights: None,
            free: FOCAL,
            focal_range: (0.0, f64::INFINITY),
            loss: Loss::Squared,
        };
        let t0 = t + Vector3::new(0.1, 0.0, 0.3);
        let out = refine_intrinsics(&inp, &r0, &t0, &guess, MAX_ITERATIONS).unwrap();
        assert!(out.converged, "trial {trial}");
        let f = out.camera.focal_lengths().0;
        assert!((f / 900.0 - 1.0).abs() < 1e-9, "trial {trial}: f {f}");
        assert!(rotation_error_deg(&out.r, &r) < 1e-8, "trial {trial}");
        assert!((out.t - t).norm() < 1e-8, "trial {trial}");
        assert!(out.cost < 1e-16, "trial {trial}: cost {}", out.cost);
        // The principal point and the distortion as given.
        let (centre, dist) = guess.intrinsic_groups();
        assert_eq!(
            out.camera.params()[centre[0]..],
            guess.params()[centre[0]..],
            "trial {trial}"
        );
        assert_eq!(dist.end, guess.params().len());
    }
}

#[test]
fn noise_free_problems_give_the_true_principal_point_and_distortion() {
    let mut rng = Pcg64::seed_from_u64(6);
    let cams = [
        Camera::from_colmap("SIMPLE_RADIAL", 640, 480, vec![600.0, 330.0, 235.0, -0.12]).unwrap(),
        Camera::from_colmap(
            "OPENCV",
            640,
            480,
            vec![610.0, 600.0, 318.0, 244.0, -0.2, 0.05, 0.001, -0.002],
        )
        .unwrap(),
        Camera::from_colmap(
            "OPENCV_FISHEYE",
            640,
            480,
            vec![300.0, 300.0, 322.0, 238.0, 0.05, -0.01, 0.002, 0.0005],
        )
        .unwrap(),
        Camera::from_colmap(
            "FULL_OPENCV",
            640,
            480,
            vec![
                600.0, 600.0, 320.0, 240.0, -0.2, 0.05, 0.001, -0.002, 0.01, 0.1, -0.02, 0.005,
            ],
        )
        .unwrap(),
    ];
    for trial in 0..24 {
        let camera = &cams[trial % cams.len()];
        let (world, pixels, r, t) = problem(&mut rng, camera, 60, 0.0);
        // The focal length 10 % off, the principal point 8 px off, the distortion zero.
        let mut params = camera.params().to_vec();
        let (centre, dist) = camera.intrinsic_groups();
        params[centre[0]] += 8.0;
        params[centre[1]] -= 5.0;
        for k in dist {
            params[k] = 0.0;
        }
        let guess = camera.with_params(&params).unwrap().with_focal_scale(1.1);
        let inp = IntrinsicsInputs {
            world: &world,
            pixels: &pixels,
            weights: None,
            free: ALL,
            focal_range: (0.0, f64::INFINITY),
            loss: Loss::Squared,
        };
        let r0 = exp_so3(&Vector3::new(0.01, -0.01, 0.01)) * r;
        let out = refine_intrinsics(&inp, &r0, &t, &guess, MAX_ITERATIONS).unwrap();
        assert!(out.cost < 1e-14, "trial {trial}: cost {}", out.cost);
        assert!(rotation_error_deg(&out.r, &r) < 1e-7, "trial {trial}");
        if camera.model() == crate::camera::CameraModel::FullOpenCv {
            // Its rational radial term's numerator and denominator trade off over a field of
            // view this narrow: the images, not the parameters, are determined.
            continue;
        }
        for (k, (a, b)) in out.camera.params().iter().zip(camera.params()).enumerate() {
            assert!(
                (a - b).abs() <= 1e-7 * b.abs().max(1.0),
                "trial {trial} ({}): parameter {k} {a} against {b}",
                camera.model()
            );
        }
    }
}
