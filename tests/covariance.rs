//! The pose covariance against Monte Carlo: over many noise draws of one problem, the
//! estimates' spread matches the predicted covariance (whitened chi-square and the eigenvalues
//! of the whitened empirical covariance), for normalised input, pixel input through a
//! distorted camera, and the estimated noise level; and RANSAC's pose carries the covariance
//! of its inliers.
use eopnp::camera::Camera;
use eopnp::covariance::NoiseModel;
use eopnp::ransac::Ransac;
use eopnp::{Solution, Solver};
use eopnp_testkit::{self as common, Problem, ProblemOptions, RotationKind, Scene};
use nalgebra::{Matrix6, Point2, Rotation3, Vector6};
use rand_distr::{Distribution, Normal};

const DRAWS: usize = 2000;

/// `[delta_q, delta_t]` of `(r, t)` from `(r0, t0)`: `r = Exp(2 delta_q) r0` (the covariance's
/// convention).
fn tangent(
    r: &nalgebra::Matrix3<f64>,
    t: &nalgebra::Vector3<f64>,
    r0: &nalgebra::Matrix3<f64>,
    t0: &nalgebra::Vector3<f64>,
) -> Vector6<f64> {
    let d = Rotation3::from_matrix_unchecked(r * r0.transpose()).scaled_axis() * 0.5;
    let dt = t - t0;
    Vector6::new(d.x, d.y, d.z, dt.x, dt.y, dt.z)
}

/// Mean whitened chi-square and the extreme eigenvalues of `C^-1/2 S C^-1/2`, `S` the
/// empirical covariance of `devs` about the truth.
fn compare(devs: &[Vector6<f64>], c: &Matrix6<f64>) -> (f64, f64, f64) {
    let l = c.cholesky().unwrap();
    let linv = l.l().try_inverse().unwrap();
    let mut s = Matrix6::zeros();
    let mut chi2 = 0.0;
    for d in devs {
        let w = linv * d;
        chi2 += w.norm_squared();
        s += w * w.transpose();
    }
    let n = devs.len() as f64;
    s /= n;
    let ev = s.symmetric_eigen().eigenvalues;
    (chi2 / n, ev.min(), ev.max())
}

/// The Monte Carlo problem: 30 points, seeded, and its noise-free pixels through `camera`.
fn fixture(camera: &Camera) -> (Problem, Vec<Point2<f64>>) {
    let p = Problem::generate(&ProblemOptions {
        n: 30,
        sigma_px: 0.0,
        scene: Scene::General,
        rotation: RotationKind::Uniform,
        seed: common::trial_seed("covariance", 1),
    });
    let clean = p.image.iter().map(|m| camera.project(*m)).collect();
    (p, clean)
}

fn run(camera: &Camera, sigma_px: f64, noise: NoiseModel) -> (f64, f64, f64, f64) {
    let (p, clean) = fixture(camera);
    let solver = Solver::default().covariance(Some(noise));
    // The predicted covariance at the noise-free pose, for the stated noise.
    let c = Solver::default()
        .covariance(Some(NoiseModel::Sigma(sigma_px)))
        .solve(&eopnp::Problem::pixels(&p.world, &clean, camera))
        .unwrap()
        .covariance
        .unwrap()
        .matrix;
    let mut rng = common::rng_from_seed(common::trial_seed("covariance_noise", 1));
    let normal = Normal::new(0.0, sigma_px).unwrap();
    let mut devs = Vec::with_capacity(DRAWS);
    let mut var = 0.0;
    for _ in 0..DRAWS {
        let px: Vec<Point2<f64>> = clean
            .iter()
            .map(|q| Point2::new(q.x + normal.sample(&mut rng), q.y + normal.sample(&mut rng)))
            .collect();
        let sol = solver
            .solve(&eopnp::Problem::pixels(&p.world, &px, camera))
            .unwrap();
        let cov = sol.covariance.unwrap();
        var += cov.sigma * cov.sigma;
        if let NoiseModel::Sigma(s) = noise {
            // A given sigma is reported as given, and the covariance scales with sigma^2: for
            // 2 sigma it is exactly 4 times that for sigma at the same pose (a power of two:
            // no rounding of its own).
            assert_eq!(cov.sigma, s, "the given sigma is reported");
            let double = Solver::default()
                .covariance(Some(NoiseModel::Sigma(2.0 * s)))
                .solve(&eopnp::Problem::pixels(&p.world, &px, camera))
                .unwrap();
            assert_eq!(
                double.rotation, sol.rotation,
                "the noise level changes the pose"
            );
            assert_eq!(
                double.covariance.unwrap().matrix,
                cov.matrix * 4.0,
                "the covariance for sigma {} is not 4 times that for sigma {s}",
                2.0 * s
            );
        }
        devs.push(tangent(&sol.rotation, &sol.translation, &p.r_gt, &p.t_gt));
    }
    let (chi2, lo, hi) = compare(&devs, &c);
    (chi2, lo, hi, (var / DRAWS as f64).sqrt())
}

