//! One test per bound: each routine reaches its bound (lowered where converging inputs never
//! reach the real one) and returns a defined result; the solver on top of it returns a correct
//! pose or a typed error, never a panic or a wrong Ok.

use super::hook::{hits, with_limit};
use super::*;

use crate::{PnpError, Solver};
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

/// Ok must be the true pose; an error must be typed (any variant is acceptable when a
/// bound is artificially tiny, but never a panic and never a wrong Ok).
fn correct_or_error(res: &Result<crate::Solution, PnpError>, r_true: &Matrix3<f64>) -> bool {
    match res {
        Ok(s) => {
            let e = crate::numeric::rotation::rotation_error_deg(&s.rotation, r_true);
            assert!(e < 1e-6, "wrong pose at a lowered bound: {e} degrees");
            true
        }
        Err(e) => {
            assert!(!e.to_string().is_empty());
            false
        }
    }
}

#[test]
fn ordinary_solves_never_exhaust_a_constant_bound() {
    let all = [
        Bound::FrameEigenSweeps,
        Bound::Svd3Sweeps,
        Bound::HessianEigenSweeps,
        Bound::NewtonDamping,
        Bound::MEigen,
        Bound::P3pEigen,
        Bound::RootBracket,
        Bound::Undistort,
    ];
    let before: Vec<usize> = all.iter().map(|&b| hits(b)).collect();
    for seed in 0..300 {
        for (n, planar) in [(4, false), (6, false), (10, true), (50, false)] {
            let (w, i, r) = problem(n, planar, seed);
            let all_sols = Solver::default().solve_all(&w, &i).unwrap();
            let e = crate::numeric::rotation::rotation_error_deg(&all_sols[0].rotation, &r);
            assert!(e < 1e-6 || n == 4, "seed {seed} n {n}: {e}");
        }
    }
    for (k, &b) in all.iter().enumerate() {
        assert_eq!(hits(b), before[k], "{b:?} ran out on ordinary input");
    }
}

#[test]
fn frame_eigen_sweeps() {
    let a = Matrix3::new(4.0, 1.0, 0.5, 1.0, 3.0, 0.25, 0.5, 0.25, 2.0);
    let (out, hit) = with_limit(Bound::FrameEigenSweeps, 1, || {
        crate::numeric::mat3::sym_eigen3(&a)
    });
    assert_eq!(hit, 1);
    let (_, v) = out.expect("a defined result at the bound");
    assert!(
        (v.transpose() * v - Matrix3::identity()).norm() < 1e-14,
        "V stays orthogonal"
    );
    // In a solve: the frame's axes are only approximately principal; the pose is exact.
    let (w, i, r) = problem(10, false, 1);
    let (res, hit) = with_limit(Bound::FrameEigenSweeps, 1, || {
        Solver::default().solve(&w, &i)
    });
    assert!(hit >= 1);
    assert!(correct_or_error(&res, &r));
}

#[test]
fn svd3_sweeps() {
    let a = Matrix3::new(4.0, 1.0, 0.5, -1.0, 3.0, 0.25, 0.5, 2.25, 2.0);
    let (out, hit) = with_limit(Bound::Svd3Sweeps, 1, || crate::numeric::mat3::svd3(&a));
    assert_eq!(hit, 1);
    let svd = out.expect("a defined result at the bound");
    assert!((svd.v.transpose() * svd.v - Matrix3::identity()).norm() < 1e-14);
    assert!((svd.u.transpose() * svd.u - Matrix3::identity()).norm() < 1e-12);
    let (w, i, r) = problem(10, false, 2);
    let (res, hit) = with_limit(Bound::Svd3Sweeps, 1, || Solver::default().solve(&w, &i));
    assert!(hit >= 1);
    assert!(correct_or_error(&res, &r));
}

#[test]
fn hessian_eigen_sweeps() {
    let h = Matrix3::new(1.0, 2.0, 0.5, 2.0, -1.0, 0.3, 0.5, 0.3, 0.2);
    let (ev, hit) = with_limit(Bound::HessianEigenSweeps, 1, || {
        crate::numeric::mat3::min_eigenvalue_sym3(&h)
    });
    assert_eq!(hit, 1);
    assert!(ev.is_finite() && ev < 0.0, "{ev}");
    // Exhaustive search: many starts with indefinite Hessians. Newton's shift is then only
    // approximate; the damping loop still only accepts decreasing steps.
    let (w, i, r) = problem(6, false, 3);
    let (res, hit) = with_limit(Bound::HessianEigenSweeps, 1, || {
        Solver::default().exhaustive(true).solve(&w, &i)
    });
    assert!(hit >= 1);
    assert!(correct_or_error(&res, &r));
}

