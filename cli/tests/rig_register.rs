//! `eopnp register` on a model with rigs (COLMAP 3.12 and later, the bundled `data/colmap-rig`
//! and its binary copy): every frame registered as one rig pose and compared with the model's;
//! the JSON's image poses are the frame's composed with each camera's pose in the rig;
//! `--write` replaces the frames' poses and their images'; `--per-image` and the options that
//! only work image by image.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::atomic::{AtomicUsize, Ordering};

use eopnp::colmap::{
    read_model, write_model, Model, ModelFormat, ReadOptions, SensorId, WriteOptions,
};
use nalgebra::{Isometry3, Matrix3, Vector3};
use serde_json::Value;

const TEXT_MODEL: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../data/colmap-rig");
const BIN_MODEL: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../data/colmap-rig-bin");

fn eopnp(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_eopnp"))
        .args(args)
        .output()
        .unwrap()
}

/// A fresh scratch directory, unique to the call.
fn scratch(name: &str) -> PathBuf {
    static NEXT: AtomicUsize = AtomicUsize::new(0);
    let n = NEXT.fetch_add(1, Ordering::Relaxed);
    let d = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("rig-register-{}-{name}-{n}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn json_of(o: &Output) -> Value {
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_slice(&o.stdout).unwrap()
}

fn matrix(v: &Value) -> Matrix3<f64> {
    Matrix3::from_fn(|r, c| v[r][c].as_f64().unwrap())
}

fn vector(v: &Value) -> Vector3<f64> {
    Vector3::from_fn(|r, _| v[r].as_f64().unwrap())
}

/// Largest entry difference of two poses, relative to the larger of 1 and the entry.
fn pose_diff(r: &Matrix3<f64>, t: &Vector3<f64>, r2: &Matrix3<f64>, t2: &Vector3<f64>) -> f64 {
    let rel = |a: f64, b: f64| (a - b).abs() / b.abs().max(1.0);
    let dr = r.iter().zip(r2.iter()).map(|(a, b)| rel(*a, *b));
    let dt = t.iter().zip(t2.iter()).map(|(a, b)| rel(*a, *b));
    dr.chain(dt).fold(0.0, f64::max)
}

/// The model's pose of image `id` composed from its frame: `cam_from_rig * rig_from_world`.
fn composed(model: &Model, frame_id: u32, image_id: u32) -> Isometry3<f64> {
    let frame = &model.frames[&frame_id];
    let camera = model.images[&image_id].camera_id;
    let cam_from_rig = model.rigs[&frame.rig_id]
        .sensor_from_rig(SensorId::camera(camera))
        .unwrap();
    cam_from_rig.isometry() * frame.rig_from_world.isometry()
}

#[test]
fn every_frame_registers_as_one_rig_pose_in_both_formats() {
    let model = read_model(TEXT_MODEL, &ReadOptions::default()).unwrap();
    for input in [TEXT_MODEL, BIN_MODEL] {
        let v = json_of(&eopnp(&["register", input, "--json"]));
        assert_eq!(v["registered"], "frames");
        assert!(v.get("images").is_none());
        let frames = v["frames"].as_array().unwrap();
        assert_eq!(frames.len(), 6);
        for f in frames {
            let id = u32::try_from(f["frame_id"].as_u64().unwrap()).unwrap();
            let frame = &model.frames[&id];
            assert_eq!(f["rig_id"], frame.rig_id);
            let ids: Vec<u32> = frame.image_ids().collect();
            assert_eq!(f["image_ids"], serde_json::json!(ids));
            assert_eq!(
                (f["n"].as_u64(), f["inliers"].as_u64()),
                (Some(120), Some(120))
            );
            // Noise-free: the model's pose to rounding.
            let rot = f["rotation_error_deg"].as_f64().unwrap();
            let trans = f["translation_error_pct"].as_f64().unwrap();
            assert!(
                rot < 1e-8 && trans < 1e-8,
                "frame {id}: {rot} deg, {trans} %"
            );
            let (r_model, t_model) = (frame.rig_from_world.rotation(), frame.rig_from_world.t);
            let d = pose_diff(
                &matrix(&f["rotation"]),
                &vector(&f["translation"]),
                &r_model,
                &t_model,
            );
            assert!(d < 1e-9, "frame {id}: {d}");
            // Each image's pose: the frame's composed with its camera's pose in the rig, which
            // is the model's image pose (COLMAP stores the composed one too).
            let images = f["images"].as_array().unwrap();
            assert_eq!(images.len(), 3);
            for img in images {
                let iid = u32::try_from(img["image_id"].as_u64().unwrap()).unwrap();
                assert_eq!(img["name"], model.images[&iid].name);
                let (r, t) = model.images[&iid].pose();
                let d = pose_diff(
                    &matrix(&img["rotation"]),
                    &vector(&img["translation"]),
                    &r,
                    &t,
                );
                assert!(d < 1e-9, "image {iid}: {d}");
            }
        }
    }
    // The table: one row per frame, and the summary.
    let o = eopnp(&["register", TEXT_MODEL, "--ransac"]);
    assert!(o.status.success());
    let table = String::from_utf8_lossy(&o.stdout);
    assert!(table.contains("2 rigs, 6 frames"), "{table}");
    assert!(table.contains("6 of 6 frames registered"), "{table}");
    assert_eq!(table.matches("ransac: ").count(), 6, "{table}");
    assert!(table.lines().any(|l| l.starts_with("4 (rig 2)")), "{table}");
}

/// The bundled model with every observation moved by up to half a pixel (a fixed pattern):
/// the frame's pose minimises the pixel error of its three images together, so it fits them
/// at least as well as the model's pose, and differs from it.
#[test]
fn noisy_frames_fit_their_pixels_better_than_the_model_pose() {
    let mut model = read_model(TEXT_MODEL, &ReadOptions::default()).unwrap();
    let mut k = 0u32;
    for img in model.images.values_mut() {
        for (px, _) in &mut img.points2d {
            k += 1;
            let h = |s: f64| ((f64::from(k) * s).sin() * 43_758.545_3).fract() * 0.5;
            px.x += h(12.9898);
            px.y += h(78.233);
        }
    }
    let base = scratch("noisy");
    let dir = base.join("model");
    write_model(&model, &dir, &WriteOptions::default()).unwrap();
    let v = json_of(&eopnp(&["register", dir.to_str().unwrap(), "--json"]));
    for f in v["frames"].as_array().unwrap() {
        let (rmse, model_rmse) = (
            f["rmse_px"].as_f64().unwrap(),
            f["model_rmse_px"].as_f64().unwrap(),
        );
        assert!(rmse <= model_rmse * (1.0 + 1e-12), "{f}");
        assert!(model_rmse > 0.1, "{f}");
        let rot = f["rotation_error_deg"].as_f64().unwrap();
        assert!(rot > 1e-6 && rot < 0.1, "{f}");
    }
    let _ = std::fs::remove_dir_all(&base);
}

#[test]
fn write_replaces_frame_poses_and_composes_image_poses() {
    let base = scratch("write");
    let input_model = read_model(TEXT_MODEL, &ReadOptions::default()).unwrap();
    // A frame that cannot be registered: its images' observations lose their 3D points.
    let mut model = input_model.clone();
    for id in model.frames[&5].image_ids().collect::<Vec<_>>() {
        for obs in &mut model.images.get_mut(&id).unwrap().points2d {
            obs.1 = None;
        }
    }
    for p in model.points.values_mut() {
        p.track.retain(|(img, _)| !(13..=15).contains(img));
    }
    let input = base.join("input");
    write_model(
        &model,
        &input,
        &WriteOptions::default().format(ModelFormat::Binary),
    )
    .unwrap();
    for (flag, format, files) in [
        (
            None,
            ModelFormat::Binary,
            [
                "cameras.bin",
                "frames.bin",
                "images.bin",
                "points3D.bin",
                "rigs.bin",
            ],
        ),
        (
            Some("text"),
            ModelFormat::Text,
            [
                "cameras.txt",
                "frames.txt",
                "images.txt",
                "points3D.txt",
                "rigs.txt",
            ],
        ),
    ] {
        let out = base.join(format!("out-{format:?}"));
        let mut args = vec![
            "register",
            input.to_str().unwrap(),
            "--json",
            "--write",
            out.to_str().unwrap(),
        ];
        if let Some(f) = flag {
            args.extend(["--write-format", f]);
        }
        let v = json_of(&eopnp(&args));
        assert_eq!(v["written"]["frames_replaced"], 5);
        assert_eq!(v["written"]["images_replaced"], 15);
        assert_eq!(
            v["written"]["frames_kept_input_pose"],
            serde_json::json!([5])
        );
        let mut names: Vec<String> = std::fs::read_dir(&out)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        assert_eq!(names, files);
        let written = read_model(&out, &ReadOptions::default()).unwrap();
        assert_eq!(written.cameras, model.cameras);
        assert_eq!(written.points, model.points);
        assert_eq!(written.rigs, model.rigs);
        for f in v["frames"].as_array().unwrap() {
            let id = u32::try_from(f["frame_id"].as_u64().unwrap()).unwrap();
            let frame = &written.frames[&id];
            assert_eq!(frame.data_ids, model.frames[&id].data_ids);
            if id == 5 {
                assert!(
                    f["error"]
                        .as_str()
                        .unwrap()
                        .contains("too few correspondences"),
                    "{f}"
                );
                assert_eq!(frame, &model.frames[&5]);
                for iid in frame.image_ids() {
                    assert_eq!(written.images[&iid], model.images[&iid]);
                }
                continue;
            }
            let d = pose_diff(
                &frame.rig_from_world.rotation(),
                &frame.rig_from_world.t,
                &matrix(&f["rotation"]),
                &vector(&f["translation"]),
            );
            assert!(d < 1e-12, "frame {id}: {d}");
            for img in f["images"].as_array().unwrap() {
                let iid = u32::try_from(img["image_id"].as_u64().unwrap()).unwrap();
                let w = &written.images[&iid];
                let (r, t) = w.pose();
                let d = pose_diff(
                    &r,
                    &t,
                    &matrix(&img["rotation"]),
                    &vector(&img["translation"]),
                );
                assert!(d < 1e-12, "image {iid}: {d}");
                // The written image pose is the written frame's composed with the rig's.
                let c = composed(&written, id, iid);
                let rc = c.rotation.to_rotation_matrix().into_inner();
                let d = pose_diff(&r, &t, &rc, &c.translation.vector);
                assert!(d < 1e-14, "image {iid}: {d}");
                let i = &model.images[&iid];
                assert_eq!(
                    (&w.name, w.camera_id, &w.points2d),
                    (&i.name, i.camera_id, &i.points2d)
                );
            }
        }
        // The table says what was written.
        let out2 = base.join(format!("table-{format:?}"));
        let o = eopnp(&[
            "register",
            input.to_str().unwrap(),
            "--write",
            out2.to_str().unwrap(),
        ]);
        assert!(o.status.success());
        let table = String::from_utf8_lossy(&o.stdout);
        assert!(
            table.contains(
                "5 of 6 frame poses replaced by the re-estimated ones, and the poses of their 15 \
                 images"
            ),
            "{table}"
        );
        assert!(
            table.contains("keeping the input model's poses: frame 5."),
            "{table}"
        );
        assert!(
            table.lines().any(
                |l| l.starts_with("5 (rig 2)") && l.contains("failed: too few correspondences")
            ),
            "{table}"
        );
    }
    let _ = std::fs::remove_dir_all(&base);
}

#[test]
fn per_image_and_the_image_by_image_options() {
    // --per-image: the images' table, as on a model without rigs.
    let v = json_of(&eopnp(&["register", TEXT_MODEL, "--json", "--per-image"]));
    assert!(v.get("registered").is_none());
    assert_eq!(v["images"].as_array().unwrap().len(), 18);
    // --outliers and --export-problems are per image: an input error without --per-image,
    // before anything is written.
    let base = scratch("options");
    let export = base.join("problems.json");
    for extra in [
        vec!["--outliers", "0.2"],
        vec!["--export-problems", export.to_str().unwrap()],
    ] {
        let mut args = vec!["register", TEXT_MODEL];
        args.extend(&extra);
        let o = eopnp(&args);
        assert_eq!(o.status.code(), Some(2));
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains("add --per-image"), "{err}");
        assert!(!export.exists());
        args.push("--per-image");
        assert!(eopnp(&args).status.success());
    }
    assert!(export.exists());
    // A model without rigs registers images as before.
    let boxes = concat!(env!("CARGO_MANIFEST_DIR"), "/../data/colmap-boxes");
    let v = json_of(&eopnp(&["register", boxes, "--json"]));
    assert!(v.get("registered").is_none() && v.get("frames").is_none());
    assert_eq!(v["images"].as_array().unwrap().len(), 6);
    let _ = std::fs::remove_dir_all(&base);
}

