//! The plain-data types of the interface: problems, poses, solutions, statistics, and the
//! enumerations of the options.

use crate::error::EopnpStatus;
use eopnp::ransac::RansacStats;
use eopnp::{CandidateSource, Solution};

/// The largest number of local minima `eopnp_solve_all` returns (the library's capacity of
/// `Solutions`).
pub const EOPNP_MAX_SOLUTIONS: usize = 32;

/// The most parameters a camera model has (`OPENCV_THIN_PRISM_TILTED`'s 18): the length of
/// `EopnpSolution::camera_params`.
// The library's `camera::MAX_PARAMS`, which it does not export; the test
// `max_camera_params_is_the_largest_model` (tests/focal_gravity.rs) checks it against the models.
pub const EOPNP_MAX_CAMERA_PARAMS: usize = 18;

/// Which cost the returned pose minimises (`eopnp_solver_set_refinement`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EopnpRefinement {
    /// EOPnP followed by Levenberg-Marquardt on the reprojection error: the maximum-likelihood
    /// pose. Default.
    EOPNP_REFINEMENT_REPROJECTION = 0,
    /// EOPnP alone: the minimiser of the paper's algebraic cost.
    EOPNP_REFINEMENT_ALGEBRAIC = 1,
}

/// How the planar branch is chosen (`eopnp_solver_set_planar_detection`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EopnpPlanarDetection {
    /// From the planarity of the world points. Default.
    EOPNP_PLANAR_AUTO = 0,
    /// Planar branch only.
    EOPNP_PLANAR_PLANAR = 1,
    /// Non-planar branch only.
    EOPNP_PLANAR_NON_PLANAR = 2,
}

/// The loss of the final refinement (`eopnp_solver_set_loss`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EopnpLoss {
    /// `rho(r2) = r2`, the maximum-likelihood pose for Gaussian noise. Default.
    EOPNP_LOSS_SQUARED = 0,
    /// `rho(r2) = r2` for `r <= s`, `2 s r - s^2` beyond.
    EOPNP_LOSS_HUBER = 1,
    /// `rho(r2) = s^2 ln(1 + r2 / s^2)`.
    EOPNP_LOSS_CAUCHY = 2,
}

/// Which covariance the solver computes (`eopnp_solver_set_covariance`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EopnpCovariance {
    /// No covariance (default).
    EOPNP_COVARIANCE_NONE = 0,
    /// The noise estimated from the residuals at the pose, `sigma^2 = cost / (2 n - 6)`.
    EOPNP_COVARIANCE_ESTIMATED = 1,
    /// A given noise standard deviation per image coordinate, in the units of the
    /// observations (pixels for pixel input, normalised units for normalised input).
    EOPNP_COVARIANCE_SIGMA = 2,
}

/// The candidate generator of a solution's winning start (`EopnpSolution::source`), the
/// library's `CandidateSource`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EopnpSource {
    /// Null-space case 1 (non-planar).
    EOPNP_SOURCE_CASE1 = 0,
    /// Null-space case 2.
    EOPNP_SOURCE_CASE2 = 1,
    /// Null-space case 3.
    EOPNP_SOURCE_CASE3 = 2,
    /// Null-space case 4.
    EOPNP_SOURCE_CASE4 = 3,
    /// Planar case 1.
    EOPNP_SOURCE_PLANAR1 = 4,
    /// Planar case 2.
    EOPNP_SOURCE_PLANAR2 = 5,
    /// An extra start of the search.
    EOPNP_SOURCE_EXTRA_START = 6,
    /// The initial pose of `eopnp_refine`.
    EOPNP_SOURCE_INITIAL = 7,
    /// The P3P minimal solver (RANSAC).
    EOPNP_SOURCE_P3P = 8,
    /// The generalized (rig) solver.
    EOPNP_SOURCE_GENERALIZED = 9,
    /// The generalized three-point solver (rig RANSAC).
    EOPNP_SOURCE_GP3P = 10,
    /// A generator added to the library after this interface.
    EOPNP_SOURCE_OTHER = 11,
}

