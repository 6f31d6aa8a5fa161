//! Input validation through the public solver: the order in which errors are reported, the
//! collinearity threshold and the representable range of world coordinates. The first stage
//! (the working frame) makes these decisions; the solver returns its error unchanged.
//! (Formerly unit tests of the working frame in `src/pipeline/frame/tests.rs`.)

use eopnp::Problem;
use eopnp::{DegenerateKind, InputKind, PnpError, Solution, Solver};
use nalgebra::{Point2, Point3, Vector3};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

/// Random world points in a 4 x 2 x 1 box (z = 0 when `planar`) and random image points.
fn cloud(rng: &mut Pcg64, n: usize, planar: bool) -> (Vec<Point3<f64>>, Vec<Point2<f64>>) {
    let world: Vec<Point3<f64>> = (0..n)
        .map(|_| {
            Point3::new(
                rng.random_range(-2.0..2.0),
                rng.random_range(-1.0..1.0),
                if planar {
                    0.0
                } else {
                    rng.random_range(-0.5..0.5)
                },
            )
        })
        .collect();
    let image = (0..n)
        .map(|_| Point2::new(rng.random_range(-0.5..0.5), rng.random_range(-0.5..0.5)))
        .collect();
    (world, image)
}

/// The solver with optional weights (`None`: [`Solver::solve`]).
fn solve(
    world: &[Point3<f64>],
    image: &[Point2<f64>],
    weights: Option<&[f64]>,
) -> Result<Solution, PnpError> {
    match weights {
        Some(w) => Solver::default().solve(&Problem::normalised(world, image).weights(w)),
        None => Solver::default().solve(&Problem::normalised(world, image)),
    }
}

#[test]
fn validation_errors_in_order() {
    let mut rng = Pcg64::seed_from_u64(13);
    let (world, image) = cloud(&mut rng, 6, false);
    let e = |r: Result<Solution, PnpError>| r.unwrap_err();
    assert_eq!(
        e(solve(&world, &image[..5], None)),
        PnpError::LengthMismatch { world: 6, image: 5 }
    );
    assert_eq!(
        e(solve(&world, &image, Some(&[1.0; 5]))),
        PnpError::WeightsLength {
            weights: 5,
            points: 6
        }
    );
    assert_eq!(
        e(solve(&world[..3], &image[..3], None)),
        PnpError::TooFewPoints { got: 3, need: 4 }
    );
    // Finiteness: first index, world before image before weight.
    let mut wb = world.clone();
    let mut ib = image.clone();
    wb[4].y = f64::NAN;
    ib[2].x = f64::INFINITY;
    assert_eq!(
        e(solve(&wb, &ib, None)),
        PnpError::NonFinite {
            index: 2,
            input: InputKind::Image
        }
    );
    ib[4].x = f64::NAN;
    ib[2].x = 0.0;
    assert_eq!(
        e(solve(&wb, &ib, None)),
        PnpError::NonFinite {
            index: 4,
            input: InputKind::World
        }
    );
    let mut w = [1.0; 6];
    w[1] = -1.0;
    w[3] = f64::NAN;
    assert_eq!(
        e(solve(&world, &image, Some(&w))),
        PnpError::NonFinite {
            index: 3,
            input: InputKind::Weight
        }
    );
    w[3] = 1.0;
    assert_eq!(
        e(solve(&world, &image, Some(&w))),
        PnpError::InvalidWeight { index: 1 }
    );
    let w = [1.0, 0.0, 1.0, 0.0, 1.0, 1e-15];
    assert!(solve(&world, &image, Some(&w)).is_ok());
    // A weight at f64 resolution of the largest cannot tell the P3P poses of the other three
    // apart: it does not count.
    let w = [1.0, 0.0, 1.0, 0.0, 1.0, 1e-300];
    assert_eq!(
        e(solve(&world, &image, Some(&w))),
        PnpError::TooFewPoints { got: 3, need: 4 }
    );
    let w = [1.0, 0.0, 1.0, 0.0, 1.0, 0.0];
    assert_eq!(
        e(solve(&world, &image, Some(&w))),
        PnpError::TooFewPoints { got: 3, need: 4 }
    );
    // Coincident world points (also at a non-zero location, and all at the origin).
    for p in [Point3::new(1.0, 2.0, 3.0), Point3::origin()] {
        let same = vec![p; 6];
        assert_eq!(
            e(solve(&same, &image, None)),
            PnpError::Degenerate(DegenerateKind::CoincidentWorldPoints)
        );
    }
    // Collinear beats coincident image points.
    let line: Vec<Point3<f64>> = (0..6)
        .map(|i| Point3::new(i as f64, 2.0 * i as f64, 1.0))
        .collect();
    let one = vec![Point2::new(0.1, 0.2); 6];
    assert_eq!(
        e(solve(&line, &one, None)),
        PnpError::Degenerate(DegenerateKind::CollinearWorldPoints)
    );
    assert_eq!(
        e(solve(&world, &one, None)),
        PnpError::Degenerate(DegenerateKind::CoincidentImagePoints)
    );
}

