//! `eopnp register` on a model with rigs (COLMAP 3.12 and later): every frame registered as one
//! rig pose from the correspondences of all its images (`eopnp::colmap::register_frame`) and
//! compared with the model's `rig_from_world`; the table, the JSON and `--write`.

use std::fmt::Write as _;
use std::io::IsTerminal;
use std::path::Path;
use std::time::Instant;

use eopnp::colmap::{
    FrameRegistration, Model, ModelFormat, Pose, RegisterError, Registrar, SensorId,
};
use nalgebra::{Isometry3, Matrix3};
use serde_json::json;

use super::super::report::{extra_json, extra_line, format_name, Extra};
use super::super::{emit, Failure, RegisterOptions};
use super::{progress_bar, write_model_to, Output, PROGRESS_AFTER};

/// One frame's outcome: its id, rig and images (id and name), the registration or why it
/// failed, and RANSAC's extras.
struct FrameRow {
    frame_id: u32,
    rig_id: u32,
    images: Vec<(u32, String)>,
    result: Result<FrameRegistration, RegisterError>,
    extra: Option<Extra>,
}

/// What `--write` wrote.
struct WrittenFrames {
    format: ModelFormat,
    /// Frames whose pose was replaced, and the images of those frames.
    frames: usize,
    images: usize,
    /// Frames that could not be registered and keep the input's poses (their images too).
    kept: Vec<u32>,
}

/// One frame's registration, plain or with `--ransac`; the time is the best of three runs, as
/// for an image.
fn estimate(
    registrar: &mut Registrar<'_>,
    frame_id: u32,
    opts: &RegisterOptions,
) -> (Result<FrameRegistration, RegisterError>, Option<Extra>) {
    let solver = opts.solver();
    let ransac = opts.ransac.then(|| opts.ransac_options());
    let mut run = || registrar.register_frame(frame_id, &solver, ransac.as_ref());
    let result = run().and_then(|mut best| {
        for _ in 0..2 {
            best.micros = best.micros.min(run()?.micros);
        }
        Ok(best)
    });
    // Every correspondence is a true one (no injected outliers on frames).
    let extra = result.as_ref().ok().and_then(|reg| {
        reg.ransac.map(|stats| Extra {
            stats: Some(stats),
            true_correspondences: reg.n,
            true_inliers: Some(reg.inliers),
            floor: None,
        })
    });
    (result, extra)
}

/// The pose of the frame's image `image_id` for the rig pose `rig_from_world`:
/// `cam_from_world = cam_from_rig * rig_from_world`, `cam_from_rig` the image's camera's pose
/// in the frame's rig (`None` if the model does not know it).
fn cam_from_world(
    model: &Model,
    rig_id: u32,
    image_id: u32,
    rig_from_world: &Isometry3<f64>,
) -> Option<Isometry3<f64>> {
    let camera = model.images.get(&image_id)?.camera_id;
    let cam_from_rig = model
        .rigs
        .get(&rig_id)?
        .sensor_from_rig(SensorId::camera(camera))?;
    Some(cam_from_rig.isometry() * rig_from_world)
}

fn matrix_json(r: &Matrix3<f64>) -> serde_json::Value {
    json!([
        [r[(0, 0)], r[(0, 1)], r[(0, 2)]],
        [r[(1, 0)], r[(1, 1)], r[(1, 2)]],
        [r[(2, 0)], r[(2, 1)], r[(2, 2)]],
    ])
}

