//! Full solves: N = 4 ... 10000, general and planar scenes, default (reprojection) and
//! algebraic refinement; `Solver::refine` from a nearby prior (N = 10, 100, 1000). Each
//! benchmark cycles through a fixed, pre-generated problem set.

use eopnp::Problem;
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
                        black_box(solver.solve(&Problem::normalised(
                            black_box(&p.world),
                            black_box(&p.image),
                        )))
                    });
                });
            }
            group.finish();
        }
    }
}

/// `Solver::refine` from a prior 2 degrees and 3 % of the distance off the truth (tracking),
/// against the full solve of the same problems (`solve/general/default`).
fn refine_from_prior(c: &mut Criterion) {
    use nalgebra::{Isometry3, Rotation3, Translation3, UnitQuaternion, Vector3};
    let solver = Solver::default();
    let mut group = c.benchmark_group("refine/general");
    for &n in &[10usize, 100, 1000] {
        let set = problems(Scene::General, n, set_size(n));
        let priors: Vec<Isometry3<f64>> = set
            .iter()
            .map(|p| {
                let w = Vector3::new(1.0, -1.0, 0.5).normalize() * 2f64.to_radians();
                let r = common::exp_so3(&w) * p.r_gt;
                Isometry3::from_parts(
                    Translation3::from(p.t_gt * 1.03),
                    UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(r)),
                )
            })
            .collect();
        group.bench_with_input(BenchmarkId::from_parameter(n), &set, |b, set| {
            let mut i = 0usize;
            b.iter(|| {
                let k = i % set.len();
                i = i.wrapping_add(1);
                let p = &set[k];
                black_box(solver.refine(
                    &Problem::normalised(black_box(&p.world), black_box(&p.image)),
                    &priors[k],
                ))
            });
        });
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = config();
    targets = full_solve, refine_from_prior
}
criterion_main!(benches);