/// One pose problem: `n` world points and their observations, like the Rust library's
/// `Problem`. Zero-initialise it (`EopnpProblem p = {0};`) and set the fields you need.
///
/// The kind of observations follows from the fields: with `rig` set, pixels observed by the
/// rig's cameras (`rig_cameras[i]` the camera of correspondence `i`); else with `camera` set,
/// pixels observed by that camera (any model, distortion included; costs in pixels^2); else
/// normalised image points `(x/z, y/z)` (costs in normalised units).
///
/// Every pointer is borrowed for the duration of the call that takes the problem only.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct EopnpProblem {
    /// The number of correspondences (at least 4 are needed to solve; 0 is reported as
    /// `EOPNP_TOO_FEW_POINTS`).
    pub n: usize,
    /// `n` world points `(x, y, z)`, point `i` at `world[i * world_stride]`. Not NULL.
    pub world: *const f64,
    /// Stride of `world` in `double`s: 0 (packed, 3) or at least 3.
    pub world_stride: usize,
    /// `n` image points `(x, y)`: normalised, or pixels with `camera` or `rig`; point `i` at
    /// `image[i * image_stride]`. Not NULL.
    pub image: *const f64,
    /// Stride of `image` in `double`s: 0 (packed, 2) or at least 2.
    pub image_stride: usize,
    /// `n` non-negative weights (a point of weight 0 is ignored), or NULL for all 1.
    pub weights: *const f64,
    /// The camera that observed the pixels `image`, or NULL.
    pub camera: *const crate::handles::EopnpCamera,
    /// The rig whose cameras observed the pixels `image`, or NULL. Not together with `camera`.
    pub rig: *const crate::handles::EopnpRig,
    /// With `rig`: `n` camera indices into the rig (which camera saw each correspondence).
    /// Must be NULL without `rig`.
    pub rig_cameras: *const u32,
    /// Normalised input only: the focal lengths `(fx, fy)` in pixels that make the RANSAC
    /// threshold a pixel distance. Both 0 (the zero-initialised default) means `(1, 1)`: the
    /// threshold in normalised units. Ignored by the plain solves and for pixel input.
    pub focal_x: f64,
    /// See `focal_x`.
    pub focal_y: f64,
    /// A known vertical: the direction of gravity (or any direction known in both frames)
    /// measured in the camera's frame (for a rig problem, the rig's), 3 doubles of any non-zero
    /// length; NULL (the zero-initialised default) for none. Set together with `gravity_world`
    /// and `gravity_sigma_deg`. The solve then returns the maximum a posteriori pose with the
    /// vertical as a prior, RANSAC samples two points, and images that contradict the vertical
    /// are `EOPNP_GRAVITY_MISMATCH` (the library's `Gravity`, `Problem::gravity`). Not with
    /// `unknown_focal`.
    pub gravity_camera: *const f64,
    /// The same direction in the world's frame, 3 doubles of any non-zero length; NULL for
    /// none. Set together with `gravity_camera`.
    pub gravity_world: *const f64,
    /// The standard deviation of the measured direction in degrees (finite, > 0, else
    /// `EOPNP_INVALID_OPTION`), with `gravity_camera`; must be 0 without it.
    pub gravity_sigma_deg: f64,
    /// Pixels through `camera` only: the focal length is unknown and estimated with the pose,
    /// `camera` being the starting guess (its two focal lengths scaled alike; the principal
    /// point and the distortion kept unless `refine_principal_point`, `refine_distortion`). The
    /// solution's `focal_estimated`, `focal_x` and `focal_y` give it, and `camera_params` the
    /// whole estimated camera. With normalised or rig input, or with a vertical:
    /// `EOPNP_INVALID_OPTION`.
    pub unknown_focal: bool,
    /// With `unknown_focal`: the range of the (first) focal length sought, pixels
    /// (`0 < focal_min_px < focal_max_px`, else `EOPNP_INVALID_OPTION`). Both 0 (the
    /// zero-initialised default): a tenth to ten times the camera's. Must be 0 without
    /// `unknown_focal`.
    pub focal_min_px: f64,
    /// See `focal_min_px`.
    pub focal_max_px: f64,
    /// Pixels through `camera` only: the principal point is refined with the pose (and the focal
    /// length with `unknown_focal`), `camera`'s the starting guess (the library's
    /// `Problem::refine_principal_point`, COLMAP's `refine_principal_point`). It is well
    /// determined only by many points over a wide field of view. The solution's
    /// `camera_estimated` and `camera_params` give it. With normalised or rig input, or with a
    /// vertical: `EOPNP_INVALID_OPTION` (the message names the option); fewer correspondences
    /// than half the free parameters (pose and intrinsics): `EOPNP_TOO_FEW_POINTS`.
    pub refine_principal_point: bool,
    /// Pixels through `camera` only: the camera's distortion parameters (those after the
    /// principal point in its COLMAP order, `eopnp_camera_params`; none for the pinhole models)
    /// are refined with the pose (and the focal length with `unknown_focal`), `camera`'s the
    /// starting guess (the library's `Problem::refine_distortion`, COLMAP's
    /// `refine_extra_params`). The solution's `camera_estimated` and `camera_params` give them.
    /// With normalised or rig input, or with a vertical: `EOPNP_INVALID_OPTION` (the message
    /// names the option); too few correspondences: `EOPNP_TOO_FEW_POINTS`.
    pub refine_distortion: bool,
}

