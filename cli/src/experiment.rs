//! The outlier experiment of `eopnp register --outliers`: wrong 3D points injected into an
//! image's correspondences, the pose re-estimated (robustly with `--ransac`), and the floor
//! (EOPnP on the true correspondences alone) to compare it with. Part of the command line
//! only, not of the library.

use std::time::Instant;

use eopnp::camera::Camera;
use eopnp::colmap::{Model, RegisterError};
use eopnp::ransac::{Ransac, RansacSolution};
use eopnp::{Solution, Solver};
use nalgebra::{Matrix3, Point2, Point3, Vector3};
use rand_core::{RngCore, SeedableRng};
use rand_pcg::Pcg64;

use crate::report::{Estimate, FocalEstimate};
use crate::solve::camera_with_focal;

/// Replaces `round(fraction * N)` of the correspondences' world points, chosen uniformly
/// without replacement, by wrong ones: a uniformly chosen point of `cloud` plus Gaussian noise
/// of standard deviation `noise` in each coordinate, all drawn from a PCG generator seeded with
/// `seed`. Returns the mask of the **true** (unchanged) correspondences. A test and
/// benchmarking tool (`eopnp register --outliers`); `fraction` is clamped to `[0, 1]`, an
/// empty cloud changes nothing.
pub(crate) fn inject_outliers(
    world: &mut [Point3<f64>],
    cloud: &[Point3<f64>],
    fraction: f64,
    noise: f64,
    seed: u64,
) -> Vec<bool> {
    let n = world.len();
    let mut truth = vec![true; n];
    if cloud.is_empty() || fraction.is_nan() || fraction <= 0.0 {
        return truth;
    }
    let k = ((fraction.min(1.0) * n as f64).round() as usize).min(n);
    let mut rng = Pcg64::seed_from_u64(seed);
    let mut order: Vec<usize> = (0..n).collect();
    // LaneSums Fisher-Yates: the first k entries are a uniform k-subset.
    for i in 0..k {
        let j = i + index(&mut rng, n - i);
        order.swap(i, j);
    }
    let noise = if noise.is_finite() { noise.abs() } else { 0.0 };
    for &i in &order[..k] {
        let p = cloud[index(&mut rng, cloud.len())];
        let d = Vector3::new(normal(&mut rng), normal(&mut rng), normal(&mut rng)) * noise;
        world[i] = p + d;
        truth[i] = false;
    }
    truth
}

