//! Issue 14, RANSAC: a consensus no better than chance is `NoConsensus` (pure noise, 99 %
//! outliers, a COLMAP image whose correspondences are all wrong), while clean and moderately
//! contaminated problems keep their true pose.
use std::path::PathBuf;

use eopnp::colmap::{read_model, register_image, ReadOptions, RegisterError};
use eopnp::ransac::Ransac;
use eopnp::{PnpError, Solver};
use eopnp_testkit::{self as common, Problem, ProblemOptions, RotationKind, Scene};
use nalgebra::Point2;
use rand::Rng;

/// A problem of `n` points of which the first `n_in` are true (sigma 1 px) and the others are
/// uniform over the 640 x 480 image (f = 800 px).
fn contaminated(n: usize, n_in: usize, seed: u64) -> Problem {
    let mut p = Problem::generate(&ProblemOptions {
        n,
        sigma_px: 1.0,
        scene: Scene::General,
        rotation: RotationKind::Uniform,
        seed,
    });
    let mut rng = common::rng_from_seed(seed ^ 0x5eed);
    for m in p.image.iter_mut().skip(n_in) {
        *m = Point2::new(
            (rng.random_range(0.0..640.0) - 320.0) / 800.0,
            (rng.random_range(0.0..480.0) - 240.0) / 800.0,
        );
    }
    p
}

fn outcome(p: &Problem, seed: u64) -> Result<(usize, f64), PnpError> {
    Ransac::default()
        .seed(seed)
        .estimate(
            &Solver::default(),
            &eopnp::Problem::normalised(&p.world, &p.image).focal(800.0, 800.0),
        )
        .map(|s| {
            let err = eopnp::internals::metrics::rotation_error_deg(&s.solution.rotation, &p.r_gt);
            (s.num_inliers, err)
        })
}

/// Pure noise and 99 % outliers (10 or 30 true points among 1,000 or 3,000; RANSAC's default
/// 10,000 samples cannot find them): never a pose, always `NoConsensus` with the counts. At
/// the larger thresholds the best wrong pose gathers many chance inliers (up to 47 of 3,000
/// at 16 px when this test was written) and only the chance criterion rejects it.
#[test]
fn no_consensus_without_signal() {
    for th in [4.0, 8.0, 16.0] {
        let mut by_chance = 0;
        for &(n, n_in) in &[(100, 0), (1000, 0), (3000, 0), (1000, 10), (3000, 30)] {
            for seed in 0..10 {
                let p = contaminated(n, n_in, common::trial_seed("consensus_noise", seed));
                let r = Ransac::default().seed(seed).threshold_px(th).estimate(
                    &Solver::default(),
                    &eopnp::Problem::normalised(&p.world, &p.image).focal(800.0, 800.0),
                );
                match r {
                    Err(PnpError::NoConsensus {
                        inliers, needed, ..
                    }) => {
                        assert!(
                            inliers < needed,
                            "N {n}, seed {seed}: {inliers} >= {needed}"
                        );
                        by_chance += usize::from(inliers >= 6);
                    }
                    other => panic!("{th} px, N {n} ({n_in} true), seed {seed}: {other:?}"),
                }
            }
        }
        if th >= 8.0 {
            assert!(by_chance >= 10, "{th} px: {by_chance}");
        }
    }
}

/// Clean and contaminated problems whose true points RANSAC can find keep the true pose.
#[test]
fn true_consensus_is_accepted() {
    for &(n, n_in) in &[(1000, 100), (200, 20), (50, 10), (20, 8), (10, 6), (6, 6)] {
        for seed in 0..10 {
            let p = contaminated(n, n_in, common::trial_seed("consensus_true", seed));
            let (k, err) = outcome(&p, seed)
                .unwrap_or_else(|e| panic!("N {n} ({n_in} true), seed {seed}: {e}"));
            assert!(k >= n_in, "N {n} ({n_in} true), seed {seed}: {k} inliers");
            assert!(err < 2.0, "N {n} ({n_in} true), seed {seed}: {err} deg");
        }
    }
}

/// Every image of the bundled model, with its observations assigned to the wrong 3D points (a
/// rotation of the list of observed points): `NoConsensus`, so `register --ransac` shows it
/// as not registered.
#[test]
fn colmap_images_with_wrong_correspondences() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data/colmap-boxes");
    let mut model = read_model(dir, &ReadOptions::default()).unwrap();
    let ids: Vec<u32> = model.images.keys().copied().collect();
    for &id in &ids {
        let image = model.images.get_mut(&id).unwrap();
        let observed: Vec<u64> = image.points2d.iter().filter_map(|o| o.1).collect();
        let shift = observed.len() / 2;
        for (k, obs) in image
            .points2d
            .iter_mut()
            .filter(|o| o.1.is_some())
            .enumerate()
        {
            obs.1 = Some(observed[(k + shift) % observed.len()]);
        }
    }
    for &id in &ids {
        let r = Ransac::default().seed(u64::from(id));
        match register_image(&model, id, &Solver::default(), Some(&r)) {
            Err(RegisterError::Solver(PnpError::NoConsensus {
                inliers, needed, ..
            })) => {
                assert!(inliers < needed);
            }
            Err(e) => panic!("image {id}: {e}"),
            Ok(reg) => panic!("image {id}: registered with {} inliers", reg.inliers),
        }
    }
}
