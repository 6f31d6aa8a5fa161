//! RANSAC through the library: determinism on the bundled COLMAP model, typed errors for bad
//! input and options, `NoConsensus`. The outlier experiment (every image solved, errors within
//! 1.25x of the floor) runs through the command line: `tests/robust_register.rs`.

use std::path::PathBuf;

use eopnp::colmap::{read_model, register_image, Model, ReadOptions};
use eopnp::ransac::Ransac;
use eopnp::Solver;

fn model() -> Model {
    read_model(
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data/colmap-boxes"),
        &ReadOptions::default(),
    )
    .unwrap()
}

#[test]
fn same_seed_same_result() {
    let model = model();
    let solver = Solver::default();
    let id = *model.images.keys().next().unwrap();
    let run = |seed: u64| {
        let r = Ransac::default().seed(seed);
        let reg = register_image(&model, id, &solver, Some(&r)).unwrap();
        let stats = reg.ransac.unwrap();
        (
            reg.solution.pose(),
            reg.inliers,
            stats.iterations,
            stats.hypotheses,
        )
    };
    let a = run(5);
    let b = run(5);
    // Bit-identical: same samples, same arithmetic.
    assert_eq!(a.0, b.0);
    assert_eq!(a.1, b.1);
    assert_eq!(a.2, b.2);
    assert_eq!(a.3, b.3);
}

#[test]
fn bad_input_is_an_error_not_a_panic() {
    use eopnp::PnpError;
    use nalgebra::{Point2, Point3};
    let r = Ransac::default();
    let s = Solver::default();
    let w = [Point3::new(0.0, 0.0, 1.0); 3];
    let i = [Point2::new(0.0, 0.0); 3];
    assert!(matches!(
        r.estimate(
            &s,
            &eopnp::Problem::normalised(&w, &i).focal(1000.0, 1000.0)
        ),
        Err(PnpError::TooFewPoints { .. })
    ));
    let w = [Point3::new(f64::NAN, 0.0, 1.0); 5];
    let i = [Point2::new(0.0, 0.0); 5];
    assert!(r
        .estimate(
            &s,
            &eopnp::Problem::normalised(&w, &i).focal(1000.0, 1000.0)
        )
        .is_err());
    // All points identical: no hypothesis, a typed error.
    let w = [Point3::new(1.0, 0.0, 1.0); 8];
    assert!(r
        .estimate(
            &s,
            &eopnp::Problem::normalised(&w, &i.repeat(2)[..8]).focal(1000.0, 1000.0)
        )
        .is_err());
}

#[test]
fn options_out_of_range_are_typed_errors() {
    use eopnp::PnpError;
    use nalgebra::{Point2, Point3};
    let s = Solver::default();
    let w: Vec<Point3<f64>> = (0..8)
        .map(|k| Point3::new(f64::from(k).sin(), f64::from(k).cos(), f64::from(k) * 0.1))
        .collect();
    let i: Vec<Point2<f64>> = w
        .iter()
        .map(|x| Point2::new(x.x / (x.z + 5.0), x.y / (x.z + 5.0)))
        .collect();
    let cases = [
        (Ransac::default().threshold_px(0.0), "threshold_px"),
        (Ransac::default().threshold_px(f64::NAN), "threshold_px"),
        // Squares that underflow (to a subnormal or 0) or overflow.
        (Ransac::default().threshold_px(1e-160), "threshold_px"),
        (Ransac::default().threshold_px(1e160), "threshold_px"),
        (
            Ransac::default()
                .threshold_px(1e150)
                .final_threshold_factor(1e10),
            "final_threshold_factor",
        ),
        (Ransac::default().confidence(1.0), "confidence"),
        (Ransac::default().confidence(-0.5), "confidence"),
        (Ransac::default().max_iterations(0), "max_iterations"),
        (
            Ransac::default().final_threshold_factor(0.5),
            "final_threshold_factor",
        ),
        (
            Ransac::default().final_threshold_factor(f64::INFINITY),
            "final_threshold_factor",
        ),
    ];
    for (r, option) in cases {
        let e = r
            .estimate(&s, &eopnp::Problem::normalised(&w, &i).focal(800.0, 800.0))
            .unwrap_err();
        assert_eq!(e, PnpError::InvalidOption { option });
        assert!(e.to_string().contains(option), "{e}");
        // Checked first, before the data.
        assert_eq!(
            r.estimate(
                &s,
                &eopnp::Problem::normalised(&w[..2], &i[..2]).focal(800.0, 800.0)
            )
            .unwrap_err(),
            PnpError::InvalidOption { option }
        );
    }
    assert!(Ransac::default()
        .estimate(&s, &eopnp::Problem::normalised(&w, &i).focal(800.0, 800.0))
        .is_ok());
}

#[test]
fn no_consensus_is_reported_with_the_sample_count() {
    use eopnp::PnpError;
    use nalgebra::{Point2, Point3};
    // Image points unrelated to the world points: no pose explains 4 of them within 0.5 px.
    let w: Vec<Point3<f64>> = (0..40)
        .map(|k| {
            let k = f64::from(k);
            Point3::new((k * 1.3).sin(), (k * 0.7).cos(), (k * 0.37).sin())
        })
        .collect();
    let i: Vec<Point2<f64>> = (0..40)
        .map(|k| {
            let k = f64::from(k);
            Point2::new((k * 2.9).sin() * 0.4, (k * 5.3).cos() * 0.4)
        })
        .collect();
    let r = Ransac::default().threshold_px(0.5).max_iterations(200);
    match r.estimate(
        &Solver::default(),
        &eopnp::Problem::normalised(&w, &i).focal(800.0, 800.0),
    ) {
        Err(e @ PnpError::NoConsensus { iterations, .. }) => {
            assert_eq!(iterations, 200);
            let msg = e.to_string();
            assert!(
                msg.contains("200 samples") && msg.contains("more than chance"),
                "{msg}"
            );
        }
        other => panic!("expected NoConsensus, got {other:?}"),
    }
}

#[test]
fn clean_problems_with_four_and_five_points_are_solved() {
    use eopnp_testkit::{Problem, ProblemOptions, RotationKind, Scene};
    for n in [4, 5] {
        for seed in 0..20 {
            let p = Problem::generate(&ProblemOptions {
                n,
                sigma_px: 0.0,
                scene: Scene::General,
                rotation: RotationKind::Uniform,
                seed,
            });
            let sol = Ransac::default()
                .seed(seed)
                .estimate(
                    &Solver::default(),
                    &eopnp::Problem::normalised(&p.world, &p.image).focal(800.0, 800.0),
                )
                .unwrap_or_else(|e| panic!("N = {n}, seed {seed}: {e}"));
            assert_eq!(sol.num_inliers, n, "N = {n}, seed {seed}");
            let err =
                eopnp::internals::metrics::rotation_error_deg(&sol.solution.rotation, &p.r_gt);
            assert!(err < 1e-6, "N = {n}, seed {seed}: {err:e} deg");
        }
    }
}
