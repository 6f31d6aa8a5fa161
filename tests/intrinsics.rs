//! Refined principal point and distortion ([`eopnp::Problem::refine_principal_point`],
//! [`eopnp::Problem::refine_distortion`]), with the focal length known or unknown: noise-free
//! problems give the camera's parameters back; with noise the returned pose and camera are a
//! local minimum of the pixel error (no parameter moved either way lowers it) below the cost at
//! the truth; RANSAC with outliers; the focal length's standard deviation in the covariance;
//! the typed errors.

use eopnp::camera::Camera;
use eopnp::covariance::NoiseModel;
use eopnp::ransac::Ransac;
use eopnp::{Gravity, PnpError, Problem, Solver};
use eopnp_testkit::{gauss, rng_from_seed, rot_err_deg, trial_seed};
use nalgebra::{Matrix3, Point2, Point3, Vector3};
use rand::Rng;

struct Case {
    world: Vec<Point3<f64>>,
    pixels: Vec<Point2<f64>>,
    r: Matrix3<f64>,
    t: Vector3<f64>,
}

/// `n` points 2 to 10 units away over the whole 640 x 480 image of `camera`, a random
/// rotation, `sigma` px of noise; the first `outliers` pixels anywhere in the image.
fn case(seed: u64, camera: &Camera, n: usize, sigma: f64, outliers: usize) -> Case {
    let mut rng = rng_from_seed(seed);
    let r = eopnp_testkit::haar_rotation(&mut rng);
    let t = Vector3::new(
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
    );
    let (mut world, mut pixels) = (Vec::new(), Vec::new());
    while world.len() < n {
        let z = rng.random_range(2.0..10.0);
        let px = Point2::new(rng.random_range(0.0..640.0), rng.random_range(0.0..480.0));
        let Ok(m) = camera.undistort(px) else {
            continue;
        };
        let cam = Vector3::new(m.x * z, m.y * z, z);
        world.push(Point3::from(r.transpose() * (cam - t)));
        let observed = if world.len() <= outliers {
            Point2::new(rng.random_range(0.0..640.0), rng.random_range(0.0..480.0))
        } else {
            Point2::new(
                px.x + sigma * gauss(&mut rng),
                px.y + sigma * gauss(&mut rng),
            )
        };
        pixels.push(observed);
    }
    Case {
        world,
        pixels,
        r,
        t,
    }
}

/// The pixel cost of the pose `(r, t)` through `camera` on the correspondences `inliers` (all
/// when `None`).
fn cost(c: &Case, camera: &Camera, r: &Matrix3<f64>, t: &Vector3<f64>) -> f64 {
    c.world
        .iter()
        .zip(&c.pixels)
        .map(|(x, m)| {
            let p = r * x.coords + t;
            (camera.project(Point2::new(p.x / p.z, p.y / p.z)) - m).norm_squared()
        })
        .sum()
}

fn opencv() -> Camera {
    Camera::from_colmap(
        "OPENCV",
        640,
        480,
        vec![600.0, 604.0, 322.0, 236.0, -0.18, 0.04, 0.001, -0.002],
    )
    .unwrap()
}

/// `camera` with its principal point moved by `(dx, dy)`, its distortion zero and its focal
/// lengths scaled by `s`: the starting guess.
fn guess(camera: &Camera, (dx, dy): (f64, f64), s: f64) -> Camera {
    let mut p = camera.params().to_vec();
    let pp = if p.len() == 8 { 2 } else { 1 };
    p[pp] += dx;
    p[pp + 1] += dy;
    for k in &mut p[pp + 2..] {
        *k = 0.0;
    }
    p[0] *= s;
    if pp == 2 {
        p[1] *= s;
    }
    Camera::from_colmap(camera.model().name(), 640, 480, p).unwrap()
}

#[test]
fn noise_free_problems_give_the_camera_back() {
    let cams = [
        opencv(),
        Camera::from_colmap("SIMPLE_RADIAL", 640, 480, vec![500.0, 318.0, 243.0, -0.08]).unwrap(),
    ];
    for trial in 0..20u64 {
        let camera = &cams[trial as usize % 2];
        let c = case(trial_seed("intrinsics_clean", trial), camera, 50, 0.0, 0);
        let unknown_focal = trial % 4 < 2;
        let start = guess(camera, (6.0, -4.0), if unknown_focal { 1.4 } else { 1.0 });
        let mut p = Problem::pixels(&c.world, &c.pixels, &start)
            .refine_principal_point()
            .refine_distortion();
        if unknown_focal {
            p = p.unknown_focal();
        }
        let sol = Solver::default().solve(&p).unwrap();
        let est = sol.camera.unwrap();
        for (k, (a, b)) in est.params().iter().zip(camera.params()).enumerate() {
            assert!(
                (a - b).abs() <= 1e-7 * b.abs().max(1.0),
                "trial {trial}: parameter {k}: {a} against {b}"
            );
        }
        assert!(rot_err_deg(&sol.rotation, &c.r) < 1e-7, "trial {trial}");
        assert!((sol.translation - c.t).norm() < 1e-7, "trial {trial}");
    }
}

