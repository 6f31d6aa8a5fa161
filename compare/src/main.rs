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
mod peers;
mod svg;

use common::{Problem, ProblemOptions, RotationKind, Scene};
use eopnp::{Refinement, Solver};
use peers::Pose;
use std::fmt::Write as _;
use std::hint::black_box;
use std::io::Write as _;
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// Default seed of the comparison (independent of the test suite's seed).
const DEFAULT_SEED: u64 = 0x0E0F_C0DE_2019;
/// Rotation error above which a trial counts as a failure, degrees.
const FAIL_DEG: f64 = 5.0;
/// A row stops calling kornia-pnp after this many of its calls hung (each hung call leaves a
/// detached, busy thread behind in the process that made it).
const KORNIA_MAX_HANGS_PER_ROW: usize = 3;
/// Peer versions (as pinned in Cargo.toml), for the report.
const PEERS: &str = "sqpnp 0.4.0, lambda-twist 0.7.0, kornia-pnp 0.1.10";

#[derive(Clone, Debug)]
struct Args {
    trials: usize,
    passes: usize,
    seed: u64,
    out: PathBuf,
    kornia_timeout: Duration,
    json: bool,
    /// `--runs K`: repeat the measurement K times and print the speed summary.
    runs: Option<usize>,
    /// Child mode: run the guarded kornia-pnp pass of this row and print the outcomes.
    kornia_row: Option<usize>,
}

fn parse_args() -> Result<Args, String> {
    let mut a = Args {
        trials: 500,
        passes: 5,
        seed: DEFAULT_SEED,
        out: PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../target/compare"),
        kornia_timeout: Duration::from_millis(200),
        json: true,
        runs: None,
        kornia_row: None,
    };
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        let mut value = || it.next().ok_or(format!("{flag} needs a value"));
        match flag.as_str() {
            "--trials" => a.trials = value()?.parse().map_err(|e| format!("--trials: {e}"))?,
            "--passes" => a.passes = value()?.parse().map_err(|e| format!("--passes: {e}"))?,
            "--seed" => {
                let v = value()?;
                a.seed = match v.strip_prefix("0x") {
                    Some(h) => u64::from_str_radix(h, 16),
                    None => v.parse(),
                }
                .map_err(|e| format!("--seed: {e}"))?;
            }
            "--out" => a.out = PathBuf::from(value()?),
            "--kornia-timeout-ms" => {
                a.kornia_timeout = Duration::from_millis(
                    value()?
                        .parse()
                        .map_err(|e| format!("--kornia-timeout-ms: {e}"))?,
                )
            }
            "--no-json" => a.json = false,
            "--runs" => a.runs = Some(value()?.parse().map_err(|e| format!("--runs: {e}"))?),
            "--kornia-row" => {
                a.kornia_row = Some(value()?.parse().map_err(|e| format!("--kornia-row: {e}"))?)
            }
            "-h" | "--help" => {
                println!(
                    "eopnp-compare [--trials N=500] [--passes P=5] [--seed S] [--out DIR] \
                     [--kornia-timeout-ms MS=200] [--no-json] [--runs K]"
                );
                std::process::exit(0);
            }
            other => return Err(format!("unknown argument {other}")),
        }
    }
    if a.trials == 0 || a.passes == 0 || a.runs == Some(0) {
        return Err("--trials, --passes and --runs must be positive".into());
    }
    Ok(a)
}

/// One row of the protocol.
#[derive(Clone, Debug)]
struct Row {
    group: usize,
    label: String,
    scene: Scene,
    n: usize,
    sigma: f64,
}

const GROUPS: [&str; 4] = [
    "General scene, N sweep (sigma = 2 px)",
    "General scene, sigma sweep (N = 10)",
    "Planar scene (random tilt), sigma = 2 px",
    "Quasi-singular scene, sigma = 2 px",
];

