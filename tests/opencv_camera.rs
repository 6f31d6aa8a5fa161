//! OpenCV interop of the cameras (public API only): `Camera::from_opencv` and
//! `Camera::from_opencv_fisheye` reproduce `cv2.projectPoints` / `cv2.fisheye.projectPoints`
//! on the reference data of `tests/data/opencv_projection.json` (written by
//! `scripts/opencv_camera_data.py`), `undistort` inverts them, and bad inputs are errors.

use eopnp::camera::{Camera, CameraError, CameraModel};
use nalgebra::{Matrix3, Point2};
use serde_json::Value;

/// Projection tolerance, pixels. Both sides evaluate the same formula in f64, in a different
/// order of operations (and OpenCV multiplies by reciprocals where this crate divides), so they
/// differ by a few ulps of the pixel coordinates: the pixels here reach ~4000, whose ulp is
/// 4.5e-13 to 9.1e-13, and the worst measured difference is 6.8e-13 px (the test prints the
/// worst per case). 1e-11 px is about ten ulps: room for another platform's libm (atan, sin,
/// cos differ by an ulp or so, which moves a pixel by ~1e-13) and nothing more; any difference
/// of formula (a missing term, a sign, a swapped coefficient) moves pixels by 1e-3 px or more.
const PROJECTION_TOL_PX: f64 = 1e-11;

/// Round-trip tolerance of `undistort(OpenCV's pixel)` against the exact normalised point.
/// What the undistortion guarantees: Newton stops when the lens equation holds to 1e-13
/// relative (absolute here: the distorted coordinates are below ~1.3), the pixel itself is
/// off by up to the projection tolerance (1e-11 px / f, f >= 300 px: 3e-14), the script keeps
/// points where the lens map is well conditioned (det J > 0.2 fx fy, so the error grows by a
/// factor ~5 at most), and for the fisheye points up to 70 degrees off axis tan() stretches
/// it by 1 / cos^2(70 deg) ~ 8.5: ~1.3e-13 * 5 * 8.5 ~ 6e-12, so 1e-11. (Newton converges
/// quadratically, so the measured errors are at the rounding level, ~1e-15.)
const ROUND_TRIP_TOL: f64 = 1e-11;

struct Case {
    fisheye: bool,
    k: Matrix3<f64>,
    dist: Vec<f64>,
    normalised: Vec<Point2<f64>>,
    pixels: Vec<Point2<f64>>,
}

fn f(v: &Value) -> f64 {
    v.as_f64().expect("number")
}

fn points(v: &Value) -> Vec<Point2<f64>> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|p| Point2::new(f(&p[0]), f(&p[1])))
        .collect()
}

fn cases() -> Vec<Case> {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/opencv_projection.json"
    ))
    .unwrap();
    let data: Value = serde_json::from_str(&text).unwrap();
    data["cases"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| {
            let k = &c["K"];
            Case {
                fisheye: c["kind"] == "fisheye",
                k: Matrix3::from_fn(|i, j| f(&k[i][j])),
                dist: c["dist"].as_array().unwrap().iter().map(f).collect(),
                normalised: points(&c["normalised"]),
                pixels: points(&c["pixels"]),
            }
        })
        .collect()
}

fn camera(c: &Case) -> Camera {
    if c.fisheye {
        let d: [f64; 4] = c.dist.as_slice().try_into().unwrap();
        Camera::from_opencv_fisheye(&c.k, &d).unwrap()
    } else {
        Camera::from_opencv(&c.k, &c.dist).unwrap()
    }
}

fn label(c: &Case) -> String {
    if c.fisheye {
        "fisheye".into()
    } else {
        format!("{} coefficients", c.dist.len())
    }
}

#[test]
fn reference_data_covers_every_case() {
    let cases = cases();
    let mut labels: Vec<String> = cases.iter().map(label).collect();
    labels.dedup();
    assert_eq!(
        labels,
        [
            "0 coefficients",
            "4 coefficients",
            "5 coefficients",
            "8 coefficients",
            "12 coefficients",
            "14 coefficients",
            "fisheye"
        ]
    );
    for c in &cases {
        assert_eq!(c.normalised.len(), c.pixels.len());
        assert!(c.pixels.len() >= 10);
    }
}

