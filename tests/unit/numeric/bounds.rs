//! One test per bound: each routine reaches its bound (lowered where converging inputs never
//! reach the real one) and returns a defined result; then the public entry point on top of it
//! (`Solver::solve` in default and exhaustive mode, `Solver::solve` of pixels for the
//! undistortion, `Ransac::estimate` for P3P) runs under the same lowered bound on seeded
//! noise-free problems, and the test asserts what it returns: the true pose (rotation error
//! < 1e-6 degrees) or the one expected typed error, never a panic or a wrong `Ok`.

use super::hook::{hits, with_limit};
use super::*;
use crate::Problem;

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

/// Asserts that `res` is the true pose (rotation error < 1e-6 degrees).
#[track_caller]
fn assert_true_pose(res: &Result<crate::Solution, PnpError>, r_true: &Matrix3<f64>, what: &str) {
    match res {
        Ok(s) => {
            let e = crate::numeric::rotation::rotation_error_deg(&s.rotation, r_true);
            assert!(
                e < 1e-6,
                "{what}: wrong pose at a lowered bound: {e} degrees"
            );
        }
        Err(e) => panic!("{what}: {e:?} at a lowered bound, expected the true pose"),
    }
}

/// The problems the solver runs on under a lowered bound: N = 4, 5, 6, 10, 50 in 3D and
/// N = 10 planar, seeds 0..10.
/// A named problem: world points, image points, true rotation.
type Named = (String, Vec<Point3<f64>>, Vec<Point2<f64>>, Matrix3<f64>);

fn problems() -> impl Iterator<Item = Named> {
    [
        (4, false),
        (5, false),
        (6, false),
        (10, false),
        (50, false),
        (10, true),
    ]
    .into_iter()
    .flat_map(|(n, planar)| {
        (0..10).map(move |seed| {
            let (w, i, r) = problem(n, planar, seed);
            (format!("n {n} planar {planar} seed {seed}"), w, i, r)
        })
    })
}