fn check(name: &str, camera: &Camera, sigma_px: f64, noise: NoiseModel) {
    let (chi2, lo, hi, sigma) = run(camera, sigma_px, noise);
    println!("{name}: mean chi2 {chi2:.3} (6 expected), whitened eigenvalues {lo:.3}..{hi:.3}, sigma {sigma:.4} px");
    // Mean of 2,000 chi-square(6) draws: standard deviation 0.077; 0.4 is five of them.
    assert!((chi2 - 6.0).abs() < 0.4, "{name}: {chi2}");
    // Eigenvalues of a 6 x 6 sample covariance of 2,000 draws: within about 0.1 of 1.
    assert!(lo > 0.85 && hi < 1.15, "{name}: {lo} {hi}");
    match noise {
        // Given: `run` asserted each draw's sigma and the covariance's sigma^2 scaling.
        NoiseModel::Sigma(_) => {}
        // Estimated: sigma^2 = cost / (2 N - 6) is unbiased to first order; its mean over the
        // draws (2,000 x 54 degrees of freedom) has a relative standard deviation of
        // sqrt(2 / 108,000) = 0.0043, so the RMS sigma is within about 0.2 % of the true one
        // (1 % is 4.6 standard deviations in sigma^2). Dividing by 2 N instead of 2 N - 6 would
        // be 5 % off.
        _ => assert!(
            (sigma / sigma_px - 1.0).abs() < 0.01,
            "{name}: estimated sigma {sigma} (RMS over the draws) for a true {sigma_px}"
        ),
    }
}

#[test]
fn covariance_matches_monte_carlo_pinhole() {
    let cam = Camera::pinhole(800.0, 800.0, 320.0, 240.0).unwrap();
    check("pinhole, sigma given", &cam, 0.5, NoiseModel::Sigma(0.5));
    check("pinhole, sigma estimated", &cam, 2.0, NoiseModel::Estimated);
}

#[test]
fn covariance_matches_monte_carlo_through_distortion() {
    let cam =
        Camera::from_colmap("RADIAL", 640, 480, vec![800.0, 320.0, 240.0, -0.25, 0.05]).unwrap();
    check(
        "radial k1 -0.25, sigma given",
        &cam,
        1.0,
        NoiseModel::Sigma(1.0),
    );
}

/// `max |a - b| / max |b|` of two covariance matrices.
fn relative_difference(a: &Solution, b: &Solution) -> f64 {
    let (a, b) = (a.covariance.unwrap().matrix, b.covariance.unwrap().matrix);
    (a - b).amax() / b.amax()
}

