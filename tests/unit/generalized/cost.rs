//! The generalized cost's moments against the direct sum: for random rays and rotations,
//! `f(R) = r^T M r + 2 g^T r + k` equals `min_t sum_i w_i |Q_i (R X_i + t - c_i)|^2`, evaluated
//! at `t = Cost::translation(R)`, and that translation is the minimiser (the gradient of the
//! direct sum in `t` vanishes there).

use super::*;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

/// A ray's world point, centre, unit direction and weight.
type Ray = (Vector3<f64>, Vector3<f64>, Vector3<f64>, f64);

fn random_rotation(rng: &mut Pcg64) -> Matrix3<f64> {
    let s = Vector3::new(
        rng.random_range(-2.0..2.0),
        rng.random_range(-2.0..2.0),
        rng.random_range(-2.0..2.0),
    );
    cgr_to_rotation(&s)
}

#[test]
fn moments_equal_the_direct_sum() {
    let mut rng = Pcg64::seed_from_u64(7);
    let mut worst: f64 = 0.0;
    for _ in 0..500 {
        let n = rng.random_range(4..40);
        let rays: Vec<Ray> = (0..n)
            .map(|_| {
                let x = Vector3::new(
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                );
                let c = Vector3::new(
                    rng.random_range(-0.5..0.5),
                    rng.random_range(-0.5..0.5),
                    rng.random_range(-0.5..0.5),
                );
                let v = Vector3::new(
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                )
                .normalize();
                (x, c, v, rng.random_range(0.1..2.0))
            })
            .collect();
        let cost = Cost::new(rays.len(), |k| rays[k]).expect("rays in general position");
        let r = random_rotation(&mut rng);
        let t = cost.translation(&r);
        let (mut direct, mut grad, mut scale) = (0.0, Vector3::zeros(), 0.0);
        for (x, c, v, w) in &rays {
            let q = Matrix3::identity() - v * v.transpose();
            let e = q * (r * x + t - c);
            direct += w * e.norm_squared();
            grad += q * e * (2.0 * w);
            scale += w * (x.norm() + t.norm() + c.norm()).powi(2);
        }
        worst = worst.max((cost.value(&r) - direct).abs() / scale);
        worst = worst.max(grad.norm() / scale);
    }
    assert!(worst < 1e-13, "worst relative difference {worst:e}");
}