fn rows() -> Vec<Row> {
    let mut v = Vec::new();
    let row = |group, scene, n, sigma: f64| Row {
        group,
        label: format!("N = {n}, sigma = {sigma} px"),
        scene,
        n,
        sigma,
    };
    for n in [4, 5, 6, 8, 10, 15, 20, 50, 100, 1000] {
        v.push(row(0, Scene::General, n, 2.0));
    }
    for s in [0.0, 0.5, 1.0, 2.0, 3.0, 5.0, 10.0] {
        v.push(row(1, Scene::General, 10, s));
    }
    for n in [4, 6, 10, 100] {
        v.push(row(2, Scene::Planar, n, 2.0));
    }
    for n in [6, 10, 100] {
        v.push(row(3, Scene::QuasiSingular, n, 2.0));
    }
    v
}

fn scene_name(s: Scene) -> &'static str {
    match s {
        Scene::General => "general",
        Scene::Planar => "planar",
        Scene::QuasiSingular => "quasi_singular",
    }
}

/// The problems of a row: trial `i` from `splitmix(seed ^ hash(row) ^ splitmix(i))`.
fn generate(row: &Row, args: &Args) -> Vec<Problem> {
    let name = format!("compare/{}/{}/{}", scene_name(row.scene), row.n, row.sigma);
    let h = common::name_hash(&name);
    (0..args.trials as u64)
        .map(|i| {
            Problem::generate(&ProblemOptions {
                n: row.n,
                sigma_px: row.sigma,
                scene: row.scene,
                rotation: RotationKind::Uniform,
                seed: common::splitmix64(args.seed ^ common::splitmix64(h ^ common::splitmix64(i))),
            })
        })
        .collect()
}

/// The methods, in table order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Method {
    EopnpDefault,
    EopnpAlgebraic,
    Sqpnp,
    LambdaTwist,
    Kornia,
    LmGt,
}

const METHODS: [Method; 6] = [
    Method::EopnpDefault,
    Method::EopnpAlgebraic,
    Method::Sqpnp,
    Method::LambdaTwist,
    Method::Kornia,
    Method::LmGt,
];

impl Method {
    fn name(self) -> &'static str {
        match self {
            Method::EopnpDefault => "eopnp (default)",
            Method::EopnpAlgebraic => "eopnp (algebraic)",
            Method::Sqpnp => "sqpnp",
            Method::LambdaTwist => "lambda-twist (P3P+1)",
            Method::Kornia => "kornia-pnp (EPnP)",
            Method::LmGt => "LM from ground truth",
        }
    }
    fn color(self) -> &'static str {
        match self {
            Method::EopnpDefault => "#d62728",
            Method::EopnpAlgebraic => "#ff7f0e",
            Method::Sqpnp => "#1f77b4",
            Method::LambdaTwist => "#9467bd",
            Method::Kornia => "#2ca02c",
            Method::LmGt => "#555555",
        }
    }
}

/// Statistics of one method on one row.
#[derive(Clone, Debug)]
struct Stats {
    method: Method,
    trials: usize,
    failures: usize,
    med_rot: f64,
    mean_rot: f64,
    med_t: f64,
    mean_t: f64,
    /// Median microseconds per solve (None: not timed).
    us: Option<f64>,
    note: Option<String>,
}

fn stats(method: Method, problems: &[Problem], poses: &[Option<Pose>]) -> Stats {
    let mut rot = Vec::new();
    let mut tr = Vec::new();
    let mut failures = 0;
    for (p, pose) in problems.iter().zip(poses) {
        let ok = pose.and_then(|(r, t)| {
            let (er, et) = (
                common::rot_err_deg(&r, &p.r_gt),
                common::trans_err_pct(&t, &p.t_gt),
            );
            (er.is_finite() && et.is_finite() && er <= FAIL_DEG).then_some((er, et))
        });
        match ok {
            Some((er, et)) => {
                rot.push(er);
                tr.push(et);
            }
            None => failures += 1,
        }
    }
    Stats {
        method,
        trials: problems.len(),
        failures,
        med_rot: common::median(&rot),
        mean_rot: common::mean(&rot),
        med_t: common::median(&tr),
        mean_t: common::mean(&tr),
        us: None,
        note: None,
    }
}