#[test]
fn noisy_solves_end_at_a_local_minimum_below_the_truth() {
    let camera = opencv();
    for trial in 0..20u64 {
        let c = case(trial_seed("intrinsics_noisy", trial), &camera, 100, 1.0, 0);
        let start = guess(&camera, (5.0, 5.0), 1.2);
        let p = Problem::pixels(&c.world, &c.pixels, &start)
            .unknown_focal()
            .refine_principal_point()
            .refine_distortion();
        let sol = Solver::default().solve(&p).unwrap();
        let est = sol.camera.unwrap();
        let (r, t) = (sol.rotation, sol.translation);
        let e = cost(&c, &est, &r, &t);
        assert!(
            (e / sol.cost - 1.0).abs() < 1e-12,
            "trial {trial}: {e} against {}",
            sol.cost
        );
        // The maximum-likelihood estimate fits the data better than the truth does.
        assert!(e < cost(&c, &camera, &c.r, &c.t), "trial {trial}");
        // No camera parameter moved by a small step either way lowers the cost (the two focal
        // lengths alike: their ratio is the given camera's).
        for k in 1..est.params().len() {
            for sign in [-1.0, 1.0] {
                let mut q = est.params().to_vec();
                if k == 1 {
                    q[0] *= 1.0 + sign * 1e-7;
                    q[1] *= 1.0 + sign * 1e-7;
                } else {
                    q[k] += sign * 1e-5 * q[k].abs().max(1e-2);
                }
                let moved = Camera::from_colmap("OPENCV", 640, 480, q).unwrap();
                assert!(
                    cost(&c, &moved, &r, &t) >= e * (1.0 - 1e-12),
                    "trial {trial}: parameter {k} moved {sign}"
                );
            }
        }
    }
}

#[test]
fn ransac_refines_the_distortion_of_its_inliers() {
    let camera = opencv();
    for trial in 0..6u64 {
        // 60 outliers first, then 140 inliers.
        let c = case(
            trial_seed("intrinsics_ransac", trial),
            &camera,
            200,
            0.5,
            60,
        );
        let start = guess(&camera, (0.0, 0.0), if trial % 2 == 0 { 1.0 } else { 1.3 });
        let mut p = Problem::pixels(&c.world, &c.pixels, &start).refine_distortion();
        if trial % 2 == 1 {
            p = p.unknown_focal();
        }
        let out = Ransac::default().estimate(&Solver::default(), &p).unwrap();
        let found = out.inliers[60..].iter().filter(|x| **x).count();
        let wrong = out.inliers[..60].iter().filter(|x| **x).count();
        assert!(
            found == 140 && wrong == 0,
            "trial {trial}: {found} inliers, {wrong} outliers"
        );
        // The same camera as the plain solve of the 140 inliers alone.
        let mut q = Problem::pixels(&c.world[60..], &c.pixels[60..], &start).refine_distortion();
        if trial % 2 == 1 {
            q = q.unknown_focal();
        }
        let plain = Solver::default().solve(&q).unwrap().camera.unwrap();
        let est = out.solution.camera.unwrap();
        for (k, (a, b)) in est.params().iter().zip(plain.params()).enumerate() {
            assert!(
                (a - b).abs() <= 1e-7 * b.abs().max(1e-2),
                "trial {trial}: parameter {k}: {a} against {b}"
            );
        }
        assert!(
            rot_err_deg(&out.solution.rotation, &c.r) < 0.1,
            "trial {trial}"
        );
    }
}

#[test]
fn the_covariance_carries_the_focal_lengths_standard_deviation() {
    let camera = Camera::pinhole(800.0, 800.0, 320.0, 240.0).unwrap();
    let c = case(trial_seed("intrinsics_cov", 0), &camera, 40, 1.0, 0);
    let solver = Solver::default().covariance(Some(NoiseModel::Sigma(1.0)));
    let p = Problem::pixels(&c.world, &c.pixels, &camera);
    let known = solver.solve(&p).unwrap().covariance.unwrap();
    assert_eq!(known.focal_sigma, None);
    let free = solver
        .solve(&p.unknown_focal())
        .unwrap()
        .covariance
        .unwrap();
    let s = free.focal_sigma.unwrap();
    // A 640 x 480 image at 800 px, 40 points: a few pixels (the spread over noise draws is
    // checked against it in the stage's unit test).
    assert!(s > 0.5 && s < 50.0, "{s}");
    // The pose's marginal covariance grows when the focal length is free.
    // (at two slightly different poses: to 1e-3).
    for k in 0..6 {
        assert!(
            free.matrix[(k, k)] >= known.matrix[(k, k)] * (1.0 - 1e-3),
            "{k}"
        );
    }
    assert!(free.matrix[(5, 5)] > 1.5 * known.matrix[(5, 5)]);
}

