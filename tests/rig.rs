//! Multi-camera rigs (`Problem::rig`, generalized EOPnP): synthetic rigs of 2 to 6 cameras
//! looking outward (a car's or a headset's), baselines 0.1 to 2 units, points 2 to 30 units
//! from their camera, pinhole and distorting cameras.

use eopnp::camera::Camera;
use eopnp::covariance::NoiseModel;
use eopnp::ransac::Ransac;
use eopnp::{DegenerateKind, InputKind, Loss, PnpError, Problem, Rig, Solver};
use nalgebra::{
    Isometry3, Matrix3, Point2, Point3, Rotation3, Translation3, UnitQuaternion, Vector3,
};
use rand::{Rng, SeedableRng};
use rand_distr::{Distribution, Normal};
use rand_pcg::Pcg64;

/// A synthetic rig problem and its truth.
struct RigCase {
    rig: Rig,
    world: Vec<Point3<f64>>,
    pixels: Vec<Point2<f64>>,
    cameras: Vec<u32>,
    truth: Isometry3<f64>,
}

/// `n_cams` cameras on a circle of diameter `baseline`, each looking outward (yaw 2 pi k / n);
/// `n` points, each seen by one camera (round robin), 2 to 30 units away within a 90-degree
/// field of view; pixel noise `sigma`; `planar`: the points on one plane of the world (each
/// camera's points where its rays meet the plane, which must be in front). Distorting cameras
/// (`SIMPLE_RADIAL`, k = -0.1) when `distort`.
fn rig_case(
    seed: u64,
    n_cams: usize,
    baseline: f64,
    n: usize,
    sigma: f64,
    distort: bool,
) -> RigCase {
    rig_case_with(seed, n_cams, baseline, n, sigma, distort, false)
}

/// [`rig_case`]; `planar`: every point on the ground plane 1.5 units below the rig (`y = 1.5`
/// in the rig frame, the cameras' `y` axis pointing down), where each camera's rays below its
/// horizon meet it 3.75 to 15 units away.
fn rig_case_with(
    seed: u64,
    n_cams: usize,
    baseline: f64,
    n: usize,
    sigma: f64,
    distort: bool,
    planar: bool,
) -> RigCase {
    let mut rng = Pcg64::seed_from_u64(seed);
    let mut cams = Vec::new();
    for k in 0..n_cams {
        let yaw = std::f64::consts::TAU * k as f64 / n_cams as f64 + rng.random_range(-0.1..0.1);
        let c = Vector3::new(yaw.sin(), 0.0, yaw.cos()) * (0.5 * baseline);
        // Camera axes in the rig frame: z outward, x to its right, y down.
        let z = Vector3::new(yaw.sin(), 0.0, yaw.cos());
        let x = Vector3::new(yaw.cos(), 0.0, -yaw.sin());
        let y = z.cross(&x);
        let rk = Matrix3::from_rows(&[x.transpose(), y.transpose(), z.transpose()]);
        let rot = UnitQuaternion::from_matrix(&rk);
        let t = -(rk * c);
        let cam = if distort {
            Camera::from_colmap("SIMPLE_RADIAL", 640, 480, vec![500.0, 320.0, 240.0, -0.1]).unwrap()
        } else {
            Camera::pinhole(500.0, 520.0, 320.0, 240.0).unwrap()
        };
        cams.push((cam, Isometry3::from_parts(Translation3::from(t), rot)));
    }
    let rig = Rig::new(cams).unwrap();
    let axis = Vector3::new(
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
    );
    let truth = Isometry3::from_parts(
        Translation3::new(
            rng.random_range(-2.0..2.0),
            rng.random_range(-2.0..2.0),
            rng.random_range(-2.0..2.0),
        ),
        UnitQuaternion::from_scaled_axis(axis.normalize() * rng.random_range(0.0..3.1)),
    );
    let noise = Normal::new(0.0, 1.0).unwrap();
    let (mut world, mut pixels, mut cameras) = (Vec::new(), Vec::new(), Vec::new());
    for i in 0..n {
        let k = i % n_cams;
        let (m, depth) = if planar {
            let m = Point2::new(rng.random_range(-0.5..0.5), rng.random_range(0.1..0.4));
            // The ray R_k^T (m, 1) from the centre c_k (y = 0) meets y = 1.5 at depth 1.5 / m.y
            // (the camera's y axis is the rig's).
            (m, 1.5 / m.y)
        } else {
            let m = Point2::new(rng.random_range(-0.5..0.5), rng.random_range(-0.4..0.4));
            (m, rng.random_range(2.0..30.0))
        };
        let p_cam = Point3::new(m.x * depth, m.y * depth, depth);
        let cam_from_rig = rig.cam_from_rig()[k];
        let x = truth.inverse() * (cam_from_rig.inverse() * p_cam);
        let px = rig.cameras()[k].project(m);
        let e = Vector3::new(noise.sample(&mut rng), noise.sample(&mut rng), 0.0) * sigma;
        world.push(x);
        pixels.push(Point2::new(px.x + e.x, px.y + e.y));
        cameras.push(k as u32);
    }
    RigCase {
        rig,
        world,
        pixels,
        cameras,
        truth,
    }
}

