//! An unknown focal length ([`eopnp::Problem::unknown_focal`]): with every correspondence an
//! inlier, the pixel cost over pose and focal length of the default solve never above that of an
//! independent Levenberg-Marquardt started at the ground truth (`eopnp_testkit::lm_refine_focal`,
//! relative 1e-9), focal lengths 300 to 3,000 px, N = 6, 10, 100 and 1000, sigma = 1 px, the
//! camera given with a focal length up to a factor 2 off; noise-free problems give the focal
//! length to 1e-9 relative; the typed errors.

use eopnp::camera::Camera;
use eopnp::{Gravity, PnpError, Problem, Solver};
use eopnp_testkit::{gauss, lm_refine_focal, rng_from_seed, rot_err_deg, trial_seed};
use nalgebra::{Point2, Point3, Vector3};
use rand::Rng;

/// The target: the default solve's cost at most the reference's times `1 + REL`.
const REL: f64 = 1e-9;

struct Case {
    world: Vec<Point3<f64>>,
    pixels: Vec<Point2<f64>>,
    r: nalgebra::Matrix3<f64>,
    t: Vector3<f64>,
    f: f64,
    c: Point2<f64>,
}

/// A camera of focal length 300 to 3,000 px (log-uniform), a 640 x 480 image, a random
/// rotation; `n` points 2 to 10 units away within the field of view; `sigma` px of noise.
fn case(seed: u64, n: usize, sigma: f64) -> Case {
    let mut rng = rng_from_seed(seed);
    let f = 10f64.powf(rng.random_range(300f64.log10()..3000f64.log10()));
    let r = eopnp_testkit::haar_rotation(&mut rng);
    let t = Vector3::new(
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
    );
    let c = Point2::new(320.0, 240.0);
    let (mut world, mut pixels) = (Vec::new(), Vec::new());
    while world.len() < n {
        let z = rng.random_range(2.0..10.0);
        let (u, v) = (rng.random_range(0.0..640.0), rng.random_range(0.0..480.0));
        let cam = Vector3::new((u - c.x) / f * z, (v - c.y) / f * z, z);
        world.push(Point3::from(r.transpose() * (cam - t)));
        pixels.push(Point2::new(
            u + sigma * gauss(&mut rng),
            v + sigma * gauss(&mut rng),
        ));
    }
    Case {
        world,
        pixels,
        r,
        t,
        f,
        c,
    }
}

/// The camera given to the solve: `c`'s with a focal length up to a factor 2 off either way.
fn guess(seed: u64, c: &Case) -> Camera {
    let mut rng = rng_from_seed(seed ^ 9);
    let f = c.f * 2f64.powf(rng.random_range(-1.0..1.0));
    Camera::pinhole(f, f, c.c.x, c.c.y).unwrap()
}

#[test]
fn the_solve_reaches_the_maximum_likelihood_pose_and_focal_length() {
    for &(n, trials) in &[(6usize, 200u64), (10, 200), (100, 200), (1000, 200)] {
        let mut worst = f64::NEG_INFINITY;
        for trial in 0..trials {
            let seed = trial_seed(&format!("focal-ml-{n}"), trial);
            let c = case(seed, n, 1.0);
            let camera = guess(seed, &c);
            let sol = Solver::default()
                .solve(&Problem::pixels(&c.world, &c.pixels, &camera).unknown_focal())
                .unwrap_or_else(|e| panic!("N = {n} seed {seed}: {e}"));
            let reference = lm_refine_focal(&c.world, &c.pixels, &c.r, &c.t, c.f, c.c);
            let rel = (sol.cost - reference.cost) / reference.cost;
            worst = worst.max(rel);
            assert!(
                rel <= REL,
                "N = {n} seed {seed}: cost {:e} above the reference's {:e} (f {} vs {})",
                sol.cost,
                reference.cost,
                sol.camera.unwrap().focal_lengths().0,
                reference.f
            );
        }
        println!("N = {n}: worst (cost - reference) / reference = {worst:e}");
    }
}

#[test]
fn noise_free_problems_give_the_focal_length() {
    for &n in &[5usize, 6, 10, 100] {
        for trial in 0..50u64 {
            let seed = trial_seed(&format!("focal-exact-{n}"), trial);
            let c = case(seed, n, 0.0);
            let camera = guess(seed, &c);
            let sol = Solver::default()
                .solve(&Problem::pixels(&c.world, &c.pixels, &camera).unknown_focal())
                .unwrap_or_else(|e| panic!("N = {n} seed {seed}: {e}"));
            let (fx, fy) = sol.camera.unwrap().focal_lengths();
            assert!(
                (fx / c.f - 1.0).abs() <= 1e-9,
                "N = {n} seed {seed}: f {fx} vs {}",
                c.f
            );
            assert_eq!(fx, fy);
            assert!(
                rot_err_deg(&sol.rotation, &c.r) <= 1e-8,
                "N = {n} seed {seed}"
            );
        }
    }
}

