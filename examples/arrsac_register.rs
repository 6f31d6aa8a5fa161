//! rust-cv's ARRSAC driving eopnp's P3P (and, as a second row, the `lambda-twist` crate's P3P),
//! next to `eopnp::ransac`, on the problems of the command line's outlier experiment:
//!
//! ```text
//! for L in 0 0.5 0.8; do
//!   cargo run --release -- register data/colmap-boxes --outliers $L --seed 42 \
//!     --export-problems target/problems-$L.json
//! done
//! cargo run --release --features sample-consensus --example arrsac_register -- \
//!   target/problems-0.json target/problems-0.5.json target/problems-0.8.json
//! ```
//!
//! Each file holds every image's correspondences with the injected wrong 3D points of
//! `eopnp register --outliers L --seed S` (noise 0.5 model units, seed mixed with the image
//! id), the camera and COLMAP's pose. Then, per image:
//!
//! - `eopnp::ransac`: [`Ransac::estimate`] of the pixels (threshold 4 px, seed `S`);
//! - `arrsac + P3pEstimator`: the pixels are undistorted, ARRSAC ([`Arrsac::new`] with its
//!   default options, threshold 4 px on `PoseModel`'s pixel residual, a PCG generator seeded
//!   with `S`) finds the inliers, and EOPnP ([`Solver::solve`] of the pixels) refits on them;
//! - `arrsac + lambda-twist`: the same with `lambda_twist::LambdaTwist` (0.7) as the minimal
//!   solver. Its model's residual is cv-core's angular `1 - cos(angle)` between bearings, so
//!   the threshold is `1 - cos(4 px / f)` (`f` the geometric mean focal length): the same
//!   threshold at the image centre, slightly looser towards the corners.
//!
//! Printed per level and method: images solved (rotation error below 5 degrees), worst and
//! median rotation error (degrees, largest axis angle) and translation error (%) against
//! COLMAP's pose, and the median time per image (best of 3 runs per image, undistortion and
//! refit included).

use std::time::Instant;

use arrsac::Arrsac;
use eopnp::camera::Camera;
use eopnp::internals::metrics::{rotation_error_deg, translation_error_pct};
use eopnp::ransac::consensus::{Correspondence, P3pEstimator};
use eopnp::ransac::Ransac;
use eopnp::Solver;
use nalgebra::{Matrix3, Point2, Point3, Vector3};
use rand_core::SeedableRng;
use sample_consensus::Consensus;

/// Inlier threshold, pixels (the default of `eopnp register --threshold`).
const THRESHOLD_PX: f64 = 4.0;
/// Runs per image; the fastest is reported.
const REPEATS: usize = 3;
/// A pose with a larger rotation error counts as not solved.
const SOLVED_DEG: f64 = 5.0;

/// `rand_pcg::Pcg64` (rand_core 0.9) as a rand_core 0.6 generator, the version `arrsac` 0.10
/// uses.
struct Pcg06(rand_pcg::Pcg64);

impl rand_core_06::RngCore for Pcg06 {
    fn next_u32(&mut self) -> u32 {
        rand_core::RngCore::next_u32(&mut self.0)
    }
    fn next_u64(&mut self) -> u64 {
        rand_core::RngCore::next_u64(&mut self.0)
    }
    fn fill_bytes(&mut self, dest: &mut [u8]) {
        rand_core::RngCore::fill_bytes(&mut self.0, dest);
    }
    fn try_fill_bytes(&mut self, dest: &mut [u8]) -> Result<(), rand_core_06::Error> {
        rand_core::RngCore::fill_bytes(&mut self.0, dest);
        Ok(())
    }
}

fn arrsac_rng(seed: u64) -> Arrsac<Pcg06> {
    Arrsac::new(THRESHOLD_PX, Pcg06(rand_pcg::Pcg64::seed_from_u64(seed)))
}

#[derive(Clone, Copy, PartialEq)]
enum Method {
    Eopnp,
    ArrsacP3p,
    ArrsacLambdaTwist,
}

impl Method {
    fn label(self) -> &'static str {
        match self {
            Method::Eopnp => "eopnp::ransac",
            Method::ArrsacP3p => "arrsac + P3pEstimator",
            Method::ArrsacLambdaTwist => "arrsac + lambda-twist",
        }
    }
}

