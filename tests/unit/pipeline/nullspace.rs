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