/// RANSAC's pose carries the covariance its solver asks for: that of the returned pose from its
/// inliers with their weights, as a solve of the same points with the outliers' weights set to
/// 0 reports it; for normalised input (where the two solves are the same computation) and for
/// pixels through a distorting camera (where RANSAC's fits start from first-order weighted
/// points and the solve does not, so the poses agree to the refinement's convergence). Without
/// the option, no covariance.
#[test]
fn ransac_pose_carries_the_covariance_of_its_inliers() {
    let n = 60;
    let p = Problem::generate(&ProblemOptions {
        n,
        sigma_px: 1.0,
        scene: Scene::General,
        rotation: RotationKind::Uniform,
        seed: common::trial_seed("covariance_ransac", 1),
    });
    // Every fifth correspondence moved by about 50 px (at f = 800).
    let wrong = |i: usize| i.is_multiple_of(5);
    let image: Vec<Point2<f64>> = p
        .image
        .iter()
        .enumerate()
        .map(|(i, m)| {
            if wrong(i) {
                Point2::new(m.x + 0.05, m.y - 0.04)
            } else {
                *m
            }
        })
        .collect();
    let weights: Vec<f64> = (0..n).map(|i| 1.0 + 0.5 * (i % 3) as f64).collect();
    let ransac = Ransac::default().threshold_px(4.0).seed(3);
    let masked = |inliers: &[bool]| -> Vec<f64> {
        (0..n)
            .map(|i| if inliers[i] { weights[i] } else { 0.0 })
            .collect()
    };

    let solver = Solver::default().covariance(Some(NoiseModel::Sigma(1.0 / 800.0)));
    let r = ransac
        .estimate(
            &solver,
            &eopnp::Problem::normalised(&p.world, &image)
                .focal(800.0, 800.0)
                .weights(&weights),
        )
        .unwrap();
    assert!((0..n).all(|i| !(wrong(i) && r.inliers[i])));
    assert!(r.num_inliers >= 40, "{}", r.num_inliers);
    let direct = solver
        .solve(&eopnp::Problem::normalised(&p.world, &image).weights(&masked(&r.inliers)))
        .unwrap();
    assert!((r.solution.rotation - direct.rotation).amax() < 1e-12);
    let d = relative_difference(&r.solution, &direct);
    assert!(d < 1e-12, "normalised: {d:e}");
    let plain = ransac
        .estimate(
            &Solver::default(),
            &eopnp::Problem::normalised(&p.world, &image)
                .focal(800.0, 800.0)
                .weights(&weights),
        )
        .unwrap();
    assert!(plain.solution.covariance.is_none());

    let cam =
        Camera::from_colmap("RADIAL", 640, 480, vec![800.0, 320.0, 240.0, -0.25, 0.05]).unwrap();
    let solver = Solver::default().covariance(Some(NoiseModel::Estimated));
    let pixels: Vec<Point2<f64>> = image.iter().map(|m| cam.project(*m)).collect();
    let r = ransac
        .estimate(
            &solver,
            &eopnp::Problem::pixels(&p.world, &pixels, &cam).weights(&weights),
        )
        .unwrap();
    assert!((0..n).all(|i| !(wrong(i) && r.inliers[i])));
    assert!(r.num_inliers >= 40, "{}", r.num_inliers);
    let direct = solver
        .solve(&eopnp::Problem::pixels(&p.world, &pixels, &cam).weights(&masked(&r.inliers)))
        .unwrap();
    assert!((r.solution.rotation - direct.rotation).amax() < 1e-9);
    let d = relative_difference(&r.solution, &direct);
    assert!(d < 1e-6, "pixels: {d:e}");
    println!(
        "RANSAC covariance against the inliers' solve: pixels {d:.2e} relative, sigma {:.4} px",
        r.solution.covariance.unwrap().sigma
    );
}

#[test]
fn covariance_with_an_unknown_focal_length_matches_monte_carlo() {
    // The pose's marginal covariance and the focal length's standard deviation
    // (`PoseCovariance::focal_sigma`) against 2,000 noise draws of one problem solved with its
    // focal length unknown.
    let camera = Camera::pinhole(800.0, 800.0, 320.0, 240.0).unwrap();
    let sigma_px = 1.0;
    let (p, clean) = fixture(&camera);
    let solver = Solver::default().covariance(Some(NoiseModel::Sigma(sigma_px)));
    let at_truth = solver
        .solve(&eopnp::Problem::pixels(&p.world, &clean, &camera).unknown_focal())
        .unwrap()
        .covariance
        .unwrap();
    let predicted = at_truth.focal_sigma.unwrap();
    let mut rng = common::rng_from_seed(common::trial_seed("covariance_noise", 2));
    let normal = Normal::new(0.0, sigma_px).unwrap();
    let (mut devs, mut focal) = (Vec::with_capacity(DRAWS), Vec::with_capacity(DRAWS));
    for _ in 0..DRAWS {
        let px: Vec<Point2<f64>> = clean
            .iter()
            .map(|q| Point2::new(q.x + normal.sample(&mut rng), q.y + normal.sample(&mut rng)))
            .collect();
        let sol = solver
            .solve(&eopnp::Problem::pixels(&p.world, &px, &camera).unknown_focal())
            .unwrap();
        assert!(sol.covariance.unwrap().focal_sigma.is_some());
        devs.push(tangent(&sol.rotation, &sol.translation, &p.r_gt, &p.t_gt));
        focal.push(sol.camera.unwrap().focal_lengths().0 - 800.0);
    }
    let (chi2, lo, hi) = compare(&devs, &at_truth.matrix);
    let spread = (focal.iter().map(|d| d * d).sum::<f64>() / DRAWS as f64).sqrt();
    println!(
        "unknown focal length, sigma given: mean chi2 {chi2:.3} (6 expected), whitened \
         eigenvalues {lo:.3}..{hi:.3}; focal length spread {spread:.3} px against \
         {predicted:.3} px predicted"
    );
    assert!((chi2 - 6.0).abs() < 0.4, "{chi2}");
    assert!(lo > 0.85 && hi < 1.15, "{lo} {hi}");
    // The RMS of 2,000 draws about the truth: relative standard deviation 1.6 %; 6 % is
    // about four of them.
    assert!(
        (spread / predicted - 1.0).abs() < 0.06,
        "{spread} against {predicted}"
    );
}