/// A model whose frames each hold one image (what COLMAP 3.12 and later write for a model
/// without rigs: a one-camera rig per camera, a frame per image) is registered image by image;
/// `--write` gives every registered image's frame the pose that gives the image's. `--per-image`
/// with `--write` on a model of multi-image frames is refused (it would leave the frames' poses
/// inconsistent with their images').
#[test]
fn one_image_frames_are_registered_image_by_image() {
    use eopnp::colmap::{DataId, Frame, Pose, SensorRig};
    let boxes = concat!(env!("CARGO_MANIFEST_DIR"), "/../data/colmap-boxes");
    let mut model = read_model(boxes, &ReadOptions::default()).unwrap();
    for &id in model.cameras.keys() {
        model.rigs.insert(
            id,
            SensorRig {
                id,
                ref_sensor: Some(SensorId::camera(id)),
                sensors: Vec::new(),
            },
        );
    }
    for (&id, img) in &model.images {
        model.frames.insert(
            id,
            Frame {
                id,
                rig_id: img.camera_id,
                rig_from_world: Pose { q: img.q, t: img.t },
                data_ids: vec![DataId {
                    sensor: SensorId::camera(img.camera_id),
                    id: u64::from(id),
                }],
            },
        );
    }
    let base = scratch("one-image-frames");
    let input = base.join("in");
    write_model(&model, &input, &WriteOptions::default()).unwrap();
    let v = json_of(&eopnp(&["register", input.to_str().unwrap(), "--json"]));
    assert!(v.get("registered").is_none() && v.get("frames").is_none());
    assert_eq!(v["images"].as_array().unwrap().len(), model.images.len());
    let out = base.join("out");
    let o = eopnp(&[
        "register",
        input.to_str().unwrap(),
        "--write",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let written = read_model(&out, &ReadOptions::default()).unwrap();
    let mut moved = 0;
    for (id, img) in &written.images {
        let frame = &written.frames[id];
        let (r, t) = (frame.rig_from_world.rotation(), frame.rig_from_world.t);
        let image = Pose { q: img.q, t: img.t };
        assert!(
            pose_diff(&r, &t, &image.rotation(), &image.t) <= 1e-12,
            "frame {id}: {r} {t} vs the image's {} {}",
            image.rotation(),
            image.t
        );
        let before = &model.frames[id].rig_from_world;
        moved += usize::from(pose_diff(&r, &t, &before.rotation(), &before.t) > 1e-9);
    }
    assert!(moved > 0, "no frame pose was replaced");
    // Multi-image frames: --per-image --write is refused, nothing written.
    let refused = base.join("refused");
    let o = eopnp(&[
        "register",
        TEXT_MODEL,
        "--per-image",
        "--write",
        refused.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("inconsistent"));
    assert!(!refused.exists());
    let _ = std::fs::remove_dir_all(&base);
}
