//! Every stage on its own, through the `eopnp::bench_hooks` wrappers, which exist only when the
//! library is compiled with `--cfg eopnp_bench`:
//!
//! ```sh
//! RUSTFLAGS="--cfg eopnp_bench" cargo bench --bench stages
//! ```
//!
//! Stages: `frame` + `moments` accumulation, the 9x9 symmetric eigen-decomposition (and the fast
//! path's smallest eigenvector and eigenvalue count), the non-planar null-space cases (`nullspace`,
//! cases 1-4 together), damped Newton (`newton`, one start) and the reprojection refinement
//! (`refine`). Inputs of each stage are computed outside the timed closure.

#[cfg(eopnp_bench)]
use eopnp_testkit as common;
#[cfg(eopnp_bench)]
mod support;

#[cfg(eopnp_bench)]
mod stages_bench {
    use super::{common, support};

    use common::{Problem, Scene};
    use criterion::{black_box, criterion_group, BenchmarkId, Criterion};
    use eopnp::bench_hooks::{self, Prepared};
    use support::{config, problems, set_size};

    /// Problems with their prepared intermediates (general scene; problems the pipeline rejects are
    /// dropped, which does not happen for this protocol in practice).
    fn prepared(n: usize) -> Vec<(Problem, Prepared)> {
        problems(Scene::General, n, set_size(n))
            .into_iter()
            .filter_map(|p| bench_hooks::prepare(&p.world, &p.image).map(|q| (p, q)))
            .collect()
    }

    fn stages(c: &mut Criterion) {
        let mut g = c.benchmark_group("stage/accumulate");
        for n in [4, 10, 100, 1000, 10000] {
            let set = problems(Scene::General, n, set_size(n));
            g.bench_with_input(BenchmarkId::from_parameter(n), &set, |b, set| {
                let mut i = 0usize;
                b.iter(|| {
                    let p = &set[i % set.len()];
                    i = i.wrapping_add(1);
                    black_box(bench_hooks::accumulate(
                        black_box(&p.world),
                        black_box(&p.image),
                    ))
                });
            });
        }
        g.finish();

        let sets: Vec<(usize, Vec<(Problem, Prepared)>)> = [4, 10, 100, 1000]
            .iter()
            .map(|&n| (n, prepared(n)))
            .collect();

        // The eigen-decomposition's cost does not depend on N, but M of N = 4 has a 4-D (near)
        // null space, which changes the convergence: both are shown.
        let mut g = c.benchmark_group("stage/eigen9");
        for (n, set) in sets.iter().filter(|(n, _)| [4, 100].contains(n)) {
            g.bench_with_input(BenchmarkId::from_parameter(n), set, |b, set| {
                let mut i = 0usize;
                b.iter(|| {
                    let m = set[i % set.len()].1.m();
                    i = i.wrapping_add(1);
                    black_box(bench_hooks::eigen9(black_box(m)))
                });
            });
        }
        g.finish();

        // The certified fast path needs only the smallest eigenvector (inverse iteration) and the
        // degeneracy test only an eigenvalue count (Sturm sequence).
        let mut g = c.benchmark_group("stage/eigen9_smallest_vector");
        for (n, set) in sets.iter().filter(|(n, _)| [4, 100].contains(n)) {
            g.bench_with_input(BenchmarkId::from_parameter(n), set, |b, set| {
                let mut i = 0usize;
                b.iter(|| {
                    let q = &set[i % set.len()].1;
                    i = i.wrapping_add(1);
                    black_box(bench_hooks::smallest_eigenvector9(
                        black_box(q.m()),
                        black_box(q.scale()),
                    ))
                });
            });
        }
        g.finish();

        let mut g = c.benchmark_group("stage/eigen9_count_below");
        for (n, set) in sets.iter().filter(|(n, _)| [4, 100].contains(n)) {
            g.bench_with_input(BenchmarkId::from_parameter(n), set, |b, set| {
                let mut i = 0usize;
                b.iter(|| {
                    let q = &set[i % set.len()].1;
                    i = i.wrapping_add(1);
                    black_box(bench_hooks::count_eigenvalues_below9(
                        black_box(q.m()),
                        black_box(1e-10 * q.scale()),
                    ))
                });
            });
        }
        g.finish();

        let mut g = c.benchmark_group("stage/nullspace_nonplanar");
        for (n, set) in sets.iter().filter(|(n, _)| [4, 10, 100].contains(n)) {
            g.bench_with_input(BenchmarkId::from_parameter(n), set, |b, set| {
                let mut i = 0usize;
                b.iter(|| {
                    let q = &set[i % set.len()].1;
                    i = i.wrapping_add(1);
                    black_box(bench_hooks::nonplanar_candidates(black_box(q)))
                });
            });
        }
        g.finish();

        let mut g = c.benchmark_group("stage/newton");
        for (n, set) in sets.iter().filter(|(n, _)| [4, 10, 100].contains(n)) {
            g.bench_with_input(BenchmarkId::from_parameter(n), set, |b, set| {
                let mut i = 0usize;
                b.iter(|| {
                    let q = &set[i % set.len()].1;
                    i = i.wrapping_add(1);
                    black_box(bench_hooks::newton(black_box(q)))
                });
            });
        }
        g.finish();

        let mut g = c.benchmark_group("stage/refine");
        for (n, set) in &sets {
            g.bench_with_input(BenchmarkId::from_parameter(n), set, |b, set| {
                let mut i = 0usize;
                b.iter(|| {
                    let (p, q) = &set[i % set.len()];
                    i = i.wrapping_add(1);
                    black_box(bench_hooks::refine(
                        black_box(&p.world),
                        black_box(&p.image),
                        black_box(q),
                    ))
                });
            });
        }
        g.finish();
    }

    criterion_group! {
        name = benches;
        config = config();
        targets = stages
    }
}

#[cfg(eopnp_bench)]
criterion::criterion_main!(stages_bench::benches);

#[cfg(not(eopnp_bench))]
fn main() {
    eprintln!("the stage benches need the hooks: RUSTFLAGS=\"--cfg eopnp_bench\" cargo bench --bench stages");
}
