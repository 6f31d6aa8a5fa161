//! Check 4: the resultant kernels of cases 2, 3, 4 (docs/algorithm.md, `nullspace` cases 2-4,
//! G4-G7).
//!
//! - Against nalgebra's determinant of the numerically built matrix (6 x 6 Sylvester matrix of eq.
//!   22 for cases 2, 3, written from the cubic formulas of `nullspace` cases 2 and 3; `M(k1)` for
//!   case 4) at random hidden values. Determinants are ill-conditioned, so the bound is derived per
//!   sample (`eopnp_verify::checks::resultant_vs_sylvester` and `case4_determinant`): kernel
//!   rounding `gamma_64` times the permanent of the absolute-value Bezout / entry matrix, plus the
//!   rounding of the numeric entries, plus nalgebra's LU error (a-posteriori, Higham Thm 9.3 with
//!   Hadamard-bounded cofactors). Errors are reported relative to Hadamard's bound.
//! - Known roots: exactly representable systems with a built-in common root, where the exact
//!   resultant vanishes, so the only error is the kernel's rounding. The resultant at the root
//!   and the cubics (case 4: `M(k1*) y* = 0`) at it are two measurements, each asserted.
//! - The cubic / quartic / matrix kernels against the formulas of docs/algorithm.md (1e-12 of the
//!   absolute-value scale, as for the cost).

use eopnp::internals::kernels as k;
use eopnp_verify::checks::{self, N_RESULTANT};
use eopnp_verify::reference as rf;

#[test]
fn case2_resultant_vs_sylvester_determinant() {
    checks::case2_resultant(N_RESULTANT).assert_ok();
}

#[test]
fn case2_known_root() {
    for m in checks::case2_known_root(N_RESULTANT) {
        m.assert_ok();
    }
}

#[test]
fn case2_cubics_vs_formulas() {
    checks::case2_cubics(N_RESULTANT).assert_ok();
}

#[test]
fn case3_quartic_vs_quadratic_form() {
    checks::case3_quartic(N_RESULTANT).assert_ok();
}

#[test]
fn case3_resultant_vs_sylvester_determinant() {
    checks::case3_resultant(N_RESULTANT).assert_ok();
}

#[test]
fn case3_known_root() {
    for m in checks::case3_known_root(N_RESULTANT) {
        m.assert_ok();
    }
}

#[test]
fn case3_cubics_vs_formulas() {
    checks::case3_cubics(N_RESULTANT).assert_ok();
}

#[test]
fn case4_matrix_vs_formulas() {
    checks::case4_matrix(N_RESULTANT).assert_ok();
}

#[test]
fn case4_determinant_vs_lu_determinant() {
    checks::case4_determinant(N_RESULTANT).assert_ok();
}

#[test]
fn case4_known_root() {
    for m in checks::case4_known_root(N_RESULTANT) {
        m.assert_ok();
    }
}

/// The input tables agree with my own enumeration of docs/algorithm.md G5 / G6.
#[test]
fn layouts_match_algorithm_md() {
    assert_eq!(rf::case3_monomials().as_slice(), &k::CASE3_MONOMIALS[..]);
    assert_eq!(rf::case4_layout().as_slice(), &k::CASE4_T_LAYOUT[..]);
}

/// The Bezout determinant (G7) is minus the Sylvester determinant, and `case2_resultant`
/// carries the Sylvester sign: checked on one exactly representable example (integer cubics).
#[test]
fn bezout_is_minus_sylvester() {
    let p = [3.0, -2.0, 5.0, 1.0];
    let q = [-1.0, 4.0, 2.0, -3.0];
    let syl = rf::sylvester(&p, &q).determinant();
    let bez = rf::bezout(&p, &q).determinant();
    assert!(
        (syl + bez).abs() <= 1e-12 * syl.abs().max(1.0),
        "syl {syl} bez {bez}"
    );
}
