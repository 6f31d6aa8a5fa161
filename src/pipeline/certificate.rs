//! Global-optimality certificates for a refined minimum of `f(R) = vec(R)^T M vec(R)`.
//!
//! At a stationary point `A` of `f` on O(3), `mat(M vec(A)) = Lambda A` for a symmetric
//! `Lambda` (the gradient lies in the normal space `{S A : S symmetric}`). With row-major
//! `vec`, `sum_jk Lambda_jk row_j(R) . row_k(R) = vec(R)^T (Lambda (x) I3) vec(R)`, so for every
//! `R` in O(3) (rows orthonormal):
//!
//! ```text
//! f(R) = vec(R)^T Q vec(R) + trace(Lambda),   Q = M - Lambda (x) I3,
//! ```
//!
//! and `trace(Lambda) = f(A)` because `Q vec(A) = 0`. If `Q` is positive semidefinite, then
//! `f(R) >= f(A)` for every rotation: `A` is a global minimum (the Lagrangian dual of the
//! problem is tight and `Lambda` is its optimal multiplier). The check is a 9x9 Cholesky
//! factorisation of `Q + eps I`; with `eps = CERT_EPS * trace(M)` the statement proven is
//! `f(R) >= f(A) - 3 eps` for all `R`. The column constraints `R^T R = I` give a second family
//! of multipliers; [`global_minimum`] tries a few ways of sharing the multiplier between rows
//! and columns, and a multiplier fitted to the problem by a 5-parameter least-squares problem
//! (`least_squares_multiplier`; any positive semidefinite `Q` is a proof). The fitted one
//! certifies most of the N = 4, 5 and quasi-singular minima that the fixed splits miss, which
//! turns their full search into the fast path.
//!
//! For planar scenes (working-frame points with z = 0) `f` depends only on the first two
//! columns `c1, c2` of `R`, through the 6x6 planar `M_p`; the analogous certificate uses the
//! column constraints `c_j . c_k = delta_jk` (the Stiefel manifold):
//! `Q_p = M_p - I3 (x) Gamma`, `Gamma` 2x2 symmetric, from `M_p r6(A) = (I3 (x) Gamma) r6(A)`.

use std::sync::OnceLock;

use nalgebra::{Matrix2, Matrix3, SMatrix, SVector};

/// Relative slack of the positive-semidefiniteness test (above the rounding level of the zero
/// eigenvalue of `Q` along `vec(A)`, ~1e-16 trace(M)).
const CERT_EPS: f64 = 1e-11;

/// Reweighted fits of [`least_squares_multiplier`] after the first. Global minima certified in
/// the test below (of 40, N = 4 / N = 5): 23 / 37 by the first fit, 29 / 40 after one
/// reweighting, no more after three.
const MULTIPLIER_REWEIGHTINGS: usize = 1;

/// Split points `alpha` tried by [`global_minimum`]: the multiplier `Lambda'` of the stationarity
/// condition is shared between the row constraints (`alpha Lambda'`) and the column constraints
/// (`(1 - alpha) A^T Lambda' A`). Rows alone certify most general scenes, columns alone most
/// planar ones; the mixed splits add a few percent (measured, 500 trials, sigma = 2: general
/// N = 6 379 -> 440 certified, quasi-singular N = 10 261 -> 297).
const SPLITS: [f64; 5] = [1.0, 0.0, 0.5, 0.9, 0.25];

/// Whether `f_a = f(A)` is certified as the global minimum of `f` over O(3) to the slack of
/// [`global_minimum`] by a bound on the spectrum: with no eigenvalue of `M` below `sigma`,
/// `f(R) >= 3 sigma` for every `R` (`|vec(R)|^2 = 3`), so `f_a <= 3 (sigma + eps)` proves
/// `f(R) >= f(A) - 3 eps`, the statement the dual certificate proves. It holds for exact and
/// nearly exact fits (`f(A)` at the rounding level, `sigma` from the factorisation of
/// `M + delta I`), where it spares the dual certificate's 9x9 factorisations.
pub(crate) fn below_spectral_bound(f_a: f64, sigma: f64, scale: f64) -> bool {
    f_a <= 3.0 * (sigma + CERT_EPS * scale)
}

