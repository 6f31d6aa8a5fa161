//! Multi-camera rigs: eopnp's RANSAC on rigs at several outlier levels, and the
//! generalized solve at N = 100 against the central solve, on seeded synthetic problems; with
//! `--export FILE`, the problems and eopnp's results as JSON for `scripts/compare_rig_peers.py`
//! (PoseLib and pycolmap on the same problems).
//!
//! ```sh
//! cargo run --release --example rig_compare -- [--problems 200] [--n 200] [--levels 0,0.5,0.8]
//!     [--seed 42] [--threshold 4] [--passes 3] [--sigma 1] [--export FILE]
//!     [--solve-problems 200] [--solve-passes 15] [--only ransac|solve]
//! ```
//!
//! The problems (one seed each, from `--seed`, the level and the problem's index): a rig of 2
//! to 6 cameras (cycled) looking outward, as a car's or a headset's: camera `k` on a circle of
//! diameter `baseline` (uniform in 0.1 to 2 units; each camera's height off the circle's plane
//! up to 5 % of it), yawed by `2 pi k / n` plus up to 0.1 rad, pitched up to 0.1 rad; each
//! camera 640 x 480 and one of PINHOLE (fx 500, fy 520), SIMPLE_RADIAL (f 500, k = -0.1) and
//! OPENCV (fx 500, fy 505, k1 = -0.08, k2 = 0.01, p1 = 0.001, p2 = -0.0005), cycled over the
//! cameras (the first camera's model cycled over the problems). The rig's pose in the world: a
//! rotation of up to 3.1 rad about a random axis, a translation up to 2 units per axis. `N`
//! points, camera `i mod n` seeing point `i`, each 2 to 30 units in front of its camera, its
//! normalised image point uniform in [-0.55, 0.55] x [-0.42, 0.42] (inside the image); pixel
//! noise `--sigma` px per coordinate. Outliers: a fraction of the correspondences (chosen at
//! random) whose world point is replaced by another point drawn the same way (a wrong match),
//! the pixel kept.
//!
//! RANSAC: `Ransac::default()` (threshold `--threshold` px, seed per problem) with
//! `Solver::default()`. Errors against the truth: rotation (largest angle between
//! corresponding axes, degrees) and the rig centre's distance to the true one (units); a
//! problem without a pose counts as an infinite error. The floor: `Solver::solve` of the
//! problem without its outliers (not timed). Time per problem: the median over `--passes`
//! passes of (one pass over the level's problems) / (number of problems), one thread.
//!
//! Solve at N = 100 (the target: within 2x the central solve): `Solver::default().solve` of `--solve-problems`
//! problems per row at sigma 1 px, no outliers: the central solve of normalised points (the
//! problems of `cargo bench --bench solve`, `solve/general/default/100`), the central solve of
//! pixels through one camera of this generator, and rigs of 2, 4 and 6 cameras, all-pinhole
//! and distorting (SIMPLE_RADIAL and OPENCV alternating over a rig's cameras, and over the
//! problems of the central row); the rows interleaved in each pass,
//! each row's time the median over `--solve-passes` passes; ratios of each rig row to the
//! central normalised solve and to the central pixel solve of the same kind of camera.

use eopnp::camera::Camera;
use eopnp::ransac::{problem_seed, Ransac};
use eopnp::{Problem, Rig, Solver};
use eopnp_testkit::{self as common, rot_err_deg};
use nalgebra::{
    Isometry3, Matrix3, Point2, Point3, Rotation3, Translation3, UnitQuaternion, Vector3,
};
use rand::{Rng, SeedableRng};
use rand_distr::{Distribution, Normal};
use rand_pcg::Pcg64;
use serde_json::{json, Value};
use std::hint::black_box;
use std::time::Instant;

/// The camera models of the generator, as COLMAP names them, and their parameters.
const MODELS: [(&str, &[f64]); 3] = [
    ("PINHOLE", &[500.0, 520.0, 320.0, 240.0]),
    ("SIMPLE_RADIAL", &[500.0, 320.0, 240.0, -0.1]),
    (
        "OPENCV",
        &[500.0, 505.0, 320.0, 240.0, -0.08, 0.01, 0.001, -0.0005],
    ),
];

