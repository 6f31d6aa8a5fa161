//! Numerical building blocks, each with hard iteration bounds and no allocation: the bounds
//! themselves, small dense linear algebra (3 x 3 in [`mat3`], 9 x 9 in [`linalg`]), real
//! polynomial roots, rotations, the P3P minimal solver, the generalized three-point, the
//! upright two-point and the four-point unknown-focal minimal solvers, an arctangent and a tangent that pack ([`trig`]),
//! and the lane layout of the vectorised O(N) passes. Nothing here knows about the PnP problem's stages.

pub(crate) mod bounds;
#[cfg_attr(not(feature = "internals"), allow(dead_code))]
pub(crate) mod gp3p;
pub(crate) mod lanes;
pub(crate) mod linalg;
pub(crate) mod mat3;
pub mod p3p;
// The minimal solver with an unknown focal length (checked by `verify/`).
#[cfg_attr(not(feature = "internals"), allow(dead_code))]
pub(crate) mod p4pf;
#[cfg_attr(not(feature = "internals"), allow(dead_code))]
pub(crate) mod roots;
pub(crate) mod rotation;
pub(crate) mod trig;
// The minimal solver with a known vertical (checked by `verify/`).
#[cfg_attr(not(feature = "internals"), allow(dead_code))]
pub(crate) mod up2p;
