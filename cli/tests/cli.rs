//! End-to-end tests of the `eopnp` binary (feature `cli`).

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

use eopnp::colmap::{read_model, ReadOptions};

fn eopnp(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_eopnp"))
        .args(args)
        .output()
        .expect("runs the eopnp binary")
}

/// Runs the binary with `input` on standard input.
fn eopnp_stdin(args: &[&str], input: &[u8]) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_eopnp"))
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("runs the eopnp binary");
    let mut stdin = child.stdin.take().unwrap();
    let input = input.to_vec();
    // A writer thread: the binary may exit (bad input) before reading everything.
    let writer = std::thread::spawn(move || {
        let _ = stdin.write_all(&input);
    });
    let out = child
        .wait_with_output()
        .expect("waits for the eopnp binary");
    writer.join().unwrap();
    out
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../data")
        .join(name)
}

fn scratch_file(name: &str, contents: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(name);
    std::fs::write(&p, contents).unwrap();
    p
}

/// A fresh copy of the bundled text model in the test's scratch directory `name`, with its
/// `images.txt` passed through `edit_images`.
fn model_copy(name: &str, edit_images: impl Fn(&str) -> String) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let src = data("colmap-boxes");
    for f in ["cameras.txt", "points3D.txt"] {
        std::fs::copy(src.join(f), dir.join(f)).unwrap();
    }
    let images = std::fs::read_to_string(src.join("images.txt")).unwrap();
    std::fs::write(dir.join("images.txt"), edit_images(&images)).unwrap();
    dir
}

/// Asserts a clean input-error exit: code 2, the message on stderr, no panic.
fn assert_input_error(o: &Output, needles: &[&str]) {
    let err = stderr(o);
    assert_eq!(o.status.code(), Some(2), "stderr: {err}");
    assert!(!err.contains("panicked"), "{err}");
    for n in needles {
        assert!(err.contains(n), "expected {n:?} in: {err}");
    }
}

