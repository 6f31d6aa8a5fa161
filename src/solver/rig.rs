//! Problems on a multi-camera rig ([`crate::Problem::rig`]): the observations of one camera
//! only are that camera's central problem, solved by the pipeline and composed with the
//! camera's pose in the rig; observations in several cameras go to generalized EOPnP
//! ([`crate::generalized`]).

use nalgebra::{Isometry3, Matrix3, Matrix6, Vector3};

use super::{check_initial, Solver};
use crate::error::PnpError;
use crate::generalized::{self, one_camera, RigInput, RigOptions};
use crate::pipeline::{Solution, Solutions};
use crate::problem::Problem;
use crate::rig::Rig;

impl Solver {
    pub(crate) fn rig_options(&self) -> RigOptions {
        RigOptions {
            refinement: self.opts.refinement,
            loss: self.opts.loss,
            newton_iterations: self.opts.newton.max_iterations,
            newton_step_tolerance: self.opts.newton.step_tolerance,
            reprojection_iterations: self.opts.reproj.max_iterations,
            exhaustive: self.opts.exhaustive,
            covariance: self.covariance,
            vertical: self.opts.reproj.vertical,
        }
    }

    /// The solve (or every minimum, `all`) of a rig problem.
    pub(crate) fn rig(
        &self,
        p: &RigInput<'_>,
        mut all: Option<&mut Solutions>,
    ) -> Result<Solution, PnpError> {
        if let Some(k) = one_camera(p)? {
            let central = central_problem(p, k);
            let sol = self.solve_problem(&central, all.as_deref_mut())?;
            for s in all.into_iter().flatten() {
                *s = in_rig(s, p.rig, k);
            }
            return Ok(in_rig(&sol, p.rig, k));
        }
        generalized::solve(&self.rig_options(), p, all)
    }

    /// [`Solver::refine`] of a rig problem.
    pub(crate) fn refine_rig(
        &self,
        p: &RigInput<'_>,
        initial: &Isometry3<f64>,
    ) -> Result<Solution, PnpError> {
        let r = check_initial(initial)?;
        let t = initial.translation.vector;
        if let Some(k) = one_camera(p)? {
            // The prior in the camera's frame: x_cam = R_k (R X + t) + t_k.
            let (rk, tk) = p.rig.pose(k);
            let prior = Isometry3::from_parts(
                (rk * t + tk).into(),
                nalgebra::UnitQuaternion::from_matrix(&(rk * r)),
            );
            let sol = self.refine(&central_problem(p, k), &prior)?;
            return Ok(in_rig(&sol, p.rig, k));
        }
        generalized::refine_from(&self.rig_options(), p, (&r, &t))
    }
}

/// Camera `k`'s central problem of the observations of a rig problem (all in camera `k`), with
/// the vertical in the camera's frame.
pub(crate) fn central_problem<'a>(p: &RigInput<'a>, k: usize) -> Problem<'a> {
    let mut central = Problem::pixels(p.world, p.pixels, &p.rig.cameras()[k]);
    if let Some(w) = p.weights {
        central = central.weights(w);
    }
    if let Some(g) = &p.gravity {
        central = central.gravity(g.rotated(p.rig.pose(k).0));
    }
    central
}

/// A solution of camera `k`'s central problem (`x_cam = R_c X + t_c`) as the rig's pose:
/// `R = R_k^T R_c`, `t = R_k^T (t_c - t_k)`; the covariance rotated into the rig frame
/// (`omega = R_k^T omega_c`, `delta t = R_k^T delta t_c`).
pub(crate) fn in_rig(s: &Solution, rig: &Rig, k: usize) -> Solution {
    let (rk, tk) = rig.pose(k);
    let rkt: Matrix3<f64> = rk.transpose();
    let mut out = *s;
    out.rotation = rkt * s.rotation;
    out.translation = rkt * (s.translation - tk);
    if let Some(c) = &mut out.covariance {
        let mut b = Matrix6::zeros();
        b.fixed_view_mut::<3, 3>(0, 0).copy_from(&rkt);
        b.fixed_view_mut::<3, 3>(3, 3).copy_from(&rkt);
        c.matrix = b * c.matrix * b.transpose();
    }
    let _: Vector3<f64> = out.translation;
    out
}
