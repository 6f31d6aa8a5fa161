use super::*;

/// Realistic parameters for every model (a 1200 x 1600 image, about 55 x 70 degrees).
fn cameras() -> Vec<Camera> {
    let (w, h) = (1200, 1600);
    let spec: Vec<(&str, Vec<f64>)> = vec![
        ("SIMPLE_PINHOLE", vec![1245.65, 600.0, 800.0]),
        ("PINHOLE", vec![1245.0, 1251.0, 601.5, 797.25]),
        ("SIMPLE_RADIAL", vec![1245.65, 600.0, 800.0, 0.0577095]),
        ("SIMPLE_RADIAL", vec![1245.65, 600.0, 800.0, -0.08]),
        ("RADIAL", vec![1245.65, 600.0, 800.0, -0.05, 0.01]),
        (
            "OPENCV",
            vec![1245.0, 1251.0, 601.5, 797.25, -0.1, 0.02, 0.001, -0.0007],
        ),
        (
            "OPENCV_FISHEYE",
            vec![700.0, 702.0, 600.0, 800.0, 0.05, -0.01, 0.002, -0.0005],
        ),
        (
            "FULL_OPENCV",
            vec![
                1245.0, 1251.0, 601.5, 797.25, -0.1, 0.02, 0.001, -0.0007, 0.001, 0.05, -0.01,
                0.002,
            ],
        ),
        ("SIMPLE_RADIAL_FISHEYE", vec![700.0, 600.0, 800.0, 0.03]),
        ("RADIAL_FISHEYE", vec![700.0, 600.0, 800.0, 0.03, -0.004]),
    ];
    let mut cams: Vec<Camera> = spec
        .into_iter()
        .map(|(m, p)| Camera::from_colmap(m, w, h, p).unwrap())
        .collect();
    // OpenCV's full model (not a COLMAP model): rational, tangential, thin prism and a tilt
    // of about 2 and -3 degrees.
    cams.push(
        Camera::new(
            CameraModel::OpenCvThinPrismTilted,
            w,
            h,
            vec![
                1245.0, 1251.0, 601.5, 797.25, -0.1, 0.02, 0.001, -0.0007, 0.001, 0.05, -0.01,
                0.002, 0.0015, -0.0004, -0.001, 0.0003, 0.035, -0.052,
            ],
        )
        .unwrap(),
    );
    cams
}

#[test]
fn tilt_matrix_is_the_identity_at_zero_and_keeps_the_axis() {
    let t = distortion::tilt_matrix(0.0, 0.0);
    assert_eq!(t, [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]);
    // Any tilt: the optical axis (0, 0) stays at (0, 0); the tilt is a projective map with
    // det T = cos^2(tau_x) cos^2(tau_y) > 0.
    let (tx, ty) = (0.04_f64, -0.03_f64);
    let t = distortion::tilt_matrix(tx, ty);
    assert!(t[0][2].abs() < 1e-17 && t[1][2].abs() < 1e-17, "{t:?}");
    let det = t[0][0] * (t[1][1] * t[2][2] - t[1][2] * t[2][1])
        - t[0][1] * (t[1][0] * t[2][2] - t[1][2] * t[2][0])
        + t[0][2] * (t[1][0] * t[2][1] - t[1][1] * t[2][0]);
    let expected = (tx.cos() * ty.cos()).powi(2);
    assert!((det - expected).abs() < 1e-15, "{det} vs {expected}");
}

#[test]
fn tilt_only_camera_is_the_homography() {
    // No lens distortion, only the tilt: project(n) = K (X/W, Y/W), (X, Y, W) = T (n, 1).
    let (tx, ty) = (0.05, -0.02);
    let mut params = vec![1000.0, 1000.0, 600.0, 400.0];
    params.extend([0.0; 12]);
    params.extend([tx, ty]);
    let cam = Camera::new(CameraModel::OpenCvThinPrismTilted, 1200, 800, params).unwrap();
    let t = distortion::tilt_matrix(tx, ty);
    for n in [
        Point2::new(0.0, 0.0),
        Point2::new(0.3, -0.2),
        Point2::new(-0.45, 0.35),
    ] {
        let w = t[2][0] * n.x + t[2][1] * n.y + t[2][2];
        let x = (t[0][0] * n.x + t[0][1] * n.y + t[0][2]) / w;
        let y = (t[1][0] * n.x + t[1][1] * n.y + t[1][2]) / w;
        let p = cam.project(n);
        assert!((p.x - (1000.0 * x + 600.0)).abs() < 1e-9, "{p}");
        assert!((p.y - (1000.0 * y + 400.0)).abs() < 1e-9, "{p}");
        // A real perspective effect: not the identity away from the axis.
        if n.x != 0.0 {
            assert!((p.x - (1000.0 * n.x + 600.0)).abs() > 1.0);
        }
        assert!((cam.undistort(p).unwrap() - n).norm() <= 1e-12);
    }
}

