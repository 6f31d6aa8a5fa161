//! The output of `eopnp register`: the table and the JSON document.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use serde_json::json;

use eopnp::colmap::{self, Model, ModelFormat, RegisterError, Registration};
use eopnp::ransac::RansacStats;
use eopnp::Solution;

/// One image's estimate, as the report shows it: a library [`Registration`], or the outlier
/// experiment's (`experiment::estimate`), whose pixel errors are over the true correspondences.
#[derive(Clone, Debug)]
pub(crate) struct Estimate {
    /// The image's 2D-3D correspondences.
    pub(crate) n: usize,
    /// The correspondences the pose was fitted to (all, or RANSAC's inliers).
    pub(crate) inliers: usize,
    /// Correspondences left out: their pixel could not be undistorted.
    pub(crate) skipped: usize,
    pub(crate) solution: Solution,
    pub(crate) ransac: Option<RansacStats>,
    pub(crate) rotation_error_deg: f64,
    pub(crate) translation_error_pct: f64,
    pub(crate) rmse_px: f64,
    pub(crate) model_rmse_px: f64,
    pub(crate) micros: f64,
    /// With an unknown focal length (`--unknown-focal`): the estimate and its error.
    pub(crate) focal: Option<FocalEstimate>,
}

/// An estimated focal length (`register --unknown-focal`) against the model's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct FocalEstimate {
    /// The estimated `(fx, fy)`, pixels.
    pub(crate) estimated: (f64, f64),
    /// The model camera's `(fx, fy)`, pixels.
    pub(crate) model: (f64, f64),
    /// The larger of the two relative errors, percent of the model's.
    pub(crate) error_pct: f64,
}

impl From<Registration> for Estimate {
    fn from(r: Registration) -> Self {
        Estimate {
            n: r.n,
            inliers: r.inliers,
            skipped: r.skipped,
            solution: r.solution,
            ransac: r.ransac,
            rotation_error_deg: r.rotation_error_deg,
            translation_error_pct: r.translation_error_pct,
            rmse_px: r.rmse_px,
            model_rmse_px: r.model_rmse_px,
            micros: r.micros,
            focal: None,
        }
    }
}

/// Robust-mode extras of one image.
#[derive(Clone, Debug)]
pub(super) struct Extra {
    /// RANSAC statistics (`None` without `--ransac`).
    pub(super) stats: Option<RansacStats>,
    /// Correspondences that were not replaced by wrong ones.
    pub(super) true_correspondences: usize,
    /// Inliers that are true correspondences (`None` without `--ransac`).
    pub(super) true_inliers: Option<usize>,
    /// EOPnP on the true correspondences alone (with `--outliers`).
    pub(super) floor: Option<Estimate>,
}

/// Outcome for one image: the registration or why it failed, and the robust-mode extras.
pub(super) type Row = (u32, String, Result<Estimate, RegisterError>, Option<Extra>);

/// What `--write` wrote.
pub(super) struct Written {
    pub(super) dir: PathBuf,
    pub(super) format: ModelFormat,
    /// Images whose pose was replaced.
    pub(super) replaced: usize,
    /// Images that could not be registered and keep the input's pose.
    pub(super) kept: Vec<u32>,
}

/// The estimated focal lengths of the registered images (`--unknown-focal`), and the median
/// and the largest of their errors, percent; `None` if no image has one.
pub(super) fn focal_errors(rows: &[Row]) -> Option<(usize, f64, f64)> {
    let mut errors: Vec<f64> = rows
        .iter()
        .filter_map(|r| r.2.as_ref().ok()?.focal.map(|f| f.error_pct))
        .collect();
    if errors.is_empty() {
        return None;
    }
    errors.sort_by(f64::total_cmp);
    let n = errors.len();
    let median = if n % 2 == 1 {
        errors[n / 2]
    } else {
        0.5 * (errors[n / 2 - 1] + errors[n / 2])
    };
    Some((n, median, errors[n - 1]))
}

/// An image's focal estimate as JSON.
fn focal_json(f: &FocalEstimate) -> serde_json::Value {
    json!({
        "estimated": [f.estimated.0, f.estimated.1],
        "model": [f.model.0, f.model.1],
        "error_pct": f.error_pct,
    })
}

pub(super) fn format_name(format: colmap::ModelFormat) -> &'static str {
    match format {
        colmap::ModelFormat::Text => "text",
        colmap::ModelFormat::Binary => "binary",
    }
}

