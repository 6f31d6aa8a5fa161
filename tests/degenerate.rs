//! Invalid and degenerate inputs (docs/algorithm.md section 6): one test per `PnpError` variant,
//! the "solve and flag" cases, and a property test that `solve` never panics and never returns
//! a non-finite pose.

// `!(err <= tol)` is deliberate throughout: a NaN error must fail the check.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use eopnp_testkit as common;

use common::*;
use eopnp::{DegenerateKind, InputKind, PnpError, Solver};
use nalgebra::{Matrix3, Point2, Point3, Vector3};
use proptest::prelude::*;
use rand::Rng;

/// A valid noise-free problem to corrupt (general scene, N points).
fn valid(n: usize, tag: &str) -> Problem {
    Problem::generate(&ProblemOptions {
        n,
        sigma_px: 0.0,
        scene: Scene::General,
        rotation: RotationKind::Uniform,
        seed: trial_seed(&format!("degenerate/{tag}"), 0),
    })
}

/// Projects world points with a pose (normalised coordinates).
fn project(world: &[Point3<f64>], r: &Matrix3<f64>, t: &Vector3<f64>) -> Vec<Point2<f64>> {
    world
        .iter()
        .map(|x| {
            let p = r * x.coords + t;
            Point2::new(p.x / p.z, p.y / p.z)
        })
        .collect()
}

/// Exactness bound for noise-free solves, as in the noise-free accuracy suite: 1e-6 deg and
/// 1e-8 relative translation (the prototype reaches ~1e-12).
fn assert_exact(sol: &eopnp::Solution, r_gt: &Matrix3<f64>, t_gt: &Vector3<f64>, what: &str) {
    let (r, t) = pose_of(sol);
    let er = rot_err_deg(&r, r_gt);
    let et = trans_err_rel(&t, t_gt);
    assert!(
        er < 1e-6 && et < 1e-8,
        "{what}: rotation {er:e} deg, translation {et:e} relative"
    );
}

#[test]
fn too_few_points() {
    let p = valid(4, "too_few");
    for n in 0..4 {
        let err = eopnp::solve(&p.world[..n], &p.image[..n]).unwrap_err();
        assert!(
            matches!(err, PnpError::TooFewPoints { got, need: 4 } if got == n),
            "n = {n}: {err:?}"
        );
    }
}

#[test]
fn length_mismatch() {
    let p = valid(6, "mismatch");
    let err = eopnp::solve(&p.world, &p.image[..5]).unwrap_err();
    assert!(
        matches!(err, PnpError::LengthMismatch { world: 6, image: 5 }),
        "{err:?}"
    );
    // The shape check comes first (docs/algorithm.md section 6 order), even with N < 4.
    let err = eopnp::solve(&p.world[..3], &p.image[..2]).unwrap_err();
    assert!(
        matches!(err, PnpError::LengthMismatch { world: 3, image: 2 }),
        "{err:?}"
    );
}

#[test]
fn weights_length_mismatch() {
    let p = valid(6, "weights_len");
    let err = Solver::default()
        .solve(&eopnp::Problem::normalised(&p.world, &p.image).weights(&[1.0; 5]))
        .unwrap_err();
    assert!(matches!(err, PnpError::WeightsLength { .. }), "{err:?}");
    let err = Solver::default()
        .solve(&eopnp::Problem::normalised(&p.world, &p.image).weights(&[1.0; 7]))
        .unwrap_err();
    assert!(matches!(err, PnpError::WeightsLength { .. }), "{err:?}");
}

#[test]
fn non_finite_world_names_the_index() {
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        for coord in 0..3 {
            let mut p = valid(8, "nonfinite_world");
            p.world[5][coord] = bad;
            // A second bad entry later: the FIRST offending index is reported.
            p.world[7][0] = f64::NAN;
            let err = eopnp::solve(&p.world, &p.image).unwrap_err();
            assert!(
                matches!(
                    err,
                    PnpError::NonFinite {
                        index: 5,
                        input: InputKind::World
                    }
                ),
                "{bad} in coordinate {coord}: {err:?}"
            );
        }
    }
}

#[test]
fn non_finite_image_names_the_index() {
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        for coord in 0..2 {
            let mut p = valid(8, "nonfinite_image");
            p.image[2][coord] = bad;
            let err = eopnp::solve(&p.world, &p.image).unwrap_err();
            assert!(
                matches!(
                    err,
                    PnpError::NonFinite {
                        index: 2,
                        input: InputKind::Image
                    }
                ),
                "{bad} in coordinate {coord}: {err:?}"
            );
        }
    }
}

