use super::*;
use crate::numeric::p3p::p3p;
use nalgebra::{Rotation3, Unit};

/// Small deterministic generator (xorshift), so the unit tests need no dev-dependency.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    fn sym(&mut self) -> f64 {
        2.0 * self.next() - 1.0
    }
}

/// A random rig problem: the rig pose `(R, t)`, three world points, and for each the centre of
/// its camera in the rig (spread by `baseline`) and the direction of its ray. `baseline` 0 is a
/// central camera.
struct RigProblem {
    r: Matrix3<f64>,
    t: Vector3<f64>,
    world: [Point3<f64>; 3],
    centres: [Point3<f64>; 3],
    directions: [Vector3<f64>; 3],
}

fn random_rig_problem(rng: &mut Rng, baseline: f64) -> RigProblem {
    let axis = Unit::new_normalize(Vector3::new(rng.sym(), rng.sym(), rng.sym()));
    let r = Rotation3::from_axis_angle(&axis, std::f64::consts::PI * rng.next()).into_inner();
    let t = Vector3::new(rng.sym(), rng.sym(), rng.sym());
    let mut world = [Point3::origin(); 3];
    let mut centres = [Point3::origin(); 3];
    let mut directions = [Vector3::zeros(); 3];
    for k in 0..3 {
        let c = Vector3::new(rng.sym(), rng.sym(), rng.sym()) * baseline;
        // A point 2 to 30 units from the camera, in any direction.
        let dir = Vector3::new(rng.sym(), rng.sym(), rng.sym()).normalize();
        let p = c + dir * (2.0 + 28.0 * rng.next());
        world[k] = Point3::from(r.transpose() * (p - t));
        centres[k] = Point3::from(c);
        // Any positive length.
        directions[k] = dir * (0.5 + rng.next());
    }
    RigProblem {
        r,
        t,
        world,
        centres,
        directions,
    }
}

/// How far the pose is from putting every world point on its ray (the sine of the angle
/// between `R X + t - c` and the ray, the largest of the three), and whether every point is in
/// front of its centre.
fn ray_residual(p: &RigProblem, pose: &P3pPose) -> (f64, bool) {
    let mut worst = 0.0f64;
    let mut front = true;
    for k in 0..3 {
        let q = pose.rotation * p.world[k].coords + pose.translation - p.centres[k].coords;
        let d = p.directions[k].normalize();
        worst = worst.max(q.cross(&d).norm() / q.norm());
        front &= q.dot(&d) > 0.0;
    }
    (worst, front)
}

/// Over 3,000 random rigs (baselines 0.1 to 2 units, points 2 to 30 units from their camera):
/// every returned pose is a rotation with a finite translation that puts the three points on
/// their rays, in front of their centres, to 1e-10; the true pose is among them to 1e-8 in all
/// but a handful of near-degenerate draws (measured: all).
#[test]
fn recovers_the_true_pose_of_random_rigs() {
    let mut rng = Rng(0x2545_F491_4F6C_DD1D);
    let trials = 3000;
    let (mut found, mut worst_found, mut worst_ray) = (0usize, 0.0f64, 0.0f64);
    for trial in 0..trials {
        let baseline = 0.1 + 1.9 * rng.next();
        let p = random_rig_problem(&mut rng, baseline);
        let sols = gp3p(&p.world, &p.centres, &p.directions);
        assert!(sols.len() <= MAX_GP3P_SOLUTIONS);
        for s in &sols {
            let orth = (s.rotation.transpose() * s.rotation - Matrix3::identity()).norm();
            assert!(orth < 1e-12, "trial {trial}: not orthonormal ({orth:e})");
            assert!((s.rotation.determinant() - 1.0).abs() < 1e-12);
            let (res, front) = ray_residual(&p, s);
            assert!(front, "trial {trial}: a point behind its camera");
            assert!(res < 1e-10, "trial {trial}: ray residual {res:e}");
            worst_ray = worst_ray.max(res);
        }
        let err = sols
            .iter()
            .map(|s| (s.rotation - p.r).norm() + (s.translation - p.t).norm() / (1.0 + p.t.norm()))
            .fold(f64::INFINITY, f64::min);
        if err < 1e-8 {
            found += 1;
            worst_found = worst_found.max(err);
        }
    }
    println!(
        "gp3p: true pose found in {found} of {trials}; worst error of a found pose {worst_found:e}, \
         worst ray residual {worst_ray:e}"
    );
    assert!(
        found >= trials - 3,
        "the true pose found in only {found} of {trials}"
    );
}

/// One centre for the three rays: the solutions are P3P's.
#[test]
fn one_centre_gives_the_p3p_solutions() {
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    for trial in 0..500 {
        let mut p = random_rig_problem(&mut rng, 0.0);
        // Move the common centre away from the origin: the solutions follow it.
        let c = Point3::new(rng.sym(), rng.sym(), rng.sym());
        p.centres = [c; 3];
        let g = gp3p(&p.world, &p.centres, &p.directions);
        // P3P in the camera at `c` (no rotation between it and the rig): x_cam = x_rig - c.
        let central = p3p(&p.world, &p.directions);
        assert_eq!(g.len(), central.len(), "trial {trial}");
        for s in &central {
            let t_rig = s.translation + c.coords;
            assert!(
                g.iter().any(|q| (q.rotation - s.rotation).norm() < 1e-8
                    && (q.translation - t_rig).norm() < 1e-8 * (1.0 + t_rig.norm())),
                "trial {trial}: a P3P solution gP3P does not have"
            );
        }
    }
}

/// Degenerate input gives no pose, never a NaN one.
#[test]
fn degenerate_input_gives_no_pose() {
    let c = [
        Point3::origin(),
        Point3::new(0.5, 0.0, 0.0),
        Point3::new(0.0, 0.5, 0.0),
    ];
    let d = [
        Vector3::new(0.0, 0.0, 1.0),
        Vector3::new(0.1, 0.0, 1.0),
        Vector3::new(0.0, 0.1, 1.0),
    ];
    let collinear = [
        Point3::new(0.0, 0.0, 5.0),
        Point3::new(1.0, 0.0, 5.0),
        Point3::new(2.0, 0.0, 5.0),
    ];
    assert!(gp3p(&collinear, &c, &d).is_empty());
    let same = [Point3::new(0.0, 0.0, 5.0); 3];
    assert!(gp3p(&same, &c, &d).is_empty());
    let w = [
        Point3::new(0.0, 0.0, 5.0),
        Point3::new(1.0, 0.0, 5.0),
        Point3::new(0.0, 1.0, 5.0),
    ];
    let zero = [Vector3::zeros(), d[1], d[2]];
    assert!(gp3p(&w, &c, &zero).is_empty());
    let nan = [Point3::new(f64::NAN, 0.0, 0.0), c[1], c[2]];
    assert!(gp3p(&w, &nan, &d).is_empty());
}
