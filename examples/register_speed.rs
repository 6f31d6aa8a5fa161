//! The speed of a registration against the solve, per image of a COLMAP model (by default the
//! bundled `data/colmap-boxes`).
//!
//! `cargo run --release --example register_speed -- [MODEL_DIR] [--calls K] [--runs R]`
//!
//! For each image, K times (default 30) one call of each, one after the other (interleaved, so
//! that the machine's drifts reach every row alike):
//!
//! - `solve`: [`Solver::solve`] on the image's correspondences already undistorted (computed
//!   once, outside the timing): "the solve on normalised points", the reference.
//! - `solve_pixels`: [`Solver::solve`] of their pixels through the image's camera
//!   (undistortion, the search on the undistorted points, the pixel-error refinement
//!   `refine_pixels`).
//! - `registrar`: [`Registrar::register`] by one registrar for the whole run (as
//!   `eopnp register` and `eopnp.register_images`): the gathering, `solve_pixels`, and the
//!   comparison with the model's pose (its pixel RMSE).
//! - `register_image`: [`register_image`], a table of the model's 3D points of its own.
//!
//! The fastest of the K calls per image is kept, and the images are summed; each row is given
//! with its ratio to `solve`, and then with the smallest and largest ratio of one image's
//! time to that image's solve. R runs (default 1) print two lines each.
//!
//! With `--part NAME` (one of the rows), only that row runs, each image once, for
//! `valgrind --tool=callgrind --toggle-collect='*register_speed*part*'`: the instructions of
//! that row over the model's images.

use eopnp::camera::Camera;
use eopnp::colmap::{read_model, register_image, Model, ReadOptions, Registrar};
use eopnp::Problem;
use eopnp::Solver;
use nalgebra::{Point2, Point3};
use std::hint::black_box;
use std::time::Instant;

/// One image: its id, the correspondences (world points and pixels), those whose pixel
/// undistorts (world points and undistorted pixels), and its camera.
struct Image<'m> {
    id: u32,
    world: Vec<Point3<f64>>,
    pixels: Vec<Point2<f64>>,
    solve_world: Vec<Point3<f64>>,
    normalised: Vec<Point2<f64>>,
    camera: &'m Camera,
}

const ROWS: [&str; 4] = ["solve", "solve_pixels", "registrar", "register_image"];

/// Row `row` on image `im` once (what is timed and what callgrind collects).
#[inline(never)]
fn part(row: usize, im: &Image, model: &Model, registrar: &mut Registrar, solver: &Solver) {
    match row {
        0 => {
            black_box(solver.solve(&Problem::normalised(
                black_box(&im.solve_world),
                black_box(&im.normalised),
            )))
            .ok();
        }
        1 => {
            black_box(solver.solve(&Problem::pixels(
                black_box(&im.world),
                black_box(&im.pixels),
                im.camera,
            )))
            .ok();
        }
        2 => {
            black_box(registrar.register(black_box(im.id), solver, None)).ok();
        }
        _ => {
            black_box(register_image(model, black_box(im.id), solver, None)).ok();
        }
    }
}

/// The message on standard error, and exit status 2.
fn fail(message: &str) -> ! {
    eprintln!("register_speed: {message}");
    std::process::exit(2)
}

fn main() {
    let mut dir = concat!(env!("CARGO_MANIFEST_DIR"), "/data/colmap-boxes").to_string();
    let (mut calls, mut runs, mut only) = (30usize, 1usize, None);
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut value = || {
            args.next()
                .unwrap_or_else(|| fail(&format!("{a} needs a value")))
        };
        let count = |v: String| match v.parse::<usize>() {
            Ok(k) if k > 0 => k,
            _ => fail(&format!("{a}: a positive number, got {v:?}")),
        };
        match a.as_str() {
            "--calls" => calls = count(value()),
            "--runs" => runs = count(value()),
            "--part" => {
                let name = value();
                only = Some(
                    ROWS.iter()
                        .position(|r| *r == name)
                        .unwrap_or_else(|| fail(&format!("--part: one of {ROWS:?}"))),
                );
            }
            _ => dir = a,
        }
    }
    let model = read_model(&dir, &ReadOptions::default()).unwrap_or_else(|e| fail(&e.to_string()));
    let images: Vec<Image> = model
        .images
        .keys()
        .map(|&id| {
            let (_, camera) = model
                .image_and_camera(id)
                .unwrap_or_else(|e| fail(&e.to_string()));
            let (world, pixels) = model.correspondences(id);
            // The solve's points: those whose pixel undistorts (a solve of pixels leaves the
            // others out too).
            let (solve_world, normalised) = world
                .iter()
                .zip(&pixels)
                .filter_map(|(w, px)| camera.undistort(*px).ok().map(|m| (*w, m)))
                .unzip();
            Image {
                id,
                world,
                pixels,
                solve_world,
                normalised,
                camera,
            }
        })
        .collect();
    let solver = Solver::default();
    let mut registrar = Registrar::new(&model);
    if let Some(row) = only {
        for im in &images {
            part(row, im, &model, &mut registrar, &solver);
        }
        return;
    }
    let n: usize = images.iter().map(|im| im.world.len()).sum();
    println!(
        "{dir}: {} images, {n} correspondences; per row the fastest of {calls} calls per image, \
         the images summed, microseconds (ratio to solve)",
        images.len()
    );
    for _ in 0..runs {
        let mut total = [0.0; ROWS.len()];
        // Per row, the smallest and largest ratio of an image's time to its solve's.
        let mut spread = [(f64::INFINITY, 0.0f64); ROWS.len()];
        for im in &images {
            let mut best = [f64::INFINITY; ROWS.len()];
            for _ in 0..calls {
                for (row, b) in best.iter_mut().enumerate() {
                    let start = Instant::now();
                    part(row, im, &model, &mut registrar, &solver);
                    *b = b.min(start.elapsed().as_secs_f64() * 1e6);
                }
            }
            for ((t, s), b) in total.iter_mut().zip(&mut spread).zip(best) {
                *t += b;
                *s = (s.0.min(b / best[0]), s.1.max(b / best[0]));
            }
        }
        let line: Vec<String> = ROWS
            .iter()
            .zip(total)
            .map(|(name, t)| format!("{name} {t:.1} ({:.2}x)", t / total[0]))
            .collect();
        println!("{}", line.join("  "));
        let line: Vec<String> = ROWS
            .iter()
            .zip(spread)
            .skip(1)
            .map(|(name, (lo, hi))| format!("{name} {lo:.2}-{hi:.2}x"))
            .collect();
        println!("  per image: {}", line.join("  "));
    }
}