/// Whether the rotation `a` is certified as a global minimum of `vec(R)^T M vec(R)` over O(3).
///
/// For every `R` with orthonormal rows and columns and any symmetric `Lambda`, `Gamma`:
/// `f(R) = vec(R)^T Q vec(R) + trace(Lambda) + trace(Gamma)`,
/// `Q = M - Lambda (x) I3 - I3 (x) Gamma`. With `Lambda' = sym(mat(M vec(A)) A^T)` (so that
/// `trace(Lambda') = f(A)`), `Lambda = alpha Lambda'` and `Gamma = (1 - alpha) A^T Lambda' A`,
/// `Q vec(A) = 0` at a stationary point and `Q >= 0` proves `f(R) >= f(A) - 3 eps`.
///
/// Tried in order: the row split (`alpha = 1`, enough for most general scenes), the column
/// split (`alpha = 0`, most planar ones), the least-squares multiplier of
/// [`least_squares_multiplier`] (most N = 4, 5 and quasi-singular minima), then the mixed
/// splits.
pub(crate) fn global_minimum(m: &SMatrix<f64, 9, 9>, a: &Matrix3<f64>, scale: f64) -> bool {
    let eps = CERT_EPS * scale;
    let (lam, lam_cols) = split_multipliers(m, a);
    let split = |alpha: f64| split_holds(m, &lam, &lam_cols, alpha, eps);
    SPLITS[..2].iter().any(|&x| split(x))
        || least_squares_multiplier(m, a, eps)
        || SPLITS[2..].iter().any(|&x| split(x))
}

/// `Lambda' = sym(mat(M vec(A)) A^T)` and `A^T Lambda' A`.
fn split_multipliers(m: &SMatrix<f64, 9, 9>, a: &Matrix3<f64>) -> (Matrix3<f64>, Matrix3<f64>) {
    let r = SVector::<f64, 9>::from_row_slice(a.transpose().as_slice());
    let u = m * r;
    let um = Matrix3::new(u[0], u[1], u[2], u[3], u[4], u[5], u[6], u[7], u[8]);
    let lam = um * a.transpose();
    let lam = (lam + lam.transpose()) * 0.5;
    (lam, a.transpose() * lam * a)
}

/// The certificate with the split `alpha` of the multiplier between rows and columns.
fn split_holds(
    m: &SMatrix<f64, 9, 9>,
    lam: &Matrix3<f64>,
    lam_cols: &Matrix3<f64>,
    alpha: f64,
    eps: f64,
) -> bool {
    psd_with_slack(m, &(lam * alpha), &(lam_cols * (1.0 - alpha)), eps)
}

/// `Lambda (x) I3 + I3 (x) Gamma` on row-major `vec(R)`: the quadratic form
/// `sum_jk Lambda_jk row_j . row_k + sum_jk Gamma_jk col_j . col_k`.
fn rows_cols(lam: &Matrix3<f64>, gamma: &Matrix3<f64>) -> SMatrix<f64, 9, 9> {
    let mut c = SMatrix::<f64, 9, 9>::zeros();
    for j in 0..3 {
        for k in 0..3 {
            for i in 0..3 {
                c[(3 * j + i, 3 * k + i)] += lam[(j, k)];
                c[(3 * i + j, 3 * i + k)] += gamma[(j, k)];
            }
        }
    }
    c
}

/// Whether `q - rows_cols(lam, gamma) + eps I` is positive definite (a Cholesky
/// factorisation exists), with its entries formed as the factorisation reads them (the same
/// values as the matrices formed one after the other, without forming them).
fn psd_with_slack(
    q: &SMatrix<f64, 9, 9>,
    lam: &Matrix3<f64>,
    gamma: &Matrix3<f64>,
    eps: f64,
) -> bool {
    crate::numeric::linalg::positive_definite::<9>(|p, r| {
        // Entry (p, r) of `rows_cols`: `Lambda` between equal columns, `Gamma` within a row.
        let (pa, pb, ra, rb) = (p / 3, p % 3, r / 3, r % 3);
        let mut c = 0.0;
        if pb == rb {
            c += lam[(pa, ra)];
        }
        if pa == ra {
            c += gamma[(pb, rb)];
        }
        (q[(p, r)] - c) + if p == r { eps } else { 0.0 }
    })
}

/// Orthonormal basis (Frobenius) of the 3x3 matrices orthogonal to `I`: five traceless
/// symmetric matrices `T_1..T_5`, then three skew ones `K_1..K_3`, each as a row-major 9-vector.
fn basis() -> [[f64; 9]; 8] {
    let h = core::f64::consts::FRAC_1_SQRT_2;
    let s6 = 1.0 / 6.0_f64.sqrt();
    [
        [0.0, h, 0.0, h, 0.0, 0.0, 0.0, 0.0, 0.0],
        [0.0, 0.0, h, 0.0, 0.0, 0.0, h, 0.0, 0.0],
        [0.0, 0.0, 0.0, 0.0, 0.0, h, 0.0, h, 0.0],
        [h, 0.0, 0.0, 0.0, -h, 0.0, 0.0, 0.0, 0.0],
        [s6, 0.0, 0.0, 0.0, s6, 0.0, 0.0, 0.0, -2.0 * s6],
        [0.0, 0.0, 0.0, 0.0, 0.0, h, 0.0, -h, 0.0],
        [0.0, 0.0, h, 0.0, 0.0, 0.0, -h, 0.0, 0.0],
        [0.0, h, 0.0, -h, 0.0, 0.0, 0.0, 0.0, 0.0],
    ]
}

