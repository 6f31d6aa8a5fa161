//! The covariance of a returned pose ([`crate::Solver::covariance`]): first-order propagation
//! of isotropic Gaussian image noise through the reprojection error at the pose, from the
//! Gauss-Newton normal equations `H = sum_i w_i J_i^T A_i^T A_i J_i` (one O(N) pass, no
//! allocation).
//!
//! Convention (pycolmap's `return_covariance=True`, i.e. COLMAP's `RefineAbsolutePose`
//! covariance): the 6 x 6 covariance of `[delta_q, delta_t]` for the pose `x_cam = R X + t`
//! perturbed as `R = Exp(2 delta_q) R_hat`, `t = t_hat + delta_t`. `delta_q` is the tangent
//! of the unit quaternion on the left (`q = [delta_q / |delta_q| sin|delta_q|,
//! cos|delta_q|] * q_hat`, Ceres's quaternion manifold): half the rotation vector, so the
//! rotation block is a quarter of the covariance of the rotation vector `2 delta_q` (multiply
//! it by 4, and the rotation-translation blocks by 2, for the covariance of
//! `[rotation vector, t]`). Measured against pycolmap 4.2.1 on one problem, the two matrices
//! agree (README, "Pose covariance").
//!
//! `J_i` is the Jacobian of the normalised projection `(x/z, y/z)` of point `i`; `A_i` maps a
//! normalised residual to image units: the identity for normalised input, the camera's
//! projection Jacobian at the point for pixel input (so the noise is isotropic in pixels,
//! through the lens distortion). The noise variance is the caller's (`NoiseModel::Sigma`) or
//! estimated from the residuals, `sum_i w_i |A_i r_i|^2 / (2 n - 6)`.

use nalgebra::{Matrix2x3, Matrix3, Matrix6, Point2, Point3, Vector3};

use crate::camera::Camera;

/// The image noise the covariance assumes.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum NoiseModel {
    /// Estimated from the residuals at the pose: `sigma^2 = cost / (2 n - 6)` with the cost in
    /// image units (pixels for pixel input) and `n` the points of weight > 0.
    Estimated,
    /// The standard deviation of each image coordinate, in the units of the observations
    /// (pixels for [`crate::Problem::pixels`], normalised units for
    /// [`crate::Problem::normalised`]; pycolmap assumes 1 pixel).
    Sigma(f64),
}

/// The covariance of a pose (module documentation for the convention).
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct PoseCovariance {
    /// Covariance of `[delta_q (3), delta_t (3)]`.
    pub matrix: Matrix6<f64>,
    /// The noise standard deviation used, in image units (given or estimated).
    pub sigma: f64,
    /// With an unknown focal length ([`crate::Problem::unknown_focal`]): the standard deviation
    /// of the estimated focal length (pixels, the first focal length; the others scale alike).
    /// The pose's covariance is then its marginal one, the focal length's (and any other
    /// refined intrinsic's) uncertainty included. `None` otherwise.
    pub focal_sigma: Option<f64>,
}

/// Maps a normalised residual at a normalised point to image units.
#[derive(Clone, Copy)]
pub(crate) enum Metric<'a> {
    /// Normalised input: image units are normalised units.
    Identity,
    /// Pixel input: the camera's projection Jacobian at the (undistorted) point.
    Camera(&'a Camera),
}

/// The covariance of the pose `(r, t)` for the observations `image` (normalised points) of `world`
/// with weights `weight(i)`, or `None` when the normal equations are not positive definite
/// (fewer than 4 weighted points, or a degenerate configuration) or the noise is not finite.
pub(crate) fn pose_covariance(
    world: &[Point3<f64>],
    image: &[Point2<f64>],
    weight: &dyn Fn(usize) -> f64,
    (r, t): (&Matrix3<f64>, &Vector3<f64>),
    metric: Metric<'_>,
    noise: NoiseModel,
) -> Option<PoseCovariance> {
    let mut h = Matrix6::<f64>::zeros();
    let mut cost = 0.0;
    let mut n = 0usize;
    for (i, (x, m)) in world.iter().zip(image).enumerate() {
        let w = weight(i);
        if !(w > 0.0) {
            continue;
        }
        let q = r * x.coords;
        let p = q + t;
        if !(p.z > 0.0) {
            return None;
        }
        let iz = 1.0 / p.z;
        let (u, v) = (p.x * iz, p.y * iz);
        // d(u, v)/dp, then dp/d(theta, t) = [-[q]x, I] for R = Exp(theta) R_hat.
        let dp = Matrix2x3::new(iz, 0.0, -u * iz, 0.0, iz, -v * iz);
        let jr = dp * -skew(&q);
        let mut j = nalgebra::Matrix2x6::<f64>::zeros();
        j.fixed_view_mut::<2, 3>(0, 0).copy_from(&jr);
        j.fixed_view_mut::<2, 3>(0, 3).copy_from(&dp);
        let res = nalgebra::Vector2::new(m.x - u, m.y - v);
        let (j, res) = match metric {
            Metric::Identity => (j, res),
            Metric::Camera(cam) => {
                let a = cam.project_jacobian(Point2::new(u, v));
                let a = nalgebra::Matrix2::new(a[0], a[1], a[2], a[3]);
                (a * j, a * res)
            }
        };
        h += (j.transpose() * j) * w;
        cost += w * res.norm_squared();
        n += 1;
    }
    if n < 4 {
        return None;
    }
    let sigma = match noise {
        NoiseModel::Sigma(s) => s,
        NoiseModel::Estimated => (cost / (2 * n - 6) as f64).sqrt(),
    };
    if !(sigma.is_finite() && sigma >= 0.0) {
        return None;
    }
    let cov_theta = h.cholesky()?.inverse() * (sigma * sigma);
    from_rotation_vector(&cov_theta, sigma, None)
}

/// The [`PoseCovariance`] of the covariance `cov_theta` of `[theta, delta_t]` (`R = Exp(theta)
/// R_hat`), or `None` if it is not finite: `theta = 2 delta_q` scales the rotation rows and
/// columns by 1/2.
pub(crate) fn from_rotation_vector(
    cov_theta: &Matrix6<f64>,
    sigma: f64,
    focal_sigma: Option<f64>,
) -> Option<PoseCovariance> {
    let mut matrix = *cov_theta;
    for k in 0..6 {
        for l in 0..6 {
            let s = match (k < 3, l < 3) {
                (true, true) => 0.25,
                (true, false) | (false, true) => 0.5,
                (false, false) => 1.0,
            };
            matrix[(k, l)] *= s;
        }
    }
    (matrix.iter().all(|x| x.is_finite()) && focal_sigma.is_none_or(f64::is_finite)).then_some(
        PoseCovariance {
            matrix,
            sigma,
            focal_sigma,
        },
    )
}

fn skew(v: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}