#[test]
fn tilt_of_ninety_degrees_is_rejected() {
    let mut params = vec![1000.0, 1000.0, 600.0, 400.0];
    params.extend([0.0; 12]);
    params.extend([0.0, -core::f64::consts::FRAC_PI_2]);
    let e = Camera::new(CameraModel::OpenCvThinPrismTilted, 1200, 800, params).unwrap_err();
    assert!(matches!(e, CameraError::InvalidParams(_)), "{e}");
}

#[test]
fn undistort_then_project_is_identity_over_the_image() {
    for cam in cameras() {
        let mut worst = 0.0f64;
        // A 41 x 41 grid over the whole image, corners included.
        for i in 0..=40 {
            for j in 0..=40 {
                let p = Point2::new(
                    cam.width() as f64 * f64::from(i) / 40.0,
                    cam.height() as f64 * f64::from(j) / 40.0,
                );
                let n = cam
                    .undistort(p)
                    .unwrap_or_else(|e| panic!("{}: {e}", cam.model()));
                let q = cam.project(n);
                worst = worst.max((q - p).norm());
            }
        }
        // 1e-9 px: the pixels are ~1e3, so this is ~1e-12 relative, a few hundred ulps;
        // Newton converges to the rounding level of the distortion evaluation.
        assert!(
            worst <= 1e-9,
            "{}: worst round trip {worst:e} px",
            cam.model()
        );
    }
}

#[test]
fn project_then_undistort_is_identity() {
    for cam in cameras() {
        for i in -5..=5 {
            for j in -5..=5 {
                let n = Point2::new(f64::from(i) * 0.08, f64::from(j) * 0.1);
                let back = cam.undistort(cam.project(n)).unwrap();
                // 1e-12 in normalised units is ~1e-9 px at f ~ 1000 (see above).
                assert!((back - n).norm() <= 1e-12, "{}: {n} -> {back}", cam.model());
            }
        }
    }
}

/// The weight of `undistort_weighted` comes from the Jacobian the undistortion's convergence
/// check evaluated (and, for the fisheye models, the equidistant map's determinant in closed
/// form): it equals `|det J| / (fx fy)` of `project_jacobian` at the undistorted point to
/// rounding, over the whole image of every model.
#[test]
fn undistortion_weight_is_the_projection_jacobian_determinant() {
    for cam in cameras() {
        let (fx, fy) = cam.focal_lengths();
        let mut worst = 0.0f64;
        for i in 0..=20 {
            for j in 0..=20 {
                let p = Point2::new(
                    cam.width() as f64 * f64::from(i) / 20.0,
                    cam.height() as f64 * f64::from(j) / 20.0,
                );
                let (n, w) = cam.undistort_weighted(p).unwrap();
                assert_eq!(n, cam.undistort(p).unwrap(), "{}", cam.model());
                let jac = cam.project_jacobian(n);
                let want = ((jac[0] * jac[3] - jac[1] * jac[2]) / (fx * fy)).abs();
                worst = worst.max((w - want).abs() / want);
            }
        }
        // Both sides are a few dozen roundings of the same quantity, at points that differ
        // by the rounding of the equidistant map (fisheye): 1e-12 relative.
        assert!(
            worst <= 1e-12,
            "{}: worst relative difference {worst:e}",
            cam.model()
        );
    }
}

#[test]
fn jacobian_matches_finite_differences() {
    for cam in cameras() {
        let n = Point2::new(0.31, -0.42);
        let j = cam.project_jacobian(n);
        let h = 1e-6;
        let dx = (cam.project(n + nalgebra::Vector2::new(h, 0.0))
            - cam.project(n - nalgebra::Vector2::new(h, 0.0)))
            / (2.0 * h);
        let dy = (cam.project(n + nalgebra::Vector2::new(0.0, h))
            - cam.project(n - nalgebra::Vector2::new(0.0, h)))
            / (2.0 * h);
        let fd = [dx.x, dy.x, dx.y, dy.y];
        for k in 0..4 {
            // Central differences with h = 1e-6: truncation ~h^2 f ~ 1e-9 and rounding
            // ~eps |p| / h ~ 1e-16 * 1e3 / 1e-6 = 1e-7 (entries ~1e3 px per unit): 1e-5.
            assert!(
                (j[k] - fd[k]).abs() <= 1e-5,
                "{}: J[{k}] = {} vs {}",
                cam.model(),
                j[k],
                fd[k]
            );
        }
    }
}

