//! `Solver::refine`: from a prior pose near the truth it returns the same pose as the full
//! solve (the ML pose), reports convergence, refuses a non-finite prior, and from a prior in
//! another basin it stays in that basin (no global search).
use eopnp::camera::Camera;
use eopnp::{CandidateSource, PnpError, Solver};
use eopnp_testkit::{self as common, Problem, ProblemOptions, RotationKind, Scene};
use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion, Vector3};

fn iso(r: &Matrix3<f64>, t: &Vector3<f64>) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::from(*t),
        UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(*r)),
    )
}

#[test]
fn refine_from_a_nearby_prior_gives_the_ml_pose() {
    for scene in [Scene::General, Scene::Planar] {
        for trial in 0..200 {
            let p = Problem::generate(&ProblemOptions {
                n: 6 + (trial % 50) as usize,
                sigma_px: 2.0,
                scene,
                rotation: RotationKind::Uniform,
                seed: common::trial_seed("refine", trial),
            });
            let full = Solver::default()
                .solve(&eopnp::Problem::normalised(&p.world, &p.image))
                .unwrap();
            // A prior 2 degrees and 3 % of the distance off the truth.
            let mut rng = common::rng_from_seed(common::trial_seed("refine_prior", trial));
            let w = common::unit_vector(&mut rng) * 2f64.to_radians();
            let r0 = common::exp_so3(&w) * p.r_gt;
            let t0 = p.t_gt + common::unit_vector(&mut rng) * 0.03 * p.t_gt.norm();
            let sol = Solver::default()
                .refine(
                    &eopnp::Problem::normalised(&p.world, &p.image),
                    &iso(&r0, &t0),
                )
                .unwrap();
            let seed = p.opts.seed;
            assert!(sol.converged, "{scene:?} seed {seed:#x}");
            assert_eq!(sol.source, CandidateSource::Initial);
            let dr = common::rot_err_deg(&sol.rotation, &full.rotation);
            assert!(
                dr < 1e-6,
                "{scene:?} seed {seed:#x}: {dr} deg from the full solve"
            );
            assert!(
                sol.cost <= full.cost * (1.0 + 1e-9),
                "{scene:?} seed {seed:#x}"
            );
        }
    }
}

#[test]
fn refine_pixels_through_a_camera() {
    let cam =
        Camera::from_colmap("RADIAL", 640, 480, vec![800.0, 320.0, 240.0, -0.2, 0.03]).unwrap();
    let p = Problem::generate(&ProblemOptions {
        n: 30,
        sigma_px: 0.0,
        scene: Scene::General,
        rotation: RotationKind::Uniform,
        seed: common::trial_seed("refine_pixels", 0),
    });
    let pixels: Vec<_> = p.image.iter().map(|m| cam.project(*m)).collect();
    let r0 = common::exp_so3(&Vector3::new(0.02, -0.01, 0.015)) * p.r_gt;
    let sol = Solver::default()
        .refine(
            &eopnp::Problem::pixels(&p.world, &pixels, &cam),
            &iso(&r0, &(p.t_gt * 1.02)),
        )
        .unwrap();
    assert!(sol.converged);
    assert!(common::rot_err_deg(&sol.rotation, &p.r_gt) < 1e-8);
}

#[test]
fn refine_refuses_a_non_finite_prior_and_bad_input() {
    let p = Problem::generate(&ProblemOptions {
        n: 10,
        sigma_px: 1.0,
        scene: Scene::General,
        rotation: RotationKind::Uniform,
        seed: 1,
    });
    let bad = iso(&p.r_gt, &Vector3::new(f64::NAN, 0.0, 1.0));
    let e = Solver::default()
        .refine(&eopnp::Problem::normalised(&p.world, &p.image), &bad)
        .unwrap_err();
    assert_eq!(e, PnpError::InvalidOption { option: "initial" });
    assert!(e.to_string().contains("initial pose"));
    let e = Solver::default()
        .refine(
            &eopnp::Problem::normalised(&p.world[..3], &p.image[..3]),
            &iso(&p.r_gt, &p.t_gt),
        )
        .unwrap_err();
    assert_eq!(e, PnpError::TooFewPoints { got: 3, need: 4 });
}

#[test]
fn refine_stays_in_the_basin_it_starts_in() {
    // A prior 180 degrees off: the refinement does not search, so it does not return the
    // ML pose (that is what `solve` is for); its cost is not below the ML cost.
    let p = Problem::generate(&ProblemOptions {
        n: 20,
        sigma_px: 1.0,
        scene: Scene::General,
        rotation: RotationKind::Uniform,
        seed: 3,
    });
    let full = Solver::default()
        .solve(&eopnp::Problem::normalised(&p.world, &p.image))
        .unwrap();
    let flip = common::axis_angle(&Vector3::new(0.0, 0.0, 1.0), std::f64::consts::PI) * p.r_gt;
    let sol = Solver::default()
        .refine(
            &eopnp::Problem::normalised(&p.world, &p.image),
            &iso(&flip, &p.t_gt),
        )
        .unwrap();
    assert!(sol.cost >= full.cost * (1.0 - 1e-12));
}