/// Which models a rig's cameras get.
#[derive(Clone, Copy)]
enum Models {
    /// Cycled over the cameras, starting at this index of [`MODELS`].
    Mixed(usize),
    /// Every camera PINHOLE.
    Pinhole,
    /// SIMPLE_RADIAL and OPENCV alternating over the cameras, the first camera's at this index
    /// (0: SIMPLE_RADIAL).
    Distorting(usize),
}

/// One synthetic rig problem.
struct Case {
    seed: u64,
    baseline: f64,
    rig: Rig,
    world: Vec<Point3<f64>>,
    pixels: Vec<Point2<f64>>,
    cameras: Vec<u32>,
    outlier: Vec<bool>,
    /// `x_rig = R X + t`.
    truth: Isometry3<f64>,
}

/// A problem of `n_cams` cameras, `n` points, noise `sigma` px, `fraction` of outliers.
fn generate(seed: u64, n_cams: usize, models: Models, n: usize, sigma: f64, fraction: f64) -> Case {
    let mut rng = Pcg64::seed_from_u64(seed);
    let baseline = rng.random_range(0.1..2.0);
    let mut cams = Vec::new();
    for k in 0..n_cams {
        let yaw = std::f64::consts::TAU * k as f64 / n_cams as f64 + rng.random_range(-0.1..0.1);
        let pitch: f64 = rng.random_range(-0.1..0.1);
        let height = rng.random_range(-0.05..0.05) * baseline;
        let c = Vector3::new(
            yaw.sin() * 0.5 * baseline,
            height,
            yaw.cos() * 0.5 * baseline,
        );
        // Camera axes in the rig frame: z outward (pitched), x to its right, y down.
        let z = Vector3::new(
            yaw.sin() * pitch.cos(),
            pitch.sin(),
            yaw.cos() * pitch.cos(),
        );
        let x = Vector3::new(yaw.cos(), 0.0, -yaw.sin());
        let y = z.cross(&x);
        let rk = Matrix3::from_rows(&[x.transpose(), y.transpose(), z.transpose()]);
        let rot = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(rk));
        let t = -(rk * c);
        let m = match models {
            Models::Mixed(first) => (first + k) % MODELS.len(),
            Models::Pinhole => 0,
            Models::Distorting(first) => 1 + (first + k) % 2,
        };
        let (name, params) = MODELS[m];
        let cam = Camera::from_colmap(name, 640, 480, params.to_vec()).expect("camera");
        cams.push((cam, Isometry3::from_parts(Translation3::from(t), rot)));
    }
    let rig = Rig::new(cams).expect("rig");
    let axis = Vector3::new(
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
    );
    let truth = Isometry3::from_parts(
        Translation3::new(
            rng.random_range(-2.0..2.0),
            rng.random_range(-2.0..2.0),
            rng.random_range(-2.0..2.0),
        ),
        UnitQuaternion::from_scaled_axis(axis.normalize() * rng.random_range(0.0..3.1)),
    );
    let world_to = |rig: &Rig, k: usize, m: Point2<f64>, depth: f64| {
        let p_cam = Point3::new(m.x * depth, m.y * depth, depth);
        truth.inverse() * (rig.cam_from_rig()[k].inverse() * p_cam)
    };
    let draw = |rng: &mut Pcg64| {
        (
            Point2::new(rng.random_range(-0.55..0.55), rng.random_range(-0.42..0.42)),
            rng.random_range(2.0..30.0),
        )
    };
    let noise = Normal::new(0.0, 1.0).expect("normal");
    let (mut world, mut pixels, mut cameras) = (Vec::new(), Vec::new(), Vec::new());
    for i in 0..n {
        let k = i % n_cams;
        let (m, depth) = draw(&mut rng);
        world.push(world_to(&rig, k, m, depth));
        let px = rig.cameras()[k].project(m);
        pixels.push(Point2::new(
            px.x + sigma * noise.sample(&mut rng),
            px.y + sigma * noise.sample(&mut rng),
        ));
        cameras.push(k as u32);
    }
    // Outliers: a random subset, each world point replaced by an independent one.
    let count = (fraction * n as f64).round() as usize;
    let mut order: Vec<usize> = (0..n).collect();
    for i in 0..count.min(n) {
        let j = rng.random_range(i..n);
        order.swap(i, j);
    }
    let mut outlier = vec![false; n];
    for &i in &order[..count.min(n)] {
        let k = rng.random_range(0..n_cams);
        let (m, depth) = draw(&mut rng);
        world[i] = world_to(&rig, k, m, depth);
        outlier[i] = true;
    }
    Case {
        seed,
        baseline,
        rig,
        world,
        pixels,
        cameras,
        outlier,
        truth,
    }
}