#[test]
fn bad_requests_are_typed_errors() {
    let camera = opencv();
    let c = case(trial_seed("intrinsics_errors", 0), &camera, 12, 0.0, 0);
    let image: Vec<Point2<f64>> = c
        .pixels
        .iter()
        .map(|p| camera.undistort(*p).unwrap())
        .collect();
    let s = Solver::default();
    let e = s
        .solve(&Problem::normalised(&c.world, &image).refine_distortion())
        .unwrap_err();
    assert_eq!(
        e,
        PnpError::InvalidOption {
            option: "refine_distortion"
        }
    );
    // The message names the option and what it needs (not the RANSAC options' range message).
    let msg = e.to_string();
    assert!(
        msg.starts_with("`refine_distortion`: the distortion parameters are refined only")
            && msg.contains("pixels through one camera"),
        "{msg}"
    );
    let g = Gravity::new(Vector3::y(), Vector3::y(), 0.5).unwrap();
    let e = s
        .solve(
            &Problem::pixels(&c.world, &c.pixels, &camera)
                .refine_principal_point()
                .gravity(g),
        )
        .unwrap_err();
    assert_eq!(
        e,
        PnpError::InvalidOption {
            option: "refine_principal_point"
        }
    );
    let msg = e.to_string();
    assert!(
        msg.starts_with("`refine_principal_point`: the principal point is refined only")
            && msg.contains("without a known vertical"),
        "{msg}"
    );
    // OPENCV with everything free: 6 + 1 + 2 + 4 = 13 parameters, 7 points at least.
    let p = Problem::pixels(&c.world[..6], &c.pixels[..6], &camera)
        .unknown_focal()
        .refine_principal_point()
        .refine_distortion();
    assert_eq!(
        s.solve(&p).unwrap_err(),
        PnpError::TooFewPoints { got: 6, need: 7 }
    );
    let p = Problem::pixels(&c.world[..7], &c.pixels[..7], &camera)
        .unknown_focal()
        .refine_principal_point()
        .refine_distortion();
    assert!(s.solve(&p).is_ok());
}

#[test]
fn a_robust_loss_applies_to_the_intrinsics_too() {
    // 100 points, 10 of them 20 to 50 px off, the focal length unknown: with a Cauchy loss
    // the pose and focal length minimise the robust cost (no focal length moved either way at
    // the returned pose lowers it), and the focal length is closer than least squares'.
    let camera = Camera::pinhole(900.0, 900.0, 320.0, 240.0).unwrap();
    let loss = eopnp::Loss::Cauchy(2.0);
    let robust_cost = |c: &Case, cam: &Camera, r: &Matrix3<f64>, t: &Vector3<f64>| -> f64 {
        c.world
            .iter()
            .zip(&c.pixels)
            .map(|(x, m)| {
                let p = r * x.coords + t;
                let r2 = (cam.project(Point2::new(p.x / p.z, p.y / p.z)) - m).norm_squared();
                4.0 * (1.0 + r2 / 4.0).ln()
            })
            .sum()
    };
    let (mut closer, trials) = (0, 10u64);
    for trial in 0..trials {
        let mut c = case(trial_seed("intrinsics_loss", trial), &camera, 100, 0.5, 0);
        let mut rng = rng_from_seed(trial_seed("intrinsics_loss_off", trial));
        for m in &mut c.pixels[..10] {
            let a = rng.random_range(0.0..std::f64::consts::TAU);
            let d = rng.random_range(20.0..50.0);
            *m += nalgebra::Vector2::new(d * a.cos(), d * a.sin());
        }
        let guess = Camera::pinhole(1170.0, 1170.0, 320.0, 240.0).unwrap();
        let p = Problem::pixels(&c.world, &c.pixels, &guess).unknown_focal();
        let sol = Solver::default().loss(loss).solve(&p).unwrap();
        let est = sol.camera.unwrap();
        let e = robust_cost(&c, &est, &sol.rotation, &sol.translation);
        assert!(
            (e / sol.cost - 1.0).abs() < 1e-12,
            "trial {trial}: {e} against {}",
            sol.cost
        );
        for sign in [-1.0, 1.0] {
            let f = est.focal_lengths().0 * (1.0 + sign * 1e-6);
            let moved = Camera::pinhole(f, f, 320.0, 240.0).unwrap();
            let moved_cost = robust_cost(&c, &moved, &sol.rotation, &sol.translation);
            assert!(moved_cost >= e * (1.0 - 1e-12), "trial {trial}: {sign}");
        }
        // The RMS residual is without the loss.
        let sq = cost(&c, &est, &sol.rotation, &sol.translation);
        let rmse = (sq / 100.0).sqrt() / est.focal_lengths().0;
        assert!(
            (sol.reprojection_rmse / rmse - 1.0).abs() < 1e-9,
            "trial {trial}"
        );
        let ls = Solver::default().solve(&p).unwrap().camera.unwrap();
        let err = |cam: &Camera| (cam.focal_lengths().0 / 900.0 - 1.0).abs();
        closer += usize::from(err(&est) < err(&ls));
    }
    assert!(
        closer >= 8,
        "the robust focal length closer in {closer} of {trials}"
    );
}
