//! `eopnp solve`: correspondence files (CSV, JSON) in, pose JSON out.

use std::path::Path;

use crate::camera::Camera;
use crate::Solver;
use nalgebra::{Point2, Point3};
use serde::Deserialize;
use serde_json::json;

use super::Failure;

/// A parsed problem: camera, pixels and world points.
pub struct Problem {
    camera: Camera,
    pixels: Vec<Point2<f64>>,
    world: Vec<Point3<f64>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct JsonCamera {
    model: String,
    params: Vec<f64>,
    #[serde(default)]
    width: u64,
    #[serde(default)]
    height: u64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct JsonProblem {
    camera: Option<JsonCamera>,
    points2d: Vec<[f64; 2]>,
    points3d: Vec<[f64; 3]>,
}

/// Parses `--camera "MODEL P1 P2 ..."`.
fn parse_camera_arg(s: &str) -> Result<Camera, Failure> {
    let mut it = s.split_whitespace();
    let model = it
        .next()
        .ok_or_else(|| Failure::input("--camera: empty; expected \"MODEL P1 P2 ...\""))?;
    let mut params = Vec::new();
    for tok in it {
        let v: f64 = tok
            .parse()
            .ok()
            .filter(|v: &f64| v.is_finite())
            .ok_or_else(|| Failure::input(format!("--camera: bad parameter \"{tok}\"")))?;
        params.push(v);
    }
    Camera::from_colmap(model, 0, 0, params).map_err(|e| Failure::input(format!("--camera: {e}")))
}

/// 1-based line of the first occurrence of `needle` in `text` (for semantic JSON errors).
fn line_of(text: &str, needle: &str) -> Option<usize> {
    text.find(needle)
        .map(|at| 1 + text[..at].bytes().filter(|&b| b == b'\n').count())
}

/// Reads a CSV or JSON problem file.
pub(crate) fn read_problem(path: &Path, camera_arg: Option<&str>) -> Result<Problem, Failure> {
    let name = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|e| Failure::input(format!("{name}: {e}")))?;
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    parse_problem(&name, &bytes, ext.as_deref(), camera_arg)
}

/// Parses the contents of a problem file named `name` (for messages) with extension `ext`
/// (`"json"`, `"csv"`, or anything else: JSON when the text starts with `{`).
pub fn parse_problem(
    name: &str,
    bytes: &[u8],
    ext: Option<&str>,
    camera_arg: Option<&str>,
) -> Result<Problem, Failure> {
    let text = std::str::from_utf8(bytes).map_err(|e| {
        let line = 1 + bytes[..e.valid_up_to()]
            .iter()
            .filter(|&&b| b == b'\n')
            .count();
        Failure::input(format!("{name}:{line}: invalid UTF-8"))
    })?;
    let camera_arg = camera_arg.map(parse_camera_arg).transpose()?;
    let is_json = match ext {
        Some("json") => true,
        Some("csv") => false,
        _ => text.trim_start().starts_with('{'),
    };
    if is_json {
        read_json(name, text, camera_arg)
    } else {
        let camera = camera_arg.ok_or_else(|| {
            Failure::input(format!(
                "{name}: a CSV file needs the camera: --camera \"MODEL P1 P2 ...\", e.g. \
                 --camera \"SIMPLE_RADIAL 1245.65 600 800 0.0577\""
            ))
        })?;
        read_csv(name, text, camera)
    }
}

fn read_json(name: &str, text: &str, camera_arg: Option<Camera>) -> Result<Problem, Failure> {
    // serde_json reports line and column for syntax errors, wrong types and wrong array
    // lengths.
    let p: JsonProblem = serde_json::from_str(text).map_err(|e| {
        // serde_json reports a fixed-size array with too many elements as trailing characters.
        let after_comma = text
            .lines()
            .nth(e.line().saturating_sub(1))
            .map(|l| {
                l.chars()
                    .take(e.column().saturating_sub(1))
                    .collect::<String>()
            })
            .is_some_and(|before| before.trim_end().ends_with(','));
        let hint = if e.to_string().starts_with("trailing characters") && after_comma {
            " (a point with too many coordinates? points2d entries are [x, y], points3d entries \
             are [X, Y, Z])"
        } else {
            ""
        };
        Failure::input(format!("{name}:{}:{}: {e}{hint}", e.line(), e.column()))
    })?;
    let camera = match (camera_arg, p.camera) {
        (Some(c), _) => c,
        (None, Some(c)) => {
            Camera::from_colmap(&c.model, c.width, c.height, c.params).map_err(|e| {
                let line = line_of(text, "\"camera\"").unwrap_or(1);
                Failure::input(format!("{name}:{line}: camera: {e}"))
            })?
        }
        (None, None) => {
            return Err(Failure::input(format!(
                "{name}: no \"camera\" object and no --camera argument"
            )))
        }
    };
    if p.points2d.len() != p.points3d.len() {
        let line = line_of(text, "\"points3d\"").unwrap_or(1);
        return Err(Failure::input(format!(
            "{name}:{line}: {} points2d but {} points3d; they must correspond one to one",
            p.points2d.len(),
            p.points3d.len()
        )));
    }
    Ok(Problem {
        camera,
        pixels: p.points2d.iter().map(|a| Point2::new(a[0], a[1])).collect(),
        world: p
            .points3d
            .iter()
            .map(|a| Point3::new(a[0], a[1], a[2]))
            .collect(),
    })
}

fn read_csv(name: &str, text: &str, camera: Camera) -> Result<Problem, Failure> {
    let mut pixels = Vec::new();
    let mut world = Vec::new();
    let mut header = false;
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let l = raw.trim();
        if l.is_empty() || l.starts_with('#') {
            continue;
        }
        let fields: Vec<&str> = l.split(',').map(str::trim).collect();
        if !header {
            if fields != ["x", "y", "X", "Y", "Z"] {
                return Err(Failure::input(format!(
                    "{name}:{line}: expected the header `x,y,X,Y,Z` (pixel x, pixel y, world \
                     X, Y, Z), found `{}`",
                    truncate(l)
                )));
            }
            header = true;
            continue;
        }
        if fields.len() != 5 {
            return Err(Failure::input(format!(
                "{name}:{line}: expected 5 comma-separated numbers x,y,X,Y,Z, found {} field{} \
                 (truncated line?)",
                fields.len(),
                if fields.len() == 1 { "" } else { "s" }
            )));
        }
        let mut v = [0.0; 5];
        for (k, f) in fields.iter().enumerate() {
            let what = format!(
                "{name}:{line}: field {} ({})",
                k + 1,
                ["x", "y", "X", "Y", "Z"][k]
            );
            // Debug-escaped, so that invisible characters in the field show.
            let shown = truncate(&f.escape_debug().to_string());
            v[k] = match f.parse::<f64>() {
                Ok(x) if x.is_finite() => x,
                Ok(_) => {
                    return Err(Failure::input(format!(
                        "{what} is not finite (NaN, inf or beyond +-1.8e308): `{shown}`"
                    )))
                }
                Err(_) => return Err(Failure::input(format!("{what} is not a number: `{shown}`"))),
            };
        }
        pixels.push(Point2::new(v[0], v[1]));
        world.push(Point3::new(v[2], v[3], v[4]));
    }
    if !header {
        return Err(Failure::input(format!(
            "{name}: empty file; expected the header `x,y,X,Y,Z` and one correspondence per line"
        )));
    }
    Ok(Problem {
        camera,
        pixels,
        world,
    })
}

fn truncate(s: &str) -> String {
    if s.chars().count() > 60 {
        let mut t: String = s.chars().take(60).collect();
        t.push_str("...");
        t
    } else {
        s.to_string()
    }
}

/// Solves the problem and renders the pose JSON.
pub fn solve(p: &Problem, solver: &Solver) -> Result<String, Failure> {
    // Undistortion failures are input errors here (`Solver::solve_pixels` would skip the point).
    for (k, px) in p.pixels.iter().enumerate() {
        p.camera
            .undistort_weighted(*px)
            .map_err(|e| Failure::input(format!("correspondence {}: {e}", k + 1)))?;
    }
    let sol = solver
        .solve_pixels(&p.world, &p.pixels, &p.camera)
        .map_err(|e| Failure::solver(format!("no pose: {e}")))?;

    let r = sol.rotation;
    let t = sol.pose.translation.vector;
    let q = sol.pose.rotation;
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

#[cfg(test)]
#[path = "../../tests/unit/cli/input.rs"]
mod tests;
