//! Issue 14, undistortion: with extreme (non-physical) distortion coefficients a pixel can have
//! several preimages; `undistort` returns the one on the pixel's side of the principal point
//! (the radial scale `1 + g(r^2)` positive, the map locally invertible there) or an error,
//! never the root mirrored through the principal point.
use eopnp::camera::Camera;
use nalgebra::Point2;

#[test]
fn no_root_mirrored_through_the_principal_point() {
    let (mut ok, mut refused) = (0, 0);
    for model in ["SIMPLE_RADIAL", "RADIAL", "OPENCV"] {
        for &k1 in &[-50.0, -5.0, -2.0, -1.0, -0.5, 0.5, 5.0] {
            for &k2 in &[0.0, -3.0, 3.0] {
                let params: Vec<f64> = match model {
                    "SIMPLE_RADIAL" => vec![500.0, 320.0, 240.0, k1],
                    "RADIAL" => vec![500.0, 320.0, 240.0, k1, k2],
                    _ => vec![500.0, 480.0, 320.0, 240.0, k1, k2, 0.001, -0.002],
                };
                let cam = Camera::from_colmap(model, 640, 480, params).unwrap();
                for i in 0..=32 {
                    for j in 0..=24 {
                        let px = Point2::new(f64::from(i) * 20.0, f64::from(j) * 20.0);
                        let Ok(n) = cam.undistort(px) else {
                            refused += 1;
                            continue;
                        };
                        ok += 1;
                        let (fx, fy) = cam.focal_lengths();
                        let (cx, cy) = cam.principal_point();
                        let d = ((px.x - cx) / fx, (px.y - cy) / fy);
                        // Same side of the principal point as the pixel.
                        let dot = n.x * d.0 + n.y * d.1;
                        assert!(
                            dot >= 0.0,
                            "{model} k1 {k1} k2 {k2} pixel {px}: mirrored preimage {n}"
                        );
                        let back = cam.project(n);
                        assert!((back - px).norm() < 1e-6, "{model} {px}: {back}");
                    }
                }
            }
        }
    }
    println!("{ok} undistorted, {refused} refused");
}
