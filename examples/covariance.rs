//! Writes one noisy problem (N = 30, sigma = 1 px, pinhole f = 800 px), eopnp's pose and its
//! covariance for 1 px noise as JSON, for `scripts/covariance_vs_pycolmap.py`, which refines
//! the same pose with pycolmap and compares its `return_covariance=True` matrix.
//!
//! `cargo run --release --example covariance -- problem.json`

use eopnp::camera::Camera;
use eopnp::covariance::NoiseModel;
use eopnp::Solver;
use eopnp_testkit::{self as common, Problem, ProblemOptions, RotationKind, Scene};

fn main() {
    let out = std::env::args().nth(1).expect("usage: covariance OUT.json");
    let p = Problem::generate(&ProblemOptions {
        n: 30,
        sigma_px: 1.0,
        scene: Scene::General,
        rotation: RotationKind::Uniform,
        seed: common::trial_seed("covariance_example", 0),
    });
    let cam = Camera::pinhole(common::F, common::F, 320.0, 240.0).unwrap();
    let sol = Solver::default()
        .covariance(Some(NoiseModel::Sigma(1.0)))
        .solve(&eopnp::Problem::pixels(&p.world, &p.pixels, &cam))
        .unwrap();
    let c = sol.covariance.unwrap().matrix;
    let t = sol.translation;
    let json = serde_json::json!({
        "camera": {"model": "PINHOLE", "width": 640, "height": 480,
                   "params": [common::F, common::F, 320.0, 240.0]},
        "world": p.world.iter().map(|x| [x.x, x.y, x.z]).collect::<Vec<_>>(),
        "pixels": p.pixels.iter().map(|x| [x.x, x.y]).collect::<Vec<_>>(),
        "R": (0..3).map(|i| (0..3).map(|j| sol.rotation[(i, j)]).collect::<Vec<_>>()).collect::<Vec<_>>(),
        "t": [t.x, t.y, t.z],
        "covariance": (0..6).map(|i| (0..6).map(|j| c[(i, j)]).collect::<Vec<_>>()).collect::<Vec<_>>(),
    });
    std::fs::write(&out, json.to_string()).unwrap();
    println!("wrote {out}");
}
