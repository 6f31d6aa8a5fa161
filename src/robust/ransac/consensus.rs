//! `impl sample_consensus::Estimator` for the P3P minimal solver (feature `sample-consensus`).

use arrayvec::ArrayVec;
use nalgebra::{Matrix3, Point2, Point3, Vector3};
use sample_consensus::{Estimator, Model};

use crate::robust::p3p::{p3p, MAX_P3P_SOLUTIONS};

/// One 2D-3D correspondence: world point, normalised image point `(x/z, y/z)` and the
/// scale from normalised to pixel residuals (e.g. the focal length).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Correspondence {
    /// World point.
    pub world: Point3<f64>,
    /// Normalised image point.
    pub image: Point2<f64>,
    /// Pixels per normalised unit at this point.
    pub pixel_scale: f64,
}

/// A world-to-camera pose `x_cam = R X + t`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PoseModel {
    /// Rotation `R`.
    pub rotation: Matrix3<f64>,
    /// Translation `t`.
    pub translation: Vector3<f64>,
}

impl Model<Correspondence> for PoseModel {
    /// Pixel reprojection error (infinite behind the camera).
    fn residual(&self, c: &Correspondence) -> f64 {
        let p = self.rotation * c.world.coords + self.translation;
        if !(p.z > 0.0) {
            return f64::INFINITY;
        }
        let d = Point2::new(p.x / p.z, p.y / p.z) - c.image;
        c.pixel_scale * d.norm()
    }
}

/// The P3P minimal solver as a `sample_consensus::Estimator` (3 samples, up to 4 models).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct P3pEstimator;

impl Estimator<Correspondence> for P3pEstimator {
    type Model = PoseModel;
    type ModelIter = ArrayVec<PoseModel, MAX_P3P_SOLUTIONS>;
    const MIN_SAMPLES: usize = 3;

    /// Poses from the first three correspondences; none (rather than the trait's suggested
    /// panic) if fewer are given or the triplet is degenerate.
    fn estimate<I>(&self, mut data: I) -> Self::ModelIter
    where
        I: Iterator<Item = Correspondence> + Clone,
    {
        let (Some(a), Some(b), Some(c)) = (data.next(), data.next(), data.next()) else {
            return ArrayVec::new();
        };
        let bearing = |c: &Correspondence| Vector3::new(c.image.x, c.image.y, 1.0);
        p3p(
            &[a.world, b.world, c.world],
            &[bearing(&a), bearing(&b), bearing(&c)],
        )
        .into_iter()
        .map(|p| PoseModel {
            rotation: p.rotation,
            translation: p.translation,
        })
        .collect()
    }
}
