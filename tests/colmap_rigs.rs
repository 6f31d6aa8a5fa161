//! COLMAP models with rigs and frames (COLMAP 3.12 and later): the bundled synthetic model
//! (`data/colmap-rig`, text, and `data/colmap-rig-bin`, binary, both written by pycolmap:
//! `scripts/make_rig_model.py`), round trips through the writer, malformed rig and frame files
//! (located errors), and frame registration.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use eopnp::colmap::{
    parse_model_with_rigs, read_model, register_frame, register_image, write_model, Location,
    Model, ModelError, ModelErrorKind, ModelFormat, Overwrite, Pose, ReadOptions, RegisterError,
    Registrar, SensorId, SensorType, WriteOptions,
};
use eopnp::ransac::Ransac;
use eopnp::{Refinement, Solver};

/// An edit of a model, of a line of a text file, of the bytes of a binary file.
type ModelEdit = Box<dyn Fn(&mut Model)>;
type LineEdit = Box<dyn Fn(&str) -> String>;
type BytesEdit = Box<dyn Fn(&mut Vec<u8>)>;

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("data")
        .join(name)
}

fn rig_model() -> Model {
    read_model(
        data("colmap-rig"),
        &ReadOptions::default().format(ModelFormat::Text),
    )
    .expect("bundled rig model reads")
}