/// A pose `x_cam = R X + t` (world to camera), the input of `eopnp_refine` (a prior pose).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EopnpPose {
    /// `R`, row-major: `rotation[3 * row + col]`. Must be a rotation (`|R^T R - I| <= 1e-6`
    /// entrywise, `det R > 0`).
    pub rotation: [f64; 9],
    /// `t`, in world units.
    pub translation: [f64; 3],
}

/// A solved pose and how it was found: the library's `Solution`. Written by the solve
/// functions into caller-owned memory.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EopnpSolution {
    /// `R` of the world-to-camera pose `x_cam = R X + t`, row-major (`rotation[3 * row + col]`).
    pub rotation: [f64; 9],
    /// `t` of the world-to-camera pose (the world origin in the camera frame), world units.
    pub translation: [f64; 3],
    /// The minimised cost: the (weighted) sum of squared reprojection residuals (normalised
    /// units for normalised input, pixels^2 for pixel input), through the loss when one is set;
    /// the algebraic cost in `EOPNP_REFINEMENT_ALGEBRAIC` mode.
    pub cost: f64,
    /// The paper's algebraic cost of the returned rotation.
    pub algebraic_cost: f64,
    /// Root-mean-square normalised reprojection residual (pixel input: the RMS pixel residual
    /// divided by `max(fx, fy)`); multiply by the focal length for pixels.
    pub reprojection_rmse: f64,
    /// The covariance of `[delta_q (3), delta_t (3)]` (the library's `covariance` module,
    /// pycolmap's convention), row-major 6 x 6, when `has_covariance`; zeros otherwise.
    pub covariance: [f64; 36],
    /// The noise standard deviation the covariance used (given or estimated), in image units;
    /// 0 without a covariance.
    pub covariance_sigma: f64,
    /// Correspondences that entered the solve (those with a weight > 0).
    pub used: u64,
    /// Correspondences left out because their pixel could not be undistorted.
    pub skipped: u64,
    /// Damped-Newton iterations of the winning candidate.
    pub newton_iterations: u32,
    /// Levenberg-Marquardt iterations of the reprojection refinement.
    pub reprojection_iterations: u32,
    /// The candidate generator of the winning start.
    pub source: EopnpSource,
    /// More than half of the points are in front of the camera.
    pub cheirality_ok: bool,
    /// The configuration is close to degenerate; the pose may be ambiguous or wrong.
    pub degenerate: bool,
    /// The planar branch produced the starting candidate.
    pub planar: bool,
    /// The reprojection refinement stopped at a minimum.
    pub converged: bool,
    /// `covariance` holds the pose's covariance (asked for by `eopnp_solver_set_covariance`,
    /// and the normal equations positive definite).
    pub has_covariance: bool,
    /// The focal length was estimated (`EopnpProblem::unknown_focal`): `focal_x`, `focal_y`
    /// hold it (`camera_estimated` is then true too, and `camera_params` holds the same focal
    /// lengths). Not set by `refine_principal_point` or `refine_distortion` alone.
    pub focal_estimated: bool,
    /// With `focal_estimated`: the estimated focal length along x, pixels; 0 otherwise.
    pub focal_x: f64,
    /// With `focal_estimated`: the estimated focal length along y, pixels (the guess camera's
    /// two focal lengths scaled alike); 0 otherwise.
    pub focal_y: f64,
    /// With `focal_estimated` and `has_covariance`: the estimated focal length's standard
    /// deviation, pixels (`covariance` is then the pose's marginal covariance); 0 otherwise.
    pub focal_sigma: f64,
    /// An intrinsic was free (`EopnpProblem::unknown_focal`, `refine_principal_point` or
    /// `refine_distortion`): `camera_n_params` and `camera_params` hold the estimated camera
    /// (the library's `Solution::camera`). With `refine_principal_point` or `refine_distortion`
    /// alone, `focal_estimated` stays false and the focal lengths in `camera_params` are the
    /// given camera's.
    pub camera_estimated: bool,
    /// With `camera_estimated`: the number of the estimated camera's parameters, its model's
    /// (the given camera's model; at most `EOPNP_MAX_CAMERA_PARAMS`); 0 otherwise.
    pub camera_n_params: u32,
    /// With `camera_estimated`: the estimated camera's parameters in its model's COLMAP order
    /// (as `eopnp_camera_params` gives them, e.g. OPENCV's `fx, fy, cx, cy, k1, k2, p1, p2`):
    /// the given camera with the free intrinsics replaced by their estimates; zeros after the
    /// first `camera_n_params`, and all zeros without `camera_estimated`.
    pub camera_params: [f64; EOPNP_MAX_CAMERA_PARAMS],
}

