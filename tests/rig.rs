//! Multi-camera rigs (`Problem::rig`, generalized EOPnP): synthetic rigs of 2 to 6 cameras
//! looking outward (a car's or a headset's), baselines 0.1 to 2 units, points 2 to 30 units
//! from their camera, pinhole and distorting cameras.

use eopnp::camera::Camera;
use eopnp::ransac::Ransac;
use eopnp::{PnpError, Problem, Rig, Solver};
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
        let alone = Rig::new(vec![(c.rig.cameras()[1].clone(), Isometry3::identity())]).unwrap();
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
    let _ = Rotation3::<f64>::identity();
}
