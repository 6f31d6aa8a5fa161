//! RANSAC's hypotheses with a known vertical: samples of two correspondences solved by the
//! upright two-point pose ([`crate::numeric::up2p`]) in frames turned so that the vertical is
//! their `y` axis.

use nalgebra::{Matrix3, Point3, Vector3};

use crate::gravity::Gravity;
use crate::numeric::mat3::orthogonal_pair;
use crate::numeric::p3p::P3pPose;
use crate::numeric::up2p::{up2p, Up2pSolutions};

/// The rotations that turn the camera's (rig's) and the world's frames so that the vertical is
/// their `y` axis: `Q g = (0, 1, 0)`.
pub(super) struct Upright {
    camera: Matrix3<f64>,
    world: Matrix3<f64>,
}

/// A rotation `Q` with `Q g = (0, 1, 0)` for the unit `g`: the rows `(a, g, a x g)`, `a` a unit
/// vector across `g`.
fn to_y(g: &Vector3<f64>) -> Matrix3<f64> {
    let (a, _) = orthogonal_pair(g);
    Matrix3::from_rows(&[a.transpose(), g.transpose(), a.cross(g).transpose()])
}

impl Upright {
    pub(super) fn new(g: &Gravity) -> Self {
        Upright {
            camera: to_y(&g.in_camera()),
            world: to_y(&g.in_world()),
        }
    }

    /// The poses `x = R X + t` (camera or rig frame) with `R g_world = g_camera` that put the
    /// two world points on their rays (`centres`, `directions` in the camera's or rig's frame):
    /// up2p in the turned frames, `x' = R' X' + t'`, gives `R = Q_c^T R' Q_w`, `t = Q_c^T t'`.
    pub(super) fn poses(
        &self,
        world: [&Point3<f64>; 2],
        centres: [&Point3<f64>; 2],
        directions: [&Vector3<f64>; 2],
    ) -> Up2pSolutions {
        let (qc, qw) = (&self.camera, &self.world);
        let mut out = up2p(
            &[
                Point3::from(qw * world[0].coords),
                Point3::from(qw * world[1].coords),
            ],
            &[
                Point3::from(qc * centres[0].coords),
                Point3::from(qc * centres[1].coords),
            ],
            &[qc * directions[0], qc * directions[1]],
        );
        for p in &mut out {
            *p = P3pPose {
                rotation: qc.transpose() * p.rotation * qw,
                translation: qc.transpose() * p.translation,
            };
        }
        out
    }
}

#[cfg(test)]
#[path = "../../../tests/unit/robust/ransac/upright.rs"]
mod tests;
