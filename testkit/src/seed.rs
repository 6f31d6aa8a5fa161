//! Seeds and the RNG: the suite seed, trial seeds, and the Gaussian draws of the generator.

use nalgebra::Vector3;
use rand::{Rng, SeedableRng};
use rand_distr::StandardNormal;
use rand_pcg::Pcg64;

use crate::DEFAULT_SUITE_SEED;

/// The suite seed: `EOPNP_TEST_SEED` (decimal or 0x-hex) or [`DEFAULT_SUITE_SEED`].
pub fn suite_seed() -> u64 {
    std::env::var("EOPNP_TEST_SEED")
        .ok()
        .and_then(|s| {
            let s = s.trim();
            match s.strip_prefix("0x") {
                Some(h) => u64::from_str_radix(h, 16).ok(),
                None => s.parse().ok(),
            }
        })
        .unwrap_or(DEFAULT_SUITE_SEED)
}

/// SplitMix64 finaliser (a bijective 64-bit mixer).
pub fn splitmix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// FNV-1a hash of a test name (stable across Rust versions, unlike `DefaultHasher`).
pub fn name_hash(name: &str) -> u64 {
    name.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// The seed of trial `trial` of test `name`: a function of (suite seed, name, trial) only.
pub fn trial_seed(name: &str, trial: u64) -> u64 {
    splitmix64(suite_seed() ^ splitmix64(name_hash(name) ^ splitmix64(trial)))
}

/// The RNG of one trial.
pub fn rng_from_seed(seed: u64) -> Pcg64 {
    Pcg64::seed_from_u64(seed)
}

/// A standard normal number.
pub fn gauss(rng: &mut Pcg64) -> f64 {
    rng.sample(StandardNormal)
}

/// A standard normal 3-vector.
pub fn gauss3(rng: &mut Pcg64) -> Vector3<f64> {
    Vector3::new(gauss(rng), gauss(rng), gauss(rng))
}

/// A uniformly distributed unit vector.
pub fn unit_vector(rng: &mut Pcg64) -> Vector3<f64> {
    loop {
        let v = gauss3(rng);
        let n = v.norm();
        if n > 1e-12 {
            return v / n;
        }
    }
}