pub(super) fn extra_json(e: &Extra) -> serde_json::Value {
    json!({
        "true_correspondences": e.true_correspondences,
        "true_inliers": e.true_inliers,
        "ransac": e.stats.map(|s| json!({
            "iterations": s.iterations,
            "hypotheses": s.hypotheses,
            "local_fits": s.local_fits,
            "final_fits": s.final_fits,
            "inliers": s.inliers,
            "inlier_ratio": s.inlier_ratio,
            "micros": s.micros,
        })),
        "floor": e.floor.as_ref().map(|f| {
            let mut v = json!({
                "rotation_error_deg": f.rotation_error_deg,
                "translation_error_pct": f.translation_error_pct,
                "rmse_px": f.rmse_px,
                "micros": f.micros,
            });
            if let Some(focal) = &f.focal {
                v["focal"] = focal_json(focal);
            }
            v
        }),
    })
}

pub(super) fn to_json(
    dir: &Path,
    format: colmap::ModelFormat,
    mode: &str,
    rows: &[Row],
    written: Option<&Written>,
) -> String {
    let images: Vec<serde_json::Value> = rows
        .iter()
        .map(|(id, name, r, extra)| match r {
            Ok(r) => {
                let rm = r.solution.rotation;
                let t = r.solution.translation;
                let q = r.solution.pose().rotation;
                let mut v = json!({
                    "image_id": id,
                    "name": name,
                    "n": r.n,
                    "inliers": r.inliers,
                    "skipped": r.skipped,
                    "rotation_error_deg": r.rotation_error_deg,
                    "translation_error_pct": r.translation_error_pct,
                    "rmse_px": r.rmse_px,
                    "model_rmse_px": r.model_rmse_px,
                    "micros": r.micros,
                    "rotation": [
                        [rm[(0, 0)], rm[(0, 1)], rm[(0, 2)]],
                        [rm[(1, 0)], rm[(1, 1)], rm[(1, 2)]],
                        [rm[(2, 0)], rm[(2, 1)], rm[(2, 2)]],
                    ],
                    "quaternion_wxyz": [q.w, q.i, q.j, q.k],
                    "translation": [t.x, t.y, t.z],
                    "cheirality_ok": r.solution.cheirality_ok,
                    "robust": extra.as_ref().map(extra_json),
                });
                if let Some(f) = &r.focal {
                    v["focal"] = focal_json(f);
                }
                v
            }
            Err(e) => json!({ "image_id": id, "name": name, "error": e.to_string() }),
        })
        .collect();
    let mut v = json!({
        "model": dir.display().to_string(),
        "format": format_name(format),
        "refinement": mode,
        "images": images,
    });
    if let Some((n, median, max)) = focal_errors(rows) {
        v["focal"] = json!({
            "images": n,
            "median_error_pct": median,
            "max_error_pct": max,
        });
    }
    if let Some(w) = written {
        v["written"] = json!({
            "dir": w.dir.display().to_string(),
            "format": format_name(w.format),
            "replaced": w.replaced,
            "kept_input_pose": w.kept,
        });
    }
    let mut s = serde_json::to_string_pretty(&v).unwrap_or_default();
    s.push('\n');
    s
}

/// The indented second line of an image in robust mode.
pub(super) fn extra_line(e: &Extra) -> String {
    let mut s = String::new();
    if let (Some(st), Some(ti)) = (&e.stats, e.true_inliers) {
        let _ = write!(
            s,
            "ransac: {} iterations, {} inliers ({ti} of the {} true correspondences)",
            st.iterations, st.inliers, e.true_correspondences
        );
    } else {
        let _ = write!(s, "{} true correspondences", e.true_correspondences);
    }
    if let Some(f) = &e.floor {
        let _ = write!(
            s,
            "; floor: rot {:.6} deg, trans {:.6} %",
            f.rotation_error_deg, f.translation_error_pct
        );
    }
    s
}

