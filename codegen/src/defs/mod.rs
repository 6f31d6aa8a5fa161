//! Kernel definitions: each polynomial is defined once here and everything else is derived.

pub mod cost;
pub mod resultant;