#[test]
fn collinearity_threshold() {
    // The collinearity rule (sv1 <= 1e-8 sv0): offset 0 to 1e-8 of the extent -> collinear
    // error; offset 1e-7 and above -> solvable.
    let mut rng = Pcg64::seed_from_u64(14);
    let image: Vec<Point2<f64>> = (0..10)
        .map(|_| Point2::new(rng.random_range(-0.5..0.5), rng.random_range(-0.5..0.5)))
        .collect();
    for (offset, ok) in [
        (0.0, false),
        (1e-9, false),
        (1e-8, false),
        (1e-7, true),
        (1e-3, true),
    ] {
        let world: Vec<Point3<f64>> = (0..10)
            .map(|i| {
                let t = i as f64 / 9.0 * 2.0 - 1.0;
                let e = Vector3::new(
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                );
                Point3::from(
                    Vector3::new(1.0, 2.0, -0.5) * t + e * offset + Vector3::new(3.0, 0.0, 1.0),
                )
            })
            .collect();
        let r = solve(&world, &image, None);
        assert_eq!(r.is_ok(), ok, "offset {offset}: {r:?}");
        if !ok {
            // (Only the input validation reports this kind.)
            assert_eq!(
                r.unwrap_err(),
                PnpError::Degenerate(DegenerateKind::CollinearWorldPoints)
            );
        }
    }
}

#[test]
fn out_of_range_world_scales() {
    let mut rng = Pcg64::seed_from_u64(15);
    let (world, image) = cloud(&mut rng, 10, false);
    // Out of range: coordinates near f64::MAX, spread in the subnormal range.
    let huge: Vec<Point3<f64>> = world
        .iter()
        .map(|x| Point3::from(x.coords * 4e307))
        .collect(); // |X| up to 8e307 > f64::MAX / 4
    assert_eq!(
        solve(&huge, &image, None).unwrap_err(),
        PnpError::Degenerate(DegenerateKind::ScaleOutOfRange)
    );
    let tiny: Vec<Point3<f64>> = world
        .iter()
        .map(|x| Point3::from(x.coords * 1e-310 + Vector3::repeat(1e-300)))
        .collect();
    let r = solve(&tiny, &image, None);
    assert!(r.is_err(), "{r:?}");
    // (Only the input validation reports this kind: the solver rejected the input there.)
    assert_eq!(
        r.unwrap_err(),
        PnpError::Degenerate(DegenerateKind::ScaleOutOfRange)
    );
    let tiny: Vec<Point3<f64>> = world
        .iter()
        .map(|x| Point3::from(x.coords * 1e-310))
        .collect();
    assert_eq!(
        solve(&tiny, &image, None).unwrap_err(),
        PnpError::Degenerate(DegenerateKind::ScaleOutOfRange)
    );
}
