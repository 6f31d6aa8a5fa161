use super::*;
use crate::numeric::lanes::with_baseline;
use crate::numeric::rotation::exp_so3;
use crate::pipeline::frame::working_frame;
use crate::pipeline::select::count_in_front;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

/// A problem for the depth counts: world points, image points, weights, their working frame
/// and a working-frame pose `(R, t)`.
type DepthCase = (
    Vec<Point3<f64>>,
    Vec<Point2<f64>>,
    Option<Vec<f64>>,
    WorkingFrame,
    Matrix3<f64>,
    Vector3<f64>,
);

/// A random [`DepthCase`]: `4 + trial % 37` points (every fourth problem nearly flat), weights
/// in every other problem (every fifth point's 0), and a pose that leaves points on both
/// sides of the camera; `None` if the points have no working frame.
fn depth_case(rng: &mut Pcg64, trial: usize) -> Option<DepthCase> {
    let n = 4 + trial % 37;
    let world: Vec<Point3<f64>> = (0..n)
        .map(|_| {
            Point3::new(
                rng.random_range(-3.0..3.0),
                rng.random_range(-2.0..2.0),
                rng.random_range(-1.0..1.0) * if trial.is_multiple_of(4) { 1e-3 } else { 1.0 },
            )
        })
        .collect();
    let image: Vec<Point2<f64>> = (0..n)
        .map(|_| Point2::new(rng.random_range(-0.5..0.5), rng.random_range(-0.5..0.5)))
        .collect();
    let weights: Option<Vec<f64>> = (trial % 2 == 1).then(|| {
        (0..n)
            .map(|k| {
                if k % 5 == 2 {
                    0.0
                } else {
                    rng.random_range(0.1..3.0)
                }
            })
            .collect()
    });
    let fr = working_frame(&world, &image, weights.as_deref(), true).ok()?;
    let w = Vector3::new(
        rng.random_range(-3.0..3.0),
        rng.random_range(-3.0..3.0),
        rng.random_range(-3.0..3.0),
    );
    let r = exp_so3(&w);
    // Depths of the working frame's points (order 1) about t_z: a small t_z leaves points on
    // both sides.
    let t = Vector3::new(
        rng.random_range(-0.5..0.5),
        rng.random_range(-0.5..0.5),
        rng.random_range(-0.3..1.5),
    );
    Some((world, image, weights, fr, r, t))
}

/// The output pass's count of the points in front (the algebraic mode's depth test) is
/// `count_in_front`'s to the unit, and its error is the world-frame reprojection error to
/// rounding, with and without weights (zeros among them), at poses that put about half of
/// the points behind the camera; the baseline and AVX2 builds give the same bits. (It fails
/// if the pass counts a point of weight 0, a lane of the partial block twice, or uses
/// another depth.)
#[test]
fn reprojection_error_counts_the_points_in_front_as_select() {
    let mut rng = Pcg64::seed_from_u64(0x07_5eed);
    let (mut mixed, mut checked) = (0, 0);
    for trial in 0..400 {
        let Some((world, image, weights, fr, r, t)) = depth_case(&mut rng, trial) else {
            continue;
        };
        let pose = Composed::new(&r, &fr.rw, fr.d, &t);
        let inv = 1.0 / fr.weight_unit;
        let run = || reprojection_error(&world, &image, weights.as_deref(), inv, &pose, &fr.c);
        let (e, front) = run();
        let (e_base, front_base) = with_baseline(run);
        assert_eq!((e.to_bits(), front), (e_base.to_bits(), front_base));
        let a = (r * fr.rw).row(2).transpose() / fr.d;
        assert_eq!(
            front,
            count_in_front(&world, weights.as_deref(), &a, &fr.c, t.z)
        );
        if front > 0 && front < fr.n_active {
            mixed += 1;
        }
        // The error at the world-frame pose, point by point.
        let (rw, tw) = fr.to_world(&r, &t);
        let mut want = 0.0;
        for (k, (x, m)) in world.iter().zip(&image).enumerate() {
            let wk = weights.as_ref().map_or(1.0, |w| w[k]) * inv;
            if wk == 0.0 {
                continue;
            }
            let p = rw * x.coords + tw;
            want += wk * ((m.x - p.x / p.z).powi(2) + (m.y - p.y / p.z).powi(2));
        }
        assert!(
            (e - want).abs() <= 1e-9 * want.max(1e-300),
            "trial {trial}: {e} vs {want}"
        );
        checked += 1;
    }
    assert!(
        checked > 300 && mixed > 100,
        "{checked} checked, {mixed} mixed"
    );
}

/// `refine_pixels`' first pass counts the points in front of its start as `select` does
/// (`count_in_front`, to the unit), with and without weights (zeros among them), through a lens
/// with distortion, at poses that put about half of the points behind the camera: `finish_with`
/// takes `select`'s depth test from it. (It fails if the pass counts a point of weight 0, a lane of
/// the partial block twice, or uses another depth.)
#[test]
fn refine_pixels_counts_the_points_in_front_as_select() {
    use crate::camera::Camera;
    use crate::pipeline::options::Loss;
    use crate::pipeline::refine::ReprojOptions;
    use crate::pipeline::refine_pixels::{refine_pixels, PixelInputs};
    let cam = Camera::from_colmap("SIMPLE_RADIAL", 640, 480, vec![500.0, 320.0, 240.0, -0.1])
        .expect("a valid camera");
    let mut rng = Pcg64::seed_from_u64(0x510_f407);
    let (mut mixed, mut checked) = (0, 0);
    for trial in 0..400 {
        let Some((world, image, weights, fr, r, t)) = depth_case(&mut rng, trial) else {
            continue;
        };
        let pixels: Vec<Point2<f64>> = image.iter().map(|m| cam.project(*m)).collect();
        let px = PixelInputs {
            pixels: &pixels,
            weights: weights.as_deref(),
            projector: cam.projector(),
            loss: Loss::Squared,
            refine: true,
            scale: 500.0,
        };
        let po = refine_pixels(&world, &px, &fr, &r, &t, &ReprojOptions::default());
        let a = (r * fr.rw).row(2).transpose() / fr.d;
        let want = count_in_front(&world, weights.as_deref(), &a, &fr.c, t.z);
        assert_eq!(po.out.start_in_front, Some(want), "trial {trial}");
        if want > 0 && want < fr.n_active {
            mixed += 1;
        }
        checked += 1;
    }
    assert!(
        checked > 300 && mixed > 100,
        "{checked} checked, {mixed} mixed"
    );
}