/// Median over `passes` of (time of one pass over all inputs) / (number of inputs), in us.
fn time_per_solve<T, R>(inputs: &[T], passes: usize, mut f: impl FnMut(&T) -> R) -> Option<f64> {
    if inputs.is_empty() {
        return None;
    }
    let mut per: Vec<f64> = (0..passes)
        .map(|_| {
            let t0 = Instant::now();
            for x in inputs {
                black_box(f(black_box(x)));
            }
            t0.elapsed().as_secs_f64() * 1e6 / inputs.len() as f64
        })
        .collect();
    per.sort_by(f64::total_cmp);
    Some(per[per.len() / 2])
}

fn eopnp_pose(s: &eopnp::Solution) -> Pose {
    (s.rotation, s.translation)
}

/// Runs one method on one row (accuracy pass, then timed passes).
fn run_method(
    method: Method,
    row_index: usize,
    row: &Row,
    problems: &[Problem],
    args: &Args,
    kornia_hangs_total: &mut usize,
) -> Option<Stats> {
    let passes = args.passes;
    match method {
        Method::EopnpDefault | Method::EopnpAlgebraic => {
            let solver = if method == Method::EopnpDefault {
                Solver::default()
            } else {
                Solver::default().refinement(Refinement::Algebraic)
            };
            let poses: Vec<_> = problems
                .iter()
                .map(|p| {
                    solver
                        .solve(&eopnp::Problem::normalised(&p.world, &p.image))
                        .ok()
                        .map(|s| eopnp_pose(&s))
                })
                .collect();
            let mut s = stats(method, problems, &poses);
            s.us = time_per_solve(problems, passes, |p| {
                solver.solve(&eopnp::Problem::normalised(&p.world, &p.image))
            });
            Some(s)
        }
        Method::Sqpnp => {
            let inputs: Vec<_> = problems.iter().map(peers::sqpnp_input).collect();
            let mut solver = peers::Sqpnp::new();
            let poses: Vec<_> = inputs.iter().map(|q| solver.solve(q)).collect();
            let mut s = stats(method, problems, &poses);
            s.us = time_per_solve(&inputs, passes, |q| solver.solve(q));
            Some(s)
        }
        Method::LambdaTwist => {
            if row.n != 4 {
                return None;
            }
            let inputs: Vec<_> = problems.iter().map(peers::lambda_input).collect();
            let poses: Vec<_> = inputs.iter().map(peers::lambda_twist).collect();
            let mut s = stats(method, problems, &poses);
            s.us = time_per_solve(&inputs, passes, peers::lambda_twist);
            Some(s)
        }
        Method::Kornia => {
            let inputs: Vec<_> = problems.iter().map(peers::kornia_input).collect();
            // The guarded accuracy pass runs in a child process (this program with
            // `--kornia-row`), so that the threads of hung calls, which keep a core busy,
            // die with it instead of disturbing the timings here; in-process if that fails.
            let outcomes = kornia_child(row_index, args)
                .filter(|o| o.len() == inputs.len())
                .unwrap_or_else(|| kornia_accuracy(&inputs, args));
            let mut poses = Vec::with_capacity(inputs.len());
            // Inputs whose call returned within the timeout: only these are timed (directly,
            // without the watchdog thread, whose spawn would dominate the time).
            let mut safe = Vec::with_capacity(inputs.len());
            let (mut hangs, mut panics, mut skipped) = (0usize, 0usize, 0usize);
            for (q, o) in inputs.iter().zip(outcomes) {
                match o {
                    KorniaOutcome::Returned(r) => {
                        safe.push(q.clone());
                        poses.push(r);
                    }
                    KorniaOutcome::Panicked => panics += 1,
                    KorniaOutcome::TimedOut => hangs += 1,
                    KorniaOutcome::Skipped => skipped += 1,
                }
                if !matches!(o, KorniaOutcome::Returned(_)) {
                    poses.push(None);
                }
            }
            *kornia_hangs_total += hangs;
            let mut s = stats(method, problems, &poses);
            s.us = time_per_solve(&safe, passes, peers::kornia);
            let mut notes = Vec::new();
            if hangs > 0 {
                notes.push(format!(
                    "{hangs} call(s) did not return within {} ms (counted as failures)",
                    args.kornia_timeout.as_millis()
                ));
            }
            if panics > 0 {
                notes.push(format!("{panics} call(s) panicked (counted as failures)"));
            }
            if skipped > 0 {
                notes.push(format!(
                    "{skipped} trial(s) not run after {KORNIA_MAX_HANGS_PER_ROW} hangs (counted \
                     as failures)"
                ));
            }
            if hangs + skipped + panics > 0 {
                notes.push(format!("time over the {} returning calls", safe.len()));
            }
            if !notes.is_empty() {
                s.note = Some(notes.join("; "));
            }
            Some(s)
        }
        Method::LmGt => {
            let poses: Vec<_> = problems
                .iter()
                .map(|p| {
                    let r = p.lm_from_gt();
                    Some((r.r, r.t))
                })
                .collect();
            Some(stats(method, problems, &poses))
        }
    }
}

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