/// A world-to-camera pose `(R, t)`.
type Pose = (Matrix3<f64>, Vector3<f64>);

/// One image of an exported problem file.
struct Problem {
    camera: Camera,
    world: Vec<Point3<f64>>,
    pixels: Vec<Point2<f64>>,
    reference: Pose,
}

/// The images of a file written by `eopnp register --export-problems`, and its outlier level
/// and seed.
fn read_problems(path: &str) -> Result<(f64, u64, Vec<Problem>), String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{path}: {e}"))?;
    let v: serde_json::Value = serde_json::from_str(&text).map_err(|e| format!("{path}: {e}"))?;
    let num = |x: &serde_json::Value| x.as_f64().ok_or_else(|| format!("{path}: not a number"));
    let mut out = Vec::new();
    for img in v["images"].as_array().ok_or(format!("{path}: no images"))? {
        let c = &img["camera"];
        let params: Vec<f64> = c["params"]
            .as_array()
            .ok_or(format!("{path}: no params"))?
            .iter()
            .map(num)
            .collect::<Result<_, _>>()?;
        let camera = Camera::from_colmap(
            c["model"].as_str().unwrap_or(""),
            c["width"].as_u64().unwrap_or(0),
            c["height"].as_u64().unwrap_or(0),
            params,
        )
        .map_err(|e| format!("{path}: {e}"))?;
        let rows = |k: &str| -> Result<Vec<Vec<f64>>, String> {
            img[k]
                .as_array()
                .ok_or(format!("{path}: no {k}"))?
                .iter()
                .map(|r| {
                    r.as_array()
                        .ok_or(format!("{path}: {k}"))?
                        .iter()
                        .map(num)
                        .collect()
                })
                .collect()
        };
        let world = rows("points3d")?
            .iter()
            .map(|p| Point3::new(p[0], p[1], p[2]))
            .collect();
        let pixels = rows("points2d")?
            .iter()
            .map(|p| Point2::new(p[0], p[1]))
            .collect();
        let r = rows("reference_rotation")?;
        let t: Vec<f64> = img["reference_translation"]
            .as_array()
            .ok_or(format!("{path}: no reference_translation"))?
            .iter()
            .map(num)
            .collect::<Result<_, _>>()?;
        out.push(Problem {
            camera,
            world,
            pixels,
            reference: (
                Matrix3::from_fn(|i, j| r[i][j]),
                Vector3::new(t[0], t[1], t[2]),
            ),
        });
    }
    let level = v["outliers"].as_f64().unwrap_or(0.0);
    let seed = v["seed"].as_u64().unwrap_or(0);
    Ok((level, seed, out))
}

/// Pose `(R, t)` of one image by `method` (`None` if it failed) and the time in
/// milliseconds: `Ransac::estimate`'s own (undistortion included) for `eopnp::ransac`,
/// undistortion + ARRSAC + refit otherwise.
fn run(method: Method, problem: &Problem, seed: u64) -> (Option<Pose>, f64) {
    let solver = Solver::default();
    if method == Method::Eopnp {
        let ransac = Ransac::default().threshold_px(THRESHOLD_PX).seed(seed);
        return match ransac.estimate(
            &solver,
            &eopnp::Problem::pixels(&problem.world, &problem.pixels, &problem.camera),
        ) {
            Ok(sol) => (
                Some((sol.solution.rotation, sol.solution.translation)),
                sol.stats.micros * 1e-3,
            ),
            Err(_) => (None, f64::NAN),
        };
    }
    let start = Instant::now();
    let pose = run_arrsac(method, problem, seed, &solver);
    (pose, start.elapsed().as_secs_f64() * 1e3)
}