fn rot_err_deg(a: &Matrix3<f64>, b: &Matrix3<f64>) -> f64 {
    (0..3)
        .map(|k| {
            let (x, y) = (a.column(k), b.column(k));
            x.cross(&y).norm().atan2(x.dot(&y))
        })
        .fold(0.0, f64::max)
        .to_degrees()
}

/// The pixel cost `sum |e|^2` of a rig pose.
fn pixel_cost(c: &RigCase, r: &Matrix3<f64>, t: &Vector3<f64>) -> f64 {
    let mut cost = 0.0;
    for i in 0..c.world.len() {
        let k = c.cameras[i] as usize;
        let p = c.rig.cam_from_rig()[k] * Point3::from(r * c.world[i].coords + t);
        let px = c.rig.cameras()[k].project(Point2::new(p.x / p.z, p.y / p.z));
        cost += (px - c.pixels[i]).norm_squared();
    }
    cost
}

/// Noise-free rigs, every configuration (2 to 6 cameras, baselines 0.1 to 2, N = 4 to 100,
/// pinhole and distorting): the rotation within 1e-8 degrees.
#[test]
fn noise_free_rigs_give_the_exact_pose() {
    let mut worst = 0.0f64;
    let mut count = 0;
    for seed in 0..300u64 {
        let n_cams = 2 + (seed % 5) as usize;
        let baseline = [0.1, 0.5, 1.0, 2.0][(seed % 4) as usize];
        let n = [4, 5, 6, 10, 30, 100][(seed % 6) as usize].max(n_cams);
        let c = rig_case(seed, n_cams, baseline, n, 0.0, seed % 3 == 0);
        let sol = Solver::default()
            .solve(&Problem::rig(&c.world, &c.pixels, &c.cameras, &c.rig))
            .unwrap_or_else(|e| panic!("seed {seed}: {e}"));
        let err = rot_err_deg(
            &sol.rotation,
            c.truth.rotation.to_rotation_matrix().matrix(),
        );
        assert!(
            err < 1e-8,
            "seed {seed} ({n_cams} cameras, N = {n}): {err:e} deg"
        );
        assert!(
            (sol.translation - c.truth.translation.vector).norm()
                < 1e-8 * (1.0 + c.truth.translation.vector.norm())
        );
        worst = worst.max(err);
        count += 1;
    }
    println!("rig, noise-free: {count} problems, worst rotation error {worst:e} deg");
}

/// Noise-free planar scenes (every point on one plane of the world): the rotation within 1e-8
/// degrees.
#[test]
fn noise_free_planar_rigs_give_the_exact_pose() {
    let mut worst = 0.0f64;
    for seed in 0..200u64 {
        let n_cams = 2 + (seed % 5) as usize;
        let n = [4, 5, 6, 10, 30, 100][(seed % 6) as usize].max(n_cams);
        let c = rig_case_with(3000 + seed, n_cams, 0.5, n, 0.0, seed % 2 == 0, true);
        let sol = Solver::default()
            .solve(&Problem::rig(&c.world, &c.pixels, &c.cameras, &c.rig))
            .unwrap_or_else(|e| panic!("seed {seed}: {e}"));
        assert!(sol.planar, "seed {seed}: not detected as planar");
        let err = rot_err_deg(
            &sol.rotation,
            c.truth.rotation.to_rotation_matrix().matrix(),
        );
        assert!(
            err < 1e-8,
            "seed {seed} ({n_cams} cameras, N = {n}): {err:e} deg"
        );
        worst = worst.max(err);
    }
    println!("rig, noise-free planar: worst rotation error {worst:e} deg");
}