#[test]
fn non_finite_weight_names_the_index() {
    for bad in [f64::NAN, f64::INFINITY] {
        let p = valid(8, "nonfinite_weight");
        let mut w = vec![1.0; 8];
        w[6] = bad;
        let err = Solver::default()
            .solve(&eopnp::Problem::normalised(&p.world, &p.image).weights(&w))
            .unwrap_err();
        assert!(
            matches!(
                err,
                PnpError::NonFinite {
                    index: 6,
                    input: InputKind::Weight
                }
            ),
            "{bad}: {err:?}"
        );
    }
}

#[test]
fn negative_weight() {
    let p = valid(8, "negative_weight");
    let mut w = vec![1.0; 8];
    w[3] = -1e-300;
    let err = Solver::default()
        .solve(&eopnp::Problem::normalised(&p.world, &p.image).weights(&w))
        .unwrap_err();
    assert!(
        matches!(err, PnpError::InvalidWeight { index: 3 }),
        "{err:?}"
    );
}

#[test]
fn coincident_world_points() {
    let p = valid(6, "coincident_world");
    let world = vec![Point3::new(1.5, -2.0, 3.25); 6];
    let err = eopnp::solve(&world, &p.image).unwrap_err();
    assert!(
        matches!(
            err,
            PnpError::Degenerate(DegenerateKind::CoincidentWorldPoints)
        ),
        "{err:?}"
    );
}

/// World points, their images, and the pose (R, t) that produced them.
type LineProblem = (
    Vec<Point3<f64>>,
    Vec<Point2<f64>>,
    Matrix3<f64>,
    Vector3<f64>,
);

/// Points on a line through `a` with direction `u` (extent ~4), offset perpendicular by
/// `offset` times the extent, and their images under a pose that sees them all in front.
fn line_problem(offset: f64, seed: u64) -> LineProblem {
    let mut rng = rng_from_seed(seed);
    let u = unit_vector(&mut rng);
    let v = u.cross(&unit_vector(&mut rng)).normalize();
    let w = u.cross(&v);
    let a = gauss3(&mut rng);
    let n = 10;
    let world: Vec<Point3<f64>> = (0..n)
        .map(|i| {
            let s = -2.0 + 4.0 * i as f64 / (n - 1) as f64;
            let o1 = 4.0 * offset * (2.0 * rng.random::<f64>() - 1.0);
            let o2 = 4.0 * offset * (2.0 * rng.random::<f64>() - 1.0);
            Point3::from(a + u * s + v * o1 + w * o2)
        })
        .collect();
    let r = haar_rotation(&mut rng);
    let t = Vector3::new(0.1, -0.2, 8.0) - r * a;
    let image = project(&world, &r, &t);
    (world, image, r, t)
}

#[test]
fn collinear_world_points() {
    for offset in [0.0, 1e-9] {
        for seed in 0..5 {
            let (world, image, _, _) = line_problem(offset, seed);
            let err = eopnp::solve(&world, &image).unwrap_err();
            assert!(
                matches!(
                    err,
                    PnpError::Degenerate(DegenerateKind::CollinearWorldPoints)
                ),
                "offset {offset}, seed {seed}: {err:?}"
            );
        }
    }
}

#[test]
fn coincident_image_points() {
    let p = valid(7, "coincident_image");
    let image = vec![Point2::new(0.01, -0.02); 7];
    let err = eopnp::solve(&p.world, &image).unwrap_err();
    assert!(
        matches!(
            err,
            PnpError::Degenerate(DegenerateKind::CoincidentImagePoints)
        ),
        "{err:?}"
    );
}

#[test]
fn all_points_behind_the_camera_is_flagged() {
    // Mirror every camera-frame point through the camera centre: same image, all depths
    // negative under the true pose. No input error: the solver returns an in-front pose and
    // must say so through cheirality_ok == false or a residual that rejects it.
    for trial in 0..20 {
        let seed = trial_seed("degenerate/behind", trial);
        let p = Problem::generate(&ProblemOptions {
            n: 10,
            sigma_px: 0.0,
            scene: Scene::General,
            rotation: RotationKind::Uniform,
            seed,
        });
        let world: Vec<Point3<f64>> = p
            .world
            .iter()
            .map(|x| {
                let pc = p.r_gt * x.coords + p.t_gt;
                Point3::from(p.r_gt.transpose() * (-pc - p.t_gt))
            })
            .collect();
        let sol =
            eopnp::solve(&world, &p.image).unwrap_or_else(|e| panic!("seed {seed:#x}: {e:?}"));
        let (r, t) = pose_of(&sol);
        assert!(
            r.iter().chain(t.iter()).all(|v| v.is_finite()),
            "seed {seed:#x}"
        );
        // The prototype returns a pose 177 deg off with f_rel = 2e-2 (docs/algorithm.md section 6).
        // A residual "flags it" when it is far above noise-free rounding: an RMS of 1e-6 in
        // normalised units is 8e-4 px at f = 800, while exact solves give ~1e-15.
        assert!(
            !sol.cheirality_ok || sol.reprojection_rmse > 1e-6,
            "seed {seed:#x}: cheirality_ok with rmse {:e}, f_rel {:e}",
            sol.reprojection_rmse,
            sol.algebraic_cost
        );
    }
}

