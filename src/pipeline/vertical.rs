//! The `vertical` stage of docs/algorithm.md: with a known vertical ([`crate::Gravity`]), the
//! maximum a posteriori pose from the maximum-likelihood one, and the test that the two agree.
//!
//! The prior is a residual on the rotation, `r_g = R g_w - g_c` (`R` the world-to-camera
//! rotation, `g_w`, `g_c` the unit vertical in the world's and the camera's frame), whose two
//! components across `R g_w` have the standard deviation `sigma` (radians). With image noise of
//! variance `s^2` per residual row (unit weight), the negative log posterior times `s^2` is
//! `E(R, t) + lambda |R g_w - g_c|^2`, `lambda = s^2 / sigma^2`: Levenberg-Marquardt minimises
//! it with the prior as one more term of the normal equations ([`PriorTerm::add`]; under the
//! update `R := Exp(w) R`, `d(R g_w) = w x R g_w`, so the term adds
//! `lambda (I - u u^T)` to `J^T W J`'s rotation block and `-lambda u x g_c` to the gradient,
//! `u = R g_w`).
//!
//! Why a prior and not the constraint `R g_w = g_c`: an IMU's vertical is good to a fraction of
//! a degree, the images often to a hundredth; the constraint would bend an accurate pose to
//! the IMU's error, where the prior weighs the two by their uncertainties (and with
//! `sigma -> 0` becomes the constraint).
//!
//! `s^2` is estimated from the maximum-likelihood pose, where the refinement starts:
//! `s^2 = E_ML / (2 N - 6)`. The same start gives the test: the vertical of the pose,
//! `u = R_ML g_w`, has the covariance `[u]x Sigma_w [u]x^T` (`Sigma_w = s^2` times the rotation
//! block of `(J^T W J)^-1`); with the measurement's, `sigma^2` across `u`, the discrepancy's
//! two components across `u` have the Mahalanobis distance `d`. When both are right, `d^2` is
//! chi-squared with two degrees of freedom if `s^2` were known; with `s^2` estimated from
//! `nu = 2 N - 6` residuals it is at most `2 F(2, nu)` distributed (equal when the images'
//! uncertainty dominates the measurement's). The solve reports a mismatch
//! ([`crate::PnpError::GravityMismatch`]) when `d^2` exceeds that distribution's quantile of
//! tail probability [`FALSE_ALARM`] (0.27 %, a one-dimensional 3-sigma test's),
//! `nu (FALSE_ALARM^(-2 / nu) - 1)`: 11.83 for large `N` (the chi-squared quantile), 37.1 at
//! `N = 6`, where six residual degrees of freedom hardly estimate `s^2`. (With the
//! chi-squared quantile at every `N`, right verticals of 0.1 degrees were reported in 1.55 %
//! of 2,000 problems at `N = 6`, 0.3 % at `N = 30`.)

use nalgebra::{Matrix2, Matrix3, Matrix6, Vector2, Vector3};

use crate::error::PnpError;
use crate::gravity::Gravity;
use crate::numeric::mat3::orthogonal_pair;

/// The probability that a right vertical is reported as a mismatch: a 3-sigma test's.
pub(crate) const FALSE_ALARM: f64 = 0.0027;

/// A known vertical in the form the refinement uses: the unit directions, the standard deviation
/// in radians and the number of correspondences `N` (the residual's degrees of freedom are
/// `2 N - 6`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Vertical {
    pub world: Vector3<f64>,
    pub camera: Vector3<f64>,
    pub sigma: f64,
    pub points: usize,
}

impl Vertical {
    /// `g`, for a solve whose number of correspondences is still to be set
    /// ([`Vertical::with_points`]).
    pub(crate) fn new(g: &Gravity) -> Self {
        Vertical {
            world: g.in_world(),
            camera: g.in_camera(),
            sigma: g.sigma_deg().to_radians(),
            points: 0,
        }
    }

    /// The same vertical for a solve of `points` correspondences.
    pub(crate) fn with_points(self, points: usize) -> Self {
        Vertical { points, ..self }
    }

    /// The residual's degrees of freedom, `2 N - 6` (at least 1).
    fn dof(&self) -> f64 {
        (2.0 * self.points as f64 - 6.0).max(1.0)
    }

    /// The mismatch threshold on `d^2`, `nu (FALSE_ALARM^(-2 / nu) - 1)` (module docs).
    fn limit(&self) -> f64 {
        let nu = self.dof();
        nu * (FALSE_ALARM.powf(-2.0 / nu) - 1.0)
    }
}

/// The measured vertical against the maximum-likelihood pose's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct VerticalCheck {
    /// The angle between them, in radians.
    pub angle: f64,
    /// Their Mahalanobis distance `d` under the combined covariance.
    pub sigmas: f64,
    /// The threshold on `d^2` ([`Vertical::limit`]).
    pub limit: f64,
}

