//! Full solves: N = 4 ... 10000, general and planar scenes, default (reprojection) and
//! algebraic refinement. Each benchmark cycles through a fixed, pre-generated problem set.

use eopnp_testkit as common;
mod support;

use common::Scene;
use criterion::{black_box, criterion_group, criterion_main, BenchmarkId, Criterion};
use eopnp::{Refinement, Solver};
use support::{config, problems, set_size};

const NS: [usize; 8] = [4, 6, 10, 20, 50, 100, 1000, 10000];

fn full_solve(c: &mut Criterion) {
    for (scene, scene_name) in [(Scene::General, "general"), (Scene::Planar, "planar")] {
        let sets: Vec<_> = NS
            .iter()
            .map(|&n| (n, problems(scene, n, set_size(n))))
            .collect();
        for (mode, mode_name) in [
            (Refinement::Reprojection, "default"),
            (Refinement::Algebraic, "algebraic"),
        ] {
            let solver = Solver::default().refinement(mode);
            let mut group = c.benchmark_group(format!("solve/{scene_name}/{mode_name}"));
            for (n, set) in &sets {
                group.bench_with_input(BenchmarkId::from_parameter(n), set, |b, set| {
                    let mut i = 0usize;
                    b.iter(|| {
                        let p = &set[i % set.len()];
                        i = i.wrapping_add(1);
                        black_box(solver.solve(black_box(&p.world), black_box(&p.image)))
                    });
                });
            }
            group.finish();
        }
    }
}

criterion_group! {
    name = benches;
    config = config();
    targets = full_solve
}
criterion_main!(benches);
