//! The cost of the C call: `eopnp_solve` (the exported function, through `EopnpProblem`, its
//! checks and `catch_unwind`, the result written to an `EopnpSolution`) against
//! `Solver::solve` on the same problem, N = 10, normalised and pixel input. Rounds of 1000
//! calls of each, interleaved; the median over the rounds of the mean time per call.
//!
//! `cargo run --release -p eopnp-capi --example overhead [-- ROUNDS]` (docs/c-cpp.md).

#[path = "../tests/support/problems.rs"]
mod problems;

use std::hint::black_box;
use std::ptr;
use std::time::Instant;

use eopnp::{Problem, Solver};
use eopnp_capi::*;
use nalgebra::Point2;
use problems::{flat2, flat3, opencv_camera, synthetic};

const CALLS: u32 = 1000;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn per_call_ns(f: &mut dyn FnMut()) -> f64 {
    let t = Instant::now();
    for _ in 0..CALLS {
        f();
    }
    t.elapsed().as_secs_f64() * 1e9 / f64::from(CALLS)
}

fn main() {
    let rounds: usize = std::env::args()
        .nth(1)
        .map_or(200, |a| a.parse().expect("ROUNDS"));
    let s = synthetic(2026, 10, 1e-3);
    let cam = opencv_camera();
    let pixels: Vec<Point2<f64>> = s.normalised.iter().map(|m| cam.project(*m)).collect();
    let (w, m, px) = (flat3(&s.world), flat2(&s.normalised), flat2(&pixels));
    let solver = Solver::default();
    let mut handle = ptr::null_mut();
    let mut chandle = ptr::null_mut();
    let params = cam.params().to_vec();
    unsafe {
        assert_eq!(eopnp_solver_create(&mut handle), EopnpStatus::EOPNP_OK);
        assert_eq!(
            eopnp_camera_from_colmap(
                c"OPENCV".as_ptr(),
                640,
                480,
                params.as_ptr(),
                params.len(),
                &mut chandle
            ),
            EopnpStatus::EOPNP_OK
        );
    }
    let mut p = EopnpProblem {
        n: 10,
        world: w.as_ptr(),
        world_stride: 0,
        image: m.as_ptr(),
        image_stride: 0,
        weights: ptr::null(),
        camera: ptr::null(),
        rig: ptr::null(),
        rig_cameras: ptr::null(),
        focal_x: 0.0,
        focal_y: 0.0,
        gravity_camera: ptr::null(),
        gravity_world: ptr::null(),
        gravity_sigma_deg: 0.0,
        unknown_focal: false,
        focal_min_px: 0.0,
        focal_max_px: 0.0,
        refine_principal_point: false,
        refine_distortion: false,
    };
    // SAFETY: all-zero is a valid `EopnpSolution`.
    let mut out: EopnpSolution = unsafe { std::mem::zeroed() };
    println!("N = 10, {rounds} rounds of {CALLS} calls each, median of the per-call means\n");
    println!("| input | Rust Solver::solve (us) | C eopnp_solve (us) | C - Rust (us) |");
    println!("|---|---|---|---|");
    for (name, pixel) in [("normalised", false), ("pixels (OPENCV camera)", true)] {
        if pixel {
            p.image = px.as_ptr();
            p.camera = chandle;
        }
        let problem = if pixel {
            Problem::pixels(&s.world, &pixels, &cam)
        } else {
            Problem::normalised(&s.world, &s.normalised)
        };
        let (mut rust, mut c) = (Vec::new(), Vec::new());
        for _ in 0..rounds {
            rust.push(per_call_ns(&mut || {
                black_box(solver.solve(black_box(&problem)).unwrap());
            }));
            c.push(per_call_ns(&mut || {
                let st = unsafe { eopnp_solve(black_box(handle), black_box(&p), &mut out) };
                assert_eq!(st, EopnpStatus::EOPNP_OK);
                black_box(&out);
            }));
        }
        let (r, cc) = (median(rust) / 1e3, median(c) / 1e3);
        println!("| {name} | {r:.3} | {cc:.3} | {:+.3} |", cc - r);
    }
    unsafe {
        eopnp_camera_free(chandle);
        eopnp_solver_free(handle);
    }
}