/// Statistics of a RANSAC run (the library's `RansacStats`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EopnpRansacStats {
    /// Samples drawn.
    pub iterations: u32,
    /// P3P poses scored.
    pub hypotheses: u32,
    /// EOPnP fits in local optimisation.
    pub local_fits: u32,
    /// EOPnP fits in the final fit.
    pub final_fits: u32,
    /// Inliers of the returned pose (final threshold).
    pub inliers: u64,
    /// `inliers / n`.
    pub inlier_ratio: f64,
    /// Wall time of the run, microseconds.
    pub micros: f64,
}

/// The intrinsics registration re-estimates with the pose (`eopnp_model_register_with`,
/// `eopnp_model_register_batch_with`), the model's camera of the image being the starting
/// guess: `EopnpProblem`'s fields of the same names, with the same rules and statuses.
/// Zero-initialise it (`EopnpFreeIntrinsics f = {0};`: none free, as a NULL pointer) and set the
/// fields you need.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EopnpFreeIntrinsics {
    /// The focal length is unknown and estimated with the pose (the model camera's two focal
    /// lengths scaled alike); `EopnpRegistration::focal_error_pct` is the estimate's error
    /// against the model camera's. As `EopnpProblem::unknown_focal`.
    pub unknown_focal: bool,
    /// With `unknown_focal`: the range of the (first) focal length sought, pixels
    /// (`0 < focal_min_px < focal_max_px`, else `EOPNP_INVALID_OPTION`). Both 0: a tenth to ten
    /// times the model camera's. Set without `unknown_focal`: `EOPNP_INVALID_ARGUMENT`.
    pub focal_min_px: f64,
    /// See `focal_min_px`.
    pub focal_max_px: f64,
    /// The principal point is refined with the pose (`EopnpProblem::refine_principal_point`).
    pub refine_principal_point: bool,
    /// The distortion parameters are refined with the pose (`EopnpProblem::refine_distortion`).
    pub refine_distortion: bool,
}

