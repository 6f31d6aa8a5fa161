use super::*;

/// Uniform numbers in [-1, 1) from a seeded xorshift generator.
fn uniform(mut seed: u64) -> impl FnMut() -> f64 {
    move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        ((seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }
}

/// Random orthogonal 9x9 matrices from a seeded generator.
fn random_orthogonal(next: &mut impl FnMut() -> f64) -> SMatrix<f64, 9, 9> {
    SMatrix::<f64, 9, 9>::from_fn(|_, _| next()).qr().q()
}

/// Also the bound the solver's probe takes from a failed Cholesky factorisation.
#[test]
fn ldlt_inertia_agrees_with_the_sturm_count_on_semidefinite_matrices() {
    // The solver's use: M positive semidefinite, tau = 1e-10 trace(M), k eigenvalues at or
    // near 0 (k = 0..6), the others spread over [1e-6, 1] times the largest.
    let mut next = uniform(0x2545_F491_4F6C_DD1D);
    let tiny = [0.0, 1e-16, 1e-14, 1e-12, 3e-11, 3e-10, 1e-9];
    let mut fast = [0usize; 7];
    #[allow(clippy::needless_range_loop)]
    for k in 0..=6usize {
        for trial in 0..300 {
            let q = random_orthogonal(&mut next);
            let lam = SVector::<f64, 9>::from_fn(|i, _| {
                if i < k {
                    tiny[(trial + i) % tiny.len()]
                } else {
                    10f64.powf(-6.0 * (0.5 + 0.5 * next()))
                }
            });
            let m = q * SMatrix::<f64, 9, 9>::from_diagonal(&lam) * q.transpose();
            let tau = 1e-10 * m.trace();
            // Eigenvalues within 1e-3 tau of tau are ambiguous in floating point: skip.
            if lam.iter().any(|&l| (l - tau).abs() < 1e-3 * tau) {
                continue;
            }
            let exact = lam.iter().filter(|&&l| l < tau).count();
            // The probe's shortcut: a factorisation of M - tau I that fails at pivot j bounds
            // the count by 9 - j (interlacing); one that succeeds proves it 0.
            match cholesky_shifted_or_pivot(&m, tau) {
                Ok(_) => assert_eq!(exact, 0, "k {k} trial {trial}"),
                Err(j) => assert!(exact >= 1 && exact <= 9 - j, "k {k} trial {trial}: {j}"),
            }
            assert_eq!(sturm_count_below(&m, tau), exact, "k {k} trial {trial}");
            if let Some(c) = inertia_ldlt(&m, tau) {
                assert_eq!(c, exact, "ldlt: k {k} trial {trial}");
                fast[k] += 1;
            }
            assert_eq!(count_eigenvalues_below(&m, tau), exact);
        }
    }
    // With at most one eigenvalue near 0 (every well-posed problem) the fast path is taken.
    assert!(
        fast[0] >= 290 && fast[1] >= 290,
        "fast path taken: {fast:?}"
    );
}

#[test]
fn eigenvalue_count_matches_a_full_decomposition() {
    // Random symmetric matrices with eigenvalues spread over decades: the Sturm count below
    // the midpoint between consecutive eigenvalues must equal the index.
    let mut seed = 0x9E37_79B9_7F4A_7C15u64;
    let mut next = || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    };
    for _ in 0..200 {
        let b = SMatrix::<f64, 9, 9>::from_fn(|_, _| next());
        let q = b.qr().q();
        let lam = SVector::<f64, 9>::from_fn(|i, _| {
            10f64.powf(-8.0 + 1.0 * i as f64) * (1.0 + 0.5 * next())
        });
        let m = q * SMatrix::<f64, 9, 9>::from_diagonal(&lam) * q.transpose();
        let mut sorted: Vec<f64> = lam.iter().copied().collect();
        sorted.sort_by(f64::total_cmp);
        for k in 0..8 {
            let mid = (sorted[k] * sorted[k + 1]).sqrt();
            assert_eq!(count_eigenvalues_below(&m, mid), k + 1);
            assert_eq!(sturm_count_below(&m, mid), k + 1);
        }
        assert_eq!(count_eigenvalues_below(&m, 0.5 * sorted[0]), 0);
    }
}

