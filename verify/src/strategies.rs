//! Random inputs spanning scales: seeded samplers (`rand_pcg::Pcg64`, shared by the tests and
//! the report) and proptest strategies (nalgebra's `tests/proptest` style).
//!
//! - CGR parameters `s`: log-uniform magnitude in [1e-3, 1e3], uniform direction; 2 % exactly
//!   zero, 10 % with one or two components set to exactly zero.
//! - Cost matrices `M`: half `K^T K` (positive semidefinite, as in the solver) with `K` 12 x 9
//!   and entries `N(0, 1) 10^U(-3, 3)` (six decades), half symmetric indefinite with entries of
//!   the same spread; all multiplied by a global `10^U(-3, 3)`.
//! - Rotations: Haar-uniform (normalised 4-D Gaussian quaternion), plus exact 180 deg rotations
//!   `2 a a^T - I` and the exact axis flips `diag(1, -1, -1)` etc.

use crate::reference::M9;
use nalgebra::{Matrix3, Quaternion, SMatrix, UnitQuaternion, Vector3};
use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

/// The seeded generator used by every sampling loop.
#[must_use]
pub fn rng(seed: u64) -> Pcg64 {
    Pcg64::seed_from_u64(seed)
}

/// Standard normal (Box-Muller).
pub fn normal(rng: &mut Pcg64) -> f64 {
    let u1: f64 = 1.0 - rng.random::<f64>(); // (0, 1]
    let u2: f64 = rng.random::<f64>();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// `10^U(lo, hi)`.
pub fn log_uniform(rng: &mut Pcg64, lo: f64, hi: f64) -> f64 {
    10f64.powf(rng.random_range(lo..hi))
}

/// Uniform unit vector.
pub fn unit_vector(rng: &mut Pcg64) -> Vector3<f64> {
    loop {
        let v = Vector3::new(normal(rng), normal(rng), normal(rng));
        let n = v.norm();
        if n > 1e-6 {
            return v / n;
        }
    }
}

/// CGR parameters spanning scales (see the module doc).
pub fn cgr(rng: &mut Pcg64) -> [f64; 3] {
    let kind = rng.random_range(0..100);
    if kind < 2 {
        return [0.0; 3];
    }
    let v = unit_vector(rng) * log_uniform(rng, -3.0, 3.0);
    let mut s = [v[0], v[1], v[2]];
    if kind < 12 {
        let keep = rng.random_range(0..3);
        for (i, si) in s.iter_mut().enumerate() {
            if i != keep && rng.random_bool(0.7) {
                *si = 0.0;
            }
        }
    }
    s
}

/// Symmetric cost matrix spanning scales (see the module doc).
pub fn cost_matrix(rng: &mut Pcg64) -> M9 {
    let global = log_uniform(rng, -3.0, 3.0);
    let mut m = if rng.random_bool(0.5) {
        let k = SMatrix::<f64, 12, 9>::from_fn(|_, _| normal(rng) * log_uniform(rng, -3.0, 3.0));
        k.transpose() * k
    } else {
        M9::from_fn(|_, _| normal(rng) * log_uniform(rng, -3.0, 3.0))
    };
    for i in 0..9 {
        for j in 0..i {
            m[(i, j)] = m[(j, i)];
        }
    }
    m * global
}

/// Rotation: 80 % Haar-uniform, 15 % exactly 180 deg about a random axis (`2 a a^T - I`), 5 %
/// an exact axis flip or the identity.
pub fn rotation(rng: &mut Pcg64) -> Matrix3<f64> {
    let kind = rng.random_range(0..100);
    if kind < 80 {
        let q = Quaternion::new(normal(rng), normal(rng), normal(rng), normal(rng));
        UnitQuaternion::from_quaternion(q)
            .to_rotation_matrix()
            .into_inner()
    } else if kind < 95 {
        let a = unit_vector(rng);
        2.0 * a * a.transpose() - Matrix3::identity()
    } else {
        let d = [
            [1.0, 1.0, 1.0],
            [1.0, -1.0, -1.0],
            [-1.0, 1.0, -1.0],
            [-1.0, -1.0, 1.0],
        ][rng.random_range(0..4)];
        Matrix3::from_diagonal(&Vector3::new(d[0], d[1], d[2]))
    }
}

/// Random integer in `[-k, k]` as f64.
pub fn small_int(rng: &mut Pcg64, k: i32) -> f64 {
    f64::from(rng.random_range(-k..=k))
}

/// Random non-zero dyadic `n / 16`, `1 <= |n| <= 40` (exact in every product formed by the
/// known-root constructions).
pub fn dyadic(rng: &mut Pcg64) -> f64 {
    let n = rng.random_range(1..=40);
    let s = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
    s * f64::from(n) / 16.0
}

// ----------------------------------------------------------------------------------------------
// proptest strategies

/// The seed of every proptest property of the verification tests.
pub const PROPTEST_SEED: u64 = 0x0E0F_2019_5EED;

/// proptest's configuration for the verification tests: the cases are drawn from a fixed seed
/// ([`PROPTEST_SEED`]), so that a failure reproduces on every run and machine (the environment
/// variable `PROPTEST_RNG_SEED=<u64>` draws another sequence), and a failure is persisted in
/// `verify/tests/<test file>.proptest-regressions` (committed: replayed first on every run).
#[must_use]
pub fn proptest_config() -> ProptestConfig {
    ProptestConfig {
        rng_seed: proptest::test_runner::RngSeed::Fixed(PROPTEST_SEED),
        failure_persistence: Some(Box::new(
            proptest::test_runner::FileFailurePersistence::WithSource("proptest-regressions"),
        )),
        ..ProptestConfig::default()
    }
}

/// CGR parameters: magnitude `10^e`, `e` in [-3, 3], direction from a box (then normalised).
pub fn cgr_strategy() -> impl Strategy<Value = [f64; 3]> {
    (-3.0f64..3.0, [-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0]).prop_map(|(e, d)| {
        let v = Vector3::new(d[0], d[1], d[2]);
        let n = v.norm();
        if n < 1e-9 {
            [0.0; 3]
        } else {
            let v = v / n * 10f64.powf(e);
            [v[0], v[1], v[2]]
        }
    })
}

/// `M = K^T K`, `K` 9 x 9 with entries `x 10^e`, `x` in [-1, 1], `e` in [-3, 3].
pub fn psd_matrix_strategy() -> impl Strategy<Value = M9> {
    proptest::collection::vec((-1.0f64..1.0, -3.0f64..3.0), 81).prop_map(|v| {
        let k = M9::from_fn(|i, j| {
            let (x, e) = v[9 * i + j];
            x * 10f64.powf(e)
        });
        let mut m = k.transpose() * k;
        for i in 0..9 {
            for j in 0..i {
                m[(i, j)] = m[(j, i)];
            }
        }
        m
    })
}

/// Rotation from a unit quaternion drawn from a box (then normalised).
pub fn rotation_strategy() -> impl Strategy<Value = Matrix3<f64>> {
    [-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0].prop_map(|q| {
        let q = Quaternion::new(q[0], q[1], q[2], q[3]);
        if q.norm() < 1e-6 {
            Matrix3::identity()
        } else {
            UnitQuaternion::from_quaternion(q)
                .to_rotation_matrix()
                .into_inner()
        }
    })
}