/// The registration of one image of a COLMAP model (`eopnp_model_register`,
/// `eopnp_model_register_with`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EopnpRegistration {
    /// The image's id.
    pub image_id: u32,
    /// `has_ransac`: `ransac` holds the RANSAC statistics (registration with RANSAC).
    pub has_ransac: bool,
    /// 2D-3D correspondences of the image (its 2D points with a 3D point).
    pub n: u64,
    /// Correspondences used: RANSAC's inliers, or those of weight > 0.
    pub inliers: u64,
    /// Correspondences whose pixel could not be undistorted.
    pub skipped: u64,
    /// The solved pose (world to camera).
    pub solution: EopnpSolution,
    /// RANSAC's statistics when `has_ransac`; zeros otherwise.
    pub ransac: EopnpRansacStats,
    /// The largest angle between corresponding columns of the solved and the model's rotation,
    /// degrees.
    pub rotation_error_deg: f64,
    /// `|t - t_model| / |t_model|`, percent.
    pub translation_error_pct: f64,
    /// RMS pixel residual of the solved pose (over the inliers with RANSAC), through the
    /// estimated camera when an intrinsic was free (`solution.camera_params`).
    pub rmse_px: f64,
    /// RMS pixel residual of the model's pose, on the same points.
    pub model_rmse_px: f64,
    /// Wall time of the solve, microseconds.
    pub micros: f64,
    /// `focal_error_pct` holds the estimated focal length's error: an intrinsic was free
    /// (`eopnp_model_register_with`; also with only the principal point or the distortion
    /// refined, whose error is then 0). False through the model's camera.
    pub has_focal_error: bool,
    /// With `has_focal_error`: the error of the estimated camera's focal length against the model
    /// camera's, percent (the larger of the two axes' `100 |f - f_model| / f_model`); 0
    /// otherwise.
    pub focal_error_pct: f64,
}

/// The registration of one frame of a COLMAP model with rigs (`eopnp_model_register_frame`):
/// the pose of the frame's rig from the correspondences of all its images, each through its own
/// camera and that camera's pose in the rig.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EopnpFrameRegistration {
    /// The frame's id.
    pub frame_id: u32,
    /// The frame's rig.
    pub rig_id: u32,
    /// `ransac` holds the RANSAC statistics (registration with RANSAC).
    pub has_ransac: bool,
    /// The number of the frame's images.
    pub images: u64,
    /// 2D-3D correspondences of the frame's images.
    pub n: u64,
    /// Correspondences the pose was fitted to: all that could be undistorted, or RANSAC's
    /// inliers.
    pub inliers: u64,
    /// Observations whose pixel could not be undistorted.
    pub skipped: u64,
    /// The rig's pose, `x_rig = R X + t` (rig from world); an image's camera pose is its
    /// `sensor_from_rig` composed with it.
    pub solution: EopnpSolution,
    /// RANSAC's statistics when `has_ransac`; zeros otherwise.
    pub ransac: EopnpRansacStats,
    /// Rotation difference to the model's rig-from-world pose, degrees.
    pub rotation_error_deg: f64,
    /// Translation difference to the model's rig-from-world pose, percent of its `|t|`.
    pub translation_error_pct: f64,
    /// RMS pixel residual of the solved pose over the fitted correspondences, each through its
    /// own camera.
    pub rmse_px: f64,
    /// RMS pixel residual of the model's frame pose on the same correspondences.
    pub model_rmse_px: f64,
    /// Wall time of undistortion plus solve (or RANSAC), microseconds.
    pub micros: f64,
}