#[test]
fn inverse_iteration_finds_the_smallest_eigenvector() {
    // M = Q diag(lambda) Q^T with a known smallest eigenvector.
    let q = nalgebra::SMatrix::<f64, 9, 9>::from_fn(|i, j| ((i * 7 + j * 3) as f64).sin())
        .qr()
        .q();
    let lam =
        SVector::<f64, 9>::from_column_slice(&[1e-9, 0.05, 0.2, 0.5, 1.0, 2.0, 3.0, 4.0, 5.0]);
    let m = q * SMatrix::<f64, 9, 9>::from_diagonal(&lam) * q.transpose();
    let v = smallest_eigenvector(&m, m.trace()).unwrap();
    let v1 = q.column(0);
    // after 4 steps the error is ~ (0.05/... )^4 relative: well below 1e-4
    assert!((v.dot(&v1).abs() - 1.0).abs() < 1e-8);
    assert_eq!(count_eigenvalues_below(&m, 1e-10 * m.trace()), 1);
    assert_eq!(count_eigenvalues_below(&m, 0.3), 3);
    let m2 =
        q * SMatrix::<f64, 9, 9>::from_diagonal(&SVector::<f64, 9>::from_column_slice(&[
            0.0, 1e-14, 1e-13, 1e-15, 0.0, 2.0, 3.0, 4.0, 5.0,
        ])) * q.transpose();
    assert_eq!(count_eigenvalues_below(&m2, 1e-10 * m2.trace()), 5);
}

#[test]
fn non_finite_input_gives_none() {
    let mut m = SMatrix::<f64, 9, 9>::identity();
    m[(3, 3)] = f64::NAN;
    assert!(smallest_eigenvector(&m, 9.0).is_none());
}

/// `solve_damped6` (`refine`'s step, `L D L^T`): the residual of `(H + lam I) delta = -g` at the
/// level of the rounding for positive definite `H + lam I` over condition numbers up to 1e12
/// (`refine`'s normal equations span about that), and `None` where it is not positive definite or
/// has a NaN entry.
#[test]
fn damped_solve_solves_positive_definite_systems_and_refuses_the_others() {
    let mut next = uniform(0x9E37_79B9_7F4A_7C15);
    for trial in 0..500 {
        let q = SMatrix::<f64, 6, 6>::from_fn(|_, _| next()).qr().q();
        let decades = 12.0 * (trial as f64 / 500.0);
        let lam_h = SVector::<f64, 6>::from_fn(|i, _| 10f64.powf(-decades * i as f64 / 5.0));
        let h = q * SMatrix::<f64, 6, 6>::from_diagonal(&lam_h) * q.transpose();
        let h = (h + h.transpose()) * 0.5;
        let ha: [[f64; 6]; 6] = core::array::from_fn(|i| core::array::from_fn(|j| h[(i, j)]));
        let g: [f64; 6] = core::array::from_fn(|_| next());
        let lam = if trial % 2 == 0 {
            0.0
        } else {
            1e-3 * next().abs()
        };
        let delta = solve_damped6(&ha, lam, &g).expect("positive definite");
        let a = h + SMatrix::<f64, 6, 6>::identity() * lam;
        let d = SVector::<f64, 6>::from_column_slice(&delta);
        let gv = SVector::<f64, 6>::from_column_slice(&g);
        // Backward error: |A d + g| relative to |A| |d| + |g|.
        let res = (a * d + gv).norm();
        let scale = a.norm() * d.norm() + gv.norm();
        assert!(
            res <= 1e-14 * scale,
            "trial {trial}: residual {res:e}, scale {scale:e}"
        );
    }
    // Indefinite, negative, NaN.
    let mut h = [[0.0; 6]; 6];
    for (i, row) in h.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    h[2][2] = -1.0;
    assert!(solve_damped6(&h, 0.5, &[1.0; 6]).is_none());
    assert!(solve_damped6(&h, 1.5, &[1.0; 6]).is_some());
    h[2][2] = 1.0;
    h[4][1] = f64::NAN;
    h[1][4] = f64::NAN;
    assert!(solve_damped6(&h, 0.0, &[1.0; 6]).is_none());
}