impl Case {
    fn problem(&self) -> Problem<'_> {
        Problem::rig(&self.world, &self.pixels, &self.cameras, &self.rig)
    }

    /// Rotation error (degrees) and rig-centre error (units) of `x_rig = r X + t`.
    fn errors(&self, r: &Matrix3<f64>, t: &Vector3<f64>) -> (f64, f64) {
        let rt = self.truth.rotation.to_rotation_matrix().into_inner();
        let tt = self.truth.translation.vector;
        let centre = -(r.transpose() * t);
        let centre_t = -(rt.transpose() * tt);
        (rot_err_deg(r, &rt), (centre - centre_t).norm())
    }

    fn to_json(&self) -> Value {
        let pose = |p: &Isometry3<f64>| {
            let q = p.rotation.quaternion();
            json!({
                "q_wxyz": [q.w, q.i, q.j, q.k],
                "t": [p.translation.vector.x, p.translation.vector.y, p.translation.vector.z],
                "R": rows(&p.rotation.to_rotation_matrix().into_inner()),
            })
        };
        json!({
            "seed": self.seed,
            "baseline": self.baseline,
            "cameras": self.rig.cameras().iter().map(|c| json!({
                "model": c.model().name(),
                "width": c.width(),
                "height": c.height(),
                "params": c.params(),
            })).collect::<Vec<_>>(),
            "cams_from_rig": self.rig.cam_from_rig().iter().map(pose).collect::<Vec<_>>(),
            "points2d": self.pixels.iter().map(|p| [p.x, p.y]).collect::<Vec<_>>(),
            "points3d": self.world.iter().map(|p| [p.x, p.y, p.z]).collect::<Vec<_>>(),
            "camera_idx": self.cameras,
            "outlier": self.outlier,
            "rig_from_world": pose(&self.truth),
        })
    }
}

fn rows(m: &Matrix3<f64>) -> [[f64; 3]; 3] {
    [0, 1, 2].map(|i| [m[(i, 0)], m[(i, 1)], m[(i, 2)]])
}

/// Median over passes of (time of one pass over `inputs`) / (number of inputs), milliseconds,
/// and every pass's value.
fn time_per_problem<T, R>(
    inputs: &[T],
    passes: usize,
    mut f: impl FnMut(&T) -> R,
) -> (f64, Vec<f64>) {
    let mut per: Vec<f64> = (0..passes)
        .map(|_| {
            let t0 = Instant::now();
            for x in inputs {
                black_box(f(black_box(x)));
            }
            t0.elapsed().as_secs_f64() * 1e3 / inputs.len() as f64
        })
        .collect();
    let all = per.clone();
    per.sort_by(f64::total_cmp);
    (per[per.len() / 2], all)
}

fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let n = s.len();
    if n % 2 == 1 {
        s[n / 2]
    } else {
        0.5 * (s[n / 2 - 1] + s[n / 2])
    }
}

fn max(v: &[f64]) -> f64 {
    v.iter().copied().fold(f64::NEG_INFINITY, f64::max)
}

struct Args {
    problems: usize,
    n: usize,
    levels: Vec<f64>,
    seed: u64,
    threshold: f64,
    passes: usize,
    sigma: f64,
    export: Option<String>,
    solve_problems: usize,
    solve_passes: usize,
    ransac: bool,
    solve: bool,
}

fn fail(message: &str) -> ! {
    eprintln!("rig_compare: {message}");
    std::process::exit(2)
}

