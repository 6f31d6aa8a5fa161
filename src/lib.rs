//! eopnp (work in progress)
#![warn(missing_docs)]

pub mod kernels;
