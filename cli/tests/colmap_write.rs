//! The COLMAP model writer (`colmap::write_model`, text and binary) and `eopnp register
//! --write`: write then read back gives the identical model; the CLI writes the registration's
//! poses; bad output paths are refused (exit code 2) with the input untouched; a failure in the
//! middle of writing leaves no partial model and no temporary files.

use std::collections::BTreeMap;
use std::io::ErrorKind;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use eopnp::colmap::{
    encode_model, parse_model, read_model, write_model, Model, ModelFormat, Overwrite, ReadOptions,
    WriteOptions,
};

const TEXT_MODEL: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../data/colmap-boxes");
const BIN_MODEL: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../data/colmap-boxes-bin");
const FORMATS: [ModelFormat; 2] = [ModelFormat::Text, ModelFormat::Binary];

/// A fresh, empty scratch directory for one test.
fn scratch(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("colmap-write-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The names in a directory, sorted.
fn entries(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// Every file of a directory (recursively) and its bytes.
fn snapshot(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    let mut out = BTreeMap::new();
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            out.extend(snapshot(&p));
        } else {
            out.insert(p.clone(), std::fs::read(&p).unwrap());
        }
    }
    out
}

fn eopnp(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_eopnp"))
        .args(args)
        .output()
        .unwrap()
}

fn format_of(dir: &Path) -> ModelFormat {
    eopnp::colmap::detect_format(dir).unwrap()
}

#[test]
fn write_then_read_gives_the_identical_model() {
    let base = scratch("roundtrip");
    for (input, name) in [(TEXT_MODEL, "text-in"), (BIN_MODEL, "bin-in")] {
        let model = read_model(input, &ReadOptions::default()).unwrap();
        assert_eq!(model.images.len(), 6);
        for format in FORMATS {
            let out = base.join(format!("{name}-{format:?}"));
            write_model(&model, &out, &WriteOptions::default().format(format)).unwrap();
            assert_eq!(format_of(&out), format);
            assert_eq!(entries(&out), {
                let mut n = format.file_names().map(String::from).to_vec();
                n.sort();
                n
            });
            let back = read_model(&out, &ReadOptions::default()).unwrap();
            assert_eq!(back, model, "{name} -> {format:?}");
            // Bit for bit (PartialEq would let 0.0 == -0.0 pass).
            for (a, b) in model.images.values().zip(back.images.values()) {
                for (x, y) in
                    a.q.iter()
                        .chain(a.t.iter())
                        .zip(b.q.iter().chain(b.t.iter()))
                {
                    assert_eq!(x.to_bits(), y.to_bits());
                }
            }
            // And through the in-memory parsers.
            let files = encode_model(&model, format).unwrap();
            let parsed = match format {
                ModelFormat::Text => parse_model(
                    ModelFormat::Text,
                    [&files[0], &files[1], &files[2]],
                    &ReadOptions::default(),
                ),
                ModelFormat::Binary => parse_model(
                    ModelFormat::Binary,
                    [&files[0], &files[1], &files[2]],
                    &ReadOptions::default(),
                ),
            };
            assert_eq!(parsed.unwrap(), model);
        }
    }
}

#[test]
fn written_files_are_colmaps_own() {
    // The binary files are byte-identical to COLMAP's; the text cameras and images files too
    // (same header comments, and COLMAP's 6-digit values print the same in shortest form);
    // points3D.txt differs only in the order of the points (written by id).
    let base = scratch("colmap-bytes");
    let bin = read_model(BIN_MODEL, &ReadOptions::default()).unwrap();
    write_model(
        &bin,
        base.join("b"),
        &WriteOptions::default().format(ModelFormat::Binary),
    )
    .unwrap();
    for f in ModelFormat::Binary.file_names() {
        let ours = std::fs::read(base.join("b").join(f)).unwrap();
        assert!(
            ours == std::fs::read(Path::new(BIN_MODEL).join(f)).unwrap(),
            "{f}"
        );
    }
    let text = read_model(TEXT_MODEL, &ReadOptions::default()).unwrap();
    write_model(
        &text,
        base.join("t"),
        &WriteOptions::default().format(ModelFormat::Text),
    )
    .unwrap();
    for f in ["cameras.txt", "images.txt"] {
        let ours = std::fs::read_to_string(base.join("t").join(f)).unwrap();
        let theirs = std::fs::read_to_string(Path::new(TEXT_MODEL).join(f)).unwrap();
        assert!(ours == theirs, "{f}");
    }
    let sorted = |s: String| {
        let mut l: Vec<String> = s.lines().map(String::from).collect();
        l.sort();
        l
    };
    let f = "points3D.txt";
    assert_eq!(
        sorted(std::fs::read_to_string(base.join("t").join(f)).unwrap()),
        sorted(std::fs::read_to_string(Path::new(TEXT_MODEL).join(f)).unwrap())
    );
}

#[test]
fn extreme_values_round_trip_exactly_in_text() {
    let mut model = read_model(TEXT_MODEL, &ReadOptions::default()).unwrap();
    let values = [
        -0.0,
        5e-324,
        f64::MIN_POSITIVE,
        1e-7,
        0.1 + 0.2,
        1e15 + 0.5,
        1e16,
        f64::MAX,
        -f64::MAX,
        std::f64::consts::PI,
    ];
    let img = model.images.values_mut().next().unwrap();
    for (k, v) in values.iter().enumerate() {
        img.points2d[k].0.x = *v;
    }
    img.t.x = 1e300;
    img.q = [1e-300, 1.0, -0.0, 5e-324];
    let pt = model.points.values_mut().next().unwrap();
    pt.xyz.y = -1e-300;
    pt.error = f64::INFINITY;
    let out = scratch("extreme").join("m");
    write_model(
        &model,
        &out,
        &WriteOptions::default().format(ModelFormat::Text),
    )
    .unwrap();
    let back = read_model(&out, &ReadOptions::default().format(ModelFormat::Text)).unwrap();
    let a = &model.images.values().next().unwrap();
    let b = &back.images.values().next().unwrap();
    for k in 0..values.len() {
        assert_eq!(a.points2d[k].0.x.to_bits(), b.points2d[k].0.x.to_bits());
    }
    assert_eq!(back, model);
    // No number needs hundreds of digits.
    let longest = std::fs::read_to_string(out.join("images.txt"))
        .unwrap()
        .split_whitespace()
        .map(str::len)
        .max()
        .unwrap();
    assert!(longest < 40, "{longest}");
}

#[test]
fn refuses_what_would_not_read_back() {
    let base = scratch("unrepresentable");
    let model = read_model(TEXT_MODEL, &ReadOptions::default()).unwrap();
    let first = *model.images.keys().next().unwrap();
    let cases: Vec<(Model, ModelFormat)> = vec![
        {
            let mut m = model.clone();
            m.images.get_mut(&first).unwrap().name = "two\nlines".into();
            (m, ModelFormat::Text)
        },
        {
            let mut m = model.clone();
            m.images.get_mut(&first).unwrap().name = " leading space".into();
            (m, ModelFormat::Text)
        },
        {
            let mut m = model.clone();
            m.images.get_mut(&first).unwrap().name = "nul\0byte".into();
            (m, ModelFormat::Binary)
        },
        {
            let mut m = model.clone();
            m.images.get_mut(&first).unwrap().q = [0.0; 4];
            (m, ModelFormat::Binary)
        },
        {
            let mut m = model.clone();
            m.images.get_mut(&first).unwrap().t.y = f64::NAN;
            (m, ModelFormat::Text)
        },
        {
            let mut m = model.clone();
            m.images.get_mut(&first).unwrap().camera_id = 999;
            (m, ModelFormat::Text)
        },
        {
            let mut m = model.clone();
            let id = *m.points.keys().next().unwrap();
            m.points.remove(&id);
            (m, ModelFormat::Binary)
        },
        {
            // A 3D point id the binary format's i64 cannot hold.
            let mut m = model.clone();
            let mut p = m.points.values().next().unwrap().clone();
            p.id = u64::MAX;
            m.points.insert(u64::MAX, p);
            m.images.get_mut(&first).unwrap().points2d[0].1 = Some(u64::MAX);
            (m, ModelFormat::Binary)
        },
        {
            let mut m = model.clone();
            let img = m.images.remove(&first).unwrap();
            m.images.insert(first + 1000, img);
            (m, ModelFormat::Text)
        },
    ];
    for (k, (m, format)) in cases.iter().enumerate() {
        let out = base.join(format!("case{k}"));
        let e = write_model(m, &out, &WriteOptions::default().format(*format)).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::InvalidInput, "case {k}: {e}");
        assert!(!out.exists(), "case {k}");
    }
    assert!(entries(&base).is_empty(), "{:?}", entries(&base));
    // The same u64 id is fine in text.
    let (m, _) = &cases[7];
    write_model(
        m,
        base.join("big-id"),
        &WriteOptions::default().format(ModelFormat::Text),
    )
    .unwrap();
    assert_eq!(
        &read_model(base.join("big-id"), &ReadOptions::default()).unwrap(),
        m
    );
}