/// sigma = 1 px: the pixel cost of the default pose is never above that of the refinement
/// started at the ground truth (relative 1e-9), N = 6, 10, 100, 1000, 200 problems each.
#[test]
fn default_pose_is_the_ml_pose() {
    for n in [6usize, 10, 100, 1000] {
        let mut worst = f64::NEG_INFINITY;
        for seed in 0..200u64 {
            let n_cams = 2 + (seed % 5) as usize;
            let baseline = 0.1 + 1.9 * ((seed * 7) % 10) as f64 / 9.0;
            let c = rig_case(1000 + seed, n_cams, baseline, n, 1.0, seed % 2 == 0);
            let problem = Problem::rig(&c.world, &c.pixels, &c.cameras, &c.rig);
            let sol = Solver::default().solve(&problem).unwrap();
            let ml = Solver::default().refine(&problem, &c.truth).unwrap();
            let (a, b) = (
                pixel_cost(&c, &sol.rotation, &sol.translation),
                pixel_cost(&c, &ml.rotation, &ml.translation),
            );
            let rel = (a - b) / b;
            assert!(
                rel <= 1e-9,
                "N = {n} seed {seed}: the default pose's cost {a} is above LM-from-GT's {b} ({rel:e})"
            );
            worst = worst.max(rel);
        }
        println!("rig, sigma 1 px, N = {n}: largest relative cost above LM-from-GT {worst:e}");
    }
}

/// A rig of one camera (at any pose in the rig) gives the central solver's pose.
#[test]
fn one_camera_rig_is_the_central_problem() {
    for seed in 0..50u64 {
        let c = rig_case(5000 + seed, 3, 0.5, 30, 1.0, seed % 2 == 0);
        // Keep camera 1's observations only.
        let keep: Vec<usize> = (0..c.world.len()).filter(|&i| c.cameras[i] == 1).collect();
        let world: Vec<Point3<f64>> = keep.iter().map(|&i| c.world[i]).collect();
        let pixels: Vec<Point2<f64>> = keep.iter().map(|&i| c.pixels[i]).collect();
        let cameras = vec![1u32; keep.len()];
        let sol = Solver::default()
            .solve(&Problem::rig(&world, &pixels, &cameras, &c.rig))
            .unwrap();
        let central = Solver::default()
            .solve(&Problem::pixels(&world, &pixels, &c.rig.cameras()[1]))
            .unwrap();
        // The central pose is camera 1's; in the rig: x_cam = R_1 x_rig + t_1.
        let cam_from_rig = c.rig.cam_from_rig()[1];
        let composed = cam_from_rig * sol.pose();
        let err = rot_err_deg(
            composed.rotation.to_rotation_matrix().matrix(),
            &central.rotation,
        );
        assert!(err <= 1e-10, "seed {seed}: {err:e} deg");
        // A rig of that camera alone, at the identity, is bit for bit the central solve.
        let alone = Rig::new(vec![(c.rig.cameras()[1], Isometry3::identity())]).unwrap();
        let zeros = vec![0u32; keep.len()];
        let s1 = Solver::default()
            .solve(&Problem::rig(&world, &pixels, &zeros, &alone))
            .unwrap();
        assert_eq!(
            (s1.rotation, s1.translation),
            (central.rotation, central.translation)
        );
    }
}

/// RANSAC on rigs: 0, 50 and 80 % of the correspondences replaced by wrong world points; the
/// pose within 0.5 degrees (sigma 1 px, N = 200) and the wrong ones outliers.
#[test]
fn ransac_on_rigs() {
    for (level, fraction) in [0.0, 0.5, 0.8].into_iter().enumerate() {
        for seed in 0..20u64 {
            let mut c = rig_case(
                7000 + seed,
                2 + (seed % 5) as usize,
                1.0,
                200,
                1.0,
                seed % 2 == 0,
            );
            let mut rng = Pcg64::seed_from_u64(seed + 100 * level as u64);
            let n = c.world.len();
            let k = (fraction * n as f64) as usize;
            for i in 0..k {
                c.world[i] += Vector3::new(
                    rng.random_range(-10.0..10.0),
                    rng.random_range(-10.0..10.0),
                    rng.random_range(-10.0..10.0),
                );
            }
            let sol = Ransac::default()
                .seed(seed)
                .estimate(
                    &Solver::default(),
                    &Problem::rig(&c.world, &c.pixels, &c.cameras, &c.rig),
                )
                .unwrap_or_else(|e| panic!("{fraction} seed {seed}: {e}"));
            let err = rot_err_deg(
                &sol.solution.rotation,
                c.truth.rotation.to_rotation_matrix().matrix(),
            );
            assert!(err < 0.5, "{fraction} seed {seed}: {err} deg");
            let wrong_inliers = sol.inliers[..k].iter().filter(|x| **x).count();
            assert!(
                wrong_inliers <= k / 50,
                "{fraction} seed {seed}: {wrong_inliers} wrong inliers"
            );
        }
    }
}