#[test]
fn no_arguments_registers_the_bundled_model_and_explains() {
    let o = eopnp(&[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    assert!(out.contains("Columns:"), "{out}");
    assert!(out.contains("6 of 6 images registered"), "{out}");
    assert!(
        out.contains("WhatsApp Image 2020-04-24 at 5.12.56 PM (1).jpeg"),
        "{out}"
    );
}

#[test]
fn register_json_on_the_binary_copy() {
    let dir = data("colmap-boxes-bin");
    let o = eopnp(&["register", dir.to_str().unwrap(), "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).expect("valid JSON");
    assert_eq!(v["format"], "binary");
    let images = v["images"].as_array().unwrap();
    assert_eq!(images.len(), 6);
    for im in images {
        // The default-mode bounds of tests/colmap.rs.
        assert!(im["rotation_error_deg"].as_f64().unwrap() <= 0.01, "{im}");
        assert!(
            im["translation_error_pct"].as_f64().unwrap() <= 0.05,
            "{im}"
        );
        assert_eq!(im["n"], im["inliers"]);
    }
}

/// Image 2's correspondences as CSV and JSON, and its camera as a `--camera` string.
fn image2_files() -> (PathBuf, PathBuf, String, nalgebra::Matrix3<f64>) {
    let m = read_model(data("colmap-boxes"), &ReadOptions::default()).unwrap();
    let img = &m.images[&2];
    let cam = &m.cameras[&img.camera_id];
    let (world, pixels) = m.correspondences(2);
    let mut csv = String::from("x,y,X,Y,Z\n");
    for (w, p) in world.iter().zip(&pixels) {
        csv.push_str(&format!("{},{},{},{},{}\n", p.x, p.y, w.x, w.y, w.z));
    }
    let camera = format!(
        "{} {}",
        cam.model().name(),
        cam.params()
            .iter()
            .map(f64::to_string)
            .collect::<Vec<_>>()
            .join(" ")
    );
    let json = serde_json::json!({
        "camera": { "model": cam.model().name(), "params": cam.params() },
        "points2d": pixels.iter().map(|p| [p.x, p.y]).collect::<Vec<_>>(),
        "points3d": world.iter().map(|w| [w.x, w.y, w.z]).collect::<Vec<_>>(),
    });
    // Distinct names per call: tests run in parallel.
    static CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let k = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    (
        scratch_file(&format!("img2-{k}.csv"), &csv),
        scratch_file(&format!("img2-{k}.json"), &json.to_string()),
        camera,
        img.pose().0,
    )
}

fn rotation_of(v: &serde_json::Value) -> nalgebra::Matrix3<f64> {
    let r = &v["rotation"];
    nalgebra::Matrix3::from_fn(|i, j| r[i][j].as_f64().unwrap())
}

#[test]
fn solve_csv_and_json_give_the_model_pose() {
    let (csv, json, camera, r_model) = image2_files();
    for out in [
        eopnp(&["solve", csv.to_str().unwrap(), "--camera", &camera]),
        eopnp(&["solve", json.to_str().unwrap()]),
    ] {
        assert!(out.status.success(), "{}", stderr(&out));
        let v: serde_json::Value = serde_json::from_str(&stdout(&out)).unwrap();
        let r = rotation_of(&v);
        // Same pixel weighting as `register`: the default-mode bound of tests/colmap.rs.
        assert!(
            eopnp::internals::metrics::rotation_error_deg(&r, &r_model) <= 0.01,
            "{v}"
        );
        assert_eq!(v["quaternion_wxyz"].as_array().unwrap().len(), 4);
        assert_eq!(v["translation"].as_array().unwrap().len(), 3);
        assert!(v["reprojection_rmse_px"].as_f64().unwrap() < 2.0, "{v}");
        assert!(v["cost"].as_f64().unwrap().is_finite());
    }
}

#[test]
fn bad_csv_reports_line_and_reason() {
    let p = scratch_file("bad1.csv", "x,y,X,Y,Z\n1,2,3,4,5\n1,2,3,4\n");
    let o = eopnp(&[
        "solve",
        p.to_str().unwrap(),
        "--camera",
        "SIMPLE_PINHOLE 1000 600 800",
    ]);
    assert_input_error(&o, &["bad1.csv:3:", "5 comma-separated"]);
    let p = scratch_file("bad2.csv", "x,y,X,Y,Z\n1,2,abc,4,5\n");
    let o = eopnp(&[
        "solve",
        p.to_str().unwrap(),
        "--camera",
        "SIMPLE_PINHOLE 1000 600 800",
    ]);
    assert_input_error(&o, &["bad2.csv:2:", "abc"]);
    let p = scratch_file("bad3.csv", "u,v\n");
    let o = eopnp(&[
        "solve",
        p.to_str().unwrap(),
        "--camera",
        "SIMPLE_PINHOLE 1000 600 800",
    ]);
    assert_input_error(&o, &["bad3.csv:1:", "x,y,X,Y,Z"]);
    // No camera for a CSV file.
    let p = scratch_file("ok.csv", "x,y,X,Y,Z\n");
    let o = eopnp(&["solve", p.to_str().unwrap()]);
    assert_input_error(&o, &["--camera"]);
}

#[test]
fn bad_json_reports_line_and_reason() {
    let p = scratch_file(
        "bad1.json",
        "{\"camera\": {\"model\": \"SIMPLE_RADIAL\", \"params\": [1, 2, 3, 4]},\n \
         \"points2d\": [[1, 2], [3]],\n \"points3d\": []}\n",
    );
    let o = eopnp(&["solve", p.to_str().unwrap()]);
    assert_input_error(&o, &["bad1.json:2:", "length"]);
    let p = scratch_file(
        "bad2.json",
        "{\"camera\": {\"model\": \"FANCY\", \"params\": [1]},\n \"points2d\": [],\n \
         \"points3d\": []}\n",
    );
    let o = eopnp(&["solve", p.to_str().unwrap()]);
    assert_input_error(&o, &["bad2.json:1:", "FANCY"]);
    let p = scratch_file(
        "bad3.json",
        "{\"points2d\": [[1, 2]],\n \"points3d\": [[1, 2, \"x\"]]}",
    );
    let o = eopnp(&["solve", p.to_str().unwrap()]);
    assert_input_error(&o, &["bad3.json:2:"]);
}

#[test]
fn unsupported_camera_and_missing_model_are_input_errors() {
    let p = scratch_file("cam.csv", "x,y,X,Y,Z\n");
    let o = eopnp(&["solve", p.to_str().unwrap(), "--camera", "FOV 1 2 3 4 5"]);
    assert_input_error(&o, &["FOV"]);
    let o = eopnp(&["register", env!("CARGO_TARGET_TMPDIR")]);
    assert_input_error(&o, &["not a COLMAP model"]);
}

#[test]
fn ransac_thresholds_whose_square_is_not_normal_are_input_errors() {
    let model = data("colmap-boxes");
    for t in ["1e-160", "1e160", "0", "nan"] {
        let o = eopnp(&[
            "register",
            model.to_str().unwrap(),
            "--ransac",
            "--threshold",
            t,
        ]);
        assert_input_error(&o, &["--threshold"]);
    }
}

#[test]
fn malformed_model_reports_file_and_line() {
    let dir =
        Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("cli-model-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for f in ["cameras.txt", "images.txt", "points3D.txt"] {
        std::fs::copy(data("colmap-boxes").join(f), dir.join(f)).unwrap();
    }
    std::fs::write(
        dir.join("cameras.txt"),
        "1 SIMPLE_RADIAL 1200 1600 1245.65 600 800 0.05\n2 SIMPLE_RADIAL 1200\n",
    )
    .unwrap();
    let o = eopnp(&["register", dir.to_str().unwrap()]);
    assert_input_error(&o, &["cameras.txt:2:", "truncated"]);
}

/// Checks a `solve` run's pose against the model's rotation.
fn assert_model_pose(out: &Output, r_model: &nalgebra::Matrix3<f64>) {
    assert!(out.status.success(), "{}", stderr(out));
    let v: serde_json::Value = serde_json::from_str(&stdout(out)).unwrap();
    assert!(
        eopnp::internals::metrics::rotation_error_deg(&rotation_of(&v), r_model) <= 0.01,
        "{v}"
    );
}

#[test]
fn solve_reads_standard_input() {
    let (csv, json, camera, r_model) = image2_files();
    let csv = std::fs::read(csv).unwrap();
    let json = std::fs::read(json).unwrap();
    // Format sniffed from the content, or named.
    assert_model_pose(
        &eopnp_stdin(&["solve", "-", "--camera", &camera], &csv),
        &r_model,
    );
    assert_model_pose(&eopnp_stdin(&["solve", "-"], &json), &r_model);
    assert_model_pose(
        &eopnp_stdin(&["solve", "-", "--format", "json"], &json),
        &r_model,
    );
    assert_model_pose(
        &eopnp_stdin(
            &["solve", "--format", "csv", "--camera", &camera, "-"],
            &csv,
        ),
        &r_model,
    );
    // The wrong format is an input error naming standard input.
    let o = eopnp_stdin(&["solve", "-", "--format", "json"], &csv);
    assert_input_error(&o, &["<stdin>:1:"]);
    let o = eopnp_stdin(
        &["solve", "-", "--format", "csv", "--camera", &camera],
        &json,
    );
    assert_input_error(&o, &["<stdin>:1:", "expected the header"]);
    // Empty input, and CSV without --camera.
    let o = eopnp_stdin(&["solve", "-", "--camera", &camera], b"");
    assert_input_error(&o, &["<stdin>", "empty"]);
    let o = eopnp_stdin(&["solve", "-"], &csv);
    assert_input_error(&o, &["--camera"]);
    // An unknown --format is a usage error (clap's exit status 2).
    let o = eopnp_stdin(&["solve", "-", "--format", "xml"], &json);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("xml"), "{}", stderr(&o));
}

#[test]
fn solve_reads_csv_dialects() {
    let (csv, _, camera, r_model) = image2_files();
    let csv = std::fs::read_to_string(csv).unwrap();
    // Byte-order mark and CRLF (a spreadsheet's export).
    let p = scratch_file("bom.csv", &format!("\u{feff}{}", csv.replace('\n', "\r\n")));
    assert_model_pose(
        &eopnp(&["solve", p.to_str().unwrap(), "--camera", &camera]),
        &r_model,
    );
    // Semicolons with decimal points, quoted header, columns reordered, a comment.
    let mut semi = String::from("# image 2\n\"X\";\"Y\";\"Z\";\"x\";\"y\"\n");
    for l in csv.lines().skip(1) {
        let f: Vec<&str> = l.split(',').collect();
        semi += &format!("{};{};{};{};{}\n", f[2], f[3], f[4], f[0], f[1]);
    }
    let p = scratch_file("semi.csv", &semi);
    assert_model_pose(
        &eopnp(&["solve", p.to_str().unwrap(), "--camera", &camera]),
        &r_model,
    );
    // Tabs, on standard input.
    assert_model_pose(
        &eopnp_stdin(
            &["solve", "-", "--camera", &camera],
            csv.replace(',', "\t").as_bytes(),
        ),
        &r_model,
    );
}

#[test]
fn csv_errors_name_line_and_field() {
    let camera = ["--camera", "SIMPLE_PINHOLE 1000 600 800"];
    let text = "# comment\n\nx;y;X;Y;Z\n1;2;3;4;5\n\n1;2,5;3;4;5\n";
    let p = scratch_file("semi-bad.csv", text);
    let o = eopnp(&["solve", p.to_str().unwrap(), camera[0], camera[1]]);
    assert_input_error(&o, &["semi-bad.csv:6: field 2 (y) is not a number: `2,5`"]);
    let o = eopnp_stdin(&["solve", "-", camera[0], camera[1]], text.as_bytes());
    assert_input_error(&o, &["<stdin>:6: field 2 (y) is not a number: `2,5`"]);
    // Reordered columns: the field's name is its header's.
    let o = eopnp_stdin(
        &["solve", "-", camera[0], camera[1]],
        b"Z\tY\tX\ty\tx\n1\t2\t3\t4\t5\n1\t2\t3\t4\t\x01\n",
    );
    assert_input_error(&o, &["<stdin>:3: field 5 (x) is not a number: `\\u{1}`"]);
    // Header only; a header with a missing column.
    let p = scratch_file(
        "header-only.csv",
        "\u{feff}\"x\",\"y\",\"X\",\"Y\",\"Z\"\n\n",
    );
    let o = eopnp(&["solve", p.to_str().unwrap(), camera[0], camera[1]]);
    assert_input_error(&o, &["header-only.csv:1:", "no correspondences"]);
    let o = eopnp_stdin(&["solve", "-", camera[0], camera[1]], b"x;y;X;Z\n1;2;3;4\n");
    assert_input_error(&o, &["<stdin>:1:", "missing column Y"]);
}

#[test]
fn degenerate_correspondences_and_a_file_as_model_are_input_errors() {
    // Collinear world points: the input cannot determine a pose (exit 2, not 1).
    let mut csv = String::from("x,y,X,Y,Z\n");
    for k in 0..8 {
        let t = k as f64;
        csv += &format!(
            "{},{},{},{},{}\n",
            300.0 + 3.0 * t,
            200.0 + 2.0 * t,
            t,
            2.0 * t,
            5.0
        );
    }
    let p = scratch_file("collinear.csv", &csv);
    let o = eopnp(&[
        "solve",
        p.to_str().unwrap(),
        "--camera",
        "PINHOLE 800 800 320 240",
    ]);
    assert_input_error(&o, &["collinear"]);
    // A file given as the model directory.
    let f = data("colmap-boxes").join("cameras.txt");
    let o = eopnp(&["register", f.to_str().unwrap()]);
    assert_input_error(&o, &["not a directory"]);
}

#[test]
fn image_names_reach_the_terminal_escaped() {
    // A copy of the bundled model whose first image name carries an escape sequence and a bell.
    let dir = model_copy("model-with-escapes", |images| {
        let mut done = false;
        let mut out = String::new();
        for line in images.lines() {
            let fields: Vec<&str> = line.split(' ').collect();
            // The first record line is an image line: nine numbers, then the name (with spaces).
            if !done && !line.starts_with('#') && fields.len() >= 10 {
                out += &fields[..9].join(" ");
                out += " \u{1b}[31mred\u{7}.jpg\n";
                done = true;
            } else {
                out += line;
                out.push('\n');
            }
        }
        assert!(done);
        out
    });
    let o = eopnp(&["register", dir.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let text = stdout(&o);
    assert!(
        !text.contains('\u{1b}') && !text.contains('\u{7}'),
        "{text}"
    );
    assert!(text.contains("\\u{1b}[31mred\\u{7}.jpg"), "{text}");
}

#[test]
fn export_problems_never_writes_into_the_input_model() {
    let dir = model_copy("model-export-target", str::to_string);
    let before = std::fs::read(dir.join("images.txt")).unwrap();
    for target in [dir.join("images.txt"), dir.join("new.json")] {
        let o = eopnp(&[
            "register",
            dir.to_str().unwrap(),
            "--export-problems",
            target.to_str().unwrap(),
        ]);
        assert_input_error(&o, &["--export-problems", "input model"]);
    }
    assert_eq!(std::fs::read(dir.join("images.txt")).unwrap(), before);
    assert!(!dir.join("new.json").exists());
    // Elsewhere it is written whole.
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("exported-problems.json");
    let o = eopnp(&[
        "register",
        dir.to_str().unwrap(),
        "--export-problems",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(&out).unwrap()).unwrap();
    assert_eq!(v["images"].as_array().unwrap().len(), 6);
}

#[test]
fn observations_left_out_by_undistortion_are_shown_in_the_table() {
    // A copy of the bundled model whose first observation of the first image lies where the
    // lens model cannot be inverted (x = 1e12 px).
    let dir = model_copy("model-with-far-pixel", |images| {
        let mut out = String::new();
        let mut records = 0;
        for line in images.lines() {
            if line.starts_with('#') {
                out += line;
            } else {
                records += 1;
                if records == 2 {
                    // The first image's observations: "x y point3d_id ...", the first one with
                    // a 3D point is moved.
                    let mut f: Vec<String> = line.split(' ').map(str::to_string).collect();
                    let k = (0..f.len() / 3).find(|k| f[3 * k + 2] != "-1").unwrap();
                    f[3 * k] = "1e12".to_string();
                    out += &f.join(" ");
                } else {
                    out += line;
                }
            }
            out.push('\n');
        }
        out
    });
    let o = eopnp(&["register", dir.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(
        stdout(&o).contains("1 observation(s) left out: their pixel could not be undistorted"),
        "{}",
        stdout(&o)
    );
}

#[test]
fn register_ransac_shows_an_image_without_consensus_as_not_registered() {
    // A copy of the bundled model whose first image's observations point at the wrong 3D
    // points (the list of observed ids rotated by half its length).
    let dir = model_copy("model-wrong-correspondences", |images| {
        let mut out = String::new();
        let mut state = 0; // 0: before the first image line, 1: its points line next, 2: done
        for line in images.lines() {
            if line.starts_with('#') || state == 2 {
                out += line;
            } else if state == 0 {
                out += line;
                state = 1;
            } else {
                let fields: Vec<&str> = line.split_whitespace().collect();
                let ids: Vec<&str> = fields
                    .chunks(3)
                    .map(|c| c[2])
                    .filter(|id| *id != "-1")
                    .collect();
                let shift = ids.len() / 2;
                let mut k = 0;
                let mut edited = Vec::new();
                for c in fields.chunks(3) {
                    let id = if c[2] == "-1" {
                        "-1"
                    } else {
                        k += 1;
                        ids[(k - 1 + shift) % ids.len()]
                    };
                    edited.push(format!("{} {} {id}", c[0], c[1]));
                }
                out += &edited.join(" ");
                state = 2;
            }
            out.push('\n');
        }
        assert_eq!(state, 2);
        out
    });
    let o = eopnp(&["register", dir.to_str().unwrap(), "--ransac"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let text = stdout(&o);
    assert!(text.contains("failed: RANSAC found no consensus"), "{text}");
    assert!(text.contains("5 of 6 images registered"), "{text}");
}

#[cfg(unix)]
#[test]
fn special_files_and_size_limits_are_input_errors() {
    let camera = "SIMPLE_PINHOLE 1000 600 800";
    // A device, a directory: refused before they are opened.
    let o = eopnp(&["solve", "/dev/zero", "--camera", camera]);
    assert_input_error(
        &o,
        &[
            "/dev/zero: not a regular file (it is a character device)",
            "`-`",
        ],
    );
    let o = eopnp(&["solve", env!("CARGO_TARGET_TMPDIR"), "--camera", camera]);
    assert_input_error(&o, &["not a regular file (it is a directory)"]);
    // Endless zeros on standard input: refused at the first line.
    let t = std::time::Instant::now();
    let o = Command::new(env!("CARGO_BIN_EXE_eopnp"))
        .args(["solve", "-", "--camera", camera])
        .stdin(std::fs::File::open("/dev/zero").unwrap())
        .output()
        .unwrap();
    assert_input_error(&o, &["<stdin>:1: expected the header"]);
    assert!(t.elapsed().as_secs() < 5, "{:?}", t.elapsed());
    // Over --max-input-size, a file and standard input.
    let text = "x,y,X,Y,Z\n1,2,3,4,5\n";
    let p = scratch_file("limit.csv", text);
    let o = eopnp(&[
        "solve",
        p.to_str().unwrap(),
        "--camera",
        camera,
        "--max-input-size",
        "10",
    ]);
    assert_input_error(
        &o,
        &["limit.csv: larger than 10 bytes", "(--max-input-size)"],
    );
    let o = eopnp_stdin(
        &["solve", "-", "--camera", camera, "--max-input-size", "10"],
        text.as_bytes(),
    );
    assert_input_error(&o, &["<stdin>: larger than 10 bytes"]);
    let o = eopnp(&[
        "solve",
        p.to_str().unwrap(),
        "--camera",
        camera,
        "--max-input-size",
        "1K",
    ]);
    assert!(!stderr(&o).contains("larger than"), "{}", stderr(&o));
    let o = eopnp(&["solve", p.to_str().unwrap(), "--max-input-size", "12Q"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("12Q"), "{}", stderr(&o));
    // A model file over --max-input-size, and one that is a device.
    let o = eopnp(&[
        "register",
        data("colmap-boxes").to_str().unwrap(),
        "--max-input-size",
        "1K",
    ]);
    assert_input_error(
        &o,
        &[
            "images.txt: the file is 925720 bytes long",
            "over the file size limit of 1 KiB",
            "raise it with --max-input-size",
        ],
    );
    let dir = model_copy("cli-model-dev-zero", str::to_string);
    std::fs::remove_file(dir.join("points3D.txt")).unwrap();
    std::os::unix::fs::symlink("/dev/zero", dir.join("points3D.txt")).unwrap();
    let o = eopnp(&["register", dir.to_str().unwrap()]);
    assert_input_error(
        &o,
        &["points3D.txt: not a regular file (it is a character device)"],
    );
}