#[test]
fn existing_directories() {
    let base = scratch("existing");
    let model = read_model(TEXT_MODEL, &ReadOptions::default()).unwrap();
    // An empty directory is written into.
    let empty = base.join("empty");
    std::fs::create_dir(&empty).unwrap();
    write_model(
        &model,
        &empty,
        &WriteOptions::default().format(ModelFormat::Binary),
    )
    .unwrap();
    assert_eq!(read_model(&empty, &ReadOptions::default()).unwrap(), model);
    // A non-empty one is refused and left as it was.
    let before = snapshot(&empty);
    let e = write_model(
        &model,
        &empty,
        &WriteOptions::default().format(ModelFormat::Text),
    )
    .unwrap_err();
    assert_eq!(e.kind(), ErrorKind::DirectoryNotEmpty, "{e}");
    assert_eq!(snapshot(&empty), before);
    // Text over a complete binary model is refused even with Overwrite::Files.
    let e = write_model(
        &model,
        &empty,
        &WriteOptions::default()
            .format(ModelFormat::Text)
            .overwrite(Overwrite::Files),
    )
    .unwrap_err();
    assert_eq!(e.kind(), ErrorKind::AlreadyExists, "{e}");
    assert_eq!(snapshot(&empty), before);
    // Overwrite::Files replaces the three files and keeps the others.
    std::fs::write(empty.join("notes.txt"), b"keep me").unwrap();
    let mut moved = model.clone();
    moved.images.values_mut().for_each(|i| i.t.x += 1.0);
    write_model(
        &moved,
        &empty,
        &WriteOptions::default().overwrite(Overwrite::Files),
    )
    .unwrap();
    assert_eq!(
        read_model(&empty, &ReadOptions::default().format(ModelFormat::Binary)).unwrap(),
        moved
    );
    assert_eq!(std::fs::read(empty.join("notes.txt")).unwrap(), b"keep me");
    assert_eq!(
        entries(&empty),
        ["cameras.bin", "images.bin", "notes.txt", "points3D.bin"]
    );
    // A file, a missing parent, a parent that is a file.
    let file = base.join("file");
    std::fs::write(&file, b"x").unwrap();
    let e = write_model(
        &model,
        &file,
        &WriteOptions::default().format(ModelFormat::Text),
    )
    .unwrap_err();
    assert_eq!(e.kind(), ErrorKind::NotADirectory, "{e}");
    let e = write_model(
        &model,
        base.join("missing/out"),
        &WriteOptions::default().format(ModelFormat::Text),
    )
    .unwrap_err();
    assert_eq!(e.kind(), ErrorKind::NotFound, "{e}");
    let e = write_model(
        &model,
        file.join("out"),
        &WriteOptions::default().format(ModelFormat::Text),
    )
    .unwrap_err();
    assert_eq!(e.kind(), ErrorKind::NotADirectory, "{e}");
    assert_eq!(std::fs::read(&file).unwrap(), b"x");
    assert_eq!(entries(&base), ["empty", "file"]);
}