#[test]
fn project_matches_opencv_and_undistort_inverts_it() {
    // Worst errors per case: (projection px, round trip normalised, round trip px).
    let mut report: Vec<(String, f64, f64, f64)> = Vec::new();
    for c in &cases() {
        let cam = camera(c);
        let expected_model = match (c.fisheye, c.dist.len()) {
            (true, _) => CameraModel::OpenCvFisheye,
            (false, 0) => CameraModel::Pinhole,
            (false, 4) => CameraModel::OpenCv,
            (false, 5 | 8) => CameraModel::FullOpenCv,
            _ => CameraModel::OpenCvThinPrismTilted,
        };
        assert_eq!(cam.model(), expected_model);
        let (mut proj, mut rt, mut rt_px) = (0.0f64, 0.0f64, 0.0f64);
        for (n, px) in c.normalised.iter().zip(&c.pixels) {
            let q = cam.project(*n);
            proj = proj.max((q - px).norm());
            let back = cam
                .undistort(*px)
                .unwrap_or_else(|e| panic!("{}: undistort {px}: {e}", label(c)));
            rt = rt.max((back - n).norm());
            rt_px = rt_px.max((cam.project(back) - px).norm());
        }
        let l = label(c);
        match report.iter_mut().find(|r| r.0 == l) {
            Some(r) => {
                r.1 = r.1.max(proj);
                r.2 = r.2.max(rt);
                r.3 = r.3.max(rt_px);
            }
            None => report.push((l, proj, rt, rt_px)),
        }
    }
    for (l, proj, rt, rt_px) in &report {
        println!(
            "{l:>16}: projection vs OpenCV {proj:.1e} px, round trip {rt:.1e} (normalised), \
             {rt_px:.1e} px"
        );
    }
    for (l, proj, rt, _) in &report {
        assert!(
            *proj <= PROJECTION_TOL_PX,
            "{l}: projection differs from OpenCV's by {proj:e} px"
        );
        assert!(*rt <= ROUND_TRIP_TOL, "{l}: round trip error {rt:e}");
    }
}

#[test]
fn to_opencv_gives_the_parameters_back() {
    for c in &cases() {
        let cam = camera(c);
        if c.fisheye {
            let (k, d) = cam.to_opencv_fisheye().unwrap();
            assert_eq!(k, c.k);
            assert_eq!(d.as_slice(), c.dist.as_slice());
            assert!(cam.to_opencv().is_none());
        } else {
            let (k, d) = cam.to_opencv().unwrap();
            assert_eq!(k, c.k);
            // Shorter vectors come back padded with zeros to the model's length.
            assert_eq!(&d[..c.dist.len()], c.dist.as_slice());
            assert!(d[c.dist.len()..].iter().all(|&v| v == 0.0));
            assert!(matches!(d.len(), 0 | 8 | 4 | 14));
            assert!(cam.to_opencv_fisheye().is_none());
            assert_eq!(Camera::from_opencv(&k, &d).unwrap().params(), cam.params());
        }
        assert_eq!((cam.width(), cam.height()), (0, 0));
    }
}

#[test]
fn colmap_models_convert_to_opencv_exactly() {
    let n = Point2::new(0.31, -0.27);
    for (name, params) in [
        ("SIMPLE_PINHOLE", vec![1000.0, 600.0, 400.0]),
        ("SIMPLE_RADIAL", vec![1000.0, 600.0, 400.0, -0.1]),
        ("RADIAL", vec![1000.0, 600.0, 400.0, -0.1, 0.02]),
    ] {
        let cam = Camera::from_colmap(name, 1200, 800, params).unwrap();
        let (k, d) = cam.to_opencv().unwrap();
        let back = Camera::from_opencv(&k, &d).unwrap();
        assert!((back.project(n) - cam.project(n)).norm() <= 1e-12, "{name}");
    }
    for (name, params) in [
        ("SIMPLE_RADIAL_FISHEYE", vec![500.0, 600.0, 400.0, 0.03]),
        ("RADIAL_FISHEYE", vec![500.0, 600.0, 400.0, 0.03, -0.004]),
    ] {
        let cam = Camera::from_colmap(name, 1200, 800, params).unwrap();
        let (k, d) = cam.to_opencv_fisheye().unwrap();
        let back = Camera::from_opencv_fisheye(&k, &d).unwrap();
        assert!((back.project(n) - cam.project(n)).norm() <= 1e-12, "{name}");
    }
}

fn k_ok() -> Matrix3<f64> {
    Matrix3::new(800.0, 0.0, 320.0, 0.0, 810.0, 240.0, 0.0, 0.0, 1.0)
}