pub(crate) fn source(s: CandidateSource) -> EopnpSource {
    use EopnpSource as E;
    match s {
        CandidateSource::Case1 => E::EOPNP_SOURCE_CASE1,
        CandidateSource::Case2 => E::EOPNP_SOURCE_CASE2,
        CandidateSource::Case3 => E::EOPNP_SOURCE_CASE3,
        CandidateSource::Case4 => E::EOPNP_SOURCE_CASE4,
        CandidateSource::Planar1 => E::EOPNP_SOURCE_PLANAR1,
        CandidateSource::Planar2 => E::EOPNP_SOURCE_PLANAR2,
        CandidateSource::ExtraStart => E::EOPNP_SOURCE_EXTRA_START,
        CandidateSource::Initial => E::EOPNP_SOURCE_INITIAL,
        CandidateSource::P3p => E::EOPNP_SOURCE_P3P,
        CandidateSource::Generalized => E::EOPNP_SOURCE_GENERALIZED,
        CandidateSource::Gp3p => E::EOPNP_SOURCE_GP3P,
        #[allow(unreachable_patterns)]
        _ => E::EOPNP_SOURCE_OTHER,
    }
}

fn to_u64(x: usize) -> u64 {
    u64::try_from(x).unwrap_or(u64::MAX)
}

/// The focal lengths `(fx, fy)` a solution estimated (`focal_free`: its problem's focal length
/// was unknown), `None` when the focal length was known (the solution's camera, if it has one,
/// then has the given camera's). The one place this interface reads them from a solution.
pub(crate) fn estimated_focal(s: &Solution, focal_free: bool) -> Option<(f64, f64)> {
    s.camera.filter(|_| focal_free).map(|c| c.focal_lengths())
}

/// The estimated camera of a solution (`EopnpSolution::camera_n_params`, `camera_params`):
/// `(0, zeros)` without one.
fn estimated_camera(s: &Solution) -> (u32, [f64; EOPNP_MAX_CAMERA_PARAMS]) {
    let mut params = [0.0; EOPNP_MAX_CAMERA_PARAMS];
    let Some(camera) = &s.camera else {
        return (0, params);
    };
    // No model has more parameters than `EOPNP_MAX_CAMERA_PARAMS` (the test
    // `max_camera_params_is_the_largest_model`, tests/focal_gravity.rs); the count written is
    // the count copied, so that a C reader never reads past the array whatever the library adds.
    let given = camera.params();
    let n = given.len().min(EOPNP_MAX_CAMERA_PARAMS);
    params[..n].copy_from_slice(&given[..n]);
    (n as u32, params)
}

impl EopnpSolution {
    /// `s` for C. `focal_free`: the problem's focal length was unknown
    /// (`EopnpProblem::unknown_focal`), which `focal_estimated` reports; a solution does not
    /// say which of its camera's intrinsics were free.
    pub(crate) fn of(s: &Solution, focal_free: bool) -> Self {
        let mut rotation = [0.0; 9];
        for r in 0..3 {
            for c in 0..3 {
                rotation[3 * r + c] = s.rotation[(r, c)];
            }
        }
        let (mut covariance, mut covariance_sigma) = ([0.0; 36], 0.0);
        if let Some(cov) = &s.covariance {
            for r in 0..6 {
                for c in 0..6 {
                    covariance[6 * r + c] = cov.matrix[(r, c)];
                }
            }
            covariance_sigma = cov.sigma;
        }
        let focal = estimated_focal(s, focal_free);
        let (camera_n_params, camera_params) = estimated_camera(s);
        EopnpSolution {
            rotation,
            translation: [s.translation.x, s.translation.y, s.translation.z],
            cost: s.cost,
            algebraic_cost: s.algebraic_cost,
            reprojection_rmse: s.reprojection_rmse,
            covariance,
            covariance_sigma,
            used: to_u64(s.used),
            skipped: to_u64(s.skipped),
            newton_iterations: s.newton_iterations,
            reprojection_iterations: s.reprojection_iterations,
            source: source(s.source),
            cheirality_ok: s.cheirality_ok,
            degenerate: s.degenerate,
            planar: s.planar,
            converged: s.converged,
            has_covariance: s.covariance.is_some(),
            focal_estimated: focal.is_some(),
            focal_x: focal.map_or(0.0, |f| f.0),
            focal_y: focal.map_or(0.0, |f| f.1),
            focal_sigma: s.covariance.and_then(|c| c.focal_sigma).unwrap_or(0.0),
            camera_estimated: s.camera.is_some(),
            camera_n_params,
            camera_params,
        }
    }
}

