//! The Markdown report: the tables of the last run and the speed summary over the runs.

use crate::args::Args;
use crate::common::{self, Problem};
use crate::measure::{Method, Stats};
use crate::rows::{Row, GROUPS};
use crate::{FAIL_DEG, KORNIA_MAX_HANGS_PER_ROW};
use std::fmt::Write as _;
use std::time::Instant;

/// Peer versions (as pinned in Cargo.toml), for the report.
const PEERS: &str = "sqpnp 0.4.0, lambda-twist 0.7.0, kornia-pnp 0.1.10";

/// `x` with about four significant digits.
fn num(x: f64) -> String {
    if !x.is_finite() {
        "–".into()
    } else if x == 0.0 {
        "0".into()
    } else if x.abs() >= 0.01 && x.abs() < 1e5 {
        format!("{:.4}", x)
            .trim_end_matches('0')
            .trim_end_matches('.')
            .to_string()
    } else {
        format!("{x:.2e}")
    }
}

fn time_str(us: Option<f64>) -> String {
    match us {
        None => "–".into(),
        Some(u) if u >= 100.0 => format!("{u:.0}"),
        Some(u) if u >= 10.0 => format!("{u:.1}"),
        Some(u) => format!("{u:.2}"),
    }
}

fn machine() -> String {
    let info = std::fs::read_to_string("/proc/cpuinfo").unwrap_or_default();
    let model = info
        .lines()
        .find_map(|l| {
            l.strip_prefix("model name")
                .map(|r| r.trim_start_matches([' ', '\t', ':']))
        })
        .unwrap_or("unknown CPU")
        .to_string();
    let cores = info.lines().filter(|l| l.starts_with("processor")).count();
    let avail = std::thread::available_parallelism().map_or(0, |n| n.get());
    format!("{model}, {cores} logical cores in /proc/cpuinfo ({avail} available to this process)")
}

/// The report (`results.md`): the tables of the last run (`results`, `kornia_hangs`), and with
/// `--runs` the speed summary over `every_run` (also written alone to `summary.md`).
pub fn markdown(
    all: &[(Row, Vec<Problem>)],
    results: &[Vec<Stats>],
    kornia_hangs: usize,
    every_run: &[(Vec<Vec<Stats>>, usize)],
    args: &Args,
    t_start: Instant,
) -> String {
    let mut md = String::new();
    let _ = writeln!(md, "# eopnp comparison\n");
    let _ = writeln!(md, "Machine: {}  ", machine());
    let _ = writeln!(
        md,
        "Build: {} profile; peers: {PEERS}. Trials per row: {}; time = median of {} timed \
         passes over the row's problems, per solve. Seed: {:#x}.\n",
        if cfg!(debug_assertions) {
            "debug (numbers meaningless)"
        } else {
            "release"
        },
        args.trials,
        args.passes,
        args.seed
    );
    let _ = writeln!(
        md,
        "Failures: no solution or rotation error > {FAIL_DEG} deg. Errors over the other trials: \
         rotation = largest angle between corresponding columns (deg), translation = \
         100 |t - t_gt| / |t_gt| (%). sqpnp and kornia-pnp work in f32 (world points centred in \
         f64 first). lambda-twist: P3P on points 1-3, pose picked by the reprojection error of all \
         4 points. LM from ground truth: the maximum-likelihood floor (not a solver, not timed). \
         Last column: sqpnp time / method time (> 1: faster than sqpnp).\n"
    );
    for (g, title) in GROUPS.iter().enumerate() {
        let _ = writeln!(md, "## {title}\n");
        let _ = writeln!(
            md,
            "| row | method | trials | failures | median rot err (deg) | mean rot err (deg) | \
             median t err (%) | mean t err (%) | median us / solve | sqpnp time / time |"
        );
        let _ = writeln!(md, "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|");
        let mut notes = Vec::new();
        for (i, (row, _)) in all.iter().enumerate().filter(|(_, (r, _))| r.group == g) {
            let sq = results[i]
                .iter()
                .find(|s| s.method == Method::Sqpnp)
                .and_then(|s| s.us);
            for s in &results[i] {
                let ratio = match (sq, s.us) {
                    (Some(a), Some(b)) if b > 0.0 => format!("{:.2}", a / b),
                    _ => "–".into(),
                };
                let _ = writeln!(
                    md,
                    "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
                    row.label,
                    s.method.name(),
                    s.trials,
                    s.failures,
                    num(s.med_rot),
                    num(s.mean_rot),
                    num(s.med_t),
                    num(s.mean_t),
                    time_str(s.us),
                    ratio
                );
                if let Some(n) = &s.note {
                    notes.push(format!("- {}, {}: {n}", row.label, s.method.name()));
                }
            }
        }
        if !notes.is_empty() {
            let _ = writeln!(md, "\n{}", notes.join("\n"));
        }
        let _ = writeln!(md);
    }
    if kornia_hangs > 0 {
        let _ = writeln!(
            md,
            "kornia-pnp: {kornia_hangs} hung call(s) in total (at most \
             {KORNIA_MAX_HANGS_PER_ROW} per row, then the rest of the row is skipped; each ran \
             on a detached watchdog thread in a child process that exited after the row).\n"
        );
    }
    if args.runs.is_some() {
        let summary = speed_summary(all, every_run);
        let _ = write!(md, "{summary}");
        // Also on its own, for the documents that quote it (scripts/refresh_docs.py).
        let path = args.out.join("summary.md");
        if let Err(e) = std::fs::write(&path, &summary) {
            eprintln!("warning: cannot write {}: {e}", path.display());
        }
    }
    let _ = writeln!(
        md,
        "Total wall time: {:.1} s.",
        t_start.elapsed().as_secs_f64()
    );
    md
}

