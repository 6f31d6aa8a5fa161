//! The maximum-likelihood pose through every camera model with distortion (`refine_pixels`): on
//! synthetic problems with strong distortion, the pixel cost of the default pose is never above
//! that of Levenberg-Marquardt started at the ground truth (relative 1e-9), for plain, weighted and
//! RANSAC solves. The reference LM (`eopnp_testkit::lm_refine_projection`) differentiates the
//! camera by central differences: independent of the library's analytic Jacobians.

use eopnp::camera::Camera;
use eopnp::ransac::Ransac;
use eopnp::{Loss, Solver};
use eopnp_testkit::{haar_rotation, lm_refine_projection, rng_from_seed, rot_err_deg, trial_seed};
use nalgebra::{Isometry3, Matrix3, Point2, Point3, Translation3, UnitQuaternion, Vector3};
use rand::Rng;

/// Problems per model.
const TRIALS: u64 = 200;
const N: usize = 30;
const SIGMA_PX: f64 = 1.0;
/// The target: the default pose's pixel cost is at most LM-from-GT's times `1 + REL`.
const REL: f64 = 1e-9;

/// A camera with strong distortion and the largest normalised radius its points reach.
struct Case {
    camera: Camera,
    /// Largest off-axis angle of a point, degrees.
    max_angle_deg: f64,
}

fn cases() -> Vec<Case> {
    let cam = |name: &str, params: Vec<f64>| Camera::from_colmap(name, 1280, 960, params).unwrap();
    // Perspective models: k1 around -0.3, points up to 38.7 degrees off axis (normalised
    // radius 0.8, where the radial map is still monotonic). Fisheye: a field of view of 150
    // degrees (75 degrees off axis).
    let persp = 0.8f64.atan().to_degrees();
    vec![
        Case {
            camera: cam("SIMPLE_RADIAL", vec![800.0, 640.0, 480.0, -0.3]),
            max_angle_deg: persp,
        },
        Case {
            camera: cam("RADIAL", vec![800.0, 640.0, 480.0, -0.3, 0.08]),
            max_angle_deg: persp,
        },
        Case {
            camera: cam(
                "OPENCV",
                vec![800.0, 790.0, 640.0, 480.0, -0.3, 0.08, 1e-3, -8e-4],
            ),
            max_angle_deg: persp,
        },
        Case {
            camera: cam(
                "FULL_OPENCV",
                vec![
                    800.0, 790.0, 640.0, 480.0, -0.3, 0.08, 1e-3, -8e-4, -0.01, 0.05, 0.01, 0.002,
                ],
            ),
            max_angle_deg: persp,
        },
        Case {
            camera: Camera::new(
                "OPENCV_THIN_PRISM_TILTED".parse().unwrap(),
                1280,
                960,
                vec![
                    800.0, 790.0, 640.0, 480.0, -0.3, 0.08, 1e-3, -8e-4, -0.01, 0.05, 0.01, 0.002,
                    1e-3, -5e-4, 8e-4, 2e-4, 0.01, -0.02,
                ],
            )
            .unwrap(),
            max_angle_deg: persp,
        },
        Case {
            camera: cam(
                "OPENCV_FISHEYE",
                vec![400.0, 400.0, 640.0, 480.0, -0.02, 0.01, -0.005, 0.001],
            ),
            max_angle_deg: 75.0,
        },
        Case {
            camera: cam("SIMPLE_RADIAL_FISHEYE", vec![400.0, 640.0, 480.0, -0.05]),
            max_angle_deg: 75.0,
        },
        Case {
            camera: cam("RADIAL_FISHEYE", vec![400.0, 640.0, 480.0, -0.05, 0.01]),
            max_angle_deg: 75.0,
        },
    ]
}

struct Problem {
    world: Vec<Point3<f64>>,
    pixels: Vec<Point2<f64>>,
    r: Matrix3<f64>,
    t: Vector3<f64>,
}