/// The constants of [`least_squares_multiplier`], see [`coupling`].
struct Coupling {
    /// [`basis`] as the columns of a 9x8 matrix.
    basis: SMatrix<f64, 9, 8>,
    /// `T_1..T_5` as matrices.
    t: [Matrix3<f64>; 5],
    /// `C_1..C_5`.
    c: [SMatrix<f64, 3, 5>; 5],
}

/// The basis of [`basis`], its traceless symmetric matrices `T_p`, and the block `C_p` of
/// `ad(T_p) = T_p (x) I3 - I3 (x) T_p` in that basis (rows `K_1..K_3`, columns `T_1..T_5`):
/// constants, computed on first use.
fn coupling() -> &'static Coupling {
    static TABLE: OnceLock<Coupling> = OnceLock::new();
    TABLE.get_or_init(|| {
        let b = basis();
        let bm = SMatrix::<f64, 9, 8>::from_fn(|r, c| b[c][r]);
        let t: [Matrix3<f64>; 5] = core::array::from_fn(|p| Matrix3::from_row_slice(&b[p]));
        let c = core::array::from_fn(|p| {
            (bm.transpose() * rows_cols(&t[p], &-t[p]) * bm)
                .fixed_view::<3, 5>(5, 0)
                .into_owned()
        });
        Coupling { basis: bm, t, c }
    })
}