pub(super) fn to_table(
    dir: &Path,
    format: colmap::ModelFormat,
    mode: &str,
    rows: &[Row],
    model: &Model,
    intro: bool,
) -> String {
    let mut s = String::new();
    let nobs: usize = model.images.values().map(|i| i.points2d.len()).sum();
    if intro {
        let _ = writeln!(
            s,
            "eopnp: camera pose from 2D-3D correspondences (Perspective-n-Point).\n\n\
             Demo on the bundled COLMAP reconstruction {} ({} images, {} cameras, {} 3D points, \
             {} observations).\nEach image's pose is re-estimated from scratch from its 2D-3D \
             correspondences alone and compared\nwith the pose COLMAP's bundle adjustment \
             found.\n",
            dir.display(),
            model.images.len(),
            model.cameras.len(),
            model.points.len(),
            nobs,
        );
    } else {
        let _ = writeln!(
            s,
            "{} ({} format): {} images, {} cameras, {} 3D points; refinement: {mode}\n",
            dir.display(),
            format_name(format),
            model.images.len(),
            model.cameras.len(),
            model.points.len(),
        );
    }
    let label = |id: &u32, name: &str| format!("{id} {}", super::escaped(name));
    let wname = rows
        .iter()
        .map(|(id, name, _, _)| label(id, name).chars().count())
        .max()
        .unwrap_or(5)
        .max(5);
    let _ = writeln!(
        s,
        "{:<wname$}  {:>6}  {:>7}  {:>13}  {:>13}  {:>15}  {:>8}",
        "image", "N", "inliers", "rot diff deg", "trans diff %", "rmse px (model)", "us"
    );
    let _ = writeln!(
        s,
        "{}",
        "-".repeat(wname + 2 + 6 + 2 + 7 + 2 + 13 + 2 + 13 + 2 + 15 + 2 + 8)
    );
    let (mut worst_r, mut worst_t, mut ok) = (0.0f64, 0.0f64, 0usize);
    let robust = rows.iter().any(|r| r.3.is_some());
    let (mut floor_r, mut floor_t) = (0.0f64, 0.0f64);
    for (id, name, r, extra) in rows {
        match r {
            Ok(r) => {
                ok += 1;
                worst_r = worst_r.max(r.rotation_error_deg);
                worst_t = worst_t.max(r.translation_error_pct);
                let rmse = format!("{:.3} ({:.3})", r.rmse_px, r.model_rmse_px);
                let _ = writeln!(
                    s,
                    "{:<wname$}  {:>6}  {:>7}  {:>13.6}  {:>13.6}  {:>15}  {:>8.0}",
                    label(id, name),
                    r.n,
                    r.inliers,
                    r.rotation_error_deg,
                    r.translation_error_pct,
                    rmse,
                    r.micros
                );
                if let Some(f) = &r.focal {
                    let _ = writeln!(
                        s,
                        "{:<wname$}  focal {:.3}, {:.3} px (model {:.3}, {:.3}): error {:.4} %",
                        "", f.estimated.0, f.estimated.1, f.model.0, f.model.1, f.error_pct
                    );
                }
                if r.skipped > 0 {
                    let _ = writeln!(
                        s,
                        "{:<wname$}  {} observation(s) left out: their pixel could not be \
                         undistorted",
                        "", r.skipped
                    );
                }
                if let Some(e) = extra {
                    if let Some(f) = &e.floor {
                        floor_r = floor_r.max(f.rotation_error_deg);
                        floor_t = floor_t.max(f.translation_error_pct);
                    }
                    let _ = writeln!(s, "{:<wname$}  {}", "", extra_line(e));
                }
            }
            Err(e) => {
                let _ = writeln!(s, "{:<wname$}  failed: {e}", label(id, name));
            }
        }
    }
    let _ = writeln!(s);
    if ok > 0 {
        let _ = writeln!(
            s,
            "{ok} of {} images registered; worst differences to COLMAP: rotation {worst_r:.6} \
             degrees, translation {worst_t:.6} %.",
            rows.len()
        );
    }
    if let Some((n, median, max)) = focal_errors(rows) {
        let _ = writeln!(
            s,
            "Focal length estimated for {n} images: error to the model's median {median:.4} %, \
             max {max:.4} %."
        );
    }
    if robust
        && rows
            .iter()
            .any(|r| r.3.as_ref().is_some_and(|e| e.floor.is_some()))
    {
        let _ = writeln!(
            s,
            "Floor (EOPnP on the true correspondences alone), worst: rotation {floor_r:.6} \
             degrees, translation {floor_t:.6} %."
        );
    }
    if intro {
        let _ = write!(
            s,
            "\nColumns:\n\
             - image: COLMAP's image id and file name.\n\
             - N: number of 2D-3D correspondences (observations of a triangulated 3D point) used.\n\
             - inliers: correspondences kept by the estimate (all of them: no outlier rejection \
             in this mode).\n\
             - rot diff deg: largest angle, in degrees, between the corresponding axes of our \
             rotation and COLMAP's.\n\
             - trans diff %: distance between our translation and COLMAP's, in percent of the \
             length of COLMAP's.\n\
             - rmse px (model): RMS reprojection error of our pose in pixels, COLMAP's own pose \
             in brackets; equal\n  values mean both poses fit the observations equally well.\n\
             - us: microseconds to undistort the pixels and solve, for this image (best of 3 \
             runs).\n\n\
             The differences are tiny because both minimise the pixel reprojection error with \
             the model's 3D points and\ncameras held fixed; what remains comes from the \
             per-point pixel weighting being first-order (the\ndistortion is undistorted \
             away first) and from the rounding of the model's text values.\n\n\
             Next: `eopnp register MODEL_DIR` for your own COLMAP model (text or binary, \
             `--json` for machine-readable\noutput, `--algebraic` for the paper's algebraic \
             cost alone), `eopnp solve FILE` for a single\nproblem, `eopnp --help` for more.\n"
        );
    }
    s
}