impl VerticalCheck {
    /// `Err(GravityMismatch)` when `d^2` is above the threshold (or not a number).
    pub(crate) fn result(&self) -> Result<(), PnpError> {
        if self.sigmas * self.sigmas <= self.limit {
            Ok(())
        } else {
            Err(PnpError::GravityMismatch {
                angle_deg: self.angle.to_degrees(),
                sigmas: self.sigmas,
            })
        }
    }
}

/// [`VerticalCheck::result`] of an optional check (`Ok` without one).
pub(crate) fn verdict(check: Option<VerticalCheck>) -> Result<(), PnpError> {
    check.map_or(Ok(()), |c| c.result())
}

/// The prior's term in one Levenberg-Marquardt run: in the working frame of the run
/// (`u = R g_w'`, `g_w' = R_w g_w` with the frame's rotation `R_w`), with its weight in the
/// run's cost unit.
pub(super) struct PriorTerm {
    world: Vector3<f64>,
    camera: Vector3<f64>,
    lambda: f64,
}

impl PriorTerm {
    /// The term of `v` for a run in the frame rotated by `rw` whose start, the maximum-likelihood
    /// pose, has the cost `e_ml` (the run's unit): `lambda = e_ml / (2 N - 6) / sigma^2`.
    pub(super) fn new(v: &Vertical, rw: &Matrix3<f64>, e_ml: f64) -> Self {
        let s2 = (e_ml / v.dof()).max(0.0);
        PriorTerm {
            world: rw * v.world,
            camera: v.camera,
            lambda: s2 / (v.sigma * v.sigma),
        }
    }

    /// `lambda |R g_w' - g_c|^2`.
    pub(super) fn cost(&self, r: &Matrix3<f64>) -> f64 {
        self.lambda * (r * self.world - self.camera).norm_squared()
    }

    /// Adds the term at the working-frame rotation `r` to a pass's cost `e` and gradient `g`
    /// (`J^T W e`, rotation first), and to its `J^T W J` `h` when given.
    pub(super) fn add(
        &self,
        r: &Matrix3<f64>,
        e: &mut f64,
        g: &mut [f64; 6],
        h: Option<&mut [[f64; 6]; 6]>,
    ) {
        let u = r * self.world;
        let l = self.lambda;
        *e += l * (u - self.camera).norm_squared();
        let gr = -l * u.cross(&self.camera);
        for k in 0..3 {
            g[k] += gr[k];
        }
        if let Some(h) = h {
            for i in 0..3 {
                for j in 0..3 {
                    let id = if i == j { 1.0 } else { 0.0 };
                    h[i][j] += l * (id - u[i] * u[j]);
                }
            }
        }
    }
}

/// The test of the module docs at the maximum-likelihood pose: working-frame rotation `r`,
/// `J^T W J` there `h`, cost `e_ml` (all in the run's units and frame, rotated by `rw`).
pub(super) fn check(
    v: &Vertical,
    rw: &Matrix3<f64>,
    r: &Matrix3<f64>,
    h: &[[f64; 6]; 6],
    e_ml: f64,
) -> VerticalCheck {
    let u = (r * (rw * v.world)).normalize();
    let g = v.camera;
    let angle = u.cross(&g).norm().atan2(u.dot(&g));
    let s2 = (e_ml / v.dof()).max(0.0);
    // The rotation block of (J^T W J)^-1, by the Schur complement of the translation block.
    let hm = Matrix6::from_fn(|i, j| h[i][j]);
    let cov_w = hm
        .try_inverse()
        .map(|inv| inv.fixed_view::<3, 3>(0, 0).into_owned() * s2)
        .filter(|c| c.iter().all(|x| x.is_finite()));
    // Across u: the basis (b1, b2); u moves by w x u = -[u]x w.
    let (b1, b2) = orthogonal_pair(&u);
    let d = Vector2::new(b1.dot(&g), b2.dot(&g));
    let var = v.sigma * v.sigma;
    // Without the data's covariance (singular normal equations) there is no test.
    let Some(cw) = cov_w else {
        return VerticalCheck {
            angle,
            sigmas: 0.0,
            limit: v.limit(),
        };
    };
    let ux = u.cross_matrix();
    let j = nalgebra::Matrix2x3::from_rows(&[(b1.transpose() * ux), (b2.transpose() * ux)]);
    let cov = Matrix2::new(var, 0.0, 0.0, var) + j * cw * j.transpose();
    let sigmas = if u.dot(&g) <= 0.0 {
        // Ninety degrees or more apart: no Gaussian model of either explains it.
        f64::INFINITY
    } else {
        cov.try_inverse().map_or(f64::INFINITY, |ci| {
            (d.transpose() * ci * d)[(0, 0)].max(0.0).sqrt()
        })
    };
    VerticalCheck {
        angle,
        sigmas,
        limit: v.limit(),
    }
}
