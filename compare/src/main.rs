//! `eopnp-compare`: accuracy and speed of eopnp against other Rust PnP solvers on identical
//! problems of the paper's protocol (docs/algorithm.md section 7), in one process.
//!
//! ```text
//! cargo run --release -p eopnp-compare -- [--trials 500] [--passes 5] [--seed S]
//!     [--out DIR] [--kornia-timeout-ms 200] [--no-json] [--runs K]
//! ```
//!
//! Rows: general scene, N sweep (4, 5, 6, 8, 10, 15, 20, 50, 100, 1000) at sigma = 2 px; sigma
//! sweep (0, 0.5, 1, 2, 3, 5, 10 px) at N = 10; planar scene (random tilt) N = 4, 6, 10, 100;
//! quasi-singular scene N = 6, 10, 100. Problems come from the test suite's generator
//! (`testkit/`, the crate `eopnp-testkit`), each from one seed derived from `--seed`, the row and the trial.
//!
//! Methods: eopnp default (reprojection refinement) and `Refinement::Algebraic`; `sqpnp` 0.4;
//! `lambda-twist` 0.7 (P3P + 4th-point disambiguation, N = 4 only); `kornia-pnp` 0.1.10 (EPnP,
//! every accuracy call on a watchdog thread with a timeout); LM from the ground truth (the
//! maximum-likelihood accuracy floor; not a solver, not timed).
//!
//! Per row and method: trials, failures (no solution, or rotation error > 5 degrees), median
//! and mean rotation error (largest column angle, degrees) and translation error (percent)
//! over the non-failed trials, and the median over `--passes` timed passes of (time of a pass
//! over all the row's problems) / (number of problems).
//!
//! Writes `DIR/results.md` (also printed), `DIR/plot.svg` and `DIR/problems.json` (every problem,
//! read by `scripts/compare_opencv.py`); `DIR` defaults to `target/compare` in the workspace.
//!
//! `--runs K`: the whole measurement (every row and method, on the same problems) K times, one
//! after the other in this process; the report and the plot are those of the last run, and the
//! report ends with the speed summary over the K runs (the README's speed table; also written
//! alone to `summary.md` in the output directory): per row, the
//! median over the runs of the time per solve of eopnp default, eopnp algebraic and sqpnp, the
//! medians of the per-run ratios sqpnp / default and sqpnp / algebraic, and the range (min-max)
//! of sqpnp / default. Without `--runs` the output is that of one run, without the summary.

use eopnp_testkit as common;
mod args;
mod kornia;
mod measure;
mod peers;
mod plot;
mod report;
mod rows;
mod svg;

use args::parse_args;
use common::Problem;
use kornia::kornia_child_main;
use measure::measure;
use rows::{generate, rows, write_problems, Row};
use std::time::Instant;

/// Rotation error above which a trial counts as a failure, degrees.
const FAIL_DEG: f64 = 5.0;
/// A row stops calling kornia-pnp after this many of its calls hung (each hung call leaves a
/// detached, busy thread behind in the process that made it).
const KORNIA_MAX_HANGS_PER_ROW: usize = 3;

fn main() {
    let args = match parse_args() {
        Ok(a) => a,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    };
    // Peers may panic on some inputs: report the first few panics, silence the rest.
    let panics = std::sync::atomic::AtomicUsize::new(0);
    let default_hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        if panics.fetch_add(1, std::sync::atomic::Ordering::Relaxed) < 3 {
            default_hook(info);
        }
    }));
    if let Some(i) = args.kornia_row {
        kornia_child_main(i, &args);
    }
    if let Err(e) = std::fs::create_dir_all(&args.out) {
        eprintln!("error: cannot create {}: {e}", args.out.display());
        std::process::exit(1);
    }

    let rows = rows();
    let t_start = Instant::now();
    let all: Vec<(Row, Vec<Problem>)> = rows
        .iter()
        .map(|r| (r.clone(), generate(r, &args)))
        .collect();
    if args.json {
        let path = args.out.join("problems.json");
        if let Err(e) = write_problems(&path, &args, &all) {
            eprintln!("warning: cannot write {}: {e}", path.display());
        }
    }

    let runs = args.runs.unwrap_or(1);
    let mut every_run = Vec::with_capacity(runs);
    for run in 0..runs {
        if runs > 1 {
            eprint!("run {} of {runs}: ", run + 1);
        }
        every_run.push(measure(&all, &args));
    }
    let (results, kornia_hangs) = every_run.last().cloned().expect("at least one run");
    let md = report::markdown(&all, &results, kornia_hangs, &every_run, &args, t_start);

    print!("{md}");
    let md_path = args.out.join("results.md");
    if let Err(e) = std::fs::write(&md_path, &md) {
        eprintln!("warning: cannot write {}: {e}", md_path.display());
    }

    let svg_path = plot::write(&args.out, &all, &results);
    eprintln!(
        "wrote {}, {}{}",
        md_path.display(),
        svg_path.display(),
        if args.json {
            format!(", {}", args.out.join("problems.json").display())
        } else {
            String::new()
        }
    );
}
