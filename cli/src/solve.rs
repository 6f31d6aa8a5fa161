//! `eopnp solve`'s output: the problem solved, the pose rendered as JSON.

use eopnp::camera::Camera;
use eopnp::{Gravity, PnpError, Solver};
use nalgebra::Point2;
use serde_json::json;

use crate::input::Problem;
use crate::Failure;

/// What `solve` knows beyond the correspondences: an unknown focal length, refined intrinsics,
/// a known vertical.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Options {
    /// The focal length is unknown: `Some(None)` in the default range (a tenth to ten times
    /// the camera's), `Some(Some((min_px, max_px)))` in that range.
    pub unknown_focal: Option<Option<(f64, f64)>>,
    /// The principal point is refined with the pose.
    pub refine_principal_point: bool,
    /// The distortion parameters are refined with the pose.
    pub refine_distortion: bool,
    /// A known vertical.
    pub gravity: Option<Gravity>,
}

/// `camera` with its focal lengths set to `(fx, fy)`, everything else equal (a single-focal
/// model's `f` is `fx`; `fy` then equals it, as the library scales the two alike).
pub(crate) fn camera_with_focal(camera: &Camera, (fx, fy): (f64, f64)) -> Result<Camera, String> {
    let mut params = camera.params().to_vec();
    params[0] = fx;
    let single = Camera::new(
        camera.model(),
        camera.width(),
        camera.height(),
        params.clone(),
    )
    .map_err(|e| e.to_string())?;
    if single.focal_lengths().1 == fy {
        return Ok(single);
    }
    params[1] = fy;
    Camera::new(camera.model(), camera.width(), camera.height(), params).map_err(|e| e.to_string())
}

/// Solves the problem and renders the pose JSON.
pub fn solve(p: &Problem, solver: &Solver) -> Result<String, Failure> {
    solve_with(p, solver, &Options::default())
}

/// Solves the problem with `options` (an unknown focal length, a known vertical) and renders
/// the pose JSON.
pub fn solve_with(p: &Problem, solver: &Solver, options: &Options) -> Result<String, Failure> {
    // Undistortion failures are input errors here (a solve would skip the point).
    for (k, px) in p.pixels.iter().enumerate() {
        p.camera
            .undistort(*px)
            .map_err(|e| Failure::input(format!("correspondence {}: {e}", k + 1)))?;
    }
    let mut problem = eopnp::Problem::pixels(&p.world, &p.pixels, &p.camera);
    problem = match options.unknown_focal {
        Some(Some((lo, hi))) => problem.unknown_focal_within(lo, hi),
        Some(None) => problem.unknown_focal(),
        None => problem,
    };
    if options.refine_principal_point {
        problem = problem.refine_principal_point();
    }
    if options.refine_distortion {
        problem = problem.refine_distortion();
    }
    if let Some(g) = options.gravity {
        problem = problem.gravity(g);
    }
    let sol = solver.solve(&problem).map_err(|e| {
        // Degenerate or malformed input is the input's problem (exit 2); only a numerical
        // failure on valid input is the solver's (exit 1). A vertical the images contradict is
        // a property of the data: an input error too.
        match e {
            PnpError::NoSolution => Failure::solver(format!("no pose: {e}")),
            PnpError::GravityMismatch { .. } => Failure::input(format!(
                "no pose: {e}; the vertical is --gravity-camera (camera frame) and \
                 --gravity-world (world frame), its uncertainty --gravity-sigma; solve without \
                 them to see the pose the correspondences alone give"
            )),
            _ => Failure::input(format!("no pose: {e}")),
        }
    })?;

    // The camera the pose goes with: the estimated one when the focal length was unknown.
    let focal = sol.camera.map(|c| c.focal_lengths());
    let camera = sol.camera.unwrap_or(p.camera);
    let r = sol.rotation;
    let t = sol.translation;
    let q = sol.pose().rotation;
    let mut s2 = 0.0;
    for (x, px) in p.world.iter().zip(&p.pixels) {
        let c = r * x.coords + t;
        s2 += (camera.project(Point2::new(c.x / c.z, c.y / c.z)) - px).norm_squared();
    }
    let rmse_px = (s2 / p.world.len().max(1) as f64).sqrt();
    let mut v = json!({
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
        "camera": { "model": camera.model().name(), "params": camera.params() },
    });
    if let Some((fx, fy)) = focal {
        v["focal"] = json!([fx, fy]);
    }
    if let Some(g) = options.gravity {
        // The angle between the measured vertical and the solved pose's.
        let predicted = r * g.in_world();
        let angle = predicted
            .cross(&g.in_camera())
            .norm()
            .atan2(predicted.dot(&g.in_camera()))
            .to_degrees();
        v["gravity"] = json!({
            "camera": [g.in_camera().x, g.in_camera().y, g.in_camera().z],
            "world": [g.in_world().x, g.in_world().y, g.in_world().z],
            "sigma_deg": g.sigma_deg(),
            "angle_deg": angle,
        });
    }
    let mut out = serde_json::to_string_pretty(&v).unwrap_or_default();
    out.push('\n');
    Ok(out)
}
