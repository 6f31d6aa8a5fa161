//! `refine_focal` on seeded noise-free problems: from a start a few degrees and 20 % of the focal
//! length off, the true pose and focal length, through a pinhole and a distorting camera.

use super::*;
use crate::numeric::rotation::rotation_error_deg;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

#[test]
fn noise_free_problems_give_the_true_focal_length() {
    let mut rng = Pcg64::seed_from_u64(5);
    let cams = [
        Camera::pinhole(900.0, 900.0, 320.0, 240.0).unwrap(),
        Camera::from_colmap("SIMPLE_RADIAL", 640, 480, vec![900.0, 320.0, 240.0, -0.1]).unwrap(),
    ];
    for trial in 0..40 {
        let camera = &cams[trial % 2];
        let r = nalgebra::Rotation3::from_euler_angles(
            rng.random_range(-3.0..3.0),
            rng.random_range(-1.5..1.5),
            rng.random_range(-3.0..3.0),
        )
        .into_inner();
        let t = Vector3::new(0.2, -0.1, 5.0);
        let (mut world, mut pixels) = (Vec::new(), Vec::new());
        for _ in 0..20 {
            let z = rng.random_range(3.0..8.0);
            let cam = Vector3::new(
                rng.random_range(-0.3..0.3) * z,
                rng.random_range(-0.25..0.25) * z,
                z,
            );
            world.push(Point3::from(r.transpose() * (cam - t)));
            pixels.push(camera.project(Point2::new(cam.x / cam.z, cam.y / cam.z)));
        }
        // The camera given with a focal length 20 % off, the start 2 degrees off.
        let guess = camera.with_focal_scale(1.2);
        let r0 = exp_so3(&Vector3::new(0.02, -0.03, 0.01)) * r;
        let inp = FocalInputs {
            world: &world,
            pixels: &pixels,
            weights: None,
            camera: &guess,
        };
        let out = refine_focal(
            &inp,
            &r0,
            &(t + Vector3::new(0.1, 0.0, 0.3)),
            1.0,
            MAX_ITERATIONS,
        )
        .unwrap();
        assert!(out.converged, "trial {trial}");
        assert!(
            (out.scale * 1.2 - 1.0).abs() < 1e-9,
            "trial {trial}: scale {}",
            out.scale
        );
        assert!(rotation_error_deg(&out.r, &r) < 1e-8, "trial {trial}");
        assert!((out.t - t).norm() < 1e-8, "trial {trial}");
        assert!(out.cost < 1e-16, "trial {trial}: cost {}", out.cost);
    }
}
