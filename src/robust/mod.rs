//! Robust estimation: the Lambda Twist P3P minimal solver ([`p3p`]) and RANSAC with EOPnP local
//! optimisation and final fit ([`ransac`]), with an adapter for rust-cv's consensus algorithms
//! (`ransac::consensus`, feature `sample-consensus`).

pub mod p3p;
pub mod ransac;