/// Writes every problem as JSON (numbers in Rust's shortest round-trip form).
fn write_problems(
    path: &std::path::Path,
    args: &Args,
    all: &[(Row, Vec<Problem>)],
) -> std::io::Result<()> {
    let mut w = std::io::BufWriter::new(std::fs::File::create(path)?);
    let v3 = |x: f64, y: f64, z: f64| format!("[{x:?},{y:?},{z:?}]");
    writeln!(
        w,
        "{{\"format\":\"eopnp-compare problems v1\",\"seed\":{},\"fail_deg\":{:?},\
         \"intrinsics\":{{\"fx\":{:?},\"fy\":{:?},\"cx\":{:?},\"cy\":{:?}}},\
         \"conventions\":\"x_cam = R X + t; pixels = f (x/z, y/z) + (cx, cy) + noise; image = \
         (pixels - (cx, cy)) / f; R row-major\",\"rows\":[",
        args.seed,
        FAIL_DEG,
        common::F,
        common::F,
        common::CX,
        common::CY
    )?;
    for (ri, (row, probs)) in all.iter().enumerate() {
        write!(
            w,
            "{}{{\"group\":{:?},\"label\":{:?},\"scene\":\"{}\",\"n\":{},\"sigma_px\":{:?},\"problems\":[",
            if ri > 0 { ",\n" } else { "" },
            GROUPS[row.group],
            row.label,
            scene_name(row.scene),
            row.n,
            row.sigma
        )?;
        for (pi, p) in probs.iter().enumerate() {
            let world: Vec<String> = p.world.iter().map(|x| v3(x.x, x.y, x.z)).collect();
            let pix: Vec<String> = p
                .pixels
                .iter()
                .map(|m| format!("[{:?},{:?}]", m.x, m.y))
                .collect();
            let img: Vec<String> = p
                .image
                .iter()
                .map(|m| format!("[{:?},{:?}]", m.x, m.y))
                .collect();
            let r = &p.r_gt;
            write!(
                w,
                "{}{{\"seed\":{},\"world\":[{}],\"pixels\":[{}],\"image\":[{}],\"r_gt\":[{},{},{}],\"t_gt\":{}}}",
                if pi > 0 { ",\n" } else { "\n" },
                p.opts.seed,
                world.join(","),
                pix.join(","),
                img.join(","),
                v3(r[(0, 0)], r[(0, 1)], r[(0, 2)]),
                v3(r[(1, 0)], r[(1, 1)], r[(1, 2)]),
                v3(r[(2, 0)], r[(2, 1)], r[(2, 2)]),
                v3(p.t_gt.x, p.t_gt.y, p.t_gt.z)
            )?;
        }
        write!(w, "]}}")?;
    }
    writeln!(w, "]}}")?;
    w.flush()
}

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

    // Markdown.
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
        let summary = speed_summary(&all, &every_run);
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

    print!("{md}");
    let md_path = args.out.join("results.md");
    if let Err(e) = std::fs::write(&md_path, &md) {
        eprintln!("warning: cannot write {}: {e}", md_path.display());
    }

    // Plot.
    let series = |group: usize, x: fn(&Row) -> f64, y: fn(&Stats) -> Option<f64>| {
        METHODS
            .iter()
            .filter_map(|&m| {
                let pts: Vec<(f64, f64)> = all
                    .iter()
                    .zip(&results)
                    .filter(|((r, _), _)| r.group == group)
                    .filter_map(|((r, _), st)| {
                        st.iter()
                            .find(|s| s.method == m)
                            .and_then(y)
                            .filter(|v| v.is_finite())
                            .map(|v| (x(r), v))
                    })
                    .collect();
                (!pts.is_empty()).then(|| svg::Series {
                    name: m.name().to_string(),
                    color: m.color().to_string(),
                    points: pts,
                })
            })
            .collect::<Vec<_>>()
    };
    let panels = [
        svg::Panel {
            title: "Median rotation error vs N (general, 2 px)".into(),
            x_label: "N".into(),
            y_label: "median rotation error (deg)".into(),
            x_log: true,
            series: series(0, |r| r.n as f64, |s| Some(s.med_rot)),
        },
        svg::Panel {
            title: "Median rotation error vs sigma (general, N = 10)".into(),
            x_label: "sigma (px)".into(),
            y_label: "median rotation error (deg)".into(),
            x_log: false,
            series: series(1, |r| r.sigma, |s| Some(s.med_rot)),
        },
        svg::Panel {
            title: "Time per solve vs N (general, 2 px)".into(),
            x_label: "N".into(),
            y_label: "median time per solve (us)".into(),
            x_log: true,
            series: series(0, |r| r.n as f64, |s| s.us),
        },
    ];
    let plot = svg::render(&panels);
    let svg_path = args.out.join("plot.svg");
    if let Err(e) = std::fs::write(&svg_path, plot) {
        eprintln!("warning: cannot write {}: {e}", svg_path.display());
    }
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

