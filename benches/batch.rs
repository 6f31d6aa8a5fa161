//! Batch throughput (feature `rayon`): 10,000 problems of N = 100 (general scene, default
//! mode) solved by `Solver::solve_batch` on rayon pools of 1 and 2 threads. The ratio of the
//! two medians is the parallel speed-up (issue target: >= 1.8 on 2 threads).
//!
//! `cargo bench --features rayon --bench batch`

use eopnp_testkit as common;
mod support;

use common::Scene;
use criterion::{black_box, criterion_group, criterion_main, BenchmarkId, Criterion};
use eopnp::Problem;
use eopnp::Solver;
use support::{config, problems};

fn batch(c: &mut Criterion) {
    let set = problems(Scene::General, 100, 10_000);
    let batch: Vec<Problem> = set
        .iter()
        .map(|p| Problem::normalised(&p.world, &p.image))
        .collect();
    let solver = Solver::default();
    let mut group = c.benchmark_group("batch/general/default/N=100 x 10000");
    group.sample_size(10);
    for threads in [1usize, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        group.bench_with_input(BenchmarkId::new("threads", threads), &batch, |b, batch| {
            b.iter(|| pool.install(|| black_box(solver.solve_batch(black_box(batch)))));
        });
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = config();
    targets = batch
}
criterion_main!(benches);
