//! Robust estimation: the Lambda Twist P3P minimal solver ([`p3p`]) and RANSAC with EOPnP local
//! optimisation and final fit ([`ransac`]), with an adapter for rust-cv's consensus algorithms
//! (`ransac::consensus`, feature `sample-consensus`).

/// The P3P solver lives in `numeric` (the solver's small-N search uses it too); this is its
/// public path.
pub use crate::numeric::p3p;
pub mod ransac;