fn parse_args() -> Args {
    let mut a = Args {
        problems: 200,
        n: 200,
        levels: vec![0.0, 0.5, 0.8],
        seed: 42,
        threshold: 4.0,
        passes: 3,
        sigma: 1.0,
        export: None,
        solve_problems: 200,
        solve_passes: 15,
        ransac: true,
        solve: true,
    };
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        let mut value = || {
            it.next()
                .unwrap_or_else(|| fail(&format!("{flag} needs a value")))
        };
        let num = |s: String| -> f64 {
            s.parse()
                .unwrap_or_else(|_| fail(&format!("bad number {s}")))
        };
        match flag.as_str() {
            "--problems" => a.problems = num(value()) as usize,
            "--n" => a.n = num(value()) as usize,
            "--levels" => a.levels = value().split(',').map(|s| num(s.to_string())).collect(),
            "--seed" => a.seed = num(value()) as u64,
            "--threshold" => a.threshold = num(value()),
            "--passes" => a.passes = num(value()) as usize,
            "--sigma" => a.sigma = num(value()),
            "--export" => a.export = Some(value()),
            "--solve-problems" => a.solve_problems = num(value()) as usize,
            "--solve-passes" => a.solve_passes = num(value()) as usize,
            "--only" => match value().as_str() {
                "ransac" => a.solve = false,
                "solve" => a.ransac = false,
                other => fail(&format!("--only ransac|solve, not {other}")),
            },
            "-h" | "--help" => {
                println!("see the top of examples/rig_compare.rs");
                std::process::exit(0)
            }
            other => fail(&format!("unknown option {other}")),
        }
    }
    if a.problems == 0 || a.passes == 0 || a.solve_problems == 0 || a.solve_passes == 0 {
        fail("--problems, --passes, --solve-problems and --solve-passes must be positive");
    }
    a
}

/// The seed of problem `i` of level `level` (the outlier fraction in thousandths, so that a
/// level's problems do not depend on the other levels asked for).
fn case_seed(base: u64, level: usize, i: usize) -> u64 {
    common::splitmix64(base ^ common::splitmix64(((level as u64) << 32) | i as u64))
}

fn ransac_level(a: &Args, fraction: f64) -> Value {
    let level_key = (fraction * 1000.0).round() as usize;
    let cases: Vec<Case> = (0..a.problems)
        .map(|i| {
            generate(
                case_seed(a.seed, level_key, i),
                2 + i % 5,
                Models::Mixed(i % MODELS.len()),
                a.n,
                a.sigma,
                fraction,
            )
        })
        .collect();
    let solver = Solver::default();
    let ransac = |i: usize| {
        Ransac::default()
            .threshold_px(a.threshold)
            .seed(problem_seed(a.seed, i))
    };
    let mut results = Vec::new();
    let (mut rot, mut centre, mut floor_rot) = (Vec::new(), Vec::new(), Vec::new());
    let mut failures = 0;
    for (i, c) in cases.iter().enumerate() {
        let got = ransac(i).estimate(&solver, &c.problem());
        let (er, ec, inliers, wrong) = match &got {
            Ok(s) => {
                let (er, ec) = c.errors(&s.solution.rotation, &s.solution.translation);
                let wrong = s
                    .inliers
                    .iter()
                    .zip(&c.outlier)
                    .filter(|(a, b)| **a && **b)
                    .count();
                (er, ec, s.num_inliers, wrong)
            }
            Err(_) => (f64::INFINITY, f64::INFINITY, 0, 0),
        };
        if er.is_nan() || er > 5.0 {
            failures += 1;
        }
        // The floor: the solve of the problem without its outliers.
        let keep: Vec<usize> = (0..c.world.len()).filter(|&j| !c.outlier[j]).collect();
        let w: Vec<_> = keep.iter().map(|&j| c.world[j]).collect();
        let p: Vec<_> = keep.iter().map(|&j| c.pixels[j]).collect();
        let k: Vec<_> = keep.iter().map(|&j| c.cameras[j]).collect();
        let fr = solver
            .solve(&Problem::rig(&w, &p, &k, &c.rig))
            .map_or(f64::INFINITY, |s| c.errors(&s.rotation, &s.translation).0);
        rot.push(er);
        centre.push(ec);
        floor_rot.push(fr);
        results.push(json!({
            "ok": got.is_ok(),
            "rotation_error_deg": if er.is_finite() { json!(er) } else { Value::Null },
            "centre_error": if ec.is_finite() { json!(ec) } else { Value::Null },
            "inliers": inliers,
            "wrong_inliers": wrong,
            "floor_rotation_error_deg": if fr.is_finite() { json!(fr) } else { Value::Null },
        }));
    }
    let (ms, passes) = time_per_problem(&(0..cases.len()).collect::<Vec<_>>(), a.passes, |&i| {
        ransac(i).estimate(&solver, &cases[i].problem()).ok()
    });
    println!(
        "{:>5.0}% {:>7} {:>5} | {:>9.4} {:>9.4} {:>9.4} | {:>9.4} | {:>8.3}  ({})",
        100.0 * fraction,
        cases.len(),
        failures,
        median(&rot),
        max(&rot),
        median(&floor_rot),
        median(&centre),
        ms,
        passes
            .iter()
            .map(|x| format!("{x:.3}"))
            .collect::<Vec<_>>()
            .join(" ")
    );
    json!({
        "outliers": fraction,
        "eopnp": {
            "ms_per_problem": ms,
            "pass_ms": passes,
            "results": results,
        },
        "problems": cases.iter().map(Case::to_json).collect::<Vec<_>>(),
    })
}