impl From<&RansacStats> for EopnpRansacStats {
    fn from(s: &RansacStats) -> Self {
        EopnpRansacStats {
            iterations: s.iterations,
            hypotheses: s.hypotheses,
            local_fits: s.local_fits,
            final_fits: s.final_fits,
            inliers: to_u64(s.inliers),
            inlier_ratio: s.inlier_ratio,
            micros: s.micros,
        }
    }
}

impl EopnpRansacStats {
    pub(crate) const ZERO: EopnpRansacStats = EopnpRansacStats {
        iterations: 0,
        hypotheses: 0,
        local_fits: 0,
        final_fits: 0,
        inliers: 0,
        inlier_ratio: 0.0,
        micros: 0.0,
    };
}

/// `EOPNP_OK`'s name, for the status array of the batch functions.
pub(crate) const OK: EopnpStatus = EopnpStatus::EOPNP_OK;

/// The length of `EopnpCameraInfo::model`, its terminating NUL included.
pub const EOPNP_MODEL_NAME_LEN: usize = 32;

/// A camera's description (`eopnp_camera_info`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EopnpCameraInfo {
    /// COLMAP's name of the camera's model (`"SIMPLE_RADIAL"`, `"OPENCV"`, ...), NUL-terminated.
    /// A camera made from OpenCV's `K` and distortion has the COLMAP model of that distortion
    /// (`PINHOLE`, `OPENCV`, `FULL_OPENCV` or `OPENCV_THIN_PRISM_TILTED`; `OPENCV_FISHEYE` for
    /// `cv::fisheye`), its parameters `K`'s `fx, fy, cx, cy` and then the coefficients, padded
    /// with zeros to the model's count.
    pub model: [std::ffi::c_char; EOPNP_MODEL_NAME_LEN],
    /// The image width in pixels, as given when the camera was made (0 for OpenCV's cameras).
    pub width: u64,
    /// The image height in pixels (0 for OpenCV's cameras).
    pub height: u64,
    /// The number of the model's parameters (`eopnp_camera_params`).
    pub n_params: usize,
    /// The focal length along x in pixels.
    pub fx: f64,
    /// The focal length along y in pixels (`fx` for the models with one focal length).
    pub fy: f64,
}

impl EopnpCameraInfo {
    pub(crate) fn of(camera: &eopnp::camera::Camera) -> Self {
        let mut model = [0 as std::ffi::c_char; EOPNP_MODEL_NAME_LEN];
        // COLMAP's names are short ASCII identifiers; the last byte stays the NUL.
        for (o, b) in model
            .iter_mut()
            .zip(camera.model().name().bytes().take(EOPNP_MODEL_NAME_LEN - 1))
        {
            *o = b as std::ffi::c_char;
        }
        let (fx, fy) = camera.focal_lengths();
        EopnpCameraInfo {
            model,
            width: camera.width(),
            height: camera.height(),
            n_params: camera.params().len(),
            fx,
            fy,
        }
    }
}
