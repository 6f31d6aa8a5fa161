//! Writes the reference file of the C and C++ tests (`tests/c/`, `tests/cpp/`): synthetic
//! problems and the poses the Rust library (`eopnp::Solver`, `eopnp::ransac::Ransac`) gives
//! them, every double as the hexadecimal of its bits, so that the tests can check that the C
//! and C++ interfaces return the library's result bit for bit.
//!
//! `cargo run --release -p eopnp-capi --example reference_poses -- FILE` (the CMake project runs
//! it before the tests). The file is written atomically (a temporary file, then a rename).
//!
//! Each case: a line `case KIND N`, then lines `world` (3 N), `image` (2 N), `weights` (N),
//! `prior` (12: the row-major rotation and the translation of an initial pose), `rotation` (9),
//! `translation` (3), `cost` (1), `covariance` (36, zeros without one), `mask` (N, 0 or 1).
//! KIND (the options each case uses, which the C and C++ tests set the same way):
//!
//! 0: normalised points, default solver.
//! 1: pixels through COLMAP's OPENCV camera 800 810 320 240 -0.05 0.01 1e-3 -5e-4.
//! 2: as 1 with weights, a Huber loss of scale 2 px, and the covariance with sigma 1 px.
//! 3: normalised points, algebraic refinement.
//! 4: normalised points, refinement from the prior pose.
//! 5: RANSAC on normalised points with outliers, focal 800 px, threshold 2 px, seed 9.
//! 6: pixels through OpenCV's K = [800 0 320; 0 810 240; 0 0 1] and distortion
//!    (-0.1, 0.02, 1e-3, -5e-4, 0.001), strided arrays in the C test.

#[path = "../tests/support/problems.rs"]
mod problems;

use std::fmt::Write as _;

use eopnp::camera::Camera;
use eopnp::covariance::NoiseModel;
use eopnp::ransac::Ransac;
use eopnp::{Loss, Problem, Refinement, Solution, Solver};
use nalgebra::{Isometry3, Matrix3, Point2, Rotation3, Translation3, UnitQuaternion, Vector3};
use problems::{flat2, flat3, opencv_camera, synthetic};

fn line(out: &mut String, name: &str, values: &[f64]) {
    out.push_str(name);
    for v in values {
        write!(out, " {:016x}", v.to_bits()).unwrap();
    }
    out.push('\n');
}

fn pose_rows(r: &Matrix3<f64>, t: &Vector3<f64>) -> Vec<f64> {
    let mut v = Vec::with_capacity(12);
    for i in 0..3 {
        for j in 0..3 {
            v.push(r[(i, j)]);
        }
    }
    v.extend_from_slice(t.as_slice());
    v
}

fn main() {
    let path = std::env::args()
        .nth(1)
        .expect("usage: reference_poses FILE");
    let colmap = opencv_camera();
    let k = Matrix3::new(800.0, 0.0, 320.0, 0.0, 810.0, 240.0, 0.0, 0.0, 1.0);
    let opencv = Camera::from_opencv(&k, &[-0.1, 0.02, 1e-3, -5e-4, 0.001]).unwrap();
    let mut out = String::new();
    let mut case = 0u64;
    for kind in 0..7u32 {
        for n in [4usize, 10, 100] {
            case += 1;
            let n = if kind == 5 { n.max(30) } else { n };
            let noise = if kind == 5 { 5e-4 } else { 1e-3 };
            let s = synthetic(1000 + case, n, noise);
            let mut image = s.normalised.clone();
            if kind == 5 {
                for m in image.iter_mut().take(n / 5) {
                    m.x += 0.2;
                }
            }
            let weights: Vec<f64> = if kind == 2 {
                (0..n).map(|i| 0.5 + (i % 3) as f64).collect()
            } else {
                vec![1.0; n]
            };
            let prior_q = UnitQuaternion::from_rotation_matrix(&s.rotation)
                * UnitQuaternion::from_euler_angles(0.01, -0.02, 0.01);
            let prior_r = prior_q.to_rotation_matrix().into_inner();
            let prior_t = s.translation + Vector3::new(0.02, -0.01, 0.05);
            let prior = pose_rows(&prior_r, &prior_t);
            let cam = if kind == 6 { &opencv } else { &colmap };
            let pixels: Vec<Point2<f64>> = image.iter().map(|m| cam.project(*m)).collect();
            let obs = if matches!(kind, 1 | 2 | 6) {
                &pixels
            } else {
                &image
            };
            let problem = match kind {
                1 | 2 | 6 => Problem::pixels(&s.world, &pixels, cam),
                _ => Problem::normalised(&s.world, &image),
            };
            let problem = if kind == 2 {
                problem.weights(&weights)
            } else {
                problem
            };
            let mut mask = vec![1.0; n];
            let sol: Result<Solution, _> = match kind {
                2 => Solver::default()
                    .loss(Loss::Huber(2.0))
                    .covariance(Some(NoiseModel::Sigma(1.0)))
                    .solve(&problem),
                3 => Solver::default()
                    .refinement(Refinement::Algebraic)
                    .solve(&problem),
                4 => {
                    // The isometry the interfaces build from the row-major matrix.
                    let m = Matrix3::from_row_slice(&prior[..9]);
                    let q =
                        UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(m));
                    let iso = Isometry3::from_parts(
                        Translation3::new(prior[9], prior[10], prior[11]),
                        UnitQuaternion::new_normalize(q.into_inner()),
                    );
                    Solver::default().refine(&problem, &iso)
                }
                5 => Ransac::default()
                    .threshold_px(2.0)
                    .seed(9)
                    .estimate(&Solver::default(), &problem.focal(800.0, 800.0))
                    .map(|r| {
                        mask = r.inliers.iter().map(|b| f64::from(u8::from(*b))).collect();
                        r.solution
                    }),
                _ => Solver::default().solve(&problem),
            };
            let sol = match sol {
                Ok(sol) => sol,
                Err(e) => panic!("case {case} (kind {kind}, n {n}): {e}"),
            };
            writeln!(out, "case {kind} {n}").unwrap();
            line(&mut out, "world", &flat3(&s.world));
            line(&mut out, "image", &flat2(obs));
            line(&mut out, "weights", &weights);
            line(&mut out, "prior", &prior);
            let rt = pose_rows(&sol.rotation, &sol.translation);
            line(&mut out, "rotation", &rt[..9]);
            line(&mut out, "translation", &rt[9..]);
            line(&mut out, "cost", &[sol.cost]);
            let mut cov = vec![0.0; 36];
            if let Some(c) = &sol.covariance {
                for i in 0..6 {
                    for j in 0..6 {
                        cov[6 * i + j] = c.matrix[(i, j)];
                    }
                }
            }
            line(&mut out, "covariance", &cov);
            out.push_str("mask");
            for m in &mask {
                write!(out, " {}", *m as u8).unwrap();
            }
            out.push('\n');
        }
    }
    let tmp = format!("{path}.tmp");
    std::fs::write(&tmp, out).expect("write the temporary file");
    std::fs::rename(&tmp, &path).expect("rename it");
    println!("wrote {case} cases to {path}");
}