/// Bad input gets a typed error.
#[test]
fn bad_rig_input_is_a_typed_error() {
    let c = rig_case(9, 3, 1.0, 20, 0.0, false);
    let solver = Solver::default();
    let short = &c.cameras[..19];
    assert_eq!(
        solver
            .solve(&Problem::rig(&c.world, &c.pixels, short, &c.rig))
            .unwrap_err(),
        PnpError::CameraIndicesLength {
            indices: 19,
            points: 20
        }
    );
    let mut bad = c.cameras.clone();
    bad[7] = 3;
    assert_eq!(
        solver
            .solve(&Problem::rig(&c.world, &c.pixels, &bad, &c.rig))
            .unwrap_err(),
        PnpError::UnknownCamera {
            index: 7,
            camera: 3
        }
    );
    assert!(matches!(
        solver.solve(&Problem::rig(
            &c.world[..3],
            &c.pixels[..3],
            &c.cameras[..3],
            &c.rig
        )),
        Err(PnpError::TooFewPoints { got: 3, need: 4 })
    ));
    assert_eq!(
        Rig::new(Vec::new()).unwrap_err(),
        PnpError::InvalidOption { option: "rig" }
    );
    // Coincident and collinear world points.
    let same = vec![c.world[0]; 20];
    assert_eq!(
        solver
            .solve(&Problem::rig(&same, &c.pixels, &c.cameras, &c.rig))
            .unwrap_err(),
        PnpError::Degenerate(DegenerateKind::CoincidentWorldPoints)
    );
    let line: Vec<Point3<f64>> = (0..20)
        .map(|i| Point3::new(1.0, 2.0, 3.0) + Vector3::new(1.0, -2.0, 0.5) * i as f64)
        .collect();
    assert_eq!(
        solver
            .solve(&Problem::rig(&line, &c.pixels, &c.cameras, &c.rig))
            .unwrap_err(),
        PnpError::Degenerate(DegenerateKind::CollinearWorldPoints)
    );
    // A non-finite pose in the rig, and a non-finite pixel.
    let nan_pose = Isometry3::from_parts(
        Translation3::new(f64::NAN, 0.0, 0.0),
        UnitQuaternion::identity(),
    );
    assert_eq!(
        Rig::new(vec![(c.rig.cameras()[0], nan_pose)]).unwrap_err(),
        PnpError::InvalidOption {
            option: "cam_from_rig"
        }
    );
    let mut pixels = c.pixels.clone();
    pixels[2].x = f64::INFINITY;
    assert!(matches!(
        solver.solve(&Problem::rig(&c.world, &pixels, &c.cameras, &c.rig)),
        Err(PnpError::NonFinite { .. })
    ));
    // Each bad value reported with its index and kind; the first bad correspondence wins.
    let mut world = c.world.clone();
    world[4].z = f64::NAN;
    let mut weights = vec![1.0; 20];
    weights[6] = -0.5;
    let mut nan_weight = vec![1.0; 20];
    nan_weight[9] = f64::NAN;
    // World points, pixels, weights, and the error they must give.
    type Case<'a> = (
        &'a [Point3<f64>],
        &'a [Point2<f64>],
        Option<&'a [f64]>,
        PnpError,
    );
    let cases: [Case<'_>; 5] = [
        (
            &world,
            &c.pixels,
            None,
            PnpError::NonFinite {
                index: 4,
                input: InputKind::World,
            },
        ),
        (
            &c.world,
            &pixels,
            None,
            PnpError::NonFinite {
                index: 2,
                input: InputKind::Image,
            },
        ),
        (
            &c.world,
            &c.pixels,
            Some(&weights),
            PnpError::InvalidWeight { index: 6 },
        ),
        (
            &c.world,
            &c.pixels,
            Some(&nan_weight),
            PnpError::NonFinite {
                index: 9,
                input: InputKind::Weight,
            },
        ),
        (
            &world,
            &pixels,
            Some(&weights),
            PnpError::NonFinite {
                index: 2,
                input: InputKind::Image,
            },
        ),
    ];
    for (world, pixels, weights, expected) in cases {
        let mut problem = Problem::rig(world, pixels, &c.cameras, &c.rig);
        if let Some(w) = weights {
            problem = problem.weights(w);
        }
        assert_eq!(solver.solve(&problem).unwrap_err(), expected);
    }
}

