//! The four-point pose with unknown focal length (`p4pf_quadrics`, `e3q3_octic` and the solvers
//! built on them): the checks of `eopnp_verify::checks` (the quadrics against the numeric Gram
//! matrix, the octic against the LU determinant of its matrix, a planted solution as a root,
//! the three-quadric solver against the companion matrix's count, the true pose and focal
//! length among P4Pf's solutions), each asserted to pass.

use eopnp_verify::checks::{
    e3q3_determinant, e3q3_known_root, e3q3_solutions, p4pf_quadrics, p4pf_solutions, N_P4PF,
};

#[test]
fn quadrics_match_the_numeric_gram_matrix() {
    let m = p4pf_quadrics(N_P4PF);
    println!("{m:?}");
    m.assert_ok();
}

#[test]
fn octic_matches_the_determinant_of_its_matrix() {
    let m = e3q3_determinant(N_P4PF);
    println!("{m:?}");
    m.assert_ok();
}

#[test]
fn planted_solution_is_a_root_and_a_null_vector() {
    let m = e3q3_known_root(N_P4PF);
    println!("{m:?}");
    m.assert_ok();
}

#[test]
fn three_quadric_solutions_are_complete() {
    let m = e3q3_solutions(N_P4PF);
    println!("{m:?}");
    m.assert_ok();
}

#[test]
fn true_pose_and_focal_length_are_found() {
    let m = p4pf_solutions(N_P4PF);
    println!("{m:?}");
    m.assert_ok();
}
