//! `eopnp solve`'s output: the problem solved, the pose rendered as JSON.

use eopnp::{PnpError, Solver};
use nalgebra::Point2;
use serde_json::json;

use crate::input::Problem;
use crate::Failure;

/// Solves the problem and renders the pose JSON.
pub fn solve(p: &Problem, solver: &Solver) -> Result<String, Failure> {
    // Undistortion failures are input errors here (a solve would skip the point).
    for (k, px) in p.pixels.iter().enumerate() {
        p.camera
            .undistort(*px)
            .map_err(|e| Failure::input(format!("correspondence {}: {e}", k + 1)))?;
    }
    let sol = solver
        .solve(&eopnp::Problem::pixels(&p.world, &p.pixels, &p.camera))
        .map_err(|e| {
            // Degenerate or malformed input is the input's problem (exit 2); only a numerical
            // failure on valid input is the solver's (exit 1).
            let message = format!("no pose: {e}");
            match e {
                PnpError::NoSolution => Failure::solver(message),
                _ => Failure::input(message),
            }
        })?;

    let r = sol.rotation;
    let t = sol.translation;
    let q = sol.pose().rotation;
    let mut s2 = 0.0;
    for (x, px) in p.world.iter().zip(&p.pixels) {
        let c = r * x.coords + t;
        s2 += (p.camera.project(Point2::new(c.x / c.z, c.y / c.z)) - px).norm_squared();
    }
    let rmse_px = (s2 / p.world.len().max(1) as f64).sqrt();
    let v = json!({
        "rotation": [
            [r[(0, 0)], r[(0, 1)], r[(0, 2)]],
            [r[(1, 0)], r[(1, 1)], r[(1, 2)]],
            [r[(2, 0)], r[(2, 1)], r[(2, 2)]],
        ],
        "quaternion_wxyz": [q.w, q.i, q.j, q.k],
        "translation": [t.x, t.y, t.z],
        "n": p.world.len(),
        "inliers": p.world.len(),
        "cost": sol.cost,
        "reprojection_rmse_px": rmse_px,
        "cheirality_ok": sol.cheirality_ok,
        "degenerate": sol.degenerate,
        "camera": { "model": p.camera.model().name(), "params": p.camera.params() },
    });
    let mut out = serde_json::to_string_pretty(&v).unwrap_or_default();
    out.push('\n');
    Ok(out)
}
