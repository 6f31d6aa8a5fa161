//! Zero heap allocations per solve in the core path.
//!
//! A counting global allocator (this test binary only) counts the allocations made by the current
//! thread while counting is switched on; `eopnp::solve`, `Solver::solve` (algebraic and exhaustive
//! modes, and with a robust loss, which runs `refine_pixels`) and `Solver::solve_all` must make
//! none after a warm-up call, for N = 4, 10, 100 in general and planar scenes.
//!
//! Finding where an allocation comes from: run with `EOPNP_ALLOC_BACKTRACE=1` (and
//! `RUST_BACKTRACE=1` for symbols):
//! `EOPNP_ALLOC_BACKTRACE=1 cargo test --test no_alloc -- --nocapture --test-threads=1`
//! prints a backtrace for every counted allocation.

use eopnp_testkit as common;

use common::{Problem, ProblemOptions, RotationKind, Scene};
use eopnp::{Loss, Refinement, Solver};
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::atomic::{AtomicBool, Ordering};

struct Counting;

thread_local! {
    /// Whether allocations of this thread are being counted.
    static ON: Cell<bool> = const { Cell::new(false) };
    /// Allocations counted on this thread.
    static COUNT: Cell<usize> = const { Cell::new(0) };
    /// Re-entrancy guard of the backtrace mode (capturing and printing allocate).
    static IN_HOOK: Cell<bool> = const { Cell::new(false) };
}

/// `EOPNP_ALLOC_BACKTRACE` was set (read once, before counting starts).
static BACKTRACE: AtomicBool = AtomicBool::new(false);

impl Counting {
    fn record() {
        // `try_with`: thread-local storage may already be torn down at thread exit.
        let counting =
            ON.try_with(Cell::get).unwrap_or(false) && !IN_HOOK.try_with(Cell::get).unwrap_or(true);
        if !counting {
            return;
        }
        let _ = COUNT.try_with(|c| c.set(c.get() + 1));
        if BACKTRACE.load(Ordering::Relaxed) {
            let _ = IN_HOOK.try_with(|g| g.set(true));
            eprintln!(
                "allocation during a counted solve:\n{}",
                std::backtrace::Backtrace::force_capture()
            );
            let _ = IN_HOOK.try_with(|g| g.set(false));
        }
    }
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        Self::record();
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        Self::record();
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        Self::record();
        unsafe { System.realloc(ptr, layout, new_size) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Allocations made by `f` on this thread.
fn count_allocations<R>(f: impl FnOnce() -> R) -> (usize, R) {
    BACKTRACE.store(
        std::env::var_os("EOPNP_ALLOC_BACKTRACE").is_some(),
        Ordering::Relaxed,
    );
    COUNT.with(|c| c.set(0));
    ON.with(|o| o.set(true));
    let r = f();
    ON.with(|o| o.set(false));
    (COUNT.with(Cell::get), r)
}

/// Problems per configuration.
const TRIALS: u64 = 20;

fn check_scene(scene: Scene, scene_name: &str) {
    let solvers = [
        ("default", Solver::default()),
        (
            "algebraic",
            Solver::default().refinement(Refinement::Algebraic),
        ),
        ("exhaustive", Solver::default().exhaustive(true)),
        // A robust loss runs `refine_pixels` (the pixel-space refinement, identity camera).
        ("cauchy", Solver::default().loss(Loss::Cauchy(2.0 / 800.0))),
        ("huber", Solver::default().loss(Loss::Huber(2.0 / 800.0))),
        (
            "algebraic+exhaustive",
            Solver::default()
                .refinement(Refinement::Algebraic)
                .exhaustive(true),
        ),
    ];
    let mut failures = Vec::new();
    for n in [4usize, 10, 100] {
        let name = format!("no_alloc/{scene_name}/{n}");
        let problems: Vec<Problem> = (0..TRIALS)
            .map(|i| {
                Problem::generate(&ProblemOptions {
                    n,
                    sigma_px: 2.0,
                    scene,
                    rotation: RotationKind::Uniform,
                    seed: common::trial_seed(&name, i),
                })
            })
            .collect();
        // Warm-up: anything lazily initialised once per process (none expected) happens here.
        for p in &problems {
            let _ = eopnp::solve(&p.world, &p.image);
            for (_, s) in &solvers {
                let _ = s.solve(&eopnp::Problem::normalised(&p.world, &p.image));
                let _ = s.solve_all(&eopnp::Problem::normalised(&p.world, &p.image));
            }
        }
        for p in &problems {
            let seed = p.opts.seed;
            let (a, r) = count_allocations(|| eopnp::solve(&p.world, &p.image));
            assert!(r.is_ok(), "seed {seed}: eopnp::solve failed: {r:?}");
            if a != 0 {
                failures.push(format!("{name} seed {seed}: eopnp::solve: {a} allocations"));
            }
            for (mode, s) in &solvers {
                let (a, r) =
                    count_allocations(|| s.solve(&eopnp::Problem::normalised(&p.world, &p.image)));
                assert!(r.is_ok(), "seed {seed}: {mode} solve failed: {r:?}");
                if a != 0 {
                    failures.push(format!("{name} seed {seed}: {mode} solve: {a} allocations"));
                }
                let (a, r) = count_allocations(|| {
                    s.solve_all(&eopnp::Problem::normalised(&p.world, &p.image))
                });
                assert!(r.is_ok(), "seed {seed}: {mode} solve_all failed: {r:?}");
                if a != 0 {
                    failures.push(format!(
                        "{name} seed {seed}: {mode} solve_all: {a} allocations"
                    ));
                }
            }
        }
    }
    assert!(
        failures.is_empty(),
        "heap allocations in the core path (rerun with EOPNP_ALLOC_BACKTRACE=1 to see where):\n{}",
        failures.join("\n")
    );
}

#[test]
fn allocator_counts_allocations() {
    // Self-test: the counter must see an allocation, or the other tests prove nothing.
    let (a, v) = count_allocations(|| vec![1u8; 16]);
    assert_eq!(v.len(), 16);
    assert!(a >= 1, "the counting allocator saw no allocation");
}

#[test]
fn no_allocation_general() {
    check_scene(Scene::General, "general");
}

#[test]
fn no_allocation_planar() {
    check_scene(Scene::Planar, "planar");
}