/// The certificate with a multiplier chosen for the problem instead of a fixed split.
///
/// In coordinates where `A = I` (`R' = R A^T`, `M' = (I3 (x) A) M (I3 (x) A^T)`, an orthogonal
/// congruence), the multipliers with `Q vec(I) = 0` are `Gamma = U - Lambda`, `U =
/// sym(mat(M' vec(I)))`, for any symmetric `Lambda`, so `Q(Lambda) = Q0 - ad(Lambda)` with
/// `Q0 = M' - I3 (x) U` and `ad(Lambda) X = Lambda X - X Lambda`. `ad(Lambda)` maps symmetric
/// matrices to skew ones and back, so in the basis of [`basis`] `Q(Lambda) = [[Q_tt, Q_kt^T -
/// C^T], [Q_kt - C, Q_kk]]` with `C` linear in the traceless part of `Lambda` (5 parameters).
/// `Q >= 0` needs `Q_tt > 0` and a positive semidefinite Schur complement
/// `Q_kk - (Q_kt - C) Q_tt^-1 (Q_kt - C)^T`; the `Lambda` that minimises the trace of the
/// subtracted term is a 5-parameter linear least-squares problem. Whatever the choice, the
/// Cholesky test of `Q(Lambda) + eps I` is the proof, exactly as for the splits.
fn least_squares_multiplier(m: &SMatrix<f64, 9, 9>, a: &Matrix3<f64>, eps: f64) -> bool {
    // M' block by block: M'_ik = A M_ik A^T.
    let mut mp = SMatrix::<f64, 9, 9>::zeros();
    for i in 0..3 {
        for k in 0..3 {
            let blk = a * m.fixed_view::<3, 3>(3 * i, 3 * k) * a.transpose();
            mp.fixed_view_mut::<3, 3>(3 * i, 3 * k).copy_from(&blk);
        }
    }
    // U = sym(mat(M' vec(I))): column j of mat is sum over the identity's entries 0, 4, 8.
    let mut um = Matrix3::zeros();
    for r in 0..9 {
        um[(r / 3, r % 3)] = mp[(r, 0)] + mp[(r, 4)] + mp[(r, 8)];
    }
    let um = (um + um.transpose()) * 0.5;
    let q0 = mp - rows_cols(&Matrix3::zeros(), &um);
    let cpl = coupling();
    let qb = cpl.basis.transpose() * q0 * cpl.basis;
    let qtt = qb.fixed_view::<5, 5>(0, 0) + SMatrix::<f64, 5, 5>::identity() * eps;
    let Some(l) = crate::numeric::linalg::cholesky(&qtt) else {
        return false; // Q_tt does not depend on Lambda: no multiplier of this family works
    };
    // Left: Q_kk + eps I = K K^T, so that the Schur condition reads ||F(Lambda)||_2 <= 1 with
    // F = K^-1 (Q_kt - C) L^-T.
    let qkk = qb.fixed_view::<3, 3>(5, 5) + Matrix3::identity() * eps;
    let Some(kf) = crate::numeric::linalg::cholesky(&qkk) else {
        return false; // Q_kk does not depend on Lambda either
    };
    // K^-1 X L^-T by two forward substitutions (the factors have positive diagonals).
    let whiten = |x: &SMatrix<f64, 3, 5>| {
        l.solve_lower_triangular(&x.transpose())
            .and_then(|y| kf.solve_lower_triangular(&y.transpose()))
            .unwrap_or_else(SMatrix::zeros)
    };
    let f0 = whiten(&qb.fixed_view::<3, 5>(5, 0).into_owned());
    let fa: [SMatrix<f64, 3, 5>; 5] = core::array::from_fn(|p| whiten(&cpl.c[p]));
    // Minimise ||W^1/2 F(x)||_F, first with W = I, then (one reweighting, the iteratively
    // reweighted least squares step towards the spectral norm) with W = F F^T of the first fit.
    let mut w_half = Matrix3::identity();
    for round in 0..=MULTIPLIER_REWEIGHTINGS {
        let wf0 = w_half * f0;
        let wfa: [SMatrix<f64, 3, 5>; 5] = core::array::from_fn(|p| w_half * fa[p]);
        let mut g = SMatrix::<f64, 5, 5>::zeros();
        let mut rhs = SVector::<f64, 5>::zeros();
        for p in 0..5 {
            rhs[p] = wfa[p].dot(&wf0);
            for q in 0..5 {
                g[(p, q)] = wfa[p].dot(&wfa[q]);
            }
        }
        let Some(x) = g.cholesky().map(|c| c.solve(&rhs)) else {
            return false;
        };
        let lam = (0..5).fold(Matrix3::zeros(), |acc, p| acc + cpl.t[p] * x[p]);
        if psd_with_slack(&q0, &lam, &-lam, eps) {
            return true;
        }
        if round == MULTIPLIER_REWEIGHTINGS {
            break;
        }
        let f = (0..5).fold(f0, |acc, p| acc - fa[p] * x[p]);
        let ff = f * f.transpose();
        let w = ff + Matrix3::identity() * (1e-12 * ff.trace());
        // tr(W F F^T) = ||L_W^T F||_F^2 with W = L_W L_W^T.
        let Some(lw) = crate::numeric::linalg::cholesky(&w) else {
            return false;
        };
        w_half = lw.transpose();
    }
    false
}

/// Planar certificate: `a`'s first two columns are a global minimum of the planar cost
/// `r6^T M_p r6` over orthonormal 2-frames (`m9` is the flattened system's 9x9 M).
pub(crate) fn global_minimum_planar(m9: &SMatrix<f64, 9, 9>, a: &Matrix3<f64>, scale: f64) -> bool {
    const IDX: [usize; 6] = [0, 1, 3, 4, 6, 7];
    let mp = SMatrix::<f64, 6, 6>::from_fn(|i, j| m9[(IDX[i], IDX[j])]);
    // r6 = [R11, R12, R21, R22, R31, R32]: row i of R contributes (R_i1, R_i2).
    let r6 = SVector::<f64, 6>::from_fn(|k, _| a[(k / 2, k % 2)]);
    let u = mp * r6;
    // Row i: (u_{2i}, u_{2i+1}) = Gamma (R_i1, R_i2)  =>  Gamma = U^T C (C^T C = I2), U, C 3x2.
    let mut gamma = Matrix2::zeros();
    for i in 0..3 {
        for j in 0..2 {
            for k in 0..2 {
                gamma[(j, k)] += u[2 * i + j] * a[(i, k)];
            }
        }
    }
    let gamma = (gamma + gamma.transpose()) * 0.5;
    let mut q = mp;
    for i in 0..3 {
        for j in 0..2 {
            for k in 0..2 {
                q[(2 * i + j, 2 * i + k)] -= gamma[(j, k)];
            }
        }
    }
    let eps = CERT_EPS * scale;
    for i in 0..6 {
        q[(i, i)] += eps;
    }
    crate::numeric::linalg::cholesky(&q).is_some()
}

#[cfg(test)]
#[path = "../../tests/unit/pipeline/certificate.rs"]
mod tests;