/// One row of the solve table: a label, the problems and how to solve one.
struct SolveRow {
    label: String,
    kind: &'static str,
    solve: Box<dyn Fn(usize) -> bool>,
    len: usize,
    errors: Vec<f64>,
}

fn solve_rows(a: &Args) {
    const N: usize = 100;
    let m = a.solve_problems;
    let mut rows: Vec<SolveRow> = Vec::new();
    // The central solve of normalised points: `cargo bench --bench solve`'s problems (sigma 1).
    let central: Vec<common::Problem> = (0..m)
        .map(|i| {
            common::Problem::generate(&common::ProblemOptions {
                n: N,
                sigma_px: 1.0,
                scene: common::Scene::General,
                rotation: common::RotationKind::Uniform,
                seed: case_seed(a.seed ^ 0x5017e, 0, i),
            })
        })
        .collect();
    let errors = central
        .iter()
        .map(|p| {
            Solver::default()
                .solve(&Problem::normalised(&p.world, &p.image))
                .map_or(f64::INFINITY, |s| rot_err_deg(&s.rotation, &p.r_gt))
        })
        .collect();
    rows.push(SolveRow {
        label: "central, normalised points".into(),
        kind: "normalised",
        len: m,
        errors,
        solve: Box::new(move |i| {
            let p = &central[i];
            Solver::default()
                .solve(&Problem::normalised(
                    black_box(&p.world),
                    black_box(&p.image),
                ))
                .is_ok()
        }),
    });
    for (models, kind) in [
        (Models::Pinhole, "pinhole"),
        (Models::Distorting(0), "distorting"),
    ] {
        for cams in [1usize, 2, 4, 6] {
            let cases: Vec<Case> = (0..m)
                .map(|i| {
                    // One camera: SIMPLE_RADIAL and OPENCV alternating over the problems, as
                    // over a rig's cameras.
                    let models = match models {
                        Models::Distorting(_) if cams == 1 => Models::Distorting(i % 2),
                        m => m,
                    };
                    generate(
                        case_seed(a.seed ^ 0x501e, cams, i),
                        cams,
                        models,
                        N,
                        1.0,
                        0.0,
                    )
                })
                .collect();
            let errors = cases
                .iter()
                .map(|c| {
                    let sol = if cams == 1 {
                        Solver::default()
                            .solve(&Problem::pixels(&c.world, &c.pixels, &c.rig.cameras()[0]))
                            .map(|s| c.rig.cam_from_rig()[0].inverse() * s.pose())
                    } else {
                        Solver::default().solve(&c.problem()).map(|s| s.pose())
                    };
                    sol.map_or(f64::INFINITY, |p| {
                        c.errors(
                            p.rotation.to_rotation_matrix().matrix(),
                            &p.translation.vector,
                        )
                        .0
                    })
                })
                .collect();
            let label = if cams == 1 {
                format!("central, pixels, {kind}")
            } else {
                format!("rig, {cams} cameras, {kind}")
            };
            rows.push(SolveRow {
                label,
                kind,
                len: m,
                errors,
                solve: Box::new(move |i| {
                    let c = &cases[i];
                    if cams == 1 {
                        Solver::default()
                            .solve(&Problem::pixels(
                                black_box(&c.world),
                                black_box(&c.pixels),
                                &c.rig.cameras()[0],
                            ))
                            .is_ok()
                    } else {
                        Solver::default().solve(black_box(&c.problem())).is_ok()
                    }
                }),
            });
        }
    }
    // Interleaved passes: each pass times every row once.
    let mut times: Vec<Vec<f64>> = vec![Vec::new(); rows.len()];
    for _ in 0..a.solve_passes {
        for (r, row) in rows.iter().enumerate() {
            let t0 = Instant::now();
            for i in 0..row.len {
                black_box((row.solve)(black_box(i)));
            }
            times[r].push(t0.elapsed().as_secs_f64() * 1e6 / row.len as f64);
        }
    }
    let us: Vec<f64> = times.iter().map(|t| median(t)).collect();
    println!(
        "\nSolve at N = 100 (Solver::default(), sigma 1 px, {m} problems per row; microseconds per \
         solve, median of {} interleaved passes):\n",
        a.solve_passes
    );
    println!(
        "| row | median rot err (deg) | max rot err (deg) | us per solve | / central normalised | / central pixels, same cameras |"
    );
    println!("|---|---|---|---|---|---|");
    for (r, row) in rows.iter().enumerate() {
        let pixel_ref = rows
            .iter()
            .position(|o| o.kind == row.kind && o.label.starts_with("central, pixels"));
        let same = pixel_ref.map_or("".to_string(), |p| format!("{:.2}x", us[r] / us[p]));
        println!(
            "| {} | {:.4} | {:.4} | {:.1} | {:.2}x | {} |",
            row.label,
            median(&row.errors),
            max(&row.errors),
            us[r],
            us[r] / us[0],
            same
        );
    }
    // The slowest rig row against the central normalised solve, and against the central pixel
    // solve through the same kind of cameras.
    let (mut worst_norm, mut worst_same) = (0.0f64, 0.0f64);
    for (r, row) in rows.iter().enumerate() {
        if !row.label.starts_with("rig") {
            continue;
        }
        worst_norm = worst_norm.max(us[r] / us[0]);
        if let Some(p) = rows
            .iter()
            .position(|o| o.kind == row.kind && o.label.starts_with("central, pixels"))
        {
            worst_same = worst_same.max(us[r] / us[p]);
        }
    }
    let verdict = |w: f64| if w <= 2.0 { "met" } else { "missed" };
    println!(
        "\nTarget: the rig solve within 2x the central default solve at N = 100. Against the \
         central solve of pixels through the same camera models: {} (the slowest rig row \
         {worst_same:.2}x); against the central solve of normalised points: {} (the slowest \
         rig row {worst_norm:.2}x)",
        verdict(worst_same),
        verdict(worst_norm)
    );
}

fn main() {
    let a = parse_args();
    if a.ransac {
        println!(
            "RANSAC on rigs: {} problems per level, N = {}, 2-6 cameras, sigma {} px, threshold {} px, \
             seed {}; ms per problem: median of {} passes, one thread\n",
            a.problems, a.n, a.sigma, a.threshold, a.seed, a.passes
        );
        println!(
            "{:>6} {:>7} {:>5} | {:>9} {:>9} {:>9} | {:>9} | {:>8}  (passes)",
            "outl", "problems", "fail", "rot med", "rot max", "floor med", "centre med", "ms"
        );
        let mut levels = Vec::new();
        for &f in &a.levels {
            levels.push(ransac_level(&a, f));
        }
        if let Some(path) = &a.export {
            let doc = json!({
                "generator": "examples/rig_compare.rs",
                "seed": a.seed,
                "n": a.n,
                "sigma_px": a.sigma,
                "threshold_px": a.threshold,
                "passes": a.passes,
                "levels": levels,
            });
            std::fs::write(path, serde_json::to_string(&doc).expect("json"))
                .unwrap_or_else(|e| fail(&format!("{path}: {e}")));
        }
    }
    if a.solve {
        solve_rows(&a);
    }
}
