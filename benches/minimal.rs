//! The four-point pose with unknown focal length (P4Pf, `eopnp::internals::p4pf`), the minimal
//! solver of RANSAC with an unknown focal length: per call on samples of four inliers (1 px of
//! noise) and on samples of four random correspondences (RANSAC's samples at high outlier
//! rates, which mostly have no solution). A pinhole camera of focal length log-uniform in 300
//! to 3,000 px (640 x 480 image), points 2 to 10 units away; 4,096 fixed-seed samples per set,
//! cycled inside the timed closure (with 256, P4Pf's times were 13 to 16 % lower: the branch
//! predictor learned part of the samples).

use eopnp_testkit as common;
mod support;

use common::{gauss, haar_rotation, rng_from_seed};
use criterion::{black_box, criterion_group, criterion_main, Criterion};
use eopnp::internals::p4pf::p4pf;
use nalgebra::{Point2, Point3, Vector3};
use rand::Rng;
use rand_pcg::Pcg64;
use support::config;

const SAMPLES: usize = 4096;

type Sample = ([Point3<f64>; 4], [Point2<f64>; 4]);

/// Four correspondences of one random camera (pixels relative to the principal point): with
/// `inliers`, the projections with 1 px of noise; otherwise uniform pixels in the image.
fn sample(rng: &mut Pcg64, inliers: bool) -> Sample {
    let f = 10f64.powf(rng.random_range(300f64.log10()..3000f64.log10()));
    let r = haar_rotation(rng);
    let t = Vector3::new(
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
    );
    let mut world = [Point3::origin(); 4];
    let mut image = [Point2::origin(); 4];
    for (x, m) in world.iter_mut().zip(&mut image) {
        let (u, v) = (
            rng.random_range(-320.0..320.0),
            rng.random_range(-240.0..240.0),
        );
        let z = rng.random_range(2.0..10.0);
        *x = Point3::from(r.transpose() * (Vector3::new(u / f * z, v / f * z, z) - t));
        *m = if inliers {
            Point2::new(u + gauss(rng), v + gauss(rng))
        } else {
            Point2::new(
                rng.random_range(-320.0..320.0),
                rng.random_range(-240.0..240.0),
            )
        };
    }
    (world, image)
}

fn minimal_bench(c: &mut Criterion) {
    for (name, inliers) in [("p4pf/inliers", true), ("p4pf/random", false)] {
        let mut rng = rng_from_seed(0x0004_0F0F);
        let samples: Vec<Sample> = (0..SAMPLES).map(|_| sample(&mut rng, inliers)).collect();
        let mut i = 0usize;
        c.bench_function(name, |b| {
            b.iter(|| {
                let (w, m) = black_box(&samples[i % SAMPLES]);
                i = i.wrapping_add(1);
                black_box(p4pf(w, m))
            })
        });
    }
}

criterion_group! {
    name = benches;
    config = config();
    targets = minimal_bench
}
criterion_main!(benches);