/// Points spread over the field of view (uniform over the image disk of the off-axis angle),
/// at depths 4-8 along their rays, a Haar rotation, pixel noise of `SIGMA_PX`.
fn problem(case: &Case, seed: u64) -> Problem {
    let mut rng = rng_from_seed(seed);
    let r = haar_rotation(&mut rng);
    let max_theta = case.max_angle_deg.to_radians();
    let cam: Vec<Vector3<f64>> = (0..N)
        .map(|_| {
            let theta = max_theta * rng.random_range(0.0f64..1.0).sqrt();
            let phi = rng.random_range(0.0..std::f64::consts::TAU);
            let range = rng.random_range(4.0..8.0);
            let dir = Vector3::new(
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            );
            dir * range
        })
        .collect();
    let t = cam.iter().sum::<Vector3<f64>>() / N as f64;
    let world = cam
        .iter()
        .map(|p| Point3::from(r.transpose() * (p - t)))
        .collect();
    let pixels = cam
        .iter()
        .map(|p| {
            let px = case.camera.project(Point2::new(p.x / p.z, p.y / p.z));
            let noise = Vector3::new(gauss(&mut rng) * SIGMA_PX, gauss(&mut rng) * SIGMA_PX, 0.0);
            Point2::new(px.x + noise.x, px.y + noise.y)
        })
        .collect();
    Problem {
        world,
        pixels,
        r,
        t,
    }
}

