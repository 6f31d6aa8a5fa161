//! Probe for the small-N search (N = 4 and 5): `cargo run --release --example small_n --
//! N SCENE TRIALS [check]`, SCENE `general` or `planar`, sigma = 2 px, seeded problems.
//!
//! Without `check` it only solves the problems (generated first), for
//! `valgrind --tool=callgrind --toggle-collect='*small_n*solve_all_problems*'`: instructions
//! per solve are the collected total over TRIALS. With `check` it also runs LM from the ground
//! truth and reports how often the default pose's pixel reprojection cost is above LM-from-GT's
//! (relative tolerance 1e-9), the worst relative difference, and which start won.

use eopnp_testkit as common;

use common::{
    pose_of, reprojection_cost, trial_seed, Problem, ProblemOptions, RotationKind, Scene,
    PIXEL_CAMERA,
};
use eopnp::{Solution, Solver};
use std::collections::BTreeMap;

#[inline(never)]
fn solve_all_problems(solver: &Solver, problems: &[Problem]) -> Vec<Option<Solution>> {
    problems
        .iter()
        .map(|p| {
            solver
                .solve(&eopnp::Problem::normalised(&p.world, &p.image))
                .ok()
        })
        .collect()
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).map_or(4, |s| s.parse().expect("N"));
    let scene = match args.get(2).map_or("general", String::as_str) {
        "planar" => Scene::Planar,
        _ => Scene::General,
    };
    let trials: u64 = args.get(3).map_or(200, |s| s.parse().expect("TRIALS"));
    let check = args.get(4).is_some_and(|s| s == "check");
    let name = std::env::var("SMALL_N_NAME").unwrap_or_else(|_| format!("small_n/{n}/{scene:?}"));
    let problems: Vec<Problem> = (0..trials)
        .map(|i| {
            Problem::generate(&ProblemOptions {
                n,
                sigma_px: 2.0,
                scene,
                rotation: RotationKind::Uniform,
                seed: trial_seed(&name, i),
            })
        })
        .filter(|p| {
            std::env::var("SMALL_N_SEED").map_or(true, |s| format!("{:#x}", p.opts.seed) == s)
        })
        .collect();
    let solver = Solver::default();
    let sols = solve_all_problems(&solver, &problems);
    if !check {
        println!("solved {} of {trials}", sols.iter().flatten().count());
        return;
    }
    let (mut above, mut errors) = (0usize, 0usize);
    let mut worst = f64::NEG_INFINITY;
    let mut sources: BTreeMap<String, usize> = BTreeMap::new();
    for (p, s) in problems.iter().zip(&sols) {
        let Some(s) = s else {
            errors += 1;
            continue;
        };
        *sources.entry(format!("{:?}", s.source)).or_default() += 1;
        let lm = p.lm_from_gt();
        let (r, t) = pose_of(s);
        let cost = reprojection_cost(&p.world, &p.pixels, &r, &t, PIXEL_CAMERA);
        let rel = (cost - lm.cost) / lm.cost;
        worst = worst.max(rel);
        if rel > 1e-9 {
            above += 1;
            if above <= 5 {
                println!(
                    "seed {:#x}: cost {cost:.6e} vs LM-from-GT {:.6e} (rel {rel:.3e})",
                    p.opts.seed, lm.cost
                );
            }
        }
    }
    println!(
        "N={n} {scene:?}: {trials} problems, {errors} errors, {above} above LM-from-GT, worst relative difference {worst:.3e}; sources {sources:?}"
    );
}
