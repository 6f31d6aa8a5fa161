//! Every generated kernel of `eopnp::internals::kernels`. Inputs: M (and the planar restriction of M, and
//! the cost coefficients) from real problems of the paper protocol; the case-2/3/4 inputs are
//! fixed pseudo-random numbers in [-1, 1] (the kernels are straight-line code, so their time
//! does not depend on the values). 64 inputs per kernel, cycled inside the timed closure.

use eopnp_testkit as common;
mod support;

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use eopnp::internals::kernels;
use rand::{Rng, SeedableRng};
use support::config;

const SETS: usize = 64;

fn uniform<const K: usize>(rng: &mut rand_pcg::Pcg64) -> [f64; K] {
    std::array::from_fn(|_| rng.random_range(-1.0..1.0))
}

/// Times `f` on each input in turn.
macro_rules! bench_kernel {
    ($c:expr, $name:literal, $inputs:expr, |$x:ident| $call:expr) => {{
        let inputs = &$inputs;
        let mut i = 0usize;
        $c.bench_function(concat!("kernel/", $name), |b| {
            b.iter(|| {
                let $x = black_box(&inputs[i % inputs.len()]);
                i = i.wrapping_add(1);
                black_box($call)
            })
        });
    }};
}

fn kernels_bench(c: &mut Criterion) {
    const PLANAR: [usize; 6] = [0, 1, 3, 4, 6, 7];
    // M of real problems: the normal matrix `K^T K` of `moments` in the working frame is a 9 x 9
    // positive semidefinite matrix; the kernels' cost does not depend on its values, so a
    // seeded random `A^T A` (A: 12 x 9) stands in for it.
    let mut state = 0x2545_F491_4F6C_DD1Du64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    let ms: Vec<nalgebra::SMatrix<f64, 9, 9>> = (0..SETS)
        .map(|_| {
            let a = nalgebra::SMatrix::<f64, 12, 9>::from_fn(|_, _| next());
            a.transpose() * a
        })
        .collect();
    let m45: Vec<[f64; 45]> = ms
        .iter()
        .map(|m| {
            let mut out = [0.0; 45];
            let mut k = 0;
            for i in 0..9 {
                for j in i..9 {
                    out[k] = m[(i, j)];
                    k += 1;
                }
            }
            out
        })
        .collect();
    let m21: Vec<[f64; 21]> = ms
        .iter()
        .map(|m| {
            let mut out = [0.0; 21];
            let mut k = 0;
            for i in 0..6 {
                for j in i..6 {
                    out[k] = m[(PLANAR[i], PLANAR[j])];
                    k += 1;
                }
            }
            out
        })
        .collect();
    let c35: Vec<[f64; 35]> = m45.iter().map(kernels::cost_coefficients).collect();
    let mut rng = rand_pcg::Pcg64::seed_from_u64(support::BENCH_SEED);
    let s3: Vec<[f64; 3]> = (0..SETS).map(|_| uniform(&mut rng)).collect();
    let with_s = |v: &[[f64; 35]]| -> Vec<([f64; 35], [f64; 3])> {
        v.iter().zip(&s3).map(|(a, s)| (*a, *s)).collect()
    };
    let c35s = with_s(&c35);
    let m21s: Vec<([f64; 21], [f64; 3])> = m21.iter().zip(&s3).map(|(a, s)| (*a, *s)).collect();
    let rots: Vec<([f64; 45], [f64; 9])> = m45
        .iter()
        .map(|m| {
            let q = nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            ));
            let r = q.to_rotation_matrix().into_inner();
            let r9 = std::array::from_fn(|k| r[(k / 3, k % 3)]);
            (*m, r9)
        })
        .collect();
    let case2: Vec<([f64; 6], [f64; 3], f64)> = (0..SETS)
        .map(|_| {
            (
                uniform(&mut rng),
                uniform(&mut rng),
                rng.random_range(0.1..1.0),
            )
        })
        .collect();
    let h21: Vec<[f64; 21]> = (0..SETS).map(|_| uniform(&mut rng)).collect();
    let c15: Vec<[f64; 15]> = h21.iter().map(kernels::case3_quartic).collect();
    let c15y: Vec<([f64; 15], f64)> = c15
        .iter()
        .map(|c| (*c, rng.random_range(-1.0..1.0)))
        .collect();
    let t21: Vec<[f64; 21]> = (0..SETS).map(|_| uniform(&mut rng)).collect();

    bench_kernel!(c, "cost_coefficients", m45, |x| kernels::cost_coefficients(
        x
    ));
    bench_kernel!(c, "cost", c35s, |x| kernels::cost(&x.0, &x.1));
    bench_kernel!(c, "cost_gradient", c35s, |x| kernels::cost_gradient(
        &x.0, &x.1
    ));
    bench_kernel!(c, "cost_hessian", c35s, |x| kernels::cost_hessian(
        &x.0, &x.1
    ));
    bench_kernel!(c, "planar_cost_coefficients", m21, |x| {
        kernels::planar_cost_coefficients(x)
    });
    bench_kernel!(c, "planar_cost_gradient", m21s, |x| {
        kernels::planar_cost_gradient(&x.0, &x.1)
    });
    bench_kernel!(c, "planar_cost_hessian", m21s, |x| {
        kernels::planar_cost_hessian(&x.0, &x.1)
    });
    bench_kernel!(c, "so3_local_model", rots, |x| kernels::so3_local_model(
        &x.0, &x.1
    ));
    bench_kernel!(c, "case2_resultant", case2, |x| kernels::case2_resultant(
        &x.0, &x.1
    ));
    bench_kernel!(c, "case2_cubics", case2, |x| kernels::case2_cubics(
        &x.0, &x.1, x.2
    ));
    bench_kernel!(c, "case3_quartic", h21, |x| kernels::case3_quartic(x));
    bench_kernel!(c, "case3_resultant", c15, |x| kernels::case3_resultant(x));
    bench_kernel!(c, "case3_cubics", c15y, |x| kernels::case3_cubics(
        &x.0, x.1
    ));
    bench_kernel!(c, "case4_matrix", t21, |x| kernels::case4_matrix(x));
    bench_kernel!(c, "case4_determinant", t21, |x| kernels::case4_determinant(
        x
    ));
    // Camera distortion: a normalised point in [-1, 1]^2 and small coefficients.
    let mut rng = rand_pcg::Pcg64::seed_from_u64(0x00CA_3E2A);
    let cam: Vec<([f64; 2], [f64; 12])> = (0..SETS)
        .map(|_| {
            let k: [f64; 12] = uniform(&mut rng);
            (uniform(&mut rng), k.map(|x| 0.1 * x))
        })
        .collect();
    let first = |k: &[f64; 12]| -> [f64; 4] { std::array::from_fn(|i| k[i]) };
    bench_kernel!(c, "distortion_simple_radial", cam, |x| {
        kernels::distortion_simple_radial(&x.0, &[x.1[0]])
    });
    bench_kernel!(c, "distortion_radial", cam, |x| {
        kernels::distortion_radial(&x.0, &[x.1[0], x.1[1]])
    });
    bench_kernel!(c, "distortion_opencv", cam, |x| {
        kernels::distortion_opencv(&x.0, &first(&x.1))
    });
    bench_kernel!(c, "distortion_fisheye", cam, |x| {
        kernels::distortion_fisheye(&x.0, &first(&x.1))
    });
    bench_kernel!(c, "distortion_full_opencv", cam, |x| {
        kernels::distortion_full_opencv(&x.0, &std::array::from_fn(|i| x.1[i]))
    });
    bench_kernel!(c, "distortion_thin_prism", cam, |x| {
        kernels::distortion_thin_prism(&x.0, &x.1)
    });
}

criterion_group! {
    name = benches;
    config = config();
    targets = kernels_bench
}
criterion_main!(benches);