/// A distorting camera: the focal length found through the model, distortion fixed.
#[test]
fn a_distorting_camera_keeps_its_distortion() {
    for trial in 0..30u64 {
        let seed = trial_seed("focal-distortion", trial);
        let c = case(seed, 30, 0.0);
        let truth =
            Camera::from_colmap("SIMPLE_RADIAL", 640, 480, vec![c.f, c.c.x, c.c.y, -0.05]).unwrap();
        // Pixels through the distorting camera.
        let pixels: Vec<Point2<f64>> = c
            .world
            .iter()
            .map(|x| {
                let p = c.r * x.coords + c.t;
                truth.project(Point2::new(p.x / p.z, p.y / p.z))
            })
            .collect();
        let guess = Camera::from_colmap(
            "SIMPLE_RADIAL",
            640,
            480,
            vec![c.f * 0.7, c.c.x, c.c.y, -0.05],
        )
        .unwrap();
        let sol = Solver::default()
            .solve(&Problem::pixels(&c.world, &pixels, &guess).unknown_focal())
            .unwrap_or_else(|e| panic!("seed {seed}: {e}"));
        let (fx, _) = sol.camera.unwrap().focal_lengths();
        assert!(
            (fx / c.f - 1.0).abs() <= 1e-9,
            "seed {seed}: f {fx} vs {}",
            c.f
        );
    }
}

#[test]
fn unsupported_inputs_are_typed_errors() {
    let c = case(1, 20, 0.0);
    let camera = Camera::pinhole(c.f, c.f, c.c.x, c.c.y).unwrap();
    let invalid = PnpError::InvalidOption {
        option: "unknown_focal",
    };
    let image: Vec<Point2<f64>> = c
        .pixels
        .iter()
        .map(|p| Point2::new((p.x - c.c.x) / c.f, (p.y - c.c.y) / c.f))
        .collect();
    let solver = Solver::default();
    assert_eq!(
        solver
            .solve(&Problem::normalised(&c.world, &image).unknown_focal())
            .err(),
        Some(invalid.clone())
    );
    let g = Gravity::new(Vector3::y(), Vector3::y(), 1.0).unwrap();
    let p = Problem::pixels(&c.world, &c.pixels, &camera);
    assert_eq!(
        solver.solve(&p.unknown_focal().gravity(g)).err(),
        Some(invalid.clone())
    );
    for (lo, hi) in [
        (0.0, 100.0),
        (500.0, 100.0),
        (-1.0, 10.0),
        (1.0, f64::INFINITY),
        (f64::NAN, 1.0),
    ] {
        assert_eq!(
            solver.solve(&p.unknown_focal_within(lo, hi)).err(),
            Some(invalid.clone()),
            "{lo} {hi}"
        );
    }
    // Within a range that holds the truth: found.
    let sol = solver
        .solve(&p.unknown_focal_within(0.5 * c.f, 2.0 * c.f))
        .unwrap();
    assert!((sol.camera.unwrap().focal_lengths().0 / c.f - 1.0).abs() < 1e-9);
    // Without an unknown focal length, no estimate.
    assert_eq!(solver.solve(&p).unwrap().camera, None);
}

/// RANSAC with an unknown focal length at 0, 50 and 80 % outliers (N = 100, 1 px, the camera
/// given up to a factor 2 off): the focal length within 2 % and the rotation within 0.5
/// degrees on every problem, the right correspondences inliers.
#[test]
fn ransac_estimates_the_focal_length() {
    use eopnp::ransac::Ransac;
    for &outliers in &[0.0, 0.5, 0.8] {
        for trial in 0..20u64 {
            let seed = trial_seed(&format!("focal-ransac-{outliers}"), trial);
            let mut c = case(seed, 100, 1.0);
            let mut rng = rng_from_seed(seed ^ 3);
            let wrong = (outliers * 100.0) as usize;
            for p in c.pixels.iter_mut().take(wrong) {
                *p = Point2::new(rng.random_range(0.0..640.0), rng.random_range(0.0..480.0));
            }
            let guess = c.f * 2f64.powf(rng.random_range(-1.0..1.0));
            let camera = Camera::pinhole(guess, guess, c.c.x, c.c.y).unwrap();
            let problem = Problem::pixels(&c.world, &c.pixels, &camera).unknown_focal();
            let r = Ransac::default()
                .seed(seed)
                .estimate(&Solver::default(), &problem)
                .unwrap_or_else(|e| panic!("{outliers} seed {seed}: f {} guess {guess}: {e}", c.f));
            let (fx, _) = r.solution.camera.unwrap().focal_lengths();
            assert!(
                (fx / c.f - 1.0).abs() < 0.02,
                "{outliers} seed {seed}: f {fx} vs {}",
                c.f
            );
            assert!(
                rot_err_deg(&r.solution.rotation, &c.r) < 0.5,
                "{outliers} seed {seed}"
            );
            assert!(
                r.inliers[wrong..].iter().filter(|x| **x).count() >= 95 - wrong,
                "{outliers} seed {seed}"
            );
        }
    }
}

