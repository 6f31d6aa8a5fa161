//! The 9 x 9 eigen-routines of the solver's S3/S4 through their public hooks
//! (`eopnp::bench_hooks`, which forward to the internal routines): inverse iteration for the
//! smallest eigenvector and the count of eigenvalues below a threshold. (Formerly in
//! `src/numeric/linalg/tests.rs`; the comparisons of the internal fast and slow counts stay
//! there.)

use eopnp::bench_hooks::{count_eigenvalues_below9, smallest_eigenvector9};
use nalgebra::{SMatrix, SVector};

#[test]
fn inverse_iteration_finds_the_smallest_eigenvector9() {
    // M = Q diag(lambda) Q^T with a known smallest eigenvector.
    let q = nalgebra::SMatrix::<f64, 9, 9>::from_fn(|i, j| ((i * 7 + j * 3) as f64).sin())
        .qr()
        .q();
    let lam =
        SVector::<f64, 9>::from_column_slice(&[1e-9, 0.05, 0.2, 0.5, 1.0, 2.0, 3.0, 4.0, 5.0]);
    let m = q * SMatrix::<f64, 9, 9>::from_diagonal(&lam) * q.transpose();
    let v = smallest_eigenvector9(&m, m.trace()).unwrap();
    let v1 = q.column(0);
    // after 4 steps the error is ~ (0.05/... )^4 relative: well below 1e-4
    assert!((v.dot(&v1).abs() - 1.0).abs() < 1e-8);
    assert_eq!(count_eigenvalues_below9(&m, 1e-10 * m.trace()), 1);
    assert_eq!(count_eigenvalues_below9(&m, 0.3), 3);
    let m2 =
        q * SMatrix::<f64, 9, 9>::from_diagonal(&SVector::<f64, 9>::from_column_slice(&[
            0.0, 1e-14, 1e-13, 1e-15, 0.0, 2.0, 3.0, 4.0, 5.0,
        ])) * q.transpose();
    assert_eq!(count_eigenvalues_below9(&m2, 1e-10 * m2.trace()), 5);
}

#[test]
fn non_finite_input_gives_none() {
    let mut m = SMatrix::<f64, 9, 9>::identity();
    m[(3, 3)] = f64::NAN;
    assert!(smallest_eigenvector9(&m, 9.0).is_none());
}