fn gauss(rng: &mut impl Rng) -> f64 {
    // Box-Muller.
    let u1: f64 = rng.random_range(f64::EPSILON..1.0);
    let u2: f64 = rng.random_range(0.0..1.0);
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// Weighted sum of squared pixel residuals through the camera.
fn pixel_cost(
    cam: &Camera,
    world: &[Point3<f64>],
    pixels: &[Point2<f64>],
    weights: Option<&[f64]>,
    r: &Matrix3<f64>,
    t: &Vector3<f64>,
) -> f64 {
    world
        .iter()
        .zip(pixels)
        .enumerate()
        .map(|(i, (x, u))| {
            let p = r * x.coords + t;
            let e = cam.project(Point2::new(p.x / p.z, p.y / p.z)) - u;
            weights.map_or(1.0, |w| w[i]) * e.norm_squared()
        })
        .sum()
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

#[test]
fn default_pose_is_the_pixel_ml_pose_for_every_distortion_model() {
    for case in cases() {
        let cam = &case.camera;
        let name = cam.model().name();
        let (mut above, mut rot_to_ml) = (Vec::new(), Vec::new());
        let mut first_order_above = Vec::new();
        for trial in 0..TRIALS {
            let p = problem(&case, trial_seed(name, trial));
            let sol = Solver::default()
                .solve(&eopnp::Problem::pixels(&p.world, &p.pixels, cam))
                .unwrap_or_else(|e| panic!("{name} trial {trial}: {e}"));
            let r = sol.rotation;
            let t = sol.translation;
            let ml = lm_refine_projection(&p.world, &p.pixels, &p.r, &p.t, &|n| cam.project(n));
            assert!(
                ml.converged,
                "{name} trial {trial}: reference LM did not converge"
            );
            let cost = pixel_cost(cam, &p.world, &p.pixels, None, &r, &t);
            let ml_cost = pixel_cost(cam, &p.world, &p.pixels, None, &ml.r, &ml.t);
            assert!(
                cost <= ml_cost * (1.0 + REL),
                "{name} trial {trial}: pixel cost {cost} above LM from the ground truth \
                 {ml_cost} (relative {:e})",
                cost / ml_cost - 1.0
            );
            // The reported cost is this pixel cost.
            assert!(
                (sol.cost - cost).abs() <= 1e-9 * cost,
                "{name} trial {trial}: reported cost {} vs {cost}",
                sol.cost
            );
            assert!(sol.converged, "{name} trial {trial}");
            above.push(cost / ml_cost - 1.0);
            rot_to_ml.push(rot_err_deg(&r, &ml.r));
            // The first-order pose (`refine` on undistorted points weighted by |det J|, as before
            // `refine_pixels`), for the record.
            let (world, image, weights): (Vec<_>, Vec<_>, Vec<_>) = {
                let mut w = Vec::new();
                let mut m = Vec::new();
                let mut k = Vec::new();
                let (fx, fy) = cam.focal_lengths();
                for (x, u) in p.world.iter().zip(&p.pixels) {
                    let n = cam.undistort(*u).unwrap();
                    let j = cam.project_jacobian(n);
                    w.push(*x);
                    m.push(n);
                    k.push((j[0] * j[3] - j[1] * j[2]).abs() / (fx * fy));
                }
                (w, m, k)
            };
            let first = Solver::default()
                .solve(&eopnp::Problem::normalised(&world, &image).weights(&weights))
                .unwrap();
            let first_cost = pixel_cost(
                cam,
                &p.world,
                &p.pixels,
                None,
                &first.rotation,
                &first.translation,
            );
            first_order_above.push(first_cost / ml_cost - 1.0);
        }
        println!(
            "{name}: default pose vs LM from GT over {TRIALS} problems: relative cost \
             difference median {:.1e}, max {:.1e}; rotation to the ML pose median {:.1e} deg, \
             max {:.1e} deg; first-order pose (before `refine_pixels`) above ML: median {:.2e}, max {:.2e}",
            median(above.clone()),
            above.iter().copied().fold(f64::MIN, f64::max),
            median(rot_to_ml.clone()),
            rot_to_ml.iter().copied().fold(0.0, f64::max),
            median(first_order_above.clone()),
            first_order_above.iter().copied().fold(f64::MIN, f64::max),
        );
    }
}

/// Integer weights are duplicated points: the weighted `refine_pixels` minimises the same pixel
/// cost.
#[test]
fn weighted_pixel_refinement_equals_duplicated_points() {
    for case in cases() {
        let cam = &case.camera;
        let name = cam.model().name();
        for trial in 0..20 {
            let p = problem(&case, trial_seed(&format!("{name}-weighted"), trial));
            let weights: Vec<f64> = (0..N).map(|i| (1 + i % 3) as f64).collect();
            let (mut world, mut pixels) = (Vec::new(), Vec::new());
            for (i, (x, u)) in p.world.iter().zip(&p.pixels).enumerate() {
                for _ in 0..(1 + i % 3) {
                    world.push(*x);
                    pixels.push(*u);
                }
            }
            let a = Solver::default()
                .solve(&eopnp::Problem::pixels(&p.world, &p.pixels, cam).weights(&weights))
                .unwrap();
            let b = Solver::default()
                .solve(&eopnp::Problem::pixels(&world, &pixels, cam))
                .unwrap();
            let ca = pixel_cost(
                cam,
                &p.world,
                &p.pixels,
                Some(&weights),
                &a.rotation,
                &a.translation,
            );
            let cb = pixel_cost(
                cam,
                &p.world,
                &p.pixels,
                Some(&weights),
                &b.rotation,
                &b.translation,
            );
            assert!(
                (ca - cb).abs() <= 1e-9 * cb,
                "{name} trial {trial}: weighted {ca} vs duplicated {cb}"
            );
            assert!(
                rot_err_deg(&a.rotation, &b.rotation) < 1e-6,
                "{name} trial {trial}"
            );
        }
    }
}

/// RANSAC's final fit is the same refinement: with 20 % gross outliers, the returned pose's
/// pixel cost on the true inliers is never above LM from the ground truth on them (when the
/// final mask is exactly the true inliers).
#[test]
fn ransac_final_fit_is_the_pixel_ml_pose_of_its_inliers() {
    for case in cases() {
        let cam = &case.camera;
        let name = cam.model().name();
        let mut exact_masks = 0;
        for trial in 0..40 {
            let mut p = problem(&case, trial_seed(&format!("{name}-ransac"), trial));
            let mut rng = rng_from_seed(trial_seed(&format!("{name}-outliers"), trial));
            let outlier: Vec<bool> = (0..N).map(|i| i % 5 == 0).collect();
            for (u, &o) in p.pixels.iter_mut().zip(&outlier) {
                if o {
                    u.x += rng.random_range(60.0..200.0)
                        * if rng.random_bool(0.5) { 1.0 } else { -1.0 };
                    u.y += rng.random_range(60.0..200.0)
                        * if rng.random_bool(0.5) { 1.0 } else { -1.0 };
                }
            }
            let rs = Ransac::default()
                .threshold_px(4.0)
                .seed(trial)
                .estimate(
                    &Solver::default(),
                    &eopnp::Problem::pixels(&p.world, &p.pixels, cam),
                )
                .unwrap_or_else(|e| panic!("{name} trial {trial}: {e}"));
            let truth: Vec<bool> = outlier.iter().map(|o| !o).collect();
            if rs.inliers != truth {
                continue;
            }
            exact_masks += 1;
            let world: Vec<_> = (0..N).filter(|&i| truth[i]).map(|i| p.world[i]).collect();
            let pixels: Vec<_> = (0..N).filter(|&i| truth[i]).map(|i| p.pixels[i]).collect();
            let ml = lm_refine_projection(&world, &pixels, &p.r, &p.t, &|n| cam.project(n));
            let s = &rs.solution;
            let cost = pixel_cost(cam, &world, &pixels, None, &s.rotation, &s.translation);
            let ml_cost = pixel_cost(cam, &world, &pixels, None, &ml.r, &ml.t);
            assert!(
                cost <= ml_cost * (1.0 + REL),
                "{name} trial {trial}: RANSAC pose's pixel cost {cost} above LM from GT {ml_cost}"
            );
        }
        assert!(
            exact_masks >= 30,
            "{name}: only {exact_masks} of 40 exact masks"
        );
    }
}

/// A robust loss with pixel input: with gross outliers and no RANSAC, Cauchy's pose is far
/// closer to the truth than the squared loss's, and its cost is the Cauchy cost in pixels.
#[test]
fn cauchy_loss_resists_outliers_through_the_camera() {
    let case = &cases()[5]; // OPENCV_FISHEYE
    let cam = &case.camera;
    let mut wins = 0;
    for trial in 0..20 {
        let mut p = problem(case, trial_seed("cauchy", trial));
        for u in p.pixels.iter_mut().step_by(10) {
            u.x += 80.0;
        }
        let plain = Solver::default()
            .solve(&eopnp::Problem::pixels(&p.world, &p.pixels, cam))
            .unwrap();
        let robust = Solver::default()
            .loss(Loss::Cauchy(2.0))
            .solve(&eopnp::Problem::pixels(&p.world, &p.pixels, cam))
            .unwrap();
        let err = |s: &eopnp::Solution| rot_err_deg(&s.rotation, &p.r);
        if err(&robust) < 0.5 * err(&plain) {
            wins += 1;
        }
        // The reported cost is sum 4 ln(1 + r2 / 4) at the pose.
        let c: f64 = p
            .world
            .iter()
            .zip(&p.pixels)
            .map(|(x, u)| {
                let q = robust.rotation * x.coords + robust.translation;
                let r2 = (cam.project(Point2::new(q.x / q.z, q.y / q.z)) - u).norm_squared();
                4.0 * (r2 / 4.0).ln_1p()
            })
            .sum();
        assert!(
            (robust.cost - c).abs() <= 1e-9 * c,
            "trial {trial}: {} vs {c}",
            robust.cost
        );
    }
    println!("Cauchy (2 px) at most half the squared loss's rotation error in {wins} of 20");
    assert!(wins >= 18, "Cauchy beat squared by 2x in only {wins} of 20");
}

/// An unusable loss scale is `InvalidOption("loss")` from every entry point, before any work;
/// scales whose square is normal are accepted.
#[test]
fn unusable_loss_scales_are_invalid_options() {
    let case = &cases()[1];
    let p = problem(case, 7);
    let image: Vec<Point2<f64>> = p
        .pixels
        .iter()
        .map(|u| case.camera.undistort(*u).unwrap())
        .collect();
    let init = nalgebra::Isometry3::from_parts(
        nalgebra::Translation3::from(p.t),
        nalgebra::UnitQuaternion::from_matrix(&p.r),
    );
    for bad in [
        Loss::Huber(0.0),
        Loss::Huber(-1.0),
        Loss::Cauchy(f64::NAN),
        Loss::Cauchy(f64::INFINITY),
        Loss::Huber(1e-200),
        Loss::Cauchy(1e200),
    ] {
        let s = Solver::default().loss(bad);
        let invalid = |r: Result<eopnp::Solution, eopnp::PnpError>| {
            matches!(r, Err(eopnp::PnpError::InvalidOption { option: "loss" }))
        };
        assert!(
            invalid(s.solve(&eopnp::Problem::normalised(&p.world, &image))),
            "{bad:?}"
        );
        assert!(
            invalid(s.solve(&eopnp::Problem::pixels(&p.world, &p.pixels, &case.camera))),
            "{bad:?}"
        );
        assert!(
            invalid(s.refine(&eopnp::Problem::normalised(&p.world, &image), &init)),
            "{bad:?}"
        );
        assert!(
            invalid(s.refine(
                &eopnp::Problem::pixels(&p.world, &p.pixels, &case.camera),
                &init
            )),
            "{bad:?}"
        );
        assert!(
            matches!(
                Ransac::default().estimate(
                    &s,
                    &eopnp::Problem::pixels(&p.world, &p.pixels, &case.camera)
                ),
                Err(eopnp::PnpError::InvalidOption { option: "loss" })
            ),
            "{bad:?}"
        );
    }
    for good in [Loss::Huber(1e-150), Loss::Cauchy(1e150), Loss::Huber(2.0)] {
        Solver::default()
            .loss(good)
            .solve(&eopnp::Problem::pixels(&p.world, &p.pixels, &case.camera))
            .unwrap_or_else(|e| panic!("{good:?}: {e}"));
    }
}

/// An unusable loss scale is `InvalidOption { option: "loss" }` from every entry point, with a
/// message that names the loss (not a RANSAC option), and `Loss::is_valid` says so beforehand.
#[test]
fn unusable_loss_scale_is_invalid_option() {
    let case = &cases()[0];
    let p = problem(case, trial_seed("loss-scale", 0));
    let normalised: Vec<Point2<f64>> = p
        .pixels
        .iter()
        .map(|u| case.camera.undistort(*u).unwrap())
        .collect();
    for loss in [
        Loss::Huber(0.0),
        Loss::Huber(-1.0),
        Loss::Cauchy(f64::NAN),
        Loss::Cauchy(f64::INFINITY),
        Loss::Huber(1e-160),
        Loss::Cauchy(1e160),
    ] {
        assert!(!loss.is_valid(), "{loss:?}");
        let s = Solver::default().loss(loss);
        let results = [
            s.solve(&eopnp::Problem::normalised(&p.world, &normalised))
                .map(|_| ()),
            s.solve(&eopnp::Problem::pixels(&p.world, &p.pixels, &case.camera))
                .map(|_| ()),
        ];
        for r in results {
            let e = r.unwrap_err();
            assert_eq!(
                e,
                eopnp::PnpError::InvalidOption { option: "loss" },
                "{loss:?}"
            );
            assert!(
                e.to_string().starts_with("the loss scale is out of range"),
                "{e}"
            );
        }
    }
    for loss in [Loss::Squared, Loss::Huber(1e-150), Loss::Cauchy(1e150)] {
        assert!(loss.is_valid(), "{loss:?}");
    }
}

/// The weighted refinement from a prior pose: from the ground truth a little perturbed, the
/// pose of a weighted solve of pixels (and of normalised points), and a point
/// of weight 0 changes nothing.
#[test]
fn weighted_refine_is_the_weighted_solve_pose() {
    for case in cases() {
        let cam = &case.camera;
        let name = cam.model().name();
        for trial in 0..10 {
            let p = problem(&case, trial_seed(&format!("{name}-refine-weighted"), trial));
            let mut weights: Vec<f64> = (0..N).map(|i| (1 + i % 3) as f64).collect();
            weights[0] = 0.0;
            let prior = Isometry3::from_parts(
                Translation3::from(p.t + Vector3::new(0.05, -0.03, 0.1)),
                UnitQuaternion::from_euler_angles(0.02, -0.01, 0.015)
                    * UnitQuaternion::from_matrix(&p.r),
            );
            let s = Solver::default();
            let solved = s
                .solve(&eopnp::Problem::pixels(&p.world, &p.pixels, cam).weights(&weights))
                .unwrap();
            let refined = s
                .refine(
                    &eopnp::Problem::pixels(&p.world, &p.pixels, cam).weights(&weights),
                    &prior,
                )
                .unwrap();
            assert!(refined.converged, "{name} trial {trial}");
            assert!(
                rot_err_deg(&refined.rotation, &solved.rotation) < 1e-7
                    && (refined.translation - solved.translation).norm() < 1e-8,
                "{name} trial {trial}: refined {refined:?} solved {solved:?}"
            );
            assert!((refined.cost - solved.cost).abs() <= 1e-9 * solved.cost);
            assert_eq!(refined.used, N - 1);
            // Weight 0 = dropped.
            let dropped = s
                .refine(
                    &eopnp::Problem::pixels(&p.world[1..], &p.pixels[1..], cam)
                        .weights(&weights[1..]),
                    &prior,
                )
                .unwrap();
            assert!(rot_err_deg(&dropped.rotation, &refined.rotation) < 1e-7);
            // Normalised input: the weighted solve's pose.
            let image: Vec<Point2<f64>> = p
                .pixels
                .iter()
                .map(|u| cam.undistort(*u).unwrap())
                .collect();
            let solved = s
                .solve(&eopnp::Problem::normalised(&p.world, &image).weights(&weights))
                .unwrap();
            let refined = s
                .refine(
                    &eopnp::Problem::normalised(&p.world, &image).weights(&weights),
                    &prior,
                )
                .unwrap();
            assert!(refined.converged, "{name} trial {trial}");
            assert!(
                rot_err_deg(&refined.rotation, &solved.rotation) < 1e-7,
                "{name} trial {trial}"
            );
            assert!((refined.cost - solved.cost).abs() <= 1e-9 * solved.cost);
        }
    }
    // Bad weights: the errors of the weighted solves.
    let case = &cases()[0];
    let p = problem(case, trial_seed("refine-weighted-errors", 0));
    let prior = Isometry3::from_parts(Translation3::from(p.t), UnitQuaternion::from_matrix(&p.r));
    let mut w = vec![1.0; N];
    w[3] = -1.0;
    let e = Solver::default()
        .refine(
            &eopnp::Problem::pixels(&p.world, &p.pixels, &case.camera).weights(&w),
            &prior,
        )
        .unwrap_err();
    assert_eq!(e, eopnp::PnpError::InvalidWeight { index: 3 });
    let e = Solver::default()
        .refine(
            &eopnp::Problem::normalised(&p.world, &p.pixels).weights(&w[..N - 1]),
            &prior,
        )
        .unwrap_err();
    assert!(matches!(e, eopnp::PnpError::WeightsLength { .. }), "{e:?}");
}