/// One run of the measurement: every method on every row (kornia-pnp last: a hung kornia call
/// leaves a busy detached thread behind, which must not disturb the timings of the other
/// methods). Per row, the methods' statistics in table order; and the number of hung kornia
/// calls.
fn measure(all: &[(Row, Vec<Problem>)], args: &Args) -> (Vec<Vec<Stats>>, usize) {
    let mut results: Vec<Vec<Stats>> = vec![Vec::new(); all.len()];
    let mut kornia_hangs = 0usize;
    for phase_kornia in [false, true] {
        for (i, (row, probs)) in all.iter().enumerate() {
            for m in METHODS {
                if (m == Method::Kornia) != phase_kornia {
                    continue;
                }
                if let Some(s) = run_method(m, i, row, probs, args, &mut kornia_hangs) {
                    results[i].push(s);
                }
            }
            eprint!(".");
        }
    }
    eprintln!();
    for r in &mut results {
        r.sort_by_key(|s| METHODS.iter().position(|&m| m == s.method));
    }
    (results, kornia_hangs)
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

/// Outcome of one guarded kornia-pnp call.
#[derive(Clone, Copy, Debug)]
enum KorniaOutcome {
    Returned(Option<Pose>),
    Panicked,
    TimedOut,
    Skipped,
}

/// The guarded accuracy pass over a row's inputs (in this process): one watchdog thread per
/// call; after [`KORNIA_MAX_HANGS_PER_ROW`] hangs the rest of the row is skipped.
fn kornia_accuracy(inputs: &[peers::KorniaInput], args: &Args) -> Vec<KorniaOutcome> {
    let mut hangs = 0;
    inputs
        .iter()
        .map(|q| {
            if hangs >= KORNIA_MAX_HANGS_PER_ROW {
                return KorniaOutcome::Skipped;
            }
            match peers::kornia_guarded(q, args.kornia_timeout) {
                peers::Guarded::Returned(r) => KorniaOutcome::Returned(r),
                peers::Guarded::Panicked => KorniaOutcome::Panicked,
                peers::Guarded::TimedOut => {
                    hangs += 1;
                    KorniaOutcome::TimedOut
                }
            }
        })
        .collect()
}

/// Child mode (`--kornia-row I`): the guarded pass of row `I`, one line per trial on stdout
/// (`ok` + 12 numbers, `none`, `panic`, `timeout`, `skipped`); then exit, which also ends the
/// threads of hung calls.
fn kornia_child_main(i: usize, args: &Args) -> ! {
    let rows = rows();
    let Some(row) = rows.get(i) else {
        std::process::exit(2)
    };
    let inputs: Vec<_> = generate(row, args)
        .iter()
        .map(peers::kornia_input)
        .collect();
    let mut out = String::new();
    for o in kornia_accuracy(&inputs, args) {
        match o {
            KorniaOutcome::Returned(Some((r, t))) => {
                let _ = write!(out, "ok");
                for x in r.iter().chain(t.iter()) {
                    let _ = write!(out, " {x:?}");
                }
                out.push('\n');
            }
            KorniaOutcome::Returned(None) => out.push_str("none\n"),
            KorniaOutcome::Panicked => out.push_str("panic\n"),
            KorniaOutcome::TimedOut => out.push_str("timeout\n"),
            KorniaOutcome::Skipped => out.push_str("skipped\n"),
        }
    }
    let mut so = std::io::stdout().lock();
    let _ = so.write_all(out.as_bytes());
    let _ = so.flush();
    std::process::exit(0)
}

/// Runs the child for row `i` and parses its outcomes; `None` if it could not be run.
fn kornia_child(i: usize, args: &Args) -> Option<Vec<KorniaOutcome>> {
    let exe = std::env::current_exe().ok()?;
    let out = std::process::Command::new(exe)
        .args([
            "--kornia-row".to_string(),
            i.to_string(),
            "--trials".into(),
            args.trials.to_string(),
            "--seed".into(),
            args.seed.to_string(),
            "--kornia-timeout-ms".into(),
            args.kornia_timeout.as_millis().to_string(),
        ])
        .stderr(std::process::Stdio::null())
        .output()
        .ok()?;
    if !out.status.success() {
        return None;
    }
    let text = String::from_utf8(out.stdout).ok()?;
    text.lines()
        .map(|l| {
            let mut w = l.split_whitespace();
            Some(match w.next()? {
                "ok" => {
                    let v: Vec<f64> = w.map(|x| x.parse().ok()).collect::<Option<_>>()?;
                    if v.len() != 12 {
                        return None;
                    }
                    KorniaOutcome::Returned(Some((
                        nalgebra::Matrix3::from_column_slice(&v[..9]),
                        nalgebra::Vector3::new(v[9], v[10], v[11]),
                    )))
                }
                "none" => KorniaOutcome::Returned(None),
                "panic" => KorniaOutcome::Panicked,
                "timeout" => KorniaOutcome::TimedOut,
                "skipped" => KorniaOutcome::Skipped,
                _ => return None,
            })
        })
        .collect()
}
