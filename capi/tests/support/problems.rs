//! Deterministic synthetic problems (a tiny 64-bit LCG, no dependency) shared by the Rust
//! tests and the reference program whose output the C and C++ tests compare with.

#![allow(dead_code)]

use eopnp::camera::Camera;
use nalgebra::{Point2, Point3, Rotation3, Vector3};

/// A 64-bit linear congruential generator (Knuth's MMIX constants).
pub struct Lcg(pub u64);

impl Lcg {
    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in [a, b).
    pub fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.uniform()
    }

    /// Approximately standard normal (sum of 12 uniforms minus 6).
    pub fn normal(&mut self) -> f64 {
        (0..12).map(|_| self.uniform()).sum::<f64>() - 6.0
    }
}

/// A pose problem: world points, their normalised image points and the true pose.
pub struct Synthetic {
    pub world: Vec<Point3<f64>>,
    pub normalised: Vec<Point2<f64>>,
    pub rotation: Rotation3<f64>,
    pub translation: Vector3<f64>,
}

/// `n` points in a box in front of a camera at a random pose, with normalised image noise of
/// `noise` (standard deviation).
pub fn synthetic(seed: u64, n: usize, noise: f64) -> Synthetic {
    let mut g = Lcg(seed);
    let rotation =
        Rotation3::from_euler_angles(g.range(-3.0, 3.0), g.range(-1.5, 1.5), g.range(-3.0, 3.0));
    let translation = Vector3::new(g.range(-1.0, 1.0), g.range(-1.0, 1.0), g.range(4.0, 8.0));
    let mut world = Vec::with_capacity(n);
    let mut normalised = Vec::with_capacity(n);
    for _ in 0..n {
        let cam = Vector3::new(g.range(-2.0, 2.0), g.range(-2.0, 2.0), g.range(4.0, 8.0));
        let x = rotation.inverse() * (cam - translation);
        world.push(Point3::from(x));
        normalised.push(Point2::new(
            cam.x / cam.z + noise * g.normal(),
            cam.y / cam.z + noise * g.normal(),
        ));
    }
    Synthetic {
        world,
        normalised,
        rotation,
        translation,
    }
}

/// The camera of the pixel cases: COLMAP's OPENCV model with mild distortion.
pub fn opencv_camera() -> Camera {
    Camera::from_colmap(
        "OPENCV",
        640,
        480,
        vec![800.0, 810.0, 320.0, 240.0, -0.05, 0.01, 1e-3, -5e-4],
    )
    .expect("valid camera")
}

/// Flattens points to their coordinates.
pub fn flat3(p: &[Point3<f64>]) -> Vec<f64> {
    p.iter().flat_map(|x| [x.x, x.y, x.z]).collect()
}

/// Flattens points to their coordinates.
pub fn flat2(p: &[Point2<f64>]) -> Vec<f64> {
    p.iter().flat_map(|x| [x.x, x.y]).collect()
}