#[test]
fn simple_radial_matches_colmap_formula() {
    let cam =
        Camera::from_colmap("SIMPLE_RADIAL", 1200, 1600, vec![1000.0, 600.0, 800.0, 0.1]).unwrap();
    let p = cam.project(Point2::new(0.3, -0.4));
    // r2 = 0.25, factor 1 + 0.1 * 0.25 = 1.025.
    assert!((p.x - (1000.0 * 0.3 * 1.025 + 600.0)).abs() < 1e-12);
    assert!((p.y - (1000.0 * -0.4 * 1.025 + 800.0)).abs() < 1e-12);
}

#[test]
fn pixels_beyond_f64_range_are_out_of_range() {
    // A pinhole camera with a tiny focal length: (px - cx) / fx overflows.
    let cam = Camera::from_colmap("PINHOLE", 10, 10, vec![1e-10, 1e-10, 5.0, 5.0]).unwrap();
    let px = Point2::new(1e300, 5.0);
    let e = cam.undistort(px).unwrap_err();
    assert_eq!(
        e,
        CameraError::OutOfRange {
            pixel: (1e300, 5.0)
        }
    );
    assert!(e.to_string().contains("1e300"), "{e}");
    // A radial camera far outside the image: the undistortion converges (the model is
    // monotone) but the local scale of the distortion overflows.
    let cam = Camera::from_colmap("SIMPLE_RADIAL", 100, 100, vec![1.0, 50.0, 50.0, 0.0]).unwrap();
    assert!(cam.undistort_weighted(Point2::new(60.0, 40.0)).is_ok());
    let radial = Camera::from_colmap("RADIAL", 100, 100, vec![1.0, 50.0, 50.0, 0.1, 0.0]).unwrap();
    for x in [1e60, 1e80, 1e100, 1e150] {
        match radial.undistort_weighted(Point2::new(x, 50.0)) {
            Ok((n, w)) => assert!(n.x.is_finite() && w.is_finite()),
            Err(e) => assert!(
                matches!(
                    e,
                    CameraError::OutOfRange { .. } | CameraError::NoConvergence { .. }
                ),
                "{e}"
            ),
        }
    }
}

#[test]
fn unsupported_model_is_named() {
    let e = Camera::from_colmap("THIN_PRISM_FISHEYE", 10, 10, vec![1.0; 12]).unwrap_err();
    assert_eq!(
        e,
        CameraError::UnsupportedModel("THIN_PRISM_FISHEYE".into())
    );
    assert!(e.to_string().contains("THIN_PRISM_FISHEYE"));
    let e = CameraModel::from_colmap_id(7).unwrap_err();
    assert!(e.to_string().contains("FOV"), "{e}");
    let e = CameraModel::from_colmap_id(99).unwrap_err();
    assert!(e.to_string().contains("99"), "{e}");
}

#[test]
fn bad_params_are_errors() {
    assert!(matches!(
        Camera::from_colmap("PINHOLE", 10, 10, vec![1.0, 2.0, 3.0]),
        Err(CameraError::ParamCount {
            expected: 4,
            got: 3,
            ..
        })
    ));
    assert!(Camera::from_colmap("PINHOLE", 10, 10, vec![1.0, f64::NAN, 3.0, 4.0]).is_err());
    assert!(Camera::from_colmap("SIMPLE_PINHOLE", 10, 10, vec![0.0, 3.0, 4.0]).is_err());
    let cam = &cameras()[2];
    assert_eq!(
        cam.undistort(Point2::new(f64::NAN, 1.0)),
        Err(CameraError::NonFinite)
    );
}

#[test]
fn non_invertible_region_is_an_error() {
    // k = -0.5: x (1 - 0.5 x^2) peaks at x = sqrt(2/3) ~ 0.816, distorted radius ~0.544.
    // A pixel at distorted radius 0.6 has no preimage.
    let cam = Camera::from_colmap(
        "SIMPLE_RADIAL",
        2000,
        2000,
        vec![1000.0, 1000.0, 1000.0, -0.5],
    )
    .unwrap();
    let e = cam.undistort(Point2::new(1600.0, 1000.0)).unwrap_err();
    assert!(matches!(e, CameraError::NoConvergence { .. }), "{e}");
    // Inside the fold: fine.
    assert!(cam.undistort(Point2::new(1500.0, 1000.0)).is_ok());
}

