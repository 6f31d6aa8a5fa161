//! User-set iteration bounds through the public API: the solver with one and zero Newton and
//! LM iterations, RANSAC at its iteration bound. (Formerly in `src/numeric/bounds/tests.rs`,
//! whose other tests lower the internal bounds through test hooks.)

use eopnp::ransac::Ransac;
use eopnp::{PnpError, Solver};
use eopnp_testkit::{Problem, ProblemOptions, RotationKind, Scene};
use nalgebra::{Matrix3, Point2, Point3};

/// A seeded noise-free general problem of the paper's protocol (the shared generator).
fn problem(n: usize, seed: u64) -> (Vec<Point3<f64>>, Vec<Point2<f64>>, Matrix3<f64>) {
    let p = Problem::generate(&ProblemOptions {
        n,
        sigma_px: 0.0,
        scene: Scene::General,
        rotation: RotationKind::Uniform,
        seed,
    });
    (p.world, p.image, p.r_gt)
}

#[test]
fn user_bounds_newton_lm_ransac() {
    // `newton` and `refine` with one iteration each: the pose is still exact (`refine` corrects
    // what `newton` did not finish) and the reported counts are at most the bound.
    let (w, i, r) = problem(10, 7);
    let res = Solver::default()
        .newton_iterations(1)
        .reprojection_iterations(1)
        .solve(&eopnp::Problem::normalised(&w, &i))
        .expect("a well-posed noise-free problem");
    assert!(res.newton_iterations <= 1 && res.reprojection_iterations <= 1);
    let err = eopnp::internals::metrics::rotation_error_deg(&res.rotation, &r);
    assert!(err < 1e-6, "one iteration each: {err:e} deg");
    // With no iteration at all the pose is the projection of the case-1 null vector onto SO(3),
    // which is exact for noise-free data.
    let res0 = Solver::default()
        .newton_iterations(0)
        .reprojection_iterations(0)
        .solve(&eopnp::Problem::normalised(&w, &i))
        .expect("a well-posed noise-free problem");
    assert_eq!(
        (res0.newton_iterations, res0.reprojection_iterations),
        (0, 0)
    );
    let err0 = eopnp::internals::metrics::rotation_error_deg(&res0.rotation, &r);
    assert!(err0 < 1e-6, "no iteration: {err0:e} deg");
    // RANSAC at its iteration bound: 90 % outliers, confidence 0.999 needs thousands of
    // samples; 30 are allowed.
    let (w, mut i, _) = problem(100, 8);
    for (k, p) in i.iter_mut().enumerate() {
        if k % 10 != 0 {
            *p = Point2::new((k as f64 * 0.37).sin() * 0.3, (k as f64 * 0.11).cos() * 0.3);
        }
    }
    let ransac = Ransac::default()
        .max_iterations(30)
        .min_iterations(0)
        .seed(3);
    match ransac.estimate(
        &Solver::default(),
        &eopnp::Problem::normalised(&w, &i).focal(500.0, 500.0),
    ) {
        Ok(sol) => assert_eq!(sol.stats.iterations, 30),
        Err(e) => assert!(
            matches!(e, PnpError::NoConsensus { iterations: 30, .. }),
            "{e:?}"
        ),
    }
}
