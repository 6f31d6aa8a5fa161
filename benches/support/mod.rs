#![allow(dead_code)]
//! Shared setup of the criterion benches: fixed-seed problem sets, generated outside the timed
//! closures with the test suite's generator (`testkit/`, the crate `eopnp-testkit`, same protocol).

use crate::common::{Problem, ProblemOptions, RotationKind, Scene};
use criterion::Criterion;
use std::time::Duration;

/// Seed of every bench problem set (independent of `EOPNP_TEST_SEED`).
pub const BENCH_SEED: u64 = 0xBE4C_2019;

/// Problems per set: the timed closure cycles through them so that branch predictors and
/// caches do not learn one input (glam-style).
pub fn set_size(n: usize) -> usize {
    match n {
        0..=100 => 64,
        101..=1000 => 32,
        _ => 8,
    }
}

/// `count` problems of the paper protocol (sigma = 2 px, Haar-uniform rotation) for one scene
/// and N, from a fixed seed.
pub fn problems(scene: Scene, n: usize, count: usize) -> Vec<Problem> {
    (0..count as u64)
        .map(|i| {
            let seed = crate::common::splitmix64(
                BENCH_SEED ^ crate::common::splitmix64((n as u64) << 8 ^ scene as u64 ^ i << 32),
            );
            Problem::generate(&ProblemOptions {
                n,
                sigma_px: 2.0,
                scene,
                rotation: RotationKind::Uniform,
                seed,
            })
        })
        .collect()
}

/// Criterion settings that keep `cargo bench` (all three benches) well under 10 minutes on
/// two cores: 30 samples, 2 s of measurement, 1 s of warm-up per benchmark.
pub fn config() -> Criterion {
    Criterion::default()
        .sample_size(30)
        .measurement_time(Duration::from_secs(2))
        .warm_up_time(Duration::from_secs(1))
}