fn assert_invalid(r: Result<Camera, CameraError>, needle: &str) {
    match r {
        Err(CameraError::InvalidParams(why)) => {
            assert!(why.contains(needle), "{why:?} does not mention {needle:?}");
        }
        other => panic!("expected InvalidParams mentioning {needle:?}, got {other:?}"),
    }
}

#[test]
fn bad_camera_matrix_is_an_error() {
    let d = [0.01, 0.0, 0.0, 0.0];
    let mut skew = k_ok();
    skew[(0, 1)] = 0.5;
    assert_invalid(Camera::from_opencv(&skew, &d), "skew");
    assert_invalid(Camera::from_opencv_fisheye(&skew, &d), "skew");
    let mut k10 = k_ok();
    k10[(1, 0)] = 1.0;
    assert_invalid(Camera::from_opencv(&k10, &d), "K[1][0]");
    for (i, j, v) in [(2, 0, 1e-3), (2, 1, -1.0), (2, 2, 2.0)] {
        let mut k = k_ok();
        k[(i, j)] = v;
        assert_invalid(Camera::from_opencv(&k, &d), "last row");
        assert_invalid(Camera::from_opencv_fisheye(&k, &d), "last row");
    }
    let mut nan = k_ok();
    nan[(0, 2)] = f64::NAN;
    assert_invalid(Camera::from_opencv(&nan, &d), "non-finite");
    let mut neg = k_ok();
    neg[(1, 1)] = -810.0;
    assert_invalid(Camera::from_opencv(&neg, &d), "focal length");
    let mut zero = k_ok();
    zero[(0, 0)] = 0.0;
    assert_invalid(Camera::from_opencv_fisheye(&zero, &d), "focal length");
}

#[test]
fn bad_distortion_vector_is_an_error() {
    for n in [1, 2, 3, 6, 7, 9, 10, 11, 13, 15, 16] {
        let d = vec![0.0; n];
        assert_invalid(Camera::from_opencv(&k_ok(), &d), &format!("got {n}"));
    }
    for n in [4, 5, 8, 12, 14] {
        let mut d = vec![0.0; n];
        d[n - 1] = f64::INFINITY;
        assert_invalid(Camera::from_opencv(&k_ok(), &d), "not finite");
    }
    assert_invalid(
        Camera::from_opencv_fisheye(&k_ok(), &[0.0, f64::NAN, 0.0, 0.0]),
        "k2",
    );
    // Tilt of 90 degrees or more: the tilted sensor plane contains the optical axis.
    let mut d = vec![0.0; 14];
    d[12] = std::f64::consts::FRAC_PI_2;
    assert_invalid(Camera::from_opencv(&k_ok(), &d), "tau");
    // Errors display a reason.
    let e = Camera::from_opencv(&k_ok(), &[0.1]).unwrap_err();
    assert!(e.to_string().contains("0, 4, 5, 8, 12 or 14"), "{e}");
}

#[test]
fn the_opencv_model_is_not_a_colmap_model() {
    let m = CameraModel::OpenCvThinPrismTilted;
    assert_eq!(m.colmap_id(), None);
    assert_eq!(m.num_params(), 18);
    assert!(!eopnp::camera::SUPPORTED_MODELS.contains(&m));
    assert!(CameraModel::from_name(m.name()).is_err());
    assert!(Camera::from_colmap(m.name(), 10, 10, vec![1.0; 18]).is_err());
    assert_eq!(m.to_string().parse::<CameraModel>(), Ok(m));
    for id in -1..=20 {
        assert_ne!(CameraModel::from_colmap_id(id).ok(), Some(m));
    }
    // The COLMAP binary writer refuses it instead of writing a wrong model id.
    let mut d = vec![0.0; 14];
    d[0] = -0.1;
    let cam = Camera::from_opencv(&k_ok(), &d).unwrap();
    let mut model = eopnp::colmap::Model::default();
    model.cameras.insert(1, cam);
    let dir = std::env::temp_dir().join(format!("eopnp_opencv_camera_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let e = eopnp::colmap::write_model(
        &model,
        &dir,
        &eopnp::colmap::WriteOptions::default().overwrite(eopnp::colmap::Overwrite::Files),
    )
    .unwrap_err();
    assert_eq!(e.kind(), std::io::ErrorKind::InvalidInput);
    assert!(e.to_string().contains("OPENCV_THIN_PRISM_TILTED"), "{e}");
    assert!(!dir.join("cameras.bin").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}
