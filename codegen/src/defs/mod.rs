//! Kernel definitions: each polynomial is defined once here and everything else is derived.

pub mod camera;
pub mod cost;
pub mod gp3p;
pub mod p4pf;
pub mod resultant;
pub mod up2p;
