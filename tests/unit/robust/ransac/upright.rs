use super::*;
use crate::numeric::rotation::rotation_error_deg;
use nalgebra::Rotation3;

/// A camera at a random pose with its vertical known: among the poses of two of its points is
/// the true one (1e-9), and every pose keeps the vertical (`R g_w = g_c` to 1e-12), for a
/// vertical along no axis and for one along `-y` (the turned frame's `-y`).
#[test]
fn poses_of_two_points_contain_the_truth_and_keep_the_vertical() {
    let rotations = [
        Rotation3::from_euler_angles(0.3, -1.1, 2.0).into_inner(),
        Rotation3::from_euler_angles(-2.9, 0.4, -0.7).into_inner(),
    ];
    for g_w in [Vector3::new(0.2, -0.3, -1.0).normalize(), -Vector3::y()] {
        for r in &rotations {
            let t = Vector3::new(0.4, -0.2, 3.0);
            let g = Gravity::new(r * g_w, g_w, 0.1).unwrap();
            let up = Upright::new(&g);
            let world = [Point3::new(0.5, -0.8, 1.2), Point3::new(-1.1, 0.3, 0.4)];
            let cam: Vec<Vector3<f64>> = world.iter().map(|x| r * x.coords + t).collect();
            let o = Point3::origin();
            let poses = up.poses([&world[0], &world[1]], [&o, &o], [&cam[0], &cam[1]]);
            assert!(!poses.is_empty());
            for p in &poses {
                assert!((p.rotation * g_w - r * g_w).norm() < 1e-12);
            }
            assert!(poses
                .iter()
                .any(|p| rotation_error_deg(&p.rotation, r) < 1e-9
                    && (p.translation - t).norm() < 1e-9));
        }
    }
}