/// The ARRSAC rows of [`run`].
fn run_arrsac(method: Method, problem: &Problem, seed: u64, solver: &Solver) -> Option<Pose> {
    let cam = &problem.camera;
    let (fx, fy) = cam.focal_lengths();
    // Undistort; a pixel that cannot be undistorted is dropped (as `Ransac::estimate` does).
    let mut world: Vec<Point3<f64>> = Vec::new();
    let mut pixels: Vec<Point2<f64>> = Vec::new();
    let mut data: Vec<Correspondence> = Vec::new();
    for (x, px) in problem.world.iter().zip(&problem.pixels) {
        let Ok(nrm) = cam.undistort(*px) else {
            continue;
        };
        let j = cam.project_jacobian(nrm);
        let w = ((j[0] * j[3] - j[1] * j[2]) / (fx * fy)).abs();
        world.push(*x);
        pixels.push(*px);
        data.push(Correspondence {
            world: *x,
            image: nrm,
            pixel_scale: (w * fx * fy).sqrt(),
        });
    }
    let inliers: Vec<usize> = match method {
        Method::ArrsacP3p => {
            let mut arrsac = arrsac_rng(seed);
            arrsac.model_inliers(&P3pEstimator, data.iter().copied())?.1
        }
        _ => {
            use cv_core::nalgebra as na21;
            let f = (fx * fy).sqrt();
            let mut arrsac = arrsac_rng(seed).inlier_threshold(1.0 - (THRESHOLD_PX / f).cos());
            let lt: Vec<_> = data
                .iter()
                .map(|c| {
                    cv_core::FeatureWorldMatch(
                        na21::Unit::new_normalize(na21::Vector3::new(c.image.x, c.image.y, 1.0)),
                        cv_core::WorldPoint(na21::Vector4::new(
                            c.world.x, c.world.y, c.world.z, 1.0,
                        )),
                    )
                })
                .collect();
            arrsac
                .model_inliers(&lambda_twist::LambdaTwist::new(), lt.into_iter())?
                .1
        }
    };
    let w: Vec<Point3<f64>> = inliers.iter().map(|&i| world[i]).collect();
    let p: Vec<Point2<f64>> = inliers.iter().map(|&i| pixels[i]).collect();
    let sol = solver.solve(&eopnp::Problem::pixels(&w, &p, cam)).ok()?;
    Some((sol.rotation, sol.translation))
}

fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let m = v.len() / 2;
    if v.len() % 2 == 1 {
        v[m]
    } else {
        0.5 * (v[m - 1] + v[m])
    }
}

fn main() {
    let files: Vec<String> = std::env::args().skip(1).collect();
    if files.is_empty() {
        eprintln!("usage: arrsac_register PROBLEMS.json... (see the example's documentation)");
        std::process::exit(2);
    }
    println!(
        "threshold {THRESHOLD_PX} px; best of {REPEATS} runs per image\n\n{:>8}  {:<22} {:>6}  {:>9} {:>9}  {:>9} {:>9}  {:>8}",
        "outliers", "method", "solved", "rot max", "rot med", "tr% max", "tr% med", "ms/img"
    );
    for path in &files {
        let (level, seed, problems) = match read_problems(path) {
            Ok(p) => p,
            Err(e) => {
                eprintln!("{e}");
                std::process::exit(2);
            }
        };
        for method in [Method::Eopnp, Method::ArrsacP3p, Method::ArrsacLambdaTwist] {
            let (mut rot, mut tra, mut ms) = (Vec::new(), Vec::new(), Vec::new());
            let mut solved = 0;
            for problem in &problems {
                let (r_ref, t_ref) = problem.reference;
                let mut best = f64::INFINITY;
                let mut pose = None;
                for _ in 0..REPEATS {
                    let (p, t) = run(method, problem, seed);
                    pose = p;
                    best = best.min(t);
                }
                ms.push(best);
                let (re, te) = match pose {
                    Some((r, t)) => (
                        rotation_error_deg(&r, &r_ref),
                        translation_error_pct(&t, &t_ref),
                    ),
                    None => (f64::INFINITY, f64::INFINITY),
                };
                if re < SOLVED_DEG {
                    solved += 1;
                }
                rot.push(re);
                tra.push(te);
            }
            let max = |v: &[f64]| v.iter().copied().fold(0.0, f64::max);
            println!(
                "{:>7.0}%  {:<22} {:>3}/{:<2}  {:>9.4} {:>9.4}  {:>9.4} {:>9.4}  {:>8.2}",
                level * 100.0,
                method.label(),
                solved,
                problems.len(),
                max(&rot),
                median(&mut rot),
                max(&tra),
                median(&mut tra),
                median(&mut ms)
            );
        }
    }
}
