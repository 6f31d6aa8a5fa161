//! What the caller chooses: the cost to minimise, the planar branch, the iteration limits of
//! `newton` and `refine`, and the exhaustive search. `crate::Solver` is the public builder over
//! [`Options`].

use super::newton::NewtonOptions;
use super::refine::ReprojOptions;

/// Which cost the returned pose minimises.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Refinement {
    /// EOPnP followed by Levenberg-Marquardt on the reprojection error (the `refine` stage, and
    /// with pixel input through a camera with distortion `refine_pixels`, on the pixel error
    /// through the camera model): the maximum-likelihood pose for isotropic Gaussian image noise
    /// (pixel noise for pixel input). Default.
    #[default]
    Reprojection,
    /// EOPnP alone (no `refine` stage): the minimiser of the paper's depth-weighted algebraic cost.
    Algebraic,
}

/// How the planar branch (the `planar` stage) is chosen.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum PlanarDetection {
    /// From the planarity ratio `sv2 / sv0` of the centred world points (`branch`):
    /// non-planar branch if `ratio >= 1e-6`, planar branch if `ratio < 1e-3`, both in between.
    /// Default.
    #[default]
    Auto,
    /// Planar branch only (the world points are treated as lying on their best-fit plane).
    Planar,
    /// Non-planar branch only.
    NonPlanar,
}

/// The loss of the final refinement: how much a residual of squared length `r2` costs.
///
/// The scale `s` is in the units of the residuals: pixels for pixel input
/// ([`crate::Problem::pixels`], in a solve or RANSAC's fits), normalised
/// units (pixels divided by the focal length) for normalised input. The refinement minimises
/// `sum_i w_i rho(r2_i)`, by iteratively reweighted Levenberg-Marquardt (the weight of a point
/// is `rho'(r2)`), to a stationary point of that cost.
///
/// When to use which:
/// - [`Loss::Squared`] (default): the maximum-likelihood pose for Gaussian noise. Use it on
///   inliers (after RANSAC, or on data without gross outliers).
/// - [`Loss::Huber`]: quadratic up to `s`, linear beyond: residuals a few times the noise
///   level keep some influence. Set `s` at 1-3 times the noise level, for data with a few
///   moderate outliers (a slightly wrong match, a rolling-shutter point).
/// - [`Loss::Cauchy`]: the influence of a residual decays beyond `s`, so gross outliers hardly
///   move the pose. For data with many outliers when RANSAC is not run, or as RANSAC's final
///   refinement when the threshold leaves a few outliers in; it starts from a pose in the right
///   basin (its cost is not convex).
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[non_exhaustive]
pub enum Loss {
    /// `rho(r2) = r2`. Default.
    #[default]
    Squared,
    /// `rho(r2) = r2` for `r <= s`, `2 s r - s^2` beyond (PoseLib's and Ceres' Huber).
    Huber(f64),
    /// `rho(r2) = s^2 ln(1 + r2 / s^2)` (PoseLib's and Ceres' Cauchy).
    Cauchy(f64),
}

impl Loss {
    /// The scale `s` (`None` for [`Loss::Squared`]).
    #[must_use]
    pub fn scale(self) -> Option<f64> {
        match self {
            Loss::Squared => None,
            Loss::Huber(s) | Loss::Cauchy(s) => Some(s),
        }
    }

    /// `rho(r2)` and `rho'(r2)` (the derivative with respect to `r2`, the IRLS weight).
    #[inline]
    pub(crate) fn eval(self, r2: f64) -> (f64, f64) {
        match self {
            Loss::Squared => (r2, 1.0),
            Loss::Huber(s) => {
                if r2 <= s * s {
                    (r2, 1.0)
                } else {
                    let r = r2.sqrt();
                    (2.0 * s * r - s * s, s / r)
                }
            }
            Loss::Cauchy(s) => {
                let inv = 1.0 / (s * s);
                let x = r2 * inv;
                (x.ln_1p() / inv, 1.0 / (1.0 + x))
            }
        }
    }

    /// Whether the solver accepts this loss: [`Loss::Squared`], or a positive scale whose
    /// square and its reciprocal are normal numbers (about `1e-154 < s < 1e154`). A solve with
    /// any other loss is [`crate::PnpError::InvalidOption`] (`"loss"`); bindings use this to
    /// reject the option before solving.
    ///
    /// ```
    /// use eopnp::Loss;
    /// assert!(Loss::Squared.is_valid() && Loss::Huber(1.0).is_valid());
    /// assert!(!Loss::Cauchy(0.0).is_valid() && !Loss::Huber(f64::NAN).is_valid());
    /// assert!(!Loss::Huber(1e-200).is_valid());
    /// ```
    #[must_use]
    pub fn is_valid(self) -> bool {
        self.scale().is_none_or(|s| {
            let s2 = s * s;
            s > 0.0 && s2.is_normal() && s2.recip().is_normal()
        })
    }
}

/// Every option of one solve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Options {
    pub refinement: Refinement,
    pub newton: NewtonOptions,
    pub reproj: ReprojOptions,
    pub planar: PlanarDetection,
    /// `false` keeps the user's world axes in the working frame (non-planar scenes only).
    pub align_world_axes: bool,
    /// Every generator, every start refined to convergence, no certified early exit.
    pub exhaustive: bool,
    /// The loss of the final refinement.
    pub loss: Loss,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            refinement: Refinement::Reprojection,
            newton: NewtonOptions::default(),
            reproj: ReprojOptions::default(),
            planar: PlanarDetection::Auto,
            align_world_axes: true,
            exhaustive: false,
            loss: Loss::Squared,
        }
    }
}