/// A fresh scratch directory under Cargo's per-test temporary directory, unique to the call
/// (the tests run in parallel, several on copies of the same file).
fn scratch(name: &str) -> PathBuf {
    static NEXT: AtomicUsize = AtomicUsize::new(0);
    let n = NEXT.fetch_add(1, Ordering::Relaxed);
    let d = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("colmap-rigs-{name}-{}-{n}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("create scratch dir");
    d
}

fn sorted_files(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn bundled_rig_model_has_the_expected_content() {
    let m = rig_model();
    assert_eq!(
        (m.cameras.len(), m.images.len(), m.points.len()),
        (6, 18, 40)
    );
    assert_eq!((m.rigs.len(), m.frames.len()), (2, 6));
    let rig = &m.rigs[&1];
    assert_eq!(rig.ref_sensor, Some(SensorId::camera(1)));
    assert_eq!(rig.sensors.len(), 2);
    assert_eq!(
        rig.sensor_from_rig(SensorId::camera(1)),
        Some(Pose::identity())
    );
    assert!(rig
        .sensors
        .iter()
        .all(|(s, p)| s.kind == SensorType::Camera && p.is_some()));
    let frame = &m.frames[&1];
    assert_eq!(frame.rig_id, 1);
    assert_eq!(frame.image_ids().collect::<Vec<_>>(), [1, 2, 3]);
    // Every image's stored pose is its camera's pose in the rig composed with its frame's.
    for f in m.frames.values() {
        let rig = &m.rigs[&f.rig_id];
        let rig_from_world = f.rig_from_world.isometry();
        for id in f.image_ids() {
            let img = &m.images[&id];
            let cam_from_rig = rig
                .sensor_from_rig(SensorId::camera(img.camera_id))
                .unwrap()
                .isometry();
            let composed = cam_from_rig * rig_from_world;
            let (r, t) = img.pose();
            let r_composed = composed.rotation.to_rotation_matrix().into_inner();
            assert!((r - r_composed).norm() < 1e-14, "image {id}");
            assert!(
                (t - composed.translation.vector).norm() < 1e-14,
                "image {id}"
            );
        }
    }
}

/// pycolmap's binary copy reads to the model of its text copy, bit for bit, and this crate's
/// binary writer reproduces pycolmap's rig and frame files byte for byte.
#[test]
fn binary_copy_reads_identically_and_encodes_as_pycolmap() {
    let text = rig_model();
    let bin = read_model(data("colmap-rig-bin"), &ReadOptions::default()).unwrap();
    assert!(bin == text);
    let dir = scratch("pycolmap-bytes");
    let out = dir.join("model");
    write_model(&text, &out, &WriteOptions::default()).unwrap();
    for f in [
        "cameras.bin",
        "rigs.bin",
        "frames.bin",
        "points3D.bin",
        "images.bin",
    ] {
        assert_eq!(
            std::fs::read(out.join(f)).unwrap(),
            std::fs::read(data("colmap-rig-bin").join(f)).unwrap(),
            "{f} differs from pycolmap's"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Written in either format from either, the model reads back identical; the directory holds
/// the five files.
#[test]
fn rig_models_round_trip_in_both_formats() {
    let m = rig_model();
    let dir = scratch("roundtrip");
    for (k, format) in [ModelFormat::Text, ModelFormat::Binary, ModelFormat::Text]
        .into_iter()
        .enumerate()
    {
        let out = dir.join(format!("m{k}"));
        write_model(&m, &out, &WriteOptions::default().format(format)).unwrap();
        let mut want: Vec<String> = format
            .file_names()
            .into_iter()
            .chain(format.rig_file_names())
            .map(String::from)
            .collect();
        want.sort();
        assert_eq!(sorted_files(&out), want);
        let back = read_model(&out, &ReadOptions::default()).unwrap();
        assert!(back == m, "{format:?}");
        // Through tiny buffers too.
        let files: Vec<Vec<u8>> = want_order(format)
            .iter()
            .map(|n| std::fs::read(out.join(n)).unwrap())
            .collect();
        let files = [&files[0][..], &files[1], &files[2], &files[3], &files[4]];
        for capacity in [None, Some(1), Some(3), Some(7)] {
            let parsed = parse_model_with_rigs(format, files, &ReadOptions::default(), capacity)
                .unwrap_or_else(|e| panic!("{format:?} through {capacity:?}: {e}"));
            assert!(parsed == m, "{format:?} through {capacity:?}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

fn want_order(format: ModelFormat) -> Vec<&'static str> {
    format
        .file_names()
        .into_iter()
        .chain(format.rig_file_names())
        .collect()
}

/// Overwriting a model with rigs by one without removes the stale rig files (which would
/// otherwise be read with the new model); the other way round adds them.
#[test]
fn overwriting_keeps_rig_files_consistent() {
    let with = rig_model();
    let mut without = with.clone();
    without.rigs.clear();
    without.frames.clear();
    let dir = scratch("overwrite");
    let files = WriteOptions::default()
        .format(ModelFormat::Text)
        .overwrite(Overwrite::Files);
    write_model(&with, &dir, &files).unwrap();
    assert_eq!(sorted_files(&dir).len(), 5);
    std::fs::write(dir.join("notes.md"), "kept").unwrap();
    write_model(&without, &dir, &files).unwrap();
    assert_eq!(
        sorted_files(&dir),
        ["cameras.txt", "images.txt", "notes.md", "points3D.txt"]
    );
    assert!(read_model(&dir, &ReadOptions::default()).unwrap() == without);
    write_model(&with, &dir, &files).unwrap();
    assert!(read_model(&dir, &ReadOptions::default()).unwrap() == with);
    assert_eq!(sorted_files(&dir).len(), 6);
    let _ = std::fs::remove_dir_all(&dir);
}

/// The writer refuses rigs and frames that would not read back, before writing anything.
#[test]
fn writer_refuses_inconsistent_rigs() {
    let m = rig_model();
    let dir = scratch("refusals");
    let cases: Vec<(&str, ModelEdit)> = vec![
        (
            "rig 9, which is not",
            Box::new(|m| m.frames.get_mut(&1).unwrap().rig_id = 9),
        ),
        (
            "image 1 is in no frame",
            Box::new(|m| {
                m.frames.get_mut(&1).unwrap().data_ids.remove(0);
            }),
        ),
        (
            "image 4 is in frames 1 and 2",
            Box::new(|m| {
                let d = m.frames[&2].data_ids[0];
                m.frames.get_mut(&1).unwrap().data_ids.push(d);
            }),
        ),
        ("image 1 is in no frame", Box::new(|m| m.frames.clear())),
        (
            "frame 1 refers to rig 1, which is not",
            Box::new(|m| m.rigs.clear()),
        ),
        (
            "not finite",
            Box::new(|m| m.frames.get_mut(&3).unwrap().rig_from_world.t.x = f64::NAN),
        ),
        (
            "zero",
            Box::new(|m| m.rigs.get_mut(&2).unwrap().sensors[0].1.as_mut().unwrap().q = [0.0; 4]),
        ),
        (
            "appears twice",
            Box::new(|m| {
                let s = m.rigs[&1].sensors[0];
                m.rigs.get_mut(&1).unwrap().sensors.push(s);
            }),
        ),
        (
            "camera 9",
            Box::new(|m| m.rigs.get_mut(&1).unwrap().ref_sensor = Some(SensorId::camera(9))),
        ),
    ];
    for (want, edit) in cases {
        let mut bad = m.clone();
        edit(&mut bad);
        for format in [ModelFormat::Text, ModelFormat::Binary] {
            let out = dir.join("never");
            let e = write_model(&bad, &out, &WriteOptions::default().format(format)).unwrap_err();
            assert_eq!(e.kind(), std::io::ErrorKind::InvalidInput, "{want}: {e}");
            assert!(e.to_string().contains(want), "{want}: {e}");
            assert!(!out.exists());
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The bundled text rig model with one file replaced by `contents`.
fn rig_model_with(file: &str, contents: &[u8]) -> Result<Model, ModelError> {
    model_with("colmap-rig", file, Some(contents))
}

/// A copy of bundled model `name` with `file` replaced by `contents` (removed if `None`).
fn model_with(name: &str, file: &str, contents: Option<&[u8]>) -> Result<Model, ModelError> {
    let dir = scratch(&format!("{name}-{}", file.replace('.', "-")));
    for f in sorted_files(&data(name)) {
        std::fs::copy(data(name).join(&f), dir.join(&f)).unwrap();
    }
    match contents {
        Some(c) => std::fs::write(dir.join(file), c).unwrap(),
        None => std::fs::remove_file(dir.join(file)).unwrap(),
    }
    let r = read_model(&dir, &ReadOptions::default());
    let _ = std::fs::remove_dir_all(&dir);
    r
}

/// `rigs.txt` or `frames.txt` with record line `line` (1-based, of the whole file) replaced.
fn with_line(file: &str, line: usize, f: impl Fn(&str) -> String) -> Vec<u8> {
    let text = std::fs::read_to_string(data("colmap-rig").join(file)).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    lines[line - 1] = f(&lines[line - 1]);
    (lines.join("\n") + "\n").into_bytes()
}

#[test]
fn malformed_text_rig_files_report_file_and_line() {
    let cases: Vec<(&str, usize, LineEdit, &str)> = vec![
        (
            "rigs.txt",
            4,
            Box::new(|l| l.replacen("CAMERA 2", "LIDAR 2", 1)),
            "bad SENSOR_TYPE: \"LIDAR\"",
        ),
        (
            "rigs.txt",
            4,
            Box::new(|l| l.replacen("CAMERA 2 1", "CAMERA 2 2", 1)),
            "bad HAS_POSE: \"2\"",
        ),
        (
            "rigs.txt",
            5,
            Box::new(|l| l.replacen("2 3", "2 4", 1)),
            "line ends before SENSOR_TYPE",
        ),
        (
            "rigs.txt",
            5,
            Box::new(|l| l.replacen("2 3", "2 2", 1)),
            "unexpected \"CAMERA\" after the 2 sensors of rig 2",
        ),
        (
            "rigs.txt",
            5,
            Box::new(|l| l.replacen("2 3", "1 3", 1)),
            "duplicate rig id 1",
        ),
        (
            "rigs.txt",
            4,
            Box::new(|l| l.replacen("CAMERA 3", "CAMERA 2", 1)),
            "rig 1: sensor CAMERA 2 appears twice",
        ),
        (
            "rigs.txt",
            4,
            Box::new(|l| l.replacen("CAMERA 3", "CAMERA 7", 1)),
            "rig 1 has camera 7, which is not in the cameras file",
        ),
        (
            "frames.txt",
            4,
            Box::new(|l| l.replacen("1 1 ", "1 7 ", 1)),
            "frame 1 refers to rig 7, which is not in the rigs file",
        ),
        (
            "frames.txt",
            5,
            Box::new(|l| l.replacen(" 3 CAMERA", " 4 CAMERA", 1)),
            "line ends before SENSOR_TYPE",
        ),
        (
            "frames.txt",
            5,
            Box::new(|l| l.replacen(" 3 CAMERA", " 2 CAMERA", 1)),
            "unexpected \"CAMERA\" after the 2 data ids of frame 2",
        ),
        (
            "frames.txt",
            5,
            Box::new(|l| l.replacen("CAMERA 3 6", "CAMERA 3 99", 1)),
            "frame 2 refers to image 99, which is not in the images file",
        ),
        (
            "frames.txt",
            5,
            Box::new(|l| l.replacen("CAMERA 3 6", "CAMERA 3 5", 1)),
            "frame 2: image 5 is of camera 2, not of camera 3",
        ),
        (
            "frames.txt",
            5,
            Box::new(|l| l.replacen("CAMERA 3 6", "CAMERA 4 6", 1)),
            "sensor CAMERA 4 of data id 6 is not a sensor of rig 1",
        ),
        (
            "frames.txt",
            5,
            Box::new(|l| l.replacen("CAMERA 3 6", "CAMERA 3 3", 1)),
            "image 3 is in frames 1 and 2",
        ),
        (
            "frames.txt",
            5,
            Box::new(|l| l.replacen("2 1 ", "2 1 0 0 0 0 ", 1)),
            "RIG_FROM_WORLD: quaternion (0, 0, 0, 0) is zero",
        ),
        (
            "frames.txt",
            5,
            Box::new(|l| l.replacen("2 1 0.", "2 1 nan 0.", 1)),
            "RIG_FROM_WORLD QW is not finite: \"nan\"",
        ),
    ];
    for (file, line, edit, want) in cases {
        let e = rig_model_with(file, &with_line(file, line, edit)).unwrap_err();
        assert_eq!(e.kind, ModelErrorKind::Invalid, "{want}: {e}");
        assert_eq!(
            (e.file.file_name().unwrap().to_str().unwrap(), e.location),
            (file, Location::Line(line)),
            "{want}: {e}"
        );
        assert!(e.reason.contains(want), "want {want:?}, got {e}");
    }
    // An image in no frame is reported where the image is (its observations line, line 40, as
    // the reader locates an image's other reference errors).
    let e = rig_model_with(
        "frames.txt",
        &with_line("frames.txt", 9, |l| {
            l.replacen(" 3 CAMERA 4 16", " 2 CAMERA 4 16", 1)
                .replacen(" CAMERA 6 18", "", 1)
        }),
    )
    .unwrap_err();
    assert_eq!(e.file.file_name().unwrap(), "images.txt", "{e}");
    assert_eq!(e.location, Location::Line(40), "{e}");
    assert!(e.reason.contains("image 18 is in no frame"), "{e}");
}

#[test]
fn rig_files_come_in_pairs() {
    for (dir, missing, present) in [
        ("colmap-rig", "frames.txt", "rigs.txt"),
        ("colmap-rig", "rigs.txt", "frames.txt"),
        ("colmap-rig-bin", "frames.bin", "rigs.bin"),
    ] {
        let e = model_with(dir, missing, None).unwrap_err();
        assert_eq!(e.kind, ModelErrorKind::Io, "{e}");
        assert_eq!(e.file.file_name().unwrap(), missing);
        assert!(e.reason.contains(&format!("{present} is there")), "{e}");
    }
    // A rig file that is not a regular file is refused as the others are.
    let d = scratch("fifo-rig");
    for f in sorted_files(&data("colmap-rig")) {
        std::fs::copy(data("colmap-rig").join(&f), d.join(&f)).unwrap();
    }
    std::fs::remove_file(d.join("rigs.txt")).unwrap();
    std::fs::create_dir(d.join("rigs.txt")).unwrap();
    let e = read_model(&d, &ReadOptions::default()).unwrap_err();
    assert_eq!(e.kind, ModelErrorKind::NotRegularFile, "{e}");
    // And the size limit applies to them.
    std::fs::remove_dir(d.join("rigs.txt")).unwrap();
    std::fs::copy(data("colmap-rig").join("rigs.txt"), d.join("rigs.txt")).unwrap();
    let e = read_model(&d, &ReadOptions::default().max_file_bytes(1000)).unwrap_err();
    assert_eq!(e.file.file_name().unwrap(), "images.txt", "{e}");
    let len = std::fs::metadata(d.join("frames.txt")).unwrap().len();
    let images_len = std::fs::metadata(d.join("images.txt")).unwrap().len();
    std::fs::write(d.join("images.txt"), vec![b'#'; 10]).unwrap();
    std::fs::write(d.join("points3D.txt"), "").unwrap();
    let e = read_model(&d, &ReadOptions::default().max_file_bytes(len - 1)).unwrap_err();
    assert!(images_len > len);
    assert_eq!(e.file.file_name().unwrap(), "frames.txt", "{e}");
    assert!(matches!(e.kind, ModelErrorKind::Limit(_)), "{e}");
    let _ = std::fs::remove_dir_all(&d);
}

/// The bundled binary rig model with `file` cut, patched or replaced.
fn binary_with(file: &str, edit: impl Fn(&mut Vec<u8>)) -> Result<Model, ModelError> {
    let mut bytes = std::fs::read(data("colmap-rig-bin").join(file)).unwrap();
    edit(&mut bytes);
    model_with("colmap-rig-bin", file, Some(&bytes))
}

#[test]
fn malformed_binary_rig_files_report_file_and_offset() {
    // rigs.bin: count 8, rig 1 at 8: id, 3 sensors, reference (type, id) at 16, then sensor 2:
    // type at 24, id at 28, has-pose at 32, pose at 33..89; sensor 3 at 89.
    let cases: Vec<(&str, BytesEdit, u64, &str)> = vec![
        (
            "rigs.bin",
            Box::new(|b| b.truncate(50)),
            49,
            "unexpected end of file",
        ),
        (
            "rigs.bin",
            Box::new(|b| b[0..8].copy_from_slice(&u64::MAX.to_le_bytes())),
            0,
            "number of rigs",
        ),
        (
            "rigs.bin",
            Box::new(|b| b[12..16].copy_from_slice(&u32::MAX.to_le_bytes())),
            12,
            "number of sensors",
        ),
        (
            "rigs.bin",
            Box::new(|b| b[24..28].copy_from_slice(&7i32.to_le_bytes())),
            24,
            "sensor type 7",
        ),
        ("rigs.bin", Box::new(|b| b[32] = 2), 32, "bad HAS_POSE: 2"),
        (
            "rigs.bin",
            Box::new(|b| b[33..41].copy_from_slice(&f64::NAN.to_le_bytes())),
            33,
            "quaternion is not finite",
        ),
        (
            "rigs.bin",
            Box::new(|b| b.push(0)),
            300,
            "1 unexpected trailing bytes",
        ),
        (
            "frames.bin",
            Box::new(|b| b[8..12].copy_from_slice(&2u32.to_le_bytes())),
            124,
            "duplicate frame id 2",
        ),
        (
            "frames.bin",
            Box::new(|b| b[72..76].copy_from_slice(&u32::MAX.to_le_bytes())),
            72,
            "number of data ids",
        ),
        (
            "frames.bin",
            Box::new(|b| b[12..16].copy_from_slice(&5u32.to_le_bytes())),
            8,
            "frame 1 refers to rig 5",
        ),
    ];
    for (file, edit, offset, want) in cases {
        let e = binary_with(file, edit).unwrap_err();
        assert_eq!(e.file.file_name().unwrap(), file, "{want}: {e}");
        assert_eq!(e.location, Location::Offset(offset), "{want}: {e}");
        assert!(e.reason.contains(want), "want {want:?}, got {e}");
    }
}

/// Noise-free synthetic frames: each frame's rig pose from its three images' correspondences
/// is the model's to rounding, plain and with RANSAC, and a registrar gives what
/// `register_frame` gives.
#[test]
fn frames_register_to_the_model_poses() {
    let m = rig_model();
    let solver = Solver::default();
    let ransac = Ransac::default().seed(3);
    let mut registrar = Registrar::new(&m);
    for id in m.frames.keys() {
        let plain = register_frame(&m, *id, &solver, None).unwrap();
        assert_eq!(plain.image_ids.len(), 3);
        assert_eq!(plain.n, 3 * 40);
        assert_eq!(plain.inliers, plain.n);
        assert!(
            plain.rotation_error_deg < 1e-8,
            "frame {id}: {}",
            plain.rotation_error_deg
        );
        assert!(
            plain.translation_error_pct < 1e-8,
            "frame {id}: {}",
            plain.translation_error_pct
        );
        assert!(
            plain.rmse_px < 1e-8 && plain.model_rmse_px < 1e-8,
            "frame {id}"
        );
        let robust = register_frame(&m, *id, &solver, Some(&ransac)).unwrap();
        assert_eq!(robust.inliers, robust.n);
        assert!(robust.ransac.is_some());
        assert!(
            robust.rotation_error_deg < 1e-8,
            "frame {id}: {}",
            robust.rotation_error_deg
        );
        let again = registrar.register_frame(*id, &solver, None).unwrap();
        assert_eq!(again.solution.rotation, plain.solution.rotation);
        assert_eq!(again.solution.translation, plain.solution.translation);
        let algebraic =
            register_frame(&m, *id, &solver.refinement(Refinement::Algebraic), None).unwrap();
        assert!(
            algebraic.rotation_error_deg < 1e-6,
            "frame {id}: {}",
            algebraic.rotation_error_deg
        );
    }
    // Each image alone registers too (the model's image poses are the composed ones).
    for id in m.images.keys() {
        let reg = register_image(&m, *id, &solver, None).unwrap();
        assert!(
            reg.rotation_error_deg < 1e-8,
            "image {id}: {}",
            reg.rotation_error_deg
        );
    }
}

#[test]
fn frame_registration_errors_are_typed() {
    let m = rig_model();
    let s = Solver::default();
    assert_eq!(
        register_frame(&m, 99, &s, None).unwrap_err(),
        RegisterError::UnknownFrame(99)
    );
    let mut bad = m.clone();
    bad.frames.get_mut(&1).unwrap().rig_id = 5;
    assert_eq!(
        register_frame(&bad, 1, &s, None).unwrap_err(),
        RegisterError::UnknownRig(5)
    );
    let mut bad = m.clone();
    bad.rigs.get_mut(&1).unwrap().sensors[1].1 = None;
    assert_eq!(
        register_frame(&bad, 2, &s, None).unwrap_err(),
        RegisterError::NoSensorPose {
            rig_id: 1,
            camera_id: 3
        }
    );
    let mut bad = m.clone();
    bad.frames.get_mut(&4).unwrap().data_ids.clear();
    assert_eq!(
        register_frame(&bad, 4, &s, None).unwrap_err(),
        RegisterError::EmptyFrame(4)
    );
    let mut bad = m;
    bad.images.remove(&2);
    assert_eq!(
        register_frame(&bad, 1, &s, None).unwrap_err(),
        RegisterError::UnknownImage(2)
    );
}

/// The bundled model's five files in `format`, in the order of `parse_model_with_rigs`.
fn bundled_files(format: ModelFormat) -> Vec<Vec<u8>> {
    let dir = match format {
        ModelFormat::Text => data("colmap-rig"),
        ModelFormat::Binary => data("colmap-rig-bin"),
    };
    want_order(format)
        .iter()
        .map(|n| std::fs::read(dir.join(n)).unwrap())
        .collect()
}

fn parse_five(format: ModelFormat, files: &[Vec<u8>]) -> Result<Model, ModelError> {
    let f = [&files[0][..], &files[1], &files[2], &files[3], &files[4]];
    parse_model_with_rigs(format, f, &ReadOptions::default(), None)
}

/// Every strict prefix of `rigs.bin` and `frames.bin` is an error located in that file (a
/// count always claims more than is left); every prefix of the text rig files, and random
/// corruptions (byte flips, insertions, truncations) of all four, return a model or an error,
/// never panic.
#[test]
fn truncations_and_corruptions_of_rig_files_never_panic() {
    use rand::{Rng, SeedableRng};
    for format in [ModelFormat::Text, ModelFormat::Binary] {
        let files = bundled_files(format);
        assert!(parse_five(format, &files).unwrap() == rig_model());
        for k in [3, 4] {
            let name = want_order(format)[k];
            for len in 0..files[k].len() {
                let mut cut = files.clone();
                cut[k].truncate(len);
                let r = parse_five(format, &cut);
                if format == ModelFormat::Binary {
                    let e = r.expect_err(&format!("{name} cut to {len} bytes"));
                    assert_eq!(e.file.file_name().unwrap(), name, "{len}: {e}");
                    assert!(matches!(e.location, Location::Offset(_)), "{len}: {e}");
                }
            }
        }
    }
    let mut rng = rand_pcg::Pcg64::seed_from_u64(11);
    let (mut ok, mut err) = (0, 0);
    for format in [ModelFormat::Text, ModelFormat::Binary] {
        let files = bundled_files(format);
        for k in [3, 4] {
            for _ in 0..300 {
                let mut bad = files.clone();
                let b = &mut bad[k];
                match rng.random_range(0..3) {
                    0 => {
                        for _ in 0..rng.random_range(1..4) {
                            let i = rng.random_range(0..b.len());
                            b[i] = rng.random();
                        }
                    }
                    1 => b.truncate(rng.random_range(0..b.len())),
                    _ => {
                        let i = rng.random_range(0..=b.len());
                        b.insert(i, rng.random());
                    }
                }
                match parse_five(format, &bad) {
                    Ok(_) => ok += 1,
                    Err(_) => err += 1,
                }
            }
        }
    }
    // Most corruptions are caught (a flipped digit of a pose can still be a valid model).
    println!("random corruptions of the rig files: {ok} read, {err} refused");
    assert_eq!(ok + err, 1200);
    assert!(err > 600, "{err} errors of 1200");
}