/// The per-image seed of [`register_image`]'s outlier injection: `seed` mixed with the image
/// id (SplitMix64 finaliser), so images get independent wrong points.
#[must_use]
pub(crate) fn image_seed(seed: u64, image_id: u32) -> u64 {
    let mut z = seed ^ u64::from(image_id).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Injected outliers for [`register_image`] (see [`inject_outliers`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Outliers {
    /// Fraction of each image's correspondences replaced by wrong 3D points.
    pub fraction: f64,
    /// Standard deviation of the noise added to the wrong points (model units).
    pub noise: f64,
    /// Seed (mixed with the image id, [`image_seed`]).
    pub seed: u64,
}

/// One image's 2D-3D problem of a model, with injected outliers.
#[derive(Clone, Debug)]
#[non_exhaustive]
pub(crate) struct ImageProblem {
    /// World points (wrong ones where `truth` is false).
    pub world: Vec<Point3<f64>>,
    /// Observed pixels.
    pub pixels: Vec<Point2<f64>>,
    /// `truth[i]`: correspondence `i` is the model's (not replaced).
    pub truth: Vec<bool>,
}

/// The correspondences of image `image_id` ([`Model::correspondences`]) with
/// `outliers.fraction` of them replaced by random points of the model's cloud plus noise.
#[must_use]
pub(crate) fn image_problem(
    model: &Model,
    image_id: u32,
    outliers: Option<&Outliers>,
) -> ImageProblem {
    let (mut world, pixels) = model.correspondences(image_id);
    let truth = match outliers {
        Some(o) => {
            let cloud: Vec<Point3<f64>> = model.points.values().map(|p| p.xyz).collect();
            inject_outliers(
                &mut world,
                &cloud,
                o.fraction,
                o.noise,
                image_seed(o.seed, image_id),
            )
        }
        None => vec![true; world.len()],
    };
    ImageProblem {
        world,
        pixels,
        truth,
    }
}

/// The problem of `pixels` through the model's camera `cam`, or, with `guess`, through the
/// guess with the focal length unknown ([`eopnp::Problem::unknown_focal`]).
pub(crate) fn pixel_problem<'a>(
    world: &'a [Point3<f64>],
    pixels: &'a [Point2<f64>],
    cam: &'a Camera,
    guess: Option<&'a Camera>,
) -> eopnp::Problem<'a> {
    match guess {
        Some(g) => eopnp::Problem::pixels(world, pixels, g).unknown_focal(),
        None => eopnp::Problem::pixels(world, pixels, cam),
    }
}

/// The model's camera `cam` with its focal length(s) multiplied by `scale`: the starting guess
/// of `register --unknown-focal --focal-guess-scale`.
///
/// # Errors
/// [`RegisterError::Solver`] (`InvalidOption("unknown_focal")`) if the scaled focal length is
/// not a finite positive number.
pub(crate) fn focal_guess(cam: &Camera, scale: f64) -> Result<Camera, RegisterError> {
    let (fx, fy) = cam.focal_lengths();
    camera_with_focal(cam, (fx * scale, fy * scale)).map_err(|_| {
        RegisterError::Solver(eopnp::PnpError::InvalidOption {
            option: "unknown_focal",
        })
    })
}

/// RANSAC ([`Ransac::estimate`] of the pixels) on the image's correspondences, optionally with
/// injected outliers ([`image_problem`]), through the model's camera or with an unknown focal
/// length from `guess`.
/// `estimate.inliers` is the RANSAC inlier count; the pixel RMSEs are over the true
/// correspondences.
///
/// # Errors
/// As [`eopnp::colmap::register_image`].
pub(crate) fn ransac_on_problem(
    model: &Model,
    image_id: u32,
    problem: &ImageProblem,
    ransac: &Ransac,
    solver: &Solver,
    guess: Option<&Camera>,
) -> Result<(Estimate, RansacSolution), RegisterError> {
    let (_, cam) = model.image_and_camera(image_id)?;
    let sol = ransac.estimate(
        solver,
        &pixel_problem(&problem.world, &problem.pixels, cam, guess),
    )?;
    let mut reg = estimate(model, image_id, problem, &sol.solution, sol.num_inliers)?;
    reg.micros = sol.stats.micros;
    reg.ransac = Some(sol.stats);
    Ok((reg, sol))
}

/// The [`Estimate`] of `solution` for image `image_id`: errors against the model's pose (as
/// the library's `Registration` measures them), pixel RMSEs over the true correspondences of
/// `problem` (the estimate's through the estimated camera when the solution estimated the focal
/// length, with its error against the model's).
///
/// # Errors
/// [`RegisterError::UnknownImage`], [`RegisterError::UnknownCamera`].
pub(crate) fn estimate(
    model: &Model,
    image_id: u32,
    problem: &ImageProblem,
    solution: &Solution,
    inliers: usize,
) -> Result<Estimate, RegisterError> {
    let (img, cam) = model.image_and_camera(image_id)?;
    let (r_ref, t_ref) = img.pose();
    let r = solution.rotation;
    let t = solution.translation;
    let rmse = |cam: &Camera, r: &Matrix3<f64>, t: &Vector3<f64>| true_rmse(cam, problem, r, t);
    let (estimated_cam, focal) = match solution.camera {
        Some(estimated) => {
            let f = estimated.focal_lengths();
            let model_f = cam.focal_lengths();
            let error = |e: f64, m: f64| 100.0 * (e - m).abs() / m;
            let focal = FocalEstimate {
                estimated: f,
                model: model_f,
                error_pct: error(f.0, model_f.0).max(error(f.1, model_f.1)),
            };
            (Some(estimated), Some(focal))
        }
        None => (None, None),
    };
    Ok(Estimate {
        n: problem.world.len(),
        inliers,
        skipped: solution.skipped,
        ransac: None,
        solution: *solution,
        rotation_error_deg: rotation_error_deg(&r, &r_ref),
        translation_error_pct: 100.0 * (t - t_ref).norm() / t_ref.norm(),
        rmse_px: rmse(estimated_cam.as_ref().unwrap_or(cam), &r, &t),
        model_rmse_px: rmse(cam, &r_ref, &t_ref),
        micros: 0.0,
        focal,
    })
}

/// The largest angle, in degrees, between corresponding columns of two rotations, each as
/// `atan2(|a x b|, a . b)`: the paper's metric, as the library reports it.
fn rotation_error_deg(a: &Matrix3<f64>, b: &Matrix3<f64>) -> f64 {
    (0..3)
        .map(|k| {
            let (x, y) = (a.column(k), b.column(k));
            x.cross(&y).norm().atan2(x.dot(&y))
        })
        .fold(0.0, f64::max)
        .to_degrees()
}

/// RMS pixel reprojection error of pose `(r, t)` through the camera over the true
/// correspondences of `problem` (NaN if there is none).
fn true_rmse(cam: &Camera, problem: &ImageProblem, r: &Matrix3<f64>, t: &Vector3<f64>) -> f64 {
    let (mut sum, mut count) = (0.0, 0usize);
    for ((x, u), ok) in problem
        .world
        .iter()
        .zip(&problem.pixels)
        .zip(&problem.truth)
    {
        if *ok {
            let p = r * x.coords + t;
            sum += (cam.project(Point2::new(p.x / p.z, p.y / p.z)) - u).norm_squared();
            count += 1;
        }
    }
    (sum / count as f64).sqrt()
}

/// A uniform index in `0..n` from one draw (Lemire's multiply-shift), as the library's RANSAC
/// draws its samples.
fn index(rng: &mut Pcg64, n: usize) -> usize {
    ((u128::from(rng.next_u64()) * n as u128) >> 64) as usize
}

/// The floor of an image problem: EOPnP ([`Solver::solve`] of the pixels with `solver`) on the
/// true correspondences only, as an [`Estimate`] (with `guess`, the focal length unknown too).
///
/// # Errors
/// As [`eopnp::colmap::register_image`].
pub(crate) fn floor(
    model: &Model,
    image_id: u32,
    problem: &ImageProblem,
    solver: &Solver,
    guess: Option<&Camera>,
) -> Result<Estimate, RegisterError> {
    let (_, cam) = model.image_and_camera(image_id)?;
    let (mut w, mut p) = (Vec::new(), Vec::new());
    for ((x, px), ok) in problem
        .world
        .iter()
        .zip(&problem.pixels)
        .zip(&problem.truth)
    {
        if *ok {
            w.push(*x);
            p.push(*px);
        }
    }
    let start = Instant::now();
    let sol = solver.solve(&pixel_problem(&w, &p, cam, guess))?;
    let micros = start.elapsed().as_secs_f64() * 1e6;
    let mut reg = estimate(model, image_id, problem, &sol, sol.used)?;
    reg.micros = micros;
    Ok(reg)
}

/// Standard normal deviate (Box-Muller on two uniform draws).
fn normal(rng: &mut Pcg64) -> f64 {
    let u1 = ((rng.next_u64() >> 11) as f64 + 0.5) / (1u64 << 53) as f64;
    let u2 = (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
    (-2.0 * u1.ln()).sqrt() * (core::f64::consts::TAU * u2).cos()
}
