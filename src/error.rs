//! Errors returned by the solver.
//!
//! Every input problem the solver can detect is reported as a [`PnpError`] (the solver never
//! panics on user input). Input checks run in a fixed order (docs/algorithm.md section 6): slice
//! lengths, weights length, number of points, finiteness, weight signs, number of points with a
//! positive weight, coincident world points, collinear world points, coincident image points.

use core::fmt;

/// Which input slice an index in [`PnpError::NonFinite`] refers to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum InputKind {
    /// The world points (`world[index]` has a NaN or infinite coordinate).
    World,
    /// The image points (`image[index]` has a NaN or infinite coordinate).
    Image,
    /// The weights (`weights[index]` is NaN or infinite).
    Weight,
}

impl fmt::Display for InputKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            InputKind::World => "world point",
            InputKind::Image => "image point",
            InputKind::Weight => "weight",
        })
    }
}

/// The kind of degenerate configuration in [`PnpError::Degenerate`].
#[non_exhaustive]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum DegenerateKind {
    /// All (positively weighted) world points are the same point.
    CoincidentWorldPoints,
    /// The world points lie on a line (second singular value of the centred points
    /// <= 1e-8 times the first): the rotation about that line is not observable.
    CollinearWorldPoints,
    /// All (positively weighted) image points are the same point (RMS spread
    /// <= 1e-12 max(1, largest absolute image coordinate)).
    CoincidentImagePoints,
    /// The world coordinates cannot be normalised in `f64`: a coordinate is so large that
    /// differences of coordinates overflow (above about 4e307), or the points' spread is
    /// below the smallest normal `f64` (about 2.2e-308).
    ScaleOutOfRange,
}

impl fmt::Display for DegenerateKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            DegenerateKind::CoincidentWorldPoints => {
                "all world points coincide; at least 4 distinct, non-collinear world points are needed"
            }
            DegenerateKind::CollinearWorldPoints => {
                "the world points are (numerically) collinear; the rotation about their line \
                 cannot be recovered, add points off that line"
            }
            DegenerateKind::CoincidentImagePoints => {
                "all image points coincide; check that the image points are distinct \
                 (and given in normalised or pixel coordinates as the API expects)"
            }
            DegenerateKind::ScaleOutOfRange => {
                "the world coordinates are outside the range f64 can normalise (magnitude above \
                 ~4e307 or spread below ~2.2e-308); rescale or re-centre the world points"
            }
        })
    }
}

/// Error returned by the solver.
#[non_exhaustive]
#[derive(Clone, Debug, PartialEq)]
pub enum PnpError {
    /// Fewer correspondences than the solver needs (`need` = 4). With weights, only the
    /// points with a weight > 0 count, and then only those whose weight is above 2^-52 times
    /// the largest weight (a lighter point cannot change a weighted sum at f64 precision).
    TooFewPoints {
        /// Number of (positively weighted) correspondences given.
        got: usize,
        /// Number needed.
        need: usize,
    },
    /// The world and image slices have different lengths.
    LengthMismatch {
        /// Length of the world-point slice.
        world: usize,
        /// Length of the image-point slice.
        image: usize,
    },
    /// The weights slice does not have one weight per correspondence.
    WeightsLength {
        /// Length of the weights slice.
        weights: usize,
        /// Number of correspondences.
        points: usize,
    },
    /// An input value is NaN or infinite; `index` is the first offending correspondence
    /// (for one index, world is checked before image before weight).
    NonFinite {
        /// Index of the first offending correspondence.
        index: usize,
        /// Which input holds the offending value.
        input: InputKind,
    },
    /// The camera indices of a rig problem ([`crate::Problem::rig`]) are not one per
    /// correspondence.
    CameraIndicesLength {
        /// Length of the camera-index slice.
        indices: usize,
        /// Number of correspondences.
        points: usize,
    },
    /// Correspondence `index` of a rig problem names camera `camera`, which the rig does not
    /// have.
    UnknownCamera {
        /// Index of the first such correspondence.
        index: usize,
        /// The camera index it gives.
        camera: u32,
    },
    /// A weight is negative (weights must be >= 0; a weight of 0 ignores the point).
    InvalidWeight {
        /// Index of the first negative weight.
        index: usize,
    },
    /// The input configuration is degenerate; see [`DegenerateKind`].
    Degenerate(DegenerateKind),
    /// No candidate rotation survived (numerical failure); not observed on valid input.
    NoSolution,
    /// A [`crate::ransac::Ransac`] option is outside its range: `threshold_px` must be finite
    /// and > 0 with a normal square, `confidence` in (0, 1), `max_iterations` >= 1, `final_threshold_factor` finite
    /// and >= 1; or the focal lengths given to [`crate::ransac::Ransac::estimate`] are not
    /// finite and > 0 (`"focal"`); or the initial pose given to [`crate::Solver::refine`] is
    /// not finite (`"initial"`); or the [`crate::Loss`] of [`crate::Solver::loss`] has an
    /// unusable scale (`"loss"`, see [`crate::Loss::is_valid`]); or a [`crate::Gravity`] with a
    /// zero or non-finite direction or a `sigma_deg` not finite and positive (`"gravity"`); or an
    /// unknown focal length ([`crate::Problem::unknown_focal`]) on input other than pixels through
    /// one camera, with a known vertical, or with a range that is not `0 < min < max`
    /// (`"unknown_focal"`).
    InvalidOption {
        /// The option's field name.
        option: &'static str,
    },
    /// RANSAC drew `iterations` samples and found no consensus: no pose had enough
    /// correspondences within the threshold for a fit, or the best pose's `inliers` are no
    /// more than a wrong pose reaches by chance at this threshold (`needed` is the least
    /// consensus accepted; see [`crate::ransac`], "Consensus").
    NoConsensus {
        /// Samples drawn.
        iterations: u32,
        /// Inliers of the best pose found (0 if none).
        inliers: usize,
        /// The least number of inliers accepted.
        needed: usize,
    },
    /// The images contradict the known vertical ([`crate::Problem::gravity`]): the vertical of
    /// the maximum-likelihood pose and the measured one differ by more than their combined
    /// uncertainties allow: a right vertical is reported with a probability of 0.27 % (a
    /// 3-sigma test's; docs/algorithm.md, `vertical`). The vertical is wrong, or its frames, or
    /// its stated uncertainty too small, or the correspondences are wrong; solve without the
    /// vertical to see the pose the images give.
    GravityMismatch {
        /// The angle between the two verticals, in degrees.
        angle_deg: f64,
        /// Their Mahalanobis distance in standard deviations (combined).
        sigmas: f64,
    },
}

