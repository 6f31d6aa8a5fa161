//! User-set iteration bounds through the public API: the solver with one and zero Newton and
//! LM iterations, RANSAC at its iteration bound. (Formerly in `src/numeric/bounds/tests.rs`,
//! whose other tests lower the internal bounds through test hooks.)

use eopnp::ransac::Ransac;
use eopnp::{PnpError, Solver};
use nalgebra::{Matrix3, Point2, Point3, Rotation3, Vector3};

/// A seeded noise-free problem: N points in a 2x2x2 box (flattened to z = 0 when
/// `planar`), 5 units in front of a rotated camera.
fn problem(
    n: usize,
    planar: bool,
    seed: u64,
) -> (Vec<Point3<f64>>, Vec<Point2<f64>>, Matrix3<f64>) {
    let mut s = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    let mut u = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    let r = Rotation3::new(Vector3::new(u() * 3.0, u() * 3.0, u() * 3.0)).into_inner();
    let t = Vector3::new(u() * 0.5, u() * 0.5, 5.0);
    let world: Vec<Point3<f64>> = (0..n)
        .map(|_| Point3::new(u(), u(), if planar { 0.0 } else { u() }))
        .collect();
    let image = world
        .iter()
        .map(|x| {
            let c = r * x.coords + t;
            Point2::new(c.x / c.z, c.y / c.z)
        })
        .collect();
    (world, image, r)
}

#[test]
fn user_bounds_newton_lm_ransac() {
    // S6 and S9 with one iteration each: the pose is still exact (S9 corrects what S6 did
    // not finish) or an error; reported counts are at most the bound.
    let (w, i, r) = problem(10, false, 7);
    let res = Solver::default()
        .newton_iterations(1)
        .reprojection_iterations(1)
        .solve(&w, &i);
    if let Ok(s) = &res {
        assert!(s.newton_iterations <= 1 && s.reprojection_iterations <= 1);
    }
    let res0 = Solver::default()
        .newton_iterations(0)
        .reprojection_iterations(0)
        .solve(&w, &i);
    if let Ok(s) = &res0 {
        assert_eq!((s.newton_iterations, s.reprojection_iterations), (0, 0));
        assert!(s.rotation.iter().all(|x| x.is_finite()));
    }
    let _ = r;
    // RANSAC at its iteration bound: 90 % outliers, confidence 0.999 needs thousands of
    // samples; 30 are allowed.
    let (w, mut i, _) = problem(100, false, 8);
    for (k, p) in i.iter_mut().enumerate() {
        if k % 10 != 0 {
            *p = Point2::new((k as f64 * 0.37).sin() * 0.3, (k as f64 * 0.11).cos() * 0.3);
        }
    }
    let ransac = Ransac::default()
        .max_iterations(30)
        .min_iterations(0)
        .seed(3);
    match ransac.estimate(&Solver::default(), &w, &i, (500.0, 500.0), None) {
        Ok(sol) => assert_eq!(sol.stats.iterations, 30),
        Err(e) => assert_eq!(e, PnpError::NoConsensus { iterations: 30 }),
    }
}
