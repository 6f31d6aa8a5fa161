//! The upright two-point pose on seeded random instances: the true pose among the solutions,
//! every solution on its rays and in front, the half-turn, one camera and a rig, and the
//! degenerate inputs.

use super::*;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

/// World points, centres, directions and the true rotation and translation.
type Instance = (
    [Point3<f64>; 2],
    [Point3<f64>; 2],
    [Vector3<f64>; 2],
    Matrix3<f64>,
    Vector3<f64>,
);

/// A random upright instance.
fn instance(rng: &mut Pcg64, theta: f64, rig: bool) -> Instance {
    let r = rotation_y((theta / 2.0).sin(), (theta / 2.0).cos());
    let t = Vector3::new(
        rng.random_range(-2.0..2.0),
        rng.random_range(-2.0..2.0),
        rng.random_range(-2.0..2.0),
    );
    let mut world = [Point3::origin(); 2];
    let mut centres = [Point3::origin(); 2];
    let mut dirs = [Vector3::zeros(); 2];
    for i in 0..2 {
        let c = if rig {
            Vector3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            )
        } else {
            Vector3::zeros()
        };
        let d = Vector3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        )
        .normalize();
        let depth = rng.random_range(0.5..10.0);
        let x = c + d * depth;
        world[i] = Point3::from(r.transpose() * (x - t));
        centres[i] = Point3::from(c);
        dirs[i] = d * rng.random_range(0.5..2.0);
    }
    (world, centres, dirs, r, t)
}

fn check(
    world: &[Point3<f64>; 2],
    centres: &[Point3<f64>; 2],
    dirs: &[Vector3<f64>; 2],
    r: &Matrix3<f64>,
    t: &Vector3<f64>,
) {
    let sols = up2p(world, centres, dirs);
    assert!(!sols.is_empty(), "no solution");
    let found = sols.iter().any(|s| {
        (s.rotation - r).norm() < 1e-9 && (s.translation - t).norm() < 1e-9 * (1.0 + t.norm())
    });
    assert!(found, "the true pose is not among {sols:?} (R {r}, t {t})");
    for s in &sols {
        // Upright: the y axis is kept.
        assert!((s.rotation * Vector3::y() - Vector3::y()).norm() < 1e-12);
        for i in 0..2 {
            let q = s.rotation * world[i].coords + s.translation - centres[i].coords;
            let sine = q.cross(&dirs[i].normalize()).norm() / q.norm();
            assert!(sine < 1e-10, "a solution off its ray: sine {sine:e}");
            assert!(q.dot(&dirs[i]) > 0.0, "a solution behind its centre");
        }
    }
}

#[test]
fn recovers_the_pose_of_one_camera_and_of_a_rig() {
    let mut rng = Pcg64::seed_from_u64(42);
    for k in 0..2000 {
        let pi = std::f64::consts::PI;
        let theta = rng.random_range(-pi..pi);
        let (w, c, d, r, t) = instance(&mut rng, theta, k % 2 == 1);
        check(&w, &c, &d, &r, &t);
    }
}

#[test]
fn the_half_turn_is_a_root() {
    let mut rng = Pcg64::seed_from_u64(7);
    for k in 0..200 {
        let theta = std::f64::consts::PI * if k % 2 == 0 { 1.0 } else { -1.0 };
        let (w, c, d, r, t) = instance(&mut rng, theta, k % 4 < 2);
        check(&w, &c, &d, &r, &t);
    }
}

#[test]
fn degenerate_input_gives_no_pose() {
    let w = [Point3::new(0.0, 0.0, 5.0), Point3::new(1.0, 0.0, 5.0)];
    let c = [Point3::origin(); 2];
    // Parallel directions; a zero direction; a NaN.
    let v = Vector3::new(0.0, 0.0, 1.0);
    assert!(up2p(&w, &c, &[v, v * 2.0]).is_empty());
    assert!(up2p(&w, &c, &[v, Vector3::zeros()]).is_empty());
    assert!(up2p(&w, &c, &[v, Vector3::new(f64::NAN, 0.0, 1.0)]).is_empty());
    let wn = [Point3::new(0.0, 0.0, f64::INFINITY), w[1]];
    assert!(up2p(&wn, &c, &[v, Vector3::new(0.1, 0.0, 1.0)]).is_empty());
}
