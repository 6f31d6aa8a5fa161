use super::*;
use crate::numeric::mat3::{smallest_right_singular_vector, svd3};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

/// The certified cross product agrees with the SVD's singular vector to rounding level, and
/// a matrix it cannot certify (rank 1, or clearly nonsingular) gets the SVD's vector.
#[test]
fn null_vector3_matches_the_smallest_singular_vector() {
    let mut rng = Pcg64::seed_from_u64(11);
    let mut crossed = 0;
    for k in 0..3000 {
        let mut m = Matrix3::from_fn(|_, _| rng.random_range(-1.0..1.0));
        let (a, b) = (rng.random_range(-2.0..2.0), rng.random_range(-2.0..2.0));
        let row = m.row(0) * a + m.row(1) * b;
        m.set_row(2, &row);
        match k % 4 {
            1 => m *= 10f64.powi(rng.random_range(-100..100)),
            2 => m[(2, 2)] += 1e-3, // nonsingular: s3 not negligible
            3 => {
                // rank 1
                let (r1, r2) = (m.row(0) * 0.5, m.row(0) * -1.3);
                m.set_row(1, &r1);
                m.set_row(2, &r2);
            }
            _ => {}
        }
        let y = null_vector3(&m).unwrap();
        let v = svd3(&m).unwrap().v.column(2).into_owned();
        let sin = y.normalize().cross(&v).norm();
        let certified = y != v;
        if certified {
            crossed += 1;
            assert!(k % 4 < 2, "{k}: certified a matrix that is not rank 2");
            assert!(sin <= 1e-13, "{k}: {sin:e}");
        } else {
            assert_eq!(y, smallest_right_singular_vector(&m).unwrap());
        }
    }
    assert!(crossed > 1000, "{crossed}");
    assert!(null_vector3(&Matrix3::from_element(f64::NAN)).is_none());
    assert!(null_vector3(&Matrix3::zeros()).is_some());
}

/// `probe`'s `degenerate` (more than four eigenvalues of M below tau) equals the inertia
/// count's verdict, on the problems whose factorisation fails early enough that it still
/// counts and on those it now settles from the failed pivot: noise-free general scenes
/// (N = 4, 5, 6, 10: the factorisation of M - tau I fails at pivot 5, 7, 8 and 8, measured)
/// and PSD matrices with k = 0..8 zero eigenvalues in random directions (pivot 9 - k).
#[test]
fn probe_degenerate_equals_the_inertia_count() {
    use crate::numeric::rotation::exp_so3;
    use crate::pipeline::frame::working_frame;
    use crate::pipeline::moments::tests::accumulate;
    use nalgebra::{Point2, Point3, SVector, Vector3};
    let mut rng = Pcg64::seed_from_u64(23);
    let check = |m: &SMatrix<f64, 9, 9>, settled: &mut usize| {
        let scale = m.trace();
        let tau = DEGENERATE_EIG * scale * (1.0 + f64::EPSILON);
        let counted = linalg::count_eigenvalues_below(m, tau);
        assert_eq!(probe(m, scale).degenerate, counted > 4, "{counted}");
        // Settled without the count: the factorisation succeeds or fails at pivot 5 or later.
        if linalg::cholesky_shifted_or_pivot(m, tau).map_or_else(|j| j >= 5, |_| true) {
            *settled += 1;
        }
    };
    let mut settled = 0;
    for n in [4, 5, 6, 10] {
        for _ in 0..50 {
            let r = exp_so3(&Vector3::from_fn(|_, _| rng.random_range(-2.0..2.0)));
            let (mut world, mut image) = (Vec::new(), Vec::new());
            for _ in 0..n {
                let pc = Vector3::new(
                    rng.random_range(-2.0..2.0),
                    rng.random_range(-2.0..2.0),
                    rng.random_range(4.0..8.0),
                );
                world.push(Point3::from(r.transpose() * pc));
                image.push(Point2::new(pc.x / pc.z, pc.y / pc.z));
            }
            let frame = working_frame(&world, &image, None, true).unwrap();
            let m = accumulate(&world, &image, None, &frame)
                .system(false)
                .unwrap()
                .m;
            check(&m, &mut settled);
        }
    }
    for k in 0..=8 {
        for _ in 0..30 {
            let q = SMatrix::<f64, 9, 9>::from_fn(|_, _| rng.random_range(-1.0..1.0))
                .qr()
                .q();
            let lam = SVector::<f64, 9>::from_fn(|i, _| {
                if i < k {
                    0.0
                } else {
                    10f64.powf(rng.random_range(-6.0..0.0))
                }
            });
            let m = q * SMatrix::<f64, 9, 9>::from_diagonal(&lam) * q.transpose();
            check(&m, &mut settled);
        }
    }
    // Every noise-free scene and every matrix with k <= 4 is settled by the factorisation.
    assert!(settled >= 200 + 5 * 30, "{settled}");
}