/// The speed summary over the runs (`--runs`): per row, the median over the runs of eopnp
/// default's, eopnp algebraic's and sqpnp's time per solve, the medians of the per-run ratios
/// sqpnp / default and sqpnp / algebraic, and the range of sqpnp / default.
fn speed_summary(all: &[(Row, Vec<Problem>)], runs: &[(Vec<Vec<Stats>>, usize)]) -> String {
    let time = |run: &(Vec<Vec<Stats>>, usize), i: usize, m: Method| {
        run.0[i].iter().find(|s| s.method == m).and_then(|s| s.us)
    };
    let cell = |v: &[f64], f: fn(f64) -> String| {
        if v.is_empty() {
            "–".to_string()
        } else {
            f(common::median(v))
        }
    };
    let ratio = |x: f64| format!("{x:.2}");
    let mut md = String::new();
    let _ = writeln!(
        md,
        "## Speed over {} runs\n\nMicroseconds per solve: the median over the runs of each \
         run's time (itself the median of its timed passes); ratios: the median over the runs \
         of each run's ratio, and the range (min-max) of sqpnp / default over the runs.\n",
        runs.len()
    );
    let _ = writeln!(
        md,
        "| row | eopnp default | eopnp algebraic | sqpnp | sqpnp / default | sqpnp / algebraic \
         | sqpnp / default, range |"
    );
    let _ = writeln!(md, "|---|---:|---:|---:|---:|---:|---|");
    let short = ["general", "general", "planar", "quasi-singular"];
    for (i, (row, _)) in all.iter().enumerate() {
        let per_run =
            |m: Method| -> Vec<f64> { runs.iter().filter_map(|r| time(r, i, m)).collect() };
        let ratios = |m: Method| -> Vec<f64> {
            runs.iter()
                .filter_map(|r| match (time(r, i, Method::Sqpnp), time(r, i, m)) {
                    (Some(a), Some(b)) if b > 0.0 => Some(a / b),
                    _ => None,
                })
                .collect()
        };
        let to_default = ratios(Method::EopnpDefault);
        let range = if to_default.is_empty() {
            "–".to_string()
        } else {
            let lo = to_default.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = to_default.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            format!("{lo:.2}-{hi:.2}")
        };
        let _ = writeln!(
            md,
            "| {} {} | {} | {} | {} | {} | {} | {} |",
            short[row.group],
            row.label,
            cell(&per_run(Method::EopnpDefault), |u| time_str(Some(u))),
            cell(&per_run(Method::EopnpAlgebraic), |u| time_str(Some(u))),
            cell(&per_run(Method::Sqpnp), |u| time_str(Some(u))),
            cell(&to_default, ratio),
            cell(&ratios(Method::EopnpAlgebraic), ratio),
            range
        );
    }
    let _ = writeln!(md);
    md
}