/// Solves every problem of [`problems`] in default and exhaustive mode with `bound` lowered to
/// `limit`, asserts the true pose every time, and returns how often the bound was reached.
fn solver_on_top_returns_true_pose(bound: Bound, limit: usize) -> usize {
    let mut total = 0;
    for (what, w, i, r) in problems() {
        for exhaustive in [false, true] {
            let (res, hit) = with_limit(bound, limit, || {
                Solver::default()
                    .exhaustive(exhaustive)
                    .solve(&Problem::normalised(&w, &i))
            });
            total += hit;
            assert_true_pose(
                &res,
                &r,
                &format!("{bound:?} = {limit}, {what}, exhaustive {exhaustive}"),
            );
        }
    }
    total
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
        Bound::P3pCubic,
        Bound::RootBracket,
        Bound::Undistort,
    ];
    let before: Vec<usize> = all.iter().map(|&b| hits(b)).collect();
    for seed in 0..300 {
        for (n, planar) in [(4, false), (6, false), (10, true), (50, false)] {
            let (w, i, r) = problem(n, planar, seed);
            let all_sols = Solver::default()
                .solve_all(&Problem::normalised(&w, &i))
                .unwrap();
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
    // In a solve: the frame's axes are only approximately principal; the pose is exact. The
    // iteration serves the clouds whose thinnest axis is below 1e-2 of the widest (the
    // frame's third pass; the others take the closed form): tilted clouds 1e-3 thick.
    let tilt = Rotation3::from_scaled_axis(Vector3::new(0.7, -0.4, 0.2)).into_inner();
    let mut total = 0;
    for seed in 0..20 {
        let (w, _, r) = problem(10, false, seed);
        let world: Vec<Point3<f64>> = w
            .iter()
            .map(|x| Point3::from(tilt * Vector3::new(x.x, x.y, 1e-3 * x.z)))
            .collect();
        // The camera of `problem` looking at the tilted cloud: R' = R tilt^T.
        let rt = r * tilt.transpose();
        let t = Vector3::new(0.1, -0.2, 5.0);
        let image: Vec<Point2<f64>> = world
            .iter()
            .map(|x| {
                let c = rt * x.coords + t;
                Point2::new(c.x / c.z, c.y / c.z)
            })
            .collect();
        for exhaustive in [false, true] {
            let (res, hit) = with_limit(Bound::FrameEigenSweeps, 1, || {
                Solver::default()
                    .exhaustive(exhaustive)
                    .solve(&Problem::normalised(&world, &image))
            });
            total += hit;
            assert_true_pose(&res, &rt, &format!("thin cloud, seed {seed}"));
        }
    }
    assert!(total >= 20, "{total}");
}

#[test]
fn svd3_sweeps() {
    let a = Matrix3::new(4.0, 1.0, 0.5, -1.0, 3.0, 0.25, 0.5, 2.25, 2.0);
    let (out, hit) = with_limit(Bound::Svd3Sweeps, 1, || crate::numeric::mat3::svd3(&a));
    assert_eq!(hit, 1);
    let svd = out.expect("a defined result at the bound");
    assert!((svd.v.transpose() * svd.v - Matrix3::identity()).norm() < 1e-14);
    assert!((svd.u.transpose() * svd.u - Matrix3::identity()).norm() < 1e-12);
    let hits = solver_on_top_returns_true_pose(Bound::Svd3Sweeps, 1);
    assert!(hits >= 100, "{hits}");
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
    let hits = solver_on_top_returns_true_pose(Bound::HessianEigenSweeps, 1);
    assert!(hits >= 100, "{hits}");
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
    // The solver on top: `newton` accepts no step, so every start stays where it is; the starts of
    // noise-free problems are exact (case 1 / p1) and `refine` polishes them.
    let hits = solver_on_top_returns_true_pose(Bound::NewtonDamping, 0);
    assert!(hits >= 100, "{hits}");
    // Algebraic mode (no `refine`): the starts themselves are returned, still the true pose.
    for (what, w, i, r) in problems() {
        let (res, _) = with_limit(Bound::NewtonDamping, 0, || {
            Solver::default()
                .refinement(crate::Refinement::Algebraic)
                .solve(&Problem::normalised(&w, &i))
        });
        assert_true_pose(&res, &r, &format!("algebraic, {what}"));
    }
}

#[test]
fn m_eigen_decomposition() {
    // nalgebra's QL iteration limited to one iteration fails to converge. Full search on 3D
    // points: no candidates, a typed NoSolution every time (the default mode's certified
    // case-1 path does not need the decomposition: the true pose, or NoSolution when the
    // certificate does not hold and the search needs it).
    // Planar points: the 6x6 decomposition of M_p fails too; the p1 start (inverse iteration,
    // no decomposition) still gives the pose, in both modes.
    let mut hits = 0;
    for (what, w, i, r) in problems() {
        let planar = what.contains("planar true");
        let (res, hit) = with_limit(Bound::MEigen, 1, || {
            Solver::default()
                .exhaustive(true)
                .solve(&Problem::normalised(&w, &i))
        });
        assert!(hit >= 1, "{what}");
        hits += hit;
        if planar {
            assert_true_pose(&res, &r, &format!("exhaustive, {what}"));
        } else {
            assert_eq!(res.err(), Some(PnpError::NoSolution), "exhaustive, {what}");
        }
        let (res, hit) = with_limit(Bound::MEigen, 1, || {
            Solver::default().solve(&Problem::normalised(&w, &i))
        });
        if planar || hit == 0 {
            assert_true_pose(&res, &r, &format!("default, {what}"));
        } else {
            assert_eq!(res.err(), Some(PnpError::NoSolution), "default, {what}");
        }
    }
    assert!(hits >= 60, "{hits}");
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
    // RANSAC on top (P3P is its minimal solver): with one QL iteration no hypothesis at all,
    // a typed NoConsensus after every allowed iteration; with five, some decompositions still
    // run out, and the others give the true pose.
    let ransac = crate::ransac::Ransac::default().seed(1).max_iterations(300);
    for seed in 0..5 {
        let (w, i, r) = problem(50, false, 20 + seed);
        let (res, hit) = with_limit(Bound::P3pEigen, 1, || {
            ransac.estimate(
                &Solver::default(),
                &Problem::normalised(&w, &i).focal(500.0, 500.0),
            )
        });
        assert!(hit >= 300, "seed {seed}: {hit}");
        assert_eq!(
            res.err(),
            Some(PnpError::NoConsensus {
                iterations: 300,
                inliers: 0,
                needed: 6
            }),
            "seed {seed}"
        );
        let (res, _) = with_limit(Bound::P3pEigen, 5, || {
            ransac.estimate(
                &Solver::default(),
                &Problem::normalised(&w, &i).focal(500.0, 500.0),
            )
        });
        let sol = res.map(|s| s.solution);
        assert_true_pose(&sol, &r, &format!("RANSAC, P3pEigen = 5, seed {seed}"));
    }
}

#[test]
fn p3p_cubic_root() {
    // With one Newton step the one root of the unpolished P3P's cubic is not reached: the
    // search over every root of the cubic decides, and the true pose is still among the
    // solutions; the solve on top (its small-N starts at N = 4 and 5 are these) returns the
    // true pose.
    let (w, i, r) = problem(3, false, 6);
    let world = [w[0], w[1], w[2]];
    let bearing = [0, 1, 2].map(|k| Vector3::new(i[k].x, i[k].y, 1.0).normalize());
    let true_pose = |sols: &crate::p3p::P3pSolutions| {
        sols.iter()
            .any(|s| crate::numeric::rotation::rotation_error_deg(&s.rotation, &r) < 1e-6)
    };
    assert!(true_pose(&crate::numeric::p3p::p3p_unpolished(
        &world, &bearing
    )));
    let (out, hit) = with_limit(Bound::P3pCubic, 1, || {
        crate::numeric::p3p::p3p_unpolished(&world, &bearing)
    });
    assert!(hit >= 1);
    assert!(true_pose(&out));
    let hits = solver_on_top_returns_true_pose(Bound::P3pCubic, 1);
    assert!(hits >= 50, "{hits}");
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
    // The solver on top (the case-2 to 4 and p2 polynomials, in the full search): the roots it
    // gets are only approximate, the Newton refinement (`newton`) that follows converges anyway.
    for limit in [0, 1, 2] {
        let hits = solver_on_top_returns_true_pose(Bound::RootBracket, limit);
        assert!(hits >= 100, "limit {limit}: {hits}");
    }
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
    // The solver on top: no polishing of the closed-form roots of the full search.
    let hits = solver_on_top_returns_true_pose(Bound::RootPolish, 0);
    assert!(hits >= 100, "{hits}");
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
    // The solver on top (a solve of pixels, which leaves out the pixels it cannot undistort):
    // exactly the pixels `Camera::undistort` refuses at the same bound are left out; the pose
    // is the true one, or TooFewPoints when fewer than 4 remain. One step: (almost) every
    // pixel of an ordinary view fails to converge, TooFewPoints. Two steps: every pixel
    // reaches the bound, the residual test accepts most of them, the true pose.
    for seed in 0..5 {
        let (w, i, r) = problem(30, false, 30 + seed);
        let px: Vec<Point2<f64>> = i.iter().map(|m| cam.project(*m)).collect();
        for limit in [1, 2] {
            let what = format!("solve_pixels, Undistort = {limit}, seed {seed}");
            let (res, hit) = with_limit(Bound::Undistort, limit, || {
                Solver::default().solve(&Problem::pixels(&w, &px, &cam))
            });
            let (refused, _) = with_limit(Bound::Undistort, limit, || {
                px.iter().filter(|p| cam.undistort(**p).is_err()).count()
            });
            // One step: every pixel reaches the bound. Two: the convergence check accepts
            // them (it runs at every iterate, so a converged pixel stops there).
            if limit == 1 {
                assert!(hit >= 25, "{what}: {hit}");
            }
            let kept = 30 - refused;
            if limit == 1 {
                assert!(kept < 4, "{what}: {kept}");
                assert_eq!(
                    res.err(),
                    Some(PnpError::TooFewPoints { got: kept, need: 4 }),
                    "{what}"
                );
            } else {
                assert!(kept >= 20, "{what}: {kept}");
                assert_eq!(
                    res.as_ref().map(|s| s.skipped).ok(),
                    Some(refused),
                    "{what}"
                );
                assert_true_pose(&res, &r, &what);
            }
        }
    }
    // A mixed view with a bound of one step: the pixels within 0.02 (normalised) of the centre
    // pass the convergence check after that step, the other 8 reach the bound and are left
    // out; the remaining points still give the true pose.
    let mut world = Vec::new();
    let mut pixels = Vec::new();
    let r = Rotation3::new(Vector3::new(0.3, -0.2, 0.4)).into_inner();
    let t = Vector3::new(0.0, 0.0, 6.0);
    let rt = r.transpose();
    for k in 0..16 {
        let (a, z) = (f64::from(k) * 2.4, 3.0 + f64::from(k % 5));
        // Camera-frame points: 8 near the optical axis (radius 0.01-0.015 of the depth), 8 far
        // off it (0.3).
        let rad = if k % 2 == 0 {
            0.01 + 0.0005 * f64::from(k)
        } else {
            0.3
        };
        let c = Vector3::new(rad * z * a.cos(), rad * z * a.sin(), z);
        world.push(Point3::from(rt * (c - t)));
        pixels.push(cam.project(Point2::new(c.x / c.z, c.y / c.z)));
    }
    let (res, hit) = with_limit(Bound::Undistort, 1, || {
        Solver::default().solve(&Problem::pixels(&world, &pixels, &cam))
    });
    assert_eq!(hit, 8);
    assert_eq!(res.as_ref().map(|s| s.skipped).ok(), Some(8));
    assert_true_pose(&res, &r, "solve_pixels, mixed view, Undistort = 1");
}