#[test]
fn nearly_collinear_solves_and_flags() {
    // Offset 1e-6 of the extent: above the collinearity threshold (sv1 / sv0 > 1e-8), but M
    // has 7 tiny eigenvalues (docs/algorithm.md section 6): solve, and set the degenerate flag.
    for seed in 0..5 {
        let (world, image, _, _) = line_problem(1e-6, 100 + seed);
        let sol = eopnp::solve(&world, &image).unwrap_or_else(|e| panic!("seed {seed}: {e:?}"));
        let (r, t) = pose_of(&sol);
        assert!(
            r.iter().chain(t.iter()).all(|v| v.is_finite()),
            "seed {seed}"
        );
        assert!(sol.degenerate, "seed {seed}: degenerate flag not set");
    }
}

#[test]
fn millimetre_world_with_large_offset_is_exact() {
    for trial in 0..20 {
        let p = valid(10, &format!("mm_offset/{trial}"));
        let off = Vector3::new(1e6, -1e6, 1e6);
        let world: Vec<Point3<f64>> = p
            .world
            .iter()
            .map(|x| Point3::from(x.coords * 1000.0 + off))
            .collect();
        let t_gt = p.t_gt * 1000.0 - p.r_gt * off;
        let sol = eopnp::solve(&world, &p.image).expect("millimetre world solves");
        assert_exact(&sol, &p.r_gt, &t_gt, &format!("trial {trial}"));
    }
}

#[test]
fn duplicated_correspondences_are_exact() {
    // One duplicated correspondence (N = 6, 5 distinct), and 4 distinct points each given
    // twice (N = 8): exact (docs/algorithm.md section 6).
    let p = valid(6, "dup");
    let mut world = p.world.clone();
    let mut image = p.image.clone();
    world[5] = world[2];
    image[5] = image[2];
    let sol = eopnp::solve(&world, &image).expect("duplicate solves");
    assert_exact(&sol, &p.r_gt, &p.t_gt, "one duplicate");
    let world: Vec<Point3<f64>> = p.world[..4].iter().chain(&p.world[..4]).copied().collect();
    let image: Vec<Point2<f64>> = p.image[..4].iter().chain(&p.image[..4]).copied().collect();
    let sol = eopnp::solve(&world, &image).expect("doubled N = 4 solves");
    assert_exact(&sol, &p.r_gt, &p.t_gt, "4 points twice");
}

/// Any f64, with the special values (NaN, infinities, zeros, extremes, subnormals) well
/// represented, and ordinary coordinates most of the time.
fn wild_f64() -> impl Strategy<Value = f64> {
    prop_oneof![
        6 => -10.0..10.0f64,
        2 => any::<f64>(),
        2 => prop::sample::select(vec![
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            0.0,
            -0.0,
            f64::MAX,
            f64::MIN,
            f64::MIN_POSITIVE,
            -f64::MIN_POSITIVE,
            5e-324,
            -5e-324,
            1e-300,
            1e300,
            1e-160,
            1e160,
        ]),
    ]
}

fn check_pose(sol: &eopnp::Solution) -> Result<(), TestCaseError> {
    let (r, t) = pose_of(sol);
    prop_assert!(
        r.iter().chain(t.iter()).all(|v| v.is_finite()),
        "Ok with a non-finite pose: R = {r}, t = {t}"
    );
    Ok(())
}

fn check_finite_or_err(res: Result<eopnp::Solution, PnpError>) -> Result<(), TestCaseError> {
    match res {
        Ok(sol) => check_pose(&sol),
        Err(_) => Ok(()),
    }
}

/// The seed of this file's properties.
const PROPTEST_SEED: u64 = 0x0E0F_2019_5EED;

