//! The upright two-point pose (`up2p_quadratic` and the solver built on it): the checks of
//! `eopnp_verify::checks` (the quadratic against the 4 x 4 determinant by LU, the true rotation
//! as a root, the solver's poses on their rays and as many as a scan of the determinant finds),
//! each asserted to pass.

use eopnp_verify::checks::{up2p_determinant, up2p_known_root, up2p_solutions, N_UP2P};

#[test]
fn quadratic_matches_the_numeric_determinant() {
    let m = up2p_determinant(N_UP2P);
    println!("{m:?}");
    m.assert_ok();
}

#[test]
fn true_rotation_is_a_root() {
    let m = up2p_known_root(N_UP2P);
    println!("{m:?}");
    m.assert_ok();
}

#[test]
fn solutions_are_on_their_rays_and_complete() {
    let m = up2p_solutions(N_UP2P);
    println!("{m:?}");
    m.assert_ok();
}
