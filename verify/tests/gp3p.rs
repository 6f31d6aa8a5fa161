//! The generalized three-point pose (`gp3p_elimination` and the solver built on it): the
//! checks of `eopnp_verify::checks` (the octic against a numeric resultant computed another
//! way, the true depths as roots, the solver's poses on their rays and as many as an
//! independent root count says), each asserted to pass.

use eopnp_verify::checks::{gp3p_known_root, gp3p_octic, gp3p_solutions, N_GP3P};

#[test]
fn octic_matches_the_numeric_resultant() {
    let m = gp3p_octic(N_GP3P);
    println!("{m:?}");
    m.assert_ok();
}

#[test]
fn true_depths_are_roots() {
    let m = gp3p_known_root(N_GP3P);
    println!("{m:?}");
    m.assert_ok();
}

#[test]
fn solutions_are_on_their_rays_and_complete() {
    let m = gp3p_solutions(N_GP3P);
    println!("{m:?}");
    m.assert_ok();
}