impl fmt::Display for PnpError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            PnpError::TooFewPoints { got, need } => write!(
                f,
                "too few correspondences: got {got}, need at least {need} (with weights, points \
                 of weight 0 or below 2^-52 times the largest do not count)"
            ),
            PnpError::LengthMismatch { world, image } => write!(
                f,
                "world and image point counts differ ({world} world points, {image} image \
                 points); pass one image point per world point"
            ),
            PnpError::WeightsLength { weights, points } => write!(
                f,
                "got {weights} weights for {points} correspondences; pass one weight per point"
            ),
            PnpError::NonFinite { index, input } => write!(
                f,
                "{input} {index} is not finite (NaN or infinite); remove or fix that \
                 correspondence"
            ),
            PnpError::CameraIndicesLength { indices, points } => write!(
                f,
                "got {indices} camera indices for {points} correspondences; pass one camera \
                 index per point"
            ),
            PnpError::UnknownCamera { index, camera } => write!(
                f,
                "correspondence {index} is in camera {camera}, which the rig does not have"
            ),
            PnpError::InvalidWeight { index } => write!(
                f,
                "weight {index} is negative; weights must be >= 0 (use 0 to ignore a point)"
            ),
            PnpError::Degenerate(kind) => write!(f, "degenerate input: {kind}"),
            PnpError::NoSolution => f.write_str(
                "no solution found (numerical failure on every candidate); the input may be \
                 extremely ill-conditioned",
            ),
            PnpError::InvalidOption { option: "initial" } => f.write_str(
                "the initial pose is not finite: its rotation and translation must be finite",
            ),
            PnpError::InvalidOption { option: "rig" } => {
                f.write_str("a rig needs at least one camera")
            }
            PnpError::InvalidOption {
                option: "cam_from_rig",
            } => f.write_str(
                "a camera's pose in the rig (cam_from_rig) is not finite: its rotation and \
                 translation must be finite",
            ),
            PnpError::InvalidOption { option: "loss" } => f.write_str(
                "the loss scale is out of range: Huber and Cauchy take a finite scale s > 0 \
                 whose square and its reciprocal are normal numbers (about 1e-154 < s < 1e154)",
            ),
            PnpError::InvalidOption {
                option: "unknown_focal",
            } => f.write_str(
                "an unknown focal length is estimated only for pixels through one camera \
                 (Problem::pixels), without a known vertical, within a range 0 < min < max",
            ),
            PnpError::InvalidOption {
                option: option @ ("refine_principal_point" | "refine_distortion"),
            } => {
                let what = if *option == "refine_distortion" {
                    "the distortion parameters are"
                } else {
                    "the principal point is"
                };
                write!(
                    f,
                    "`{option}`: {what} refined only for pixels through one camera \
                     (Problem::pixels), without a known vertical"
                )
            }
            PnpError::InvalidOption { option: "gravity" } => f.write_str(
                "the gravity direction is out of range: its two directions must be finite and \
                 non-zero, its sigma_deg finite and > 0",
            ),
            PnpError::InvalidOption { option } => {
                let range = match *option {
                    "threshold_px" => "a finite number of pixels > 0 whose square is a normal number (above about 1e-154)",
                    "confidence" => "a probability strictly between 0 and 1",
                    "max_iterations" => "at least 1",
                    "final_threshold_factor" => "finite and >= 1",
                    "focal" => "two finite focal lengths > 0, in pixels",
                    _ => "see the option's documentation",
                };
                write!(
                    f,
                    "RANSAC option `{option}` is out of range: it must be {range}"
                )
            }
            PnpError::NoConsensus {
                iterations,
                inliers,
                needed,
            } => write!(
                f,
                "RANSAC found no consensus after {iterations} samples: the best pose has \
                 {inliers} inliers, {needed} needed to be more than chance at this threshold; \
                 check the correspondences and the intrinsics (focal length in pixels), or \
                 raise max_iterations"
            ),
            PnpError::GravityMismatch { angle_deg, sigmas } => write!(
                f,
                "the images contradict the given gravity direction: the pose they give is \
                 {angle_deg:.3} degrees off it, {sigmas:.1} standard deviations of the combined \
                 uncertainty; check the gravity vector's frames and its stated uncertainty \
                 (sigma_deg)"
            ),
        }
    }
}

impl std::error::Error for PnpError {}

#[cfg(test)]
#[path = "../tests/unit/error.rs"]
mod tests;
