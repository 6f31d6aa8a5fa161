//! What the caller chooses: the cost to minimise, the planar branch, the iteration limits of
//! S6 and S9, and the exhaustive search. `crate::Solver` is the public builder over [`Options`].

use super::newton::NewtonOptions;
use super::reprojection::ReprojOptions;

/// Which cost the returned pose minimises.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Refinement {
    /// EOPnP (S0-S8) followed by Levenberg-Marquardt on the reprojection error (S9): the
    /// maximum-likelihood pose for isotropic Gaussian image noise. Default.
    #[default]
    Reprojection,
    /// EOPnP alone (S0-S8): the minimiser of the paper's depth-weighted algebraic cost.
    Algebraic,
}

/// How the planar branch (S4') is chosen.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum PlanarDetection {
    /// From the planarity ratio `sv2 / sv0` of the centred world points (S3):
    /// non-planar branch if `ratio >= 1e-6`, planar branch if `ratio < 1e-3`, both in between.
    /// Default.
    #[default]
    Auto,
    /// Planar branch only (the world points are treated as lying on their best-fit plane).
    Planar,
    /// Non-planar branch only.
    NonPlanar,
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
        }
    }
}
