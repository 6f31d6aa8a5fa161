//! Issue 14, degeneracy: points whose image spans a tiny part of the view determine the pose
//! only through perspective effects that shrink with the span; below f64 resolution the pose is
//! flagged `degenerate` or refused, never returned as a confident wrong pose.
use eopnp::Solver;
use eopnp_testkit::{self as common, Problem, ProblemOptions, RotationKind, Scene};
use nalgebra::{Point2, Point3};

/// The problem of `seed` with its world pattern shrunk by `s` around its first point (the same
/// camera), projected without noise.
fn shrunk(
    seed: u64,
    n: usize,
    scene: Scene,
    s: f64,
) -> (Problem, Vec<Point3<f64>>, Vec<Point2<f64>>) {
    let p = Problem::generate(&ProblemOptions {
        n,
        sigma_px: 0.0,
        scene,
        rotation: RotationKind::Uniform,
        seed,
    });
    let x0 = p.world[0];
    let world: Vec<Point3<f64>> = p.world.iter().map(|x| x0 + (x - x0) * s).collect();
    let image = world
        .iter()
        .map(|x| {
            let q = p.r_gt * x.coords + p.t_gt;
            Point2::new(q.x / q.z, q.y / q.z)
        })
        .collect();
    (p, world, image)
}

/// Patterns shrunk by 10^-1 .. 10^-12: every pose returned is either within 1 degree of the
/// truth or flagged `degenerate`; general scenes down to 10^-5 are solved and not flagged.
#[test]
fn no_wrong_pose_unflagged_over_shrinking_patterns() {
    for scene in [Scene::General, Scene::Planar] {
        for e in 1..=12 {
            let s = 10f64.powi(-e);
            let (mut good, mut flagged, mut errors) = (0, 0, 0);
            for seed in 0..50 {
                let (p, w, i) = shrunk(common::trial_seed("tiny_image", seed), 10, scene, s);
                match Solver::default().solve(&eopnp::Problem::normalised(&w, &i)) {
                    Ok(sol) if sol.degenerate => flagged += 1,
                    Ok(sol) => {
                        let err = common::rot_err_deg(&sol.rotation, &p.r_gt);
                        assert!(
                            err < 1.0,
                            "{scene:?} shrunk 1e-{e}, seed {:#x}: {err} deg, not flagged",
                            p.opts.seed
                        );
                        good += 1;
                    }
                    Err(_) => errors += 1,
                }
            }
            if scene == Scene::General && e <= 5 {
                assert_eq!(
                    good, 50,
                    "{scene:?} 1e-{e}: {flagged} flagged, {errors} errors"
                );
            }
        }
    }
}