/// proptest's configuration: `cases` cases drawn from a fixed seed, so that a failure
/// reproduces on every run and machine (the environment variable `PROPTEST_RNG_SEED=<u64>`
/// draws another sequence), and a failure persisted in `tests/degenerate.proptest-regressions`
/// (committed: replayed first on every run).
fn proptest_config(cases: u32) -> ProptestConfig {
    ProptestConfig {
        cases,
        rng_seed: proptest::test_runner::RngSeed::Fixed(PROPTEST_SEED),
        failure_persistence: Some(Box::new(
            proptest::test_runner::FileFailurePersistence::WithSource("proptest-regressions"),
        )),
        ..ProptestConfig::default()
    }
}

proptest! {
    #![proptest_config(proptest_config(1024))]

    /// `solve` never panics and never returns Ok with a non-finite pose.
    #[test]
    fn solve_never_panics(
        world in prop::collection::vec((wild_f64(), wild_f64(), wild_f64()), 0..40),
        image in prop::collection::vec((wild_f64(), wild_f64()), 0..40),
        weights in prop::collection::vec(prop_oneof![3 => 0.0..10.0f64, 1 => wild_f64()], 0..40),
        same_len in any::<bool>(),
    ) {
        let mut world: Vec<Point3<f64>> = world.into_iter().map(|(x, y, z)| Point3::new(x, y, z)).collect();
        let mut image: Vec<Point2<f64>> = image.into_iter().map(|(u, v)| Point2::new(u, v)).collect();
        let mut weights = weights;
        if same_len {
            let n = world.len().min(image.len());
            world.truncate(n);
            image.truncate(n);
            weights.resize(n, 1.0);
        }
        check_finite_or_err(eopnp::solve(&world, &image))?;
        check_finite_or_err(Solver::default().solve(&eopnp::Problem::normalised(&world, &image).weights(&weights)))?;
        check_finite_or_err(
            Solver::default().refinement(eopnp::Refinement::Algebraic).solve(&eopnp::Problem::normalised(&world, &image)),
        )?;
        if let Ok(all) = Solver::default().solve_all(&eopnp::Problem::normalised(&world, &image)) {
            for s in all.iter() {
                check_pose(s)?;
            }
        }
    }

    /// Valid geometry with a few wild image coordinates or wild world points mixed in.
    #[test]
    fn valid_problem_with_wild_entries_never_panics(
        seed in any::<u64>(),
        n in 4usize..30,
        edits in prop::collection::vec((0usize..30, 0usize..5, wild_f64()), 1..4),
    ) {
        let mut p = Problem::generate(&ProblemOptions {
            n,
            sigma_px: 1.0,
            scene: Scene::General,
            rotation: RotationKind::Uniform,
            seed,
        });
        for (i, c, v) in edits {
            let i = i % n;
            if c < 3 {
                p.world[i][c] = v;
            } else {
                p.image[i][c - 3] = v;
            }
        }
        check_finite_or_err(eopnp::solve(&p.world, &p.image))?;
    }
}

/// Regression (found by `solve_never_panics` in CI rehearsal): world coordinates at 1e300 with
/// an image coordinate at 1.2e137 made the translation overflow when the working-frame scale
/// was undone, and `solve` returned `Ok` with an infinite translation. Every exit now checks
/// that the world-frame pose is finite.
#[test]
fn huge_world_and_image_coordinates_never_give_a_non_finite_pose() {
    let world = [
        Point3::new(0.0, 0.0, 0.0),
        Point3::new(0.0, 0.0, 0.0),
        Point3::new(0.0, 0.0, 0.0),
        Point3::new(0.0, 0.0, 1e300),
        Point3::new(1e300, 0.0, 0.0),
    ];
    let image = [
        Point2::new(0.0, 0.0),
        Point2::new(0.0, 1.1912733123490079e137),
        Point2::new(0.0, 0.0),
        Point2::new(0.0, 0.0),
        Point2::new(0.0, 0.0),
    ];
    for solver in [
        eopnp::Solver::default(),
        eopnp::Solver::default().refinement(eopnp::Refinement::Algebraic),
    ] {
        match solver.solve(&eopnp::Problem::normalised(&world, &image)) {
            Ok(s) => {
                assert!(s.translation.iter().all(|x| x.is_finite()));
                assert!(s.rotation.iter().all(|x| x.is_finite()));
            }
            Err(e) => assert_eq!(e, eopnp::PnpError::NoSolution, "{e}"),
        }
        if let Ok(all) = solver.solve_all(&eopnp::Problem::normalised(&world, &image)) {
            assert!(all
                .iter()
                .all(|s| s.translation.iter().all(|x| x.is_finite())));
        }
    }
}