/// Cameras that share one centre (baseline 0, looking different ways): every ray through one
/// point is the central case, not an error. Noise-free: the exact pose; sigma = 1 px: the ML
/// pose (the pixel cost not above LM from the ground truth, relative 1e-9).
#[test]
fn co_centred_cameras_are_the_central_case() {
    for seed in 0..100u64 {
        let n_cams = 2 + (seed % 4) as usize;
        let n = [6usize, 10, 30, 100][(seed % 4) as usize];
        let c = rig_case(9000 + seed, n_cams, 0.0, n, 0.0, seed % 2 == 0);
        let sol = Solver::default()
            .solve(&Problem::rig(&c.world, &c.pixels, &c.cameras, &c.rig))
            .unwrap_or_else(|e| panic!("seed {seed}: {e}"));
        let err = rot_err_deg(
            &sol.rotation,
            c.truth.rotation.to_rotation_matrix().matrix(),
        );
        assert!(err < 1e-8, "seed {seed}: {err:e} deg");
        let c = rig_case(9500 + seed, n_cams, 0.0, n, 1.0, seed % 2 == 0);
        let problem = Problem::rig(&c.world, &c.pixels, &c.cameras, &c.rig);
        let sol = Solver::default().solve(&problem).unwrap();
        let ml = Solver::default().refine(&problem, &c.truth).unwrap();
        let (a, b) = (
            pixel_cost(&c, &sol.rotation, &sol.translation),
            pixel_cost(&c, &ml.rotation, &ml.translation),
        );
        assert!((a - b) / b <= 1e-9, "seed {seed}: {a} above {b}");
    }
}

/// Weights: a point of weight 0 is the same as a point removed (same pose to 1e-12), and
/// doubling every weight changes nothing but the cost's scale.
#[test]
fn weights_on_rigs() {
    for seed in 0..30u64 {
        let c = rig_case(11_000 + seed, 3, 1.0, 30, 1.0, seed % 2 == 0);
        let mut w = vec![1.0; 30];
        w[4] = 0.0;
        w[17] = 0.0;
        let weighted = Solver::default()
            .solve(&Problem::rig(&c.world, &c.pixels, &c.cameras, &c.rig).weights(&w))
            .unwrap();
        let keep: Vec<usize> = (0..30).filter(|&i| w[i] > 0.0).collect();
        let world: Vec<Point3<f64>> = keep.iter().map(|&i| c.world[i]).collect();
        let pixels: Vec<Point2<f64>> = keep.iter().map(|&i| c.pixels[i]).collect();
        let cameras: Vec<u32> = keep.iter().map(|&i| c.cameras[i]).collect();
        let removed = Solver::default()
            .solve(&Problem::rig(&world, &pixels, &cameras, &c.rig))
            .unwrap();
        let err = rot_err_deg(&weighted.rotation, &removed.rotation);
        assert!(err < 1e-10, "seed {seed}: {err:e} deg");
        assert!((weighted.translation - removed.translation).norm() < 1e-10);
        let twice = vec![2.0; 30];
        let doubled = Solver::default()
            .solve(&Problem::rig(&c.world, &c.pixels, &c.cameras, &c.rig).weights(&twice))
            .unwrap();
        let plain = Solver::default()
            .solve(&Problem::rig(&c.world, &c.pixels, &c.cameras, &c.rig))
            .unwrap();
        assert!(rot_err_deg(&doubled.rotation, &plain.rotation) < 1e-10);
    }
}