/// The radial models' lockstep undistortion (`radial_chunk`, used by a solve of pixels through
/// `undistort_into`) against the one-pixel iteration (`Camera::undistort_weighted`):
/// every pixel gets the same outcome (no point, or the same point and weight to rounding),
/// over strong distortion with folds (pixels beyond them have no preimage), the image centre,
/// far-out and non-finite pixels, and with the iteration bound lowered so that the lanes give
/// up and the one-pixel iteration decides. The cameras without distortion (their own loop of
/// the affine map) are checked the same way.
#[test]
fn radial_lanes_match_the_one_pixel_iteration() {
    use crate::numeric::bounds::{hook, Bound};
    use rand::{Rng, SeedableRng};
    let (w, h) = (2000, 1600);
    let models: Vec<(&str, Vec<f64>)> = vec![
        ("SIMPLE_PINHOLE", vec![1000.0, 1000.0, 800.0]),
        ("PINHOLE", vec![1000.0, 1010.0, 1000.0, 800.0]),
        ("SIMPLE_RADIAL", vec![1000.0, 1000.0, 800.0, 0.0577095]),
        ("SIMPLE_RADIAL", vec![1000.0, 1000.0, 800.0, -0.3]),
        ("SIMPLE_RADIAL", vec![1000.0, 1000.0, 800.0, 0.3]),
        ("RADIAL", vec![1000.0, 1000.0, 800.0, -0.3, 0.1]),
        ("RADIAL", vec![1000.0, 1000.0, 800.0, -0.5, 0.05]),
        ("RADIAL", vec![1000.0, 1000.0, 800.0, 0.1, -0.05]),
        ("SIMPLE_RADIAL_FISHEYE", vec![500.0, 1000.0, 800.0, 0.03]),
        ("RADIAL_FISHEYE", vec![500.0, 1000.0, 800.0, -0.2, 0.01]),
        (
            "OPENCV_FISHEYE",
            vec![500.0, 502.0, 1000.0, 800.0, 0.05, -0.01, 0.002, -0.0005],
        ),
        (
            "OPENCV_FISHEYE",
            vec![400.0, 400.0, 1000.0, 800.0, -0.3, 0.2, -0.1, 0.02],
        ),
    ];
    let mut rng = rand_pcg::Pcg64::seed_from_u64(0x5AD1A1);
    let (mut agreed_ok, mut agreed_err) = (0, 0);
    for (name, params) in models {
        let cam = Camera::from_colmap(name, w, h, params.clone()).unwrap();
        let proj = cam.projector();
        let mut pixels: Vec<Point2<f64>> = (0..3000)
            .map(|k| {
                // Most in the image, one in five out to three image half-widths from the
                // centre (past every fold here).
                let reach = if k % 5 == 0 { 3000.0 } else { 1000.0 };
                Point2::new(
                    1000.0 + rng.random_range(-reach..reach),
                    800.0 + rng.random_range(-reach..reach),
                )
            })
            .collect();
        pixels.extend([
            Point2::new(1000.0, 800.0),
            Point2::new(1000.0 + 1e-300, 800.0),
            Point2::new(1e200, 800.0),
            Point2::new(f64::NAN, 800.0),
            Point2::new(f64::INFINITY, 800.0),
        ]);
        for limit in [None, Some(1), Some(2)] {
            let run = || {
                // (The entries of a pixel left out are unspecified.)
                let mut out = vec![Point2::new(f64::NAN, 7.0); pixels.len()];
                let mut weights = vec![-1.0; pixels.len()];
                let mut failed = Vec::new();
                proj.undistort_into(&pixels, &mut out, Some(&mut weights), |i| failed.push(i));
                assert!(failed.windows(2).all(|p| p[0] < p[1]), "in order");
                let got: Vec<_> = (0..pixels.len())
                    .map(|i| {
                        if failed.contains(&i) {
                            (i, None)
                        } else {
                            (i, Some((out[i], weights[i])))
                        }
                    })
                    .collect();
                // Without weights: the same points, the same pixels left out.
                let mut bare = vec![Point2::origin(); pixels.len()];
                let mut failed_bare = Vec::new();
                proj.undistort_into(&pixels, &mut bare, None, |i| failed_bare.push(i));
                assert_eq!(failed_bare, failed);
                for (i, g) in &got {
                    if let Some((p, _)) = g {
                        assert_eq!(bare[*i], *p);
                    }
                }
                let want: Vec<_> = pixels
                    .iter()
                    .map(|p| cam.undistort_weighted(*p).ok())
                    .collect();
                (got, want)
            };
            let (got, want) = match limit {
                None => run(),
                Some(l) => hook::with_limit(Bound::Undistort, l, run).0,
            };
            assert_eq!(got.len(), pixels.len());
            for ((i, g), wnt) in got.into_iter().zip(want) {
                let ctx = format!("{name} {params:?} limit {limit:?} pixel {:?}", pixels[i]);
                match (g, wnt) {
                    (Some((a, wa)), Some((b, wb))) => {
                        // Rounding, amplified (fisheye models) by r = tan(theta) near 90
                        // degrees off axis: dr / dtheta = 1 + r^2.
                        let scale = 1.0 + b.coords.norm();
                        assert!((a - b).norm() <= 1e-12 * scale * scale, "{ctx}: {a} vs {b}");
                        assert!(
                            (wa - wb).abs() <= 1e-12 * scale * wb.abs(),
                            "{ctx}: weight {wa} vs {wb}"
                        );
                        agreed_ok += 1;
                    }
                    (None, None) => agreed_err += 1,
                    (a, b) => panic!("{ctx}: lanes {a:?}, one pixel {b:?}"),
                }
            }
        }
    }
    // Both outcomes are exercised in quantity (not a test that cannot fail).
    assert!(
        agreed_ok > 15_000 && agreed_err > 5_000,
        "{agreed_ok} / {agreed_err}"
    );
    // And the lanes decide in-image pixels themselves (the one-pixel iteration is only their
    // fallback): a chunk of them all converges.
    let lens = distortion::SimpleRadial([0.0577095]);
    let px: Vec<Point2<f64>> = (0..distortion::RADIAL_CHUNK)
        .map(|k| Point2::new(50.0 + 30.0 * k as f64, 1500.0 - 20.0 * k as f64))
        .collect();
    // The points, their determinants and the mask of the undecided ones.
    type Chunk = (Vec<Point2<f64>>, [f64; distortion::RADIAL_CHUNK], u64);
    type Fill<'a> = &'a dyn Fn(&mut [Point2<f64>], &mut [f64; distortion::RADIAL_CHUNK]) -> u64;
    let chunk = |fill: Fill<'_>| {
        let mut out = vec![Point2::origin(); px.len()];
        let mut dets = [0.0; distortion::RADIAL_CHUNK];
        let undecided = fill(&mut out, &mut dets);
        (out, dets, undecided) as Chunk
    };
    let lanes = chunk(&|o, d| {
        distortion::radial_chunk::<_, false>(&lens, (1000.0, 1000.0), (1000.0, 800.0), &px, o, d)
    });
    assert_eq!(lanes.2, 0);
    // The baseline and AVX2 builds agree to the bit (a perspective and a fisheye lens).
    let fisheye = distortion::Fisheye([0.05, -0.01, 0.002, -0.0005]);
    let chunks = || {
        (
            chunk(&|o, d| {
                distortion::radial_chunk::<_, false>(
                    &lens,
                    (1000.0, 1000.0),
                    (1000.0, 800.0),
                    &px,
                    o,
                    d,
                )
            }),
            chunk(&|o, d| {
                distortion::radial_chunk::<_, true>(
                    &fisheye,
                    (1000.0, 1000.0),
                    (1000.0, 800.0),
                    &px,
                    o,
                    d,
                )
            }),
        )
    };
    let (wide, base) = (chunks(), crate::numeric::lanes::with_baseline(chunks));
    assert_eq!((wide.1 .2, base.0 .2, base.1 .2), (0, 0, 0));
    for (a, b) in [(&wide.0, &base.0), (&wide.1, &base.1)] {
        for (p, q) in a.0.iter().zip(&b.0) {
            assert_eq!(
                (p.x.to_bits(), p.y.to_bits()),
                (q.x.to_bits(), q.y.to_bits())
            );
        }
        for (p, q) in a.1.iter().zip(&b.1) {
            assert_eq!(p.to_bits(), q.to_bits());
        }
    }
}
