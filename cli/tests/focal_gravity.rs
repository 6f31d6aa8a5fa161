//! `eopnp solve --unknown-focal [--focal-range MIN MAX]` and `--gravity-camera/-world/-sigma`,
//! and `eopnp register --unknown-focal [--focal-guess-scale S]`, run as a user runs them: on
//! synthetic problems whose focal length and vertical are known, and on the bundled model.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use eopnp_testkit::{axis_angle, gauss, rng_from_seed};
use nalgebra::{Matrix3, Point3, Rotation3, Vector3};
use rand_core::RngCore;
use serde_json::Value;

fn eopnp(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_eopnp"))
        .args(args)
        .output()
        .expect("runs the eopnp binary")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn json_of(o: &Output) -> Value {
    assert!(o.status.success(), "stderr: {}", stderr(o));
    serde_json::from_slice(&o.stdout).expect("JSON output")
}

/// Asserts a clean input-error exit: code 2, the needles on stderr, no panic.
fn assert_input_error(o: &Output, needles: &[&str]) {
    let err = stderr(o);
    assert_eq!(o.status.code(), Some(2), "stderr: {err}");
    assert!(!err.contains("panicked"), "{err}");
    for n in needles {
        assert!(err.contains(n), "`{n}` not in: {err}");
    }
}

fn f64s(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap_or_else(|| panic!("array: {v}"))
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

/// The true pose of the synthetic problems, `x_cam = R X + t`.
fn truth() -> (Matrix3<f64>, Vector3<f64>) {
    let r = Rotation3::from_euler_angles(0.1, -0.2, 0.3).into_inner();
    (r, Vector3::new(0.1, -0.2, 6.0))
}

/// A JSON problem of 40 points seen by a PINHOLE camera of focal length `f` (principal point
/// 320, 240) under [`truth`], pixel noise of `noise_px` (seeded), the file's camera given with
/// focal length `f_file`. Written to the test's scratch directory as `name`.
fn problem_file(name: &str, f: f64, f_file: f64, noise_px: f64) -> PathBuf {
    let (r, t) = truth();
    let mut rng = rng_from_seed(7);
    let (mut p2, mut p3) = (Vec::new(), Vec::new());
    for i in 0..40 {
        let x = Point3::new(
            (i % 5) as f64 - 2.0 + 0.3 * gauss(&mut rng),
            (i % 4) as f64 - 1.5 + 0.3 * gauss(&mut rng),
            (i % 3) as f64 - 1.0 + 0.3 * gauss(&mut rng),
        );
        let c = r * x.coords + t;
        let u = f * c.x / c.z + 320.0 + noise_px * gauss(&mut rng);
        let v = f * c.y / c.z + 240.0 + noise_px * gauss(&mut rng);
        p2.push([u, v]);
        p3.push([x.x, x.y, x.z]);
    }
    let doc = serde_json::json!({
        "camera": { "model": "PINHOLE", "params": [f_file, f_file, 320.0, 240.0] },
        "points2d": p2,
        "points3d": p3,
    });
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("fg-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, serde_json::to_string(&doc).unwrap()).unwrap();
    path
}

fn rotation_of(v: &Value) -> Matrix3<f64> {
    let rows: Vec<Vec<f64>> = v["rotation"].as_array().unwrap().iter().map(f64s).collect();
    Matrix3::from_fn(|i, j| rows[i][j])
}

fn angle_deg(a: &Matrix3<f64>, b: &Matrix3<f64>) -> f64 {
    Rotation3::from_matrix(&(a.transpose() * b))
        .angle()
        .to_degrees()
}

/// `v` as the command line's `X,Y,Z`.
fn arg(v: &Vector3<f64>) -> String {
    format!("{},{},{}", v.x, v.y, v.z)
}

#[test]
fn unknown_focal_recovers_the_focal_length_from_a_wrong_guess() {
    // Exact pixels, a guess of 800 px for a 1200 px camera.
    let file = problem_file("exact.json", 1200.0, 800.0, 0.0);
    let path = file.to_str().unwrap();
    let v = json_of(&eopnp(&["solve", path, "--unknown-focal"]));
    let focal = f64s(&v["focal"]);
    assert_eq!(focal.len(), 2);
    for f in &focal {
        assert!((f - 1200.0).abs() < 1e-6, "focal {focal:?}");
    }
    // The camera block is the estimated camera, the RMSE through it.
    let params = f64s(&v["camera"]["params"]);
    assert!((params[0] - 1200.0).abs() < 1e-6 && (params[1] - 1200.0).abs() < 1e-6);
    assert_eq!(&params[2..], &[320.0, 240.0]);
    assert!(v["reprojection_rmse_px"].as_f64().unwrap() < 1e-6, "{v}");
    let (r, t) = truth();
    assert!(angle_deg(&rotation_of(&v), &r) < 1e-6);
    assert!((Vector3::from_vec(f64s(&v["translation"])) - t).norm() < 1e-6);

    // Without the option the guess is taken as the camera: no "focal", a poor fit.
    let v = json_of(&eopnp(&["solve", path]));
    assert!(v.get("focal").is_none(), "{v}");
    assert_eq!(f64s(&v["camera"]["params"])[0], 800.0);
    assert!(v["reprojection_rmse_px"].as_f64().unwrap() > 1.0, "{v}");

    // --camera replaces the file's camera as the guess: a guess too long works as well.
    let v = json_of(&eopnp(&[
        "solve",
        path,
        "--unknown-focal",
        "--camera",
        "SIMPLE_PINHOLE 2000 320 240",
    ]));
    assert!((f64s(&v["focal"])[0] - 1200.0).abs() < 1e-6, "{v}");
    assert_eq!(v["camera"]["model"], "SIMPLE_PINHOLE");
}

#[test]
fn unknown_focal_with_noise_and_a_range() {
    // One pixel of noise: the focal length within 1 % of the truth.
    let file = problem_file("noisy.json", 1500.0, 1000.0, 1.0);
    let path = file.to_str().unwrap();
    let v = json_of(&eopnp(&[
        "solve",
        path,
        "--unknown-focal",
        "--focal-range",
        "1000",
        "2000",
    ]));
    let fx = f64s(&v["focal"])[0];
    assert!((fx / 1500.0 - 1.0).abs() < 0.01, "focal {fx}");
    let rmse = v["reprojection_rmse_px"].as_f64().unwrap();
    assert!(rmse > 0.5 && rmse < 1.5, "rmse {rmse}");
    // A range that excludes the truth cannot return it.
    let v = json_of(&eopnp(&[
        "solve",
        path,
        "--unknown-focal",
        "--focal-range",
        "600",
        "1200",
    ]));
    let fx = f64s(&v["focal"])[0];
    assert!(
        (600.0..=1200.0).contains(&fx),
        "focal {fx} outside the range"
    );
    // A range without the guess (the file's camera, 1000 px): the truth, 1500 px, found in it.
    let v = json_of(&eopnp(&[
        "solve",
        path,
        "--unknown-focal",
        "--focal-range",
        "1100",
        "2000",
    ]));
    let fx = f64s(&v["focal"])[0];
    assert!((fx / 1500.0 - 1.0).abs() < 0.01, "focal {fx}");
}

#[test]
fn focal_option_errors() {
    let file = problem_file("errors.json", 1200.0, 800.0, 0.0);
    let path = file.to_str().unwrap();
    for range in [["900", "800"], ["0", "800"], ["-5", "800"], ["800", "inf"]] {
        let o = eopnp(&[
            "solve",
            path,
            "--unknown-focal",
            "--focal-range",
            range[0],
            range[1],
        ]);
        assert_input_error(&o, &["--focal-range", "0 < MIN_PX < MAX_PX"]);
    }
    // --focal-range needs --unknown-focal; --unknown-focal excludes the vertical.
    let o = eopnp(&["solve", path, "--focal-range", "100", "900"]);
    assert_input_error(&o, &["--unknown-focal"]);
    let o = eopnp(&[
        "solve",
        path,
        "--unknown-focal",
        "--gravity-camera",
        "0,0,1",
        "--gravity-world",
        "0,0,1",
        "--gravity-sigma",
        "1",
    ]);
    assert_input_error(&o, &["cannot be used with"]);
}

#[test]
fn gravity_prior_solves_and_reports_the_vertical() {
    let (r, t) = truth();
    // Half a pixel of noise; the vertical measured exactly.
    let file = problem_file("gravity.json", 1000.0, 1000.0, 0.5);
    let path = file.to_str().unwrap();
    let down_world = Vector3::new(0.0, 0.0, -1.0);
    let down_camera = r * down_world;
    let (gc, gw) = (arg(&down_camera), arg(&down_world));
    let v = json_of(&eopnp(&[
        "solve",
        path,
        "--gravity-camera",
        &gc,
        "--gravity-world",
        &gw,
        "--gravity-sigma",
        "0.01",
    ]));
    let with = rotation_of(&v);
    let g = &v["gravity"];
    assert_eq!(g["sigma_deg"].as_f64(), Some(0.01));
    let reported = g["angle_deg"].as_f64().unwrap();
    let angle = |rot: &Matrix3<f64>| {
        let p = rot * down_world;
        p.cross(&down_camera)
            .norm()
            .atan2(p.dot(&down_camera))
            .to_degrees()
    };
    assert!((reported - angle(&with)).abs() < 1e-9, "{reported}");
    assert!(angle_deg(&with, &r) < 0.2, "{}", angle_deg(&with, &r));
    assert!((Vector3::from_vec(f64s(&v["translation"])) - t).norm() < 0.05);
    // The prior pulls the vertical of the pose towards the (exact) measurement: closer than
    // the images' own maximum-likelihood pose.
    let without = rotation_of(&json_of(&eopnp(&["solve", path])));
    assert!(
        angle(&with) < angle(&without),
        "{} !< {}",
        angle(&with),
        angle(&without)
    );
    // The camera's vertical of any length: the same solve.
    let long = arg(&(down_camera * 9.81));
    let v2 = json_of(&eopnp(&[
        "solve",
        path,
        "--gravity-camera",
        &long,
        "--gravity-world",
        &gw,
        "--gravity-sigma",
        "0.01",
    ]));
    assert!(angle_deg(&rotation_of(&v2), &with) < 1e-9);
}

#[test]
fn a_vertical_the_images_contradict_is_an_input_error() {
    let (r, _) = truth();
    let file = problem_file("mismatch.json", 1000.0, 1000.0, 0.2);
    let path = file.to_str().unwrap();
    let down_world = Vector3::new(0.0, 0.0, -1.0);
    // The measured vertical 10 degrees off the truth, claimed to 0.1 degree.
    let tilted = axis_angle(&Vector3::x(), 10f64.to_radians()) * (r * down_world);
    let o = eopnp(&[
        "solve",
        path,
        "--gravity-camera",
        &arg(&tilted),
        "--gravity-world",
        &arg(&down_world),
        "--gravity-sigma",
        "0.1",
    ]);
    assert_input_error(
        &o,
        &["contradict", "standard deviations", "--gravity-sigma"],
    );
    // The message gives the angle: about the 10 degrees of the tilt.
    let err = stderr(&o);
    let angle: f64 = err
        .split(" degrees off")
        .next()
        .and_then(|s| s.rsplit(' ').next())
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("no angle in: {err}"));
    assert!((angle - 10.0).abs() < 0.5, "angle {angle}");
    // With an honest uncertainty the same vertical is accepted.
    let o = eopnp(&[
        "solve",
        path,
        "--gravity-camera",
        &arg(&tilted),
        "--gravity-world",
        &arg(&down_world),
        "--gravity-sigma",
        "20",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
}

#[test]
fn gravity_option_errors() {
    let file = problem_file("gravity-errors.json", 1000.0, 1000.0, 0.0);
    let path = file.to_str().unwrap();
    let run = |c: &str, w: &str, s: &str| {
        eopnp(&[
            "solve",
            path,
            "--gravity-camera",
            c,
            "--gravity-world",
            w,
            "--gravity-sigma",
            s,
        ])
    };
    for sigma in ["0", "-1", "NaN", "inf"] {
        assert_input_error(&run("0,0,1", "0,0,1", sigma), &["--gravity-sigma", "> 0"]);
    }
    assert_input_error(&run("0,0,0", "0,0,1", "1"), &["non-zero"]);
    assert_input_error(&run("0,0,1", "0,0,0", "1"), &["non-zero"]);
    for bad in ["1,2", "1,2,3,4", "a,b,c", "1,2,inf", ""] {
        assert_input_error(&run(bad, "0,0,1", "1"), &["three finite numbers"]);
    }
    // The three go together.
    let o = eopnp(&[
        "solve",
        path,
        "--gravity-camera",
        "0,0,1",
        "--gravity-sigma",
        "1",
    ]);
    assert_input_error(&o, &["--gravity-world"]);
    let o = eopnp(&["solve", path, "--gravity-sigma", "1"]);
    assert_input_error(&o, &["--gravity-camera"]);
}

fn model(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../data")
        .join(name)
        .to_string_lossy()
        .into_owned()
}

/// Every image's focal error (percent) of `register --unknown-focal ... --json`, checked
/// against the summary, and the summary's median and max.
fn focal_errors(args: &[&str]) -> (Vec<f64>, f64, f64) {
    let v = json_of(&eopnp(args));
    let images = v["images"].as_array().unwrap();
    let mut errors = Vec::new();
    for img in images {
        assert!(img.get("error").is_none(), "{img}");
        let f = &img["focal"];
        let est = f64s(&f["estimated"]);
        let model = f64s(&f["model"]);
        let e = f["error_pct"].as_f64().unwrap();
        let recomputed = 100.0 * ((est[0] - model[0]) / model[0]).abs();
        assert!((e - recomputed).abs() < 1e-9, "{img}");
        assert!(img["rotation_error_deg"].as_f64().unwrap() < 0.1, "{img}");
        errors.push(e);
    }
    let s = &v["focal"];
    assert_eq!(s["images"].as_u64(), Some(images.len() as u64));
    let mut sorted = errors.clone();
    sorted.sort_by(f64::total_cmp);
    let n = sorted.len();
    let median = 0.5 * (sorted[(n - 1) / 2] + sorted[n / 2]);
    assert_eq!(s["max_error_pct"].as_f64(), Some(sorted[n - 1]));
    assert!((s["median_error_pct"].as_f64().unwrap() - median).abs() < 1e-12);
    (errors, median, sorted[n - 1])
}

#[test]
fn register_unknown_focal_on_the_bundled_model() {
    let m = model("colmap-boxes");
    for extra in [&[][..], &["--ransac"][..]] {
        for scale in ["0.7", "1.4"] {
            let mut args = vec![
                "register",
                &m,
                "--json",
                "--unknown-focal",
                "--focal-guess-scale",
                scale,
            ];
            args.extend_from_slice(extra);
            let (errors, median, max) = focal_errors(&args);
            eprintln!("{extra:?} scale {scale}: median {median:.5} %, max {max:.5} %");
            assert_eq!(errors.len(), 6);
            assert!(max < 1.0, "{errors:?}");
        }
    }
    // The table says the same.
    let o = eopnp(&[
        "register",
        &m,
        "--unknown-focal",
        "--focal-guess-scale",
        "0.7",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    assert_eq!(text.matches(" px (model ").count(), 6, "{text}");
    assert!(
        text.contains("Focal length estimated for 6 images"),
        "{text}"
    );
    // Without the option, no focal report.
    let v = json_of(&eopnp(&["register", &m, "--json"]));
    assert!(v.get("focal").is_none() && v["images"][0].get("focal").is_none());
}

#[test]
fn register_unknown_focal_with_outliers_reports_the_floor_focal() {
    let m = model("colmap-boxes");
    let args = [
        "register",
        &m,
        "--json",
        "--unknown-focal",
        "--focal-guess-scale",
        "1.3",
        "--ransac",
        "--outliers",
        "0.5",
        "--seed",
        "42",
    ];
    let (_, _, max) = focal_errors(&args);
    assert!(max < 1.0, "{max}");
    let v = json_of(&eopnp(&args));
    for img in v["images"].as_array().unwrap() {
        let floor = img["robust"]["floor"]["focal"]["error_pct"].as_f64();
        assert!(floor.is_some_and(|e| e < 1.0), "{img}");
    }
}

#[test]
fn register_unknown_focal_errors() {
    let m = model("colmap-boxes");
    let o = eopnp(&["register", &m, "--focal-guess-scale", "2"]);
    assert_input_error(&o, &["--unknown-focal"]);
    for s in ["0", "-1", "NaN", "inf"] {
        let o = eopnp(&["register", &m, "--unknown-focal", "--focal-guess-scale", s]);
        assert_input_error(&o, &["--focal-guess-scale must be a finite number > 0"]);
    }
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("fg-never-written");
    let o = eopnp(&[
        "register",
        &m,
        "--unknown-focal",
        "--write",
        out.to_str().unwrap(),
    ]);
    assert_input_error(&o, &["cannot be used with"]);
    assert!(!out.exists());
    // A model whose frames hold several images: image by image only.
    let rig = model("colmap-rig");
    let o = eopnp(&["register", &rig, "--unknown-focal"]);
    assert_input_error(&o, &["--unknown-focal", "--per-image"]);
    let (errors, _, max) = focal_errors(&[
        "register",
        &rig,
        "--unknown-focal",
        "--focal-guess-scale",
        "1.2",
        "--per-image",
        "--json",
    ]);
    assert!(!errors.is_empty() && max < 1.0, "{errors:?}");
}

/// A uniform draw in [0, 1).
fn unit(rng: &mut impl RngCore) -> f64 {
    (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64
}

#[test]
fn refined_principal_point_and_distortion() {
    // 60 noise-free points through a SIMPLE_RADIAL camera (f 800, principal point (322, 236),
    // k -0.12); the file's camera has the principal point 8 px off and no distortion.
    let truth_cam = eopnp::camera::Camera::from_colmap(
        "SIMPLE_RADIAL",
        640,
        480,
        vec![800.0, 322.0, 236.0, -0.12],
    )
    .unwrap();
    let (r, t) = truth();
    let mut rng = rng_from_seed(8);
    let (mut p2, mut p3) = (Vec::new(), Vec::new());
    while p2.len() < 60 {
        let px =
            nalgebra::Point2::new(20.0 + 600.0 * unit(&mut rng), 20.0 + 440.0 * unit(&mut rng));
        let m = truth_cam.undistort(px).unwrap();
        let z = 3.0 + 5.0 * unit(&mut rng);
        let c = Vector3::new(m.x * z, m.y * z, z);
        let x = r.transpose() * (c - t);
        p2.push([px.x, px.y]);
        p3.push([x.x, x.y, x.z]);
    }
    let doc = serde_json::json!({
        "camera": { "model": "SIMPLE_RADIAL", "params": [800.0, 330.0, 230.0, 0.0] },
        "points2d": p2,
        "points3d": p3,
    });
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("fg-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("intrinsics.json");
    std::fs::write(&path, serde_json::to_string(&doc).unwrap()).unwrap();
    let path = path.to_str().unwrap();
    let v = json_of(&eopnp(&[
        "solve",
        path,
        "--refine-principal-point",
        "--refine-distortion",
    ]));
    let params = f64s(&v["camera"]["params"]);
    for (a, b) in params.iter().zip([800.0, 322.0, 236.0, -0.12]) {
        assert!((a - b).abs() < 1e-7 * f64::max(1.0, b.abs()), "{params:?}");
    }
    let rmse = v["reprojection_rmse_px"].as_f64().unwrap();
    assert!(rmse < 1e-6, "rmse {rmse}");
    // Without the options the camera stays the file's, and the residuals are pixels.
    let v = json_of(&eopnp(&["solve", path]));
    assert_eq!(f64s(&v["camera"]["params"]), vec![800.0, 330.0, 230.0, 0.0]);
    assert!(v["reprojection_rmse_px"].as_f64().unwrap() > 1.0);
    // Not with a known vertical.
    let o = eopnp(&[
        "solve",
        path,
        "--refine-distortion",
        "--gravity-camera",
        "0,1,0",
        "--gravity-world",
        "0,1,0",
        "--gravity-sigma",
        "1",
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
}