/// A robust loss keeps a few gross outliers from pulling the pose: with 10 % of the pixels
/// moved by 40 to 80 px, the Cauchy pose is within 0.3 degrees of the truth on every problem,
/// and closer than the squared loss's on most.
#[test]
fn robust_loss_on_rigs() {
    let mut better = 0;
    for seed in 0..40u64 {
        let mut c = rig_case(12_000 + seed, 4, 1.0, 60, 0.5, seed % 2 == 0);
        let mut rng = Pcg64::seed_from_u64(seed);
        for i in (0..60).step_by(10) {
            let a = rng.random_range(0.0..std::f64::consts::TAU);
            let d = rng.random_range(40.0..80.0);
            c.pixels[i] += Vector3::new(a.cos() * d, a.sin() * d, 0.0).xy();
        }
        let problem = Problem::rig(&c.world, &c.pixels, &c.cameras, &c.rig);
        let truth = c.truth.rotation.to_rotation_matrix();
        let robust = Solver::default()
            .loss(Loss::Cauchy(2.0))
            .solve(&problem)
            .unwrap();
        let plain = Solver::default().solve(&problem).unwrap();
        let (er, ep) = (
            rot_err_deg(&robust.rotation, truth.matrix()),
            rot_err_deg(&plain.rotation, truth.matrix()),
        );
        assert!(er < 0.3, "seed {seed}: Cauchy {er} deg");
        better += usize::from(er < ep);
    }
    assert!(better >= 35, "Cauchy closer on {better} of 40");
}

/// Refinement from a prior rig pose (a tracker's previous frame): from within a few degrees of
/// the truth it returns the default solve's (ML) pose.
#[test]
fn refine_from_a_prior_rig_pose() {
    for seed in 0..50u64 {
        let c = rig_case(13_000 + seed, 3, 1.0, 40, 1.0, seed % 2 == 0);
        let problem = Problem::rig(&c.world, &c.pixels, &c.cameras, &c.rig);
        let prior = Isometry3::from_parts(
            Translation3::from(c.truth.translation.vector + Vector3::new(0.05, -0.03, 0.04)),
            UnitQuaternion::from_scaled_axis(Vector3::new(0.03, -0.02, 0.04)) * c.truth.rotation,
        );
        let tracked = Solver::default().refine(&problem, &prior).unwrap();
        let global = Solver::default().solve(&problem).unwrap();
        assert!(tracked.converged);
        let err = rot_err_deg(&tracked.rotation, &global.rotation);
        assert!(err < 1e-7, "seed {seed}: {err:e} deg");
    }
}

/// The covariance of the rig's pose (pycolmap's convention: `[delta_q, delta_t]`, `R =
/// Exp(2 delta_q) R_hat`) against the spread of the default pose over 400 noise draws of one
/// rig (sigma = 1 px): each of the 6 variances within 25 % of the prediction (400 draws give
/// each sample variance a relative standard deviation of about 7 %).
#[test]
fn covariance_matches_the_spread_of_the_pose() {
    let base = rig_case(14_000, 3, 1.0, 60, 0.0, true);
    let predicted = Solver::default()
        .covariance(Some(NoiseModel::Sigma(1.0)))
        .solve(&Problem::rig(
            &base.world,
            &base.pixels,
            &base.cameras,
            &base.rig,
        ))
        .unwrap()
        .covariance
        .expect("covariance");
    let truth_r = base.truth.rotation.to_rotation_matrix();
    let noise = Normal::new(0.0, 1.0).unwrap();
    let mut rng = Pcg64::seed_from_u64(14);
    let draws = 400;
    let mut second = nalgebra::Matrix6::<f64>::zeros();
    for _ in 0..draws {
        let pixels: Vec<Point2<f64>> = base
            .pixels
            .iter()
            .map(|p| Point2::new(p.x + noise.sample(&mut rng), p.y + noise.sample(&mut rng)))
            .collect();
        let sol = Solver::default()
            .solve(&Problem::rig(
                &base.world,
                &pixels,
                &base.cameras,
                &base.rig,
            ))
            .unwrap();
        let omega = Rotation3::from_matrix_unchecked(sol.rotation * truth_r.matrix().transpose())
            .scaled_axis();
        let dt = sol.translation - base.truth.translation.vector;
        let d = nalgebra::Vector6::new(
            omega.x / 2.0,
            omega.y / 2.0,
            omega.z / 2.0,
            dt.x,
            dt.y,
            dt.z,
        );
        second += d * d.transpose();
    }
    let sample = second / draws as f64;
    for i in 0..6 {
        let ratio = sample[(i, i)] / predicted.matrix[(i, i)];
        assert!(
            (0.75..=1.33).contains(&ratio),
            "variance {i}: sample {:e}, predicted {:e} (ratio {ratio})",
            sample[(i, i)],
            predicted.matrix[(i, i)]
        );
    }
}