/// The bundled COLMAP model with its focal lengths withheld: each image's camera given with a
/// focal length 1.5 times COLMAP's (and, as a second guess, 0.6 times), the focal length
/// estimated with the pose from the model's correspondences (plain solve, and RANSAC): within
/// 1 % of COLMAP's, the rotation within 0.05 degrees of the model's.
#[test]
fn the_bundled_model_with_its_focal_lengths_withheld() {
    use eopnp::colmap::{read_model, ReadOptions};
    use eopnp::ransac::Ransac;
    let model = read_model(
        concat!(env!("CARGO_MANIFEST_DIR"), "/data/colmap-boxes"),
        &ReadOptions::default(),
    )
    .unwrap();
    let mut rows = Vec::new();
    for (id, img) in &model.images {
        let cam = &model.cameras[&img.camera_id];
        let (mut world, mut pixels) = (Vec::new(), Vec::new());
        for (xy, p3) in &img.points2d {
            if let Some(p) = p3.and_then(|k| model.points.get(&k)) {
                world.push(p.xyz);
                pixels.push(*xy);
            }
        }
        let (r_ref, _) = img.pose();
        let (f_ref, _) = cam.focal_lengths();
        for factor in [1.5, 0.6] {
            let guess = Camera::from_colmap(cam.model().name(), cam.width(), cam.height(), {
                let mut p = cam.params().to_vec();
                p[0] *= factor;
                if !matches!(
                    cam.model().name(),
                    "SIMPLE_PINHOLE"
                        | "SIMPLE_RADIAL"
                        | "RADIAL"
                        | "SIMPLE_RADIAL_FISHEYE"
                        | "RADIAL_FISHEYE"
                ) {
                    p[1] *= factor;
                }
                p
            })
            .unwrap();
            let problem = Problem::pixels(&world, &pixels, &guess).unknown_focal();
            let plain = Solver::default().solve(&problem).unwrap();
            let robust = Ransac::default()
                .estimate(&Solver::default(), &problem)
                .unwrap()
                .solution;
            for (kind, s) in [("plain", plain), ("ransac", robust)] {
                let f = s.camera.unwrap().focal_lengths().0;
                let (df, dr) = ((f / f_ref - 1.0).abs(), rot_err_deg(&s.rotation, &r_ref));
                rows.push((*id, factor, kind, df, dr));
                assert!(df <= 0.01, "image {id} x{factor} {kind}: f {f} vs {f_ref}");
                assert!(dr <= 0.05, "image {id} x{factor} {kind}: {dr} degrees");
            }
        }
    }
    let worst_f = rows.iter().map(|r| r.3).fold(0.0, f64::max);
    let worst_r = rows.iter().map(|r| r.4).fold(0.0, f64::max);
    println!(
        "{} solves of {} images: worst focal error {:.4} %, worst rotation error {worst_r:.4} degrees",
        rows.len(),
        model.images.len(),
        100.0 * worst_f
    );
}

#[test]
fn a_range_without_the_truth_or_the_guess_returns_a_focal_length_within_it() {
    // The truth 1,500 px, the guess 1,000 px, the range 300 to 900 px: the search's minima lie
    // outside it; the solution is still a pose at a focal length within the range.
    for trial in 0..10 {
        let mut c = case(trial_seed("focal_range_out", trial), 40, 1.0);
        let scale = 1500.0 / c.f;
        for p in &mut c.pixels {
            *p = c.c + (*p - c.c) * scale;
        }
        let guess = Camera::pinhole(1000.0, 1000.0, c.c.x, c.c.y).unwrap();
        let p = Problem::pixels(&c.world, &c.pixels, &guess).unknown_focal_within(300.0, 900.0);
        let sol = Solver::default().solve(&p).unwrap();
        let (fx, _) = sol.camera.unwrap().focal_lengths();
        assert!((300.0..=900.0).contains(&fx), "trial {trial}: {fx}");
        let r = Solver::default().refine(&p, &sol.pose()).unwrap();
        let (fx, _) = r.camera.unwrap().focal_lengths();
        assert!((300.0..=900.0).contains(&fx), "trial {trial}: refine {fx}");
    }
}