fn isometry_json(pose: &Isometry3<f64>) -> [(&'static str, serde_json::Value); 3] {
    let q = pose.rotation;
    let t = pose.translation.vector;
    [
        (
            "rotation",
            matrix_json(&q.to_rotation_matrix().into_inner()),
        ),
        ("quaternion_wxyz", json!([q.w, q.i, q.j, q.k])),
        ("translation", json!([t.x, t.y, t.z])),
    ]
}

fn to_json(
    dir: &Path,
    format: ModelFormat,
    mode: &str,
    model: &Model,
    rows: &[FrameRow],
    written: Option<(&Output, &WrittenFrames)>,
) -> String {
    let frames: Vec<serde_json::Value> = rows
        .iter()
        .map(|row| {
            let ids: Vec<u32> = row.images.iter().map(|(id, _)| *id).collect();
            let mut v = json!({
                "frame_id": row.frame_id,
                "rig_id": row.rig_id,
                "image_ids": ids,
            });
            match &row.result {
                Ok(r) => {
                    let pose = r.solution.pose();
                    v["n"] = json!(r.n);
                    v["inliers"] = json!(r.inliers);
                    v["skipped"] = json!(r.skipped);
                    v["rotation_error_deg"] = json!(r.rotation_error_deg);
                    v["translation_error_pct"] = json!(r.translation_error_pct);
                    v["rmse_px"] = json!(r.rmse_px);
                    v["model_rmse_px"] = json!(r.model_rmse_px);
                    v["micros"] = json!(r.micros);
                    // The rig's pose, x_rig = R X + t (the rotation matrix the solver's).
                    v["rotation"] = matrix_json(&r.solution.rotation);
                    let q = pose.rotation;
                    v["quaternion_wxyz"] = json!([q.w, q.i, q.j, q.k]);
                    let t = r.solution.translation;
                    v["translation"] = json!([t.x, t.y, t.z]);
                    v["cheirality_ok"] = json!(r.solution.cheirality_ok);
                    v["robust"] = row.extra.as_ref().map_or(json!(null), extra_json);
                    // Each image's camera pose, as --write writes it.
                    let images: Vec<serde_json::Value> = row
                        .images
                        .iter()
                        .map(|(id, name)| {
                            let mut image = json!({ "image_id": id, "name": name });
                            if let Some(p) = cam_from_world(model, row.rig_id, *id, &pose) {
                                for (k, value) in isometry_json(&p) {
                                    image[k] = value;
                                }
                            }
                            image
                        })
                        .collect();
                    v["images"] = json!(images);
                }
                Err(e) => v["error"] = json!(e.to_string()),
            }
            v
        })
        .collect();
    let mut v = json!({
        "model": dir.display().to_string(),
        "format": format_name(format),
        "refinement": mode,
        "registered": "frames",
        "frames": frames,
    });
    if let Some((out, w)) = written {
        v["written"] = json!({
            "dir": out.dir.display().to_string(),
            "format": format_name(w.format),
            "frames_replaced": w.frames,
            "images_replaced": w.images,
            "frames_kept_input_pose": w.kept,
        });
    }
    let mut s = serde_json::to_string_pretty(&v).unwrap_or_default();
    s.push('\n');
    s
}

fn to_table(
    dir: &Path,
    format: ModelFormat,
    mode: &str,
    model: &Model,
    rows: &[FrameRow],
) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{} ({} format): {} images, {} cameras, {} 3D points, {} rigs, {} frames; refinement: \
         {mode}\nEach frame registered as one rig pose from the correspondences of all its \
         images, compared with the model's rig_from_world.\n",
        dir.display(),
        format_name(format),
        model.images.len(),
        model.cameras.len(),
        model.points.len(),
        model.rigs.len(),
        model.frames.len(),
    );
    let label = |row: &FrameRow| format!("{} (rig {})", row.frame_id, row.rig_id);
    let wname = rows
        .iter()
        .map(|r| label(r).chars().count())
        .max()
        .unwrap_or(5)
        .max(5);
    let _ = writeln!(
        s,
        "{:<wname$}  {:>6}  {:>6}  {:>7}  {:>13}  {:>13}  {:>15}  {:>8}",
        "frame", "images", "N", "inliers", "rot diff deg", "trans diff %", "rmse px (model)", "us"
    );
    let _ = writeln!(
        s,
        "{}",
        "-".repeat(wname + 2 + 6 + 2 + 6 + 2 + 7 + 2 + 13 + 2 + 13 + 2 + 15 + 2 + 8)
    );
    let (mut worst_r, mut worst_t, mut ok) = (0.0f64, 0.0f64, 0usize);
    for row in rows {
        match &row.result {
            Ok(r) => {
                ok += 1;
                worst_r = worst_r.max(r.rotation_error_deg);
                worst_t = worst_t.max(r.translation_error_pct);
                let rmse = format!("{:.3} ({:.3})", r.rmse_px, r.model_rmse_px);
                let _ = writeln!(
                    s,
                    "{:<wname$}  {:>6}  {:>6}  {:>7}  {:>13.6}  {:>13.6}  {:>15}  {:>8.0}",
                    label(row),
                    row.images.len(),
                    r.n,
                    r.inliers,
                    r.rotation_error_deg,
                    r.translation_error_pct,
                    rmse,
                    r.micros
                );
                if r.skipped > 0 {
                    let _ = writeln!(
                        s,
                        "{:<wname$}  {} observation(s) left out: their pixel could not be \
                         undistorted",
                        "", r.skipped
                    );
                }
                if let Some(e) = &row.extra {
                    let _ = writeln!(s, "{:<wname$}  {}", "", extra_line(e));
                }
            }
            Err(e) => {
                let _ = writeln!(s, "{:<wname$}  failed: {e}", label(row));
            }
        }
    }
    let _ = writeln!(s);
    if ok > 0 {
        let _ = writeln!(
            s,
            "{ok} of {} frames registered; worst differences to COLMAP's frame poses: rotation \
             {worst_r:.6} degrees, translation {worst_t:.6} %.",
            rows.len()
        );
    }
    s
}