#[test]
fn newton_damping() {
    // No damping step at all: Newton accepts nothing and returns its start.
    let (w, i, r) = problem(10, false, 4);
    let (m, ..) = crate::pipeline::tests::intermediates(&w, &i).unwrap();
    let m45 = crate::pipeline::moments::m_upper(&m);
    let r0 = Rotation3::new(Vector3::new(0.3, -0.2, 0.1)).into_inner() * r;
    let (out, hit) = with_limit(Bound::NewtonDamping, 0, || {
        crate::pipeline::newton::refine_so3(&m45, m.trace(), &r0, &Default::default())
    });
    assert_eq!(hit, 1);
    assert_eq!(out.r, r0);
    assert_eq!(out.iterations, 1);
    // Solve in algebraic mode (no S9 to hide it): every start stays where it is, so the
    // result is either not the truth (and then must not be Ok with a wrong pose... it is
    // the best start) or an error. Reprojection mode: S9 still converges from the start.
    let (res, hit) = with_limit(Bound::NewtonDamping, 0, || Solver::default().solve(&w, &i));
    assert!(hit >= 1);
    assert!(correct_or_error(&res, &r));
}

#[test]
fn m_eigen_decomposition() {
    // nalgebra's QL iteration limited to one iteration fails to converge: no candidates,
    // a typed NoSolution (the certified case-1 path does not need the decomposition, so
    // the full search is forced).
    let (w, i, _) = problem(10, false, 5);
    let (res, hit) = with_limit(Bound::MEigen, 1, || {
        Solver::default().exhaustive(true).solve(&w, &i)
    });
    assert!(hit >= 1);
    assert_eq!(res.err(), Some(PnpError::NoSolution));
    // Planar: the 6x6 decomposition of M_p fails too; the p1 start (inverse iteration, no
    // decomposition) still gives the pose.
    let (w, i, r) = problem(10, true, 5);
    let (res, hit) = with_limit(Bound::MEigen, 1, || {
        Solver::default().exhaustive(true).solve(&w, &i)
    });
    assert!(hit >= 1);
    assert!(correct_or_error(&res, &r));
}

#[test]
fn p3p_eigen_decomposition() {
    let (w, i, r) = problem(3, false, 6);
    let world = [w[0], w[1], w[2]];
    let bearing = [0, 1, 2].map(|k| Vector3::new(i[k].x, i[k].y, 1.0).normalize());
    let full = crate::p3p::p3p(&world, &bearing);
    assert!(full
        .iter()
        .any(|s| crate::numeric::rotation::rotation_error_deg(&s.rotation, &r) < 1e-6));
    let (out, hit) = with_limit(Bound::P3pEigen, 1, || crate::p3p::p3p(&world, &bearing));
    assert!(hit >= 1);
    assert!(out.is_empty(), "no pose without the decomposition");
}

#[test]
fn root_bracket_iterations() {
    // Degree 8 with well separated roots 1..8: one iteration per bracket cannot converge;
    // the best iterate so far is returned (finite, inside its bracket).
    let mut c = vec![1.0];
    for k in 1..=8 {
        // multiply by (x - k)
        let mut n = vec![0.0; c.len() + 1];
        for (j, &cj) in c.iter().enumerate() {
            n[j] -= cj * k as f64;
            n[j + 1] += cj;
        }
        c = n;
    }
    let exact = crate::numeric::roots::real_roots(&c);
    assert_eq!(exact.len(), 8);
    let (out, hit) = with_limit(Bound::RootBracket, 1, || {
        crate::numeric::roots::real_roots(&c)
    });
    assert!(hit >= 1);
    assert!(out.iter().all(|x| x.is_finite()));
    assert!(out.len() <= 8);
}

#[test]
fn root_polish_steps() {
    // Closed-form cubic roots are polished; without polishing, a candidate that fails the
    // backward-error check sends the polynomial to the bracketing solver: still a root.
    let c = [-2.0, 0.0, 0.0, 1.0]; // x^3 = 2
    let (out, hit) = with_limit(Bound::RootPolish, 0, || {
        crate::numeric::roots::cubic_real_roots(&c)
    });
    assert!(hit >= 1);
    assert_eq!(out.len(), 1);
    assert!((out.as_slice()[0] - 2f64.cbrt()).abs() < 1e-14);
}

#[test]
fn undistortion_steps() {
    use crate::camera::{Camera, CameraError};
    let cam =
        Camera::from_colmap("RADIAL", 640, 480, vec![500.0, 320.0, 240.0, 0.1, 0.05]).unwrap();
    // A pixel far from the centre needs several Newton steps.
    let px = Point2::new(620.0, 470.0);
    assert!(cam.undistort(px).is_ok());
    let (res, hit) = with_limit(Bound::Undistort, 1, || cam.undistort(px));
    assert_eq!(hit, 1);
    assert!(
        matches!(res, Err(CameraError::NoConvergence { .. })),
        "{res:?}"
    );
}