/// `x` equals `y` to `tol` relative to the larger of `|y|` and 1.
fn close(x: f64, y: f64, tol: f64) -> bool {
    (x - y).abs() <= tol * y.abs().max(1.0)
}

#[test]
fn cli_writes_the_registered_poses() {
    let base = scratch("cli-poses");
    for (input, format, flag) in [
        (TEXT_MODEL, ModelFormat::Text, None),
        (TEXT_MODEL, ModelFormat::Binary, Some("binary")),
        (BIN_MODEL, ModelFormat::Binary, None),
        (BIN_MODEL, ModelFormat::Text, Some("text")),
    ] {
        let out = base.join(format!("{}-{format:?}", input.len()));
        let out_s = out.to_str().unwrap();
        let mut args = vec!["register", input, "--json", "--write", out_s];
        if let Some(f) = flag {
            args.extend(["--write-format", f]);
        }
        let o = eopnp(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(v["written"]["replaced"], 6);
        assert_eq!(v["written"]["kept_input_pose"], serde_json::json!([]));
        assert_eq!(format_of(&out), format);
        let input_model = read_model(input, &ReadOptions::default()).unwrap();
        let written = read_model(&out, &ReadOptions::default()).unwrap();
        // Everything but the poses is the input's.
        assert_eq!(written.cameras, input_model.cameras);
        assert_eq!(written.points, input_model.points);
        for img in v["images"].as_array().unwrap() {
            let id = u32::try_from(img["image_id"].as_u64().unwrap()).unwrap();
            let w = &written.images[&id];
            let i = &input_model.images[&id];
            assert_eq!(
                (&w.name, w.camera_id, &w.points2d),
                (&i.name, i.camera_id, &i.points2d)
            );
            let (r, t) = w.pose();
            for row in 0..3 {
                let want = img["translation"][row].as_f64().unwrap();
                assert!(
                    close(t[row], want, 1e-12),
                    "image {id}: t {} vs {want}",
                    t[row]
                );
                for col in 0..3 {
                    let want = img["rotation"][row][col].as_f64().unwrap();
                    let got = r[(row, col)];
                    assert!(close(got, want, 1e-12), "image {id}: R {got} vs {want}");
                }
            }
            let q = &img["quaternion_wxyz"];
            for k in 0..4 {
                // (serde_json's default float parsing may be one ulp off.)
                let want = q[k].as_f64().unwrap();
                assert!(close(w.q[k], want, 1e-15), "image {id}: q {:?} vs {q}", w.q);
            }
        }
        // Table output names the written model.
        let out2 = base.join(format!("{}-{format:?}-table", input.len()));
        let o = eopnp(&["register", input, "--write", out2.to_str().unwrap()]);
        assert!(o.status.success());
        let stdout = String::from_utf8_lossy(&o.stdout);
        assert!(stdout.contains("6 of 6 image poses replaced"), "{stdout}");
    }
}

#[test]
fn cli_refuses_bad_output_paths_and_leaves_the_input_alone() {
    let base = scratch("cli-refuse");
    // A private copy of the input, so that nothing else races on it.
    let input = base.join("in");
    write_model(
        &read_model(TEXT_MODEL, &ReadOptions::default()).unwrap(),
        &input,
        &WriteOptions::default().format(ModelFormat::Text),
    )
    .unwrap();
    std::fs::write(base.join("a-file"), b"not a directory").unwrap();
    let non_empty = base.join("non-empty");
    std::fs::create_dir(&non_empty).unwrap();
    std::fs::write(non_empty.join("something"), b"x").unwrap();
    #[cfg(unix)]
    std::os::unix::fs::symlink(&input, base.join("link-to-in")).unwrap();
    let before = snapshot(&base);
    let mut bad = vec![
        input.clone(),
        input.join("."),
        base.join("in/../in"),
        input.join("sub"),
        base.join("a-file"),
        non_empty.clone(),
        base.join("missing/out"),
        base.join("a-file/out"),
    ];
    if cfg!(unix) {
        bad.push(base.join("link-to-in"));
        bad.push(base.join("link-to-in/sub"));
    }
    for out in &bad {
        let o = eopnp(&[
            "register",
            input.to_str().unwrap(),
            "--write",
            out.to_str().unwrap(),
        ]);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{}: {stderr}", out.display());
        // The refusal names the output path (not, e.g., a clap usage error).
        let prefix = format!("error: --write {}: ", out.display());
        assert!(stderr.starts_with(&prefix), "{stderr}");
        assert!(o.stdout.is_empty(), "refused before any work");
        assert!(
            snapshot(&base) == before,
            "{} changed something",
            out.display()
        );
        assert_eq!(
            entries(&base),
            if cfg!(unix) {
                vec!["a-file", "in", "link-to-in", "non-empty"]
            } else {
                vec!["a-file", "in", "non-empty"]
            }
        );
    }
}

/// Runs `eopnp register INPUT --write OUT` with a file-size limit of about 100 KB (SIGXFSZ
/// ignored, so that the write fails with EFBIG instead of killing the process): cameras.txt
/// (428 bytes) is written, images.txt (900 KB) fails half-way.
#[cfg(unix)]
fn register_with_file_size_limit(out: &Path) -> Output {
    let script = format!(
        "trap '' XFSZ; ulimit -f 200 && exec '{}' register '{}' --write '{}'",
        env!("CARGO_BIN_EXE_eopnp"),
        TEXT_MODEL,
        out.display()
    );
    Command::new("sh").arg("-c").arg(script).output().unwrap()
}

#[cfg(unix)]
#[test]
fn a_failure_half_way_leaves_nothing() {
    let input_before = snapshot(Path::new(TEXT_MODEL));
    // New directory: the temporary directory is removed, OUT never appears.
    let base = scratch("half-way-new");
    let out = base.join("out");
    let o = register_with_file_size_limit(&out);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("cannot write the model"), "{stderr}");
    assert!(entries(&base).is_empty(), "{:?}", entries(&base));

    // Existing empty directory: the temporary files are removed, OUT stays empty.
    let base = scratch("half-way-empty");
    let out = base.join("out");
    std::fs::create_dir(&out).unwrap();
    let o = register_with_file_size_limit(&out);
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(entries(&base), ["out"]);
    assert!(entries(&out).is_empty(), "{:?}", entries(&out));

    // A read-only parent (meaningless as root, who may write anyway).
    use std::os::unix::fs::PermissionsExt;
    let base = scratch("read-only");
    std::fs::set_permissions(&base, std::fs::Permissions::from_mode(0o555)).unwrap();
    let writable = std::fs::write(base.join("probe"), b"").is_ok();
    if !writable {
        let out = base.join("out");
        let o = eopnp(&["register", TEXT_MODEL, "--write", out.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(1));
        assert!(entries(&base).is_empty());
    }
    std::fs::set_permissions(&base, std::fs::Permissions::from_mode(0o755)).unwrap();

    assert!(snapshot(Path::new(TEXT_MODEL)) == input_before);
}

#[test]
fn library_failure_half_way_in_an_existing_directory_restores_it() {
    // Overwrite::Files into a directory where one target name is a non-empty directory: the
    // rename of that file fails after the others were renamed; they are put back.
    let base = scratch("restore");
    let dir = base.join("m");
    let model = read_model(BIN_MODEL, &ReadOptions::default()).unwrap();
    write_model(
        &model,
        &dir,
        &WriteOptions::default().format(ModelFormat::Binary),
    )
    .unwrap();
    std::fs::remove_file(dir.join("points3D.bin")).unwrap();
    std::fs::create_dir(dir.join("points3D.bin")).unwrap();
    std::fs::write(dir.join("points3D.bin").join("x"), b"x").unwrap();
    let before = snapshot(&dir);
    let mut moved = model.clone();
    moved.images.values_mut().for_each(|i| i.t.z -= 2.0);
    let e = write_model(
        &moved,
        &dir,
        &WriteOptions::default()
            .format(ModelFormat::Binary)
            .overwrite(Overwrite::Files),
    )
    .unwrap_err();
    assert!(e.to_string().contains("points3D.bin"), "{e}");
    assert!(snapshot(&dir) == before, "directory not restored");
    assert_eq!(entries(&dir), ["cameras.bin", "images.bin", "points3D.bin"]);
}