/// The input model with every registered frame's pose replaced, and the poses of its images
/// composed from it (`cam_from_rig * rig_from_world`, as COLMAP derives them), written
/// atomically to `out`.
fn write_output(
    model: &Model,
    input_format: ModelFormat,
    rows: &[FrameRow],
    out: &Output,
) -> Result<WrittenFrames, Failure> {
    let mut new = model.clone();
    let (mut frames, mut images, mut kept) = (0, 0, Vec::new());
    for row in rows {
        let (Ok(reg), Some(frame)) = (&row.result, new.frames.get_mut(&row.frame_id)) else {
            kept.push(row.frame_id);
            continue;
        };
        let rig_from_world = reg.solution.pose();
        frame.rig_from_world = Pose::from_isometry(&rig_from_world);
        frames += 1;
        for (id, _) in &row.images {
            // Registered, so every image's camera has a pose in the rig.
            let Some(pose) = cam_from_world(model, row.rig_id, *id, &rig_from_world) else {
                continue;
            };
            if let Some(img) = new.images.get_mut(id) {
                let q = pose.rotation;
                img.q = [q.w, q.i, q.j, q.k];
                img.t = pose.translation.vector;
                images += 1;
            }
        }
    }
    let format = out.format.unwrap_or(input_format);
    write_model_to(&new, out, format)?;
    Ok(WrittenFrames {
        format,
        frames,
        images,
        kept,
    })
}

fn written_line(out: &Output, w: &WrittenFrames, total: usize) -> String {
    let mut s = format!(
        "Wrote {} ({} format): {} of {total} frame poses replaced by the re-estimated ones, and \
         the poses of their {} images composed from them.",
        out.dir.display(),
        format_name(w.format),
        w.frames,
        w.images
    );
    if !w.kept.is_empty() {
        let ids: Vec<String> = w.kept.iter().map(u32::to_string).collect();
        let _ = write!(
            s,
            " Not registered, keeping the input model's poses: frame{} {}.",
            if ids.len() == 1 { "" } else { "s" },
            ids.join(", ")
        );
    }
    s.push('\n');
    s
}

/// `eopnp register` on a model with rigs: every frame, in id order.
pub(super) fn run(
    dir: &Path,
    format: ModelFormat,
    model: &Model,
    opts: &RegisterOptions,
    mode: &str,
    out: Option<&Output>,
) -> Result<(), Failure> {
    let bar = progress_bar(model.frames.len() as u64, "frames");
    let started = Instant::now();
    let mut rows = Vec::with_capacity(model.frames.len());
    let mut registrar = Registrar::new(model);
    for (id, frame) in &model.frames {
        if started.elapsed() >= PROGRESS_AFTER && std::io::stderr().is_terminal() {
            bar.set_draw_target(indicatif::ProgressDrawTarget::stderr());
        }
        let (result, extra) = estimate(&mut registrar, *id, opts);
        let images = frame
            .image_ids()
            .map(|i| {
                let name = model.images.get(&i).map_or("", |img| &img.name);
                (i, name.to_string())
            })
            .collect();
        rows.push(FrameRow {
            frame_id: *id,
            rig_id: frame.rig_id,
            images,
            result,
            extra,
        });
        bar.inc(1);
    }
    bar.finish_and_clear();

    let written = out
        .map(|o| write_output(model, format, &rows, o).map(|w| (o, w)))
        .transpose()?;
    let text = if opts.json {
        to_json(
            dir,
            format,
            mode,
            model,
            &rows,
            written.as_ref().map(|(o, w)| (*o, w)),
        )
    } else {
        let mut t = to_table(dir, format, mode, model, &rows);
        if let Some((o, w)) = &written {
            t.push_str(&written_line(o, w, rows.len()));
        }
        t
    };
    emit(&text)?;
    if rows.iter().all(|r| r.result.is_err()) && !rows.is_empty() {
        return Err(Failure::solver("no frame could be registered"));
    }
    Ok(())
}
