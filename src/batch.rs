//! Many independent problems at once, in parallel (feature `rayon`).
//!
//! [`Solver::solve_batch`] and [`Ransac::estimate_batch`] run one problem per task on rayon's
//! current thread pool (the global one, or the pool of an enclosing
//! `rayon::ThreadPool::install`, which sets the thread count). Each result is exactly what
//! the one-problem call returns: the solver is deterministic, and problem `i` of a RANSAC
//! batch uses the seed [`problem_seed`]`(ransac.seed, i)` whatever the thread count or the
//! order in which the tasks run.
//!
//! ```
//! use eopnp::batch::Problem;
//! use eopnp::Solver;
//! use nalgebra::{Point2, Point3, Vector3};
//!
//! // 100 views of the same six points from different distances.
//! let world = [
//!     Point3::new(-1.0, -1.0, 0.5), Point3::new(1.0, -1.0, -0.5), Point3::new(1.0, 1.0, 0.2),
//!     Point3::new(-1.0, 1.0, -0.1), Point3::new(0.3, 0.2, 1.0), Point3::new(-0.4, 0.6, -0.8),
//! ];
//! let images: Vec<Vec<Point2<f64>>> = (0..100)
//!     .map(|k| {
//!         let t = Vector3::new(0.1, -0.2, 5.0 + 0.01 * k as f64);
//!         world.iter().map(|x| { let p = x.coords + t; Point2::new(p.x / p.z, p.y / p.z) }).collect()
//!     })
//!     .collect();
//! let problems: Vec<Problem> = images.iter().map(|im| Problem::normalised(&world, im)).collect();
//! let results = Solver::default().solve_batch(&problems);
//! assert!((results[7].as_ref().unwrap().pose.translation.vector.z - 5.07).abs() < 1e-9);
//! ```

use nalgebra::{Point2, Point3};
use rayon::prelude::*;

use crate::camera::Camera;
use crate::ransac::{Ransac, RansacSolution};
use crate::{PnpError, Solution, Solver};

/// One problem of a batch: world points and their observations, normalised image points or
/// pixels through a camera, with optional per-point weights.
#[derive(Clone, Copy, Debug)]
#[non_exhaustive]
pub struct Problem<'a> {
    /// World points.
    pub world: &'a [Point3<f64>],
    /// The observations.
    pub observations: Observations<'a>,
    /// One non-negative weight per correspondence (`None`: all 1).
    pub weights: Option<&'a [f64]>,
}

/// The observations of a [`Problem`].
#[derive(Clone, Copy, Debug)]
pub enum Observations<'a> {
    /// Normalised image points `(x/z, y/z)`, with the focal lengths `(fx, fy)` in pixels that
    /// make RANSAC's threshold a pixel distance ([`Ransac::estimate`]; plain solves ignore
    /// them).
    Normalised {
        /// The points.
        points: &'a [Point2<f64>],
        /// Focal lengths in pixels.
        focal: (f64, f64),
    },
    /// Observed pixels and the camera that took them ([`Solver::solve_pixels`],
    /// [`Ransac::estimate_pixels`]).
    Pixels {
        /// The pixels.
        points: &'a [Point2<f64>],
        /// The camera.
        camera: &'a Camera,
    },
}

impl<'a> Problem<'a> {
    /// Normalised image points (focal lengths 1: for RANSAC, prefer
    /// [`Problem::normalised_with_focal`]).
    #[must_use]
    pub fn normalised(world: &'a [Point3<f64>], image: &'a [Point2<f64>]) -> Self {
        Self::normalised_with_focal(world, image, (1.0, 1.0))
    }

    /// Normalised image points with the camera's focal lengths in pixels.
    #[must_use]
    pub fn normalised_with_focal(
        world: &'a [Point3<f64>],
        image: &'a [Point2<f64>],
        focal: (f64, f64),
    ) -> Self {
        Problem {
            world,
            observations: Observations::Normalised {
                points: image,
                focal,
            },
            weights: None,
        }
    }

    /// Observed pixels through `camera`.
    #[must_use]
    pub fn pixels(world: &'a [Point3<f64>], pixels: &'a [Point2<f64>], camera: &'a Camera) -> Self {
        Problem {
            world,
            observations: Observations::Pixels {
                points: pixels,
                camera,
            },
            weights: None,
        }
    }

    /// With one weight per correspondence.
    #[must_use]
    pub fn weights(mut self, weights: &'a [f64]) -> Self {
        self.weights = Some(weights);
        self
    }
}

/// The RANSAC seed of problem `index` of a batch whose base seed is `base`: SplitMix64 of the
/// base mixed with SplitMix64 of the index, so that nearby indices and bases give unrelated
/// sample sequences.
#[must_use]
pub fn problem_seed(base: u64, index: usize) -> u64 {
    splitmix64(base ^ splitmix64(index as u64))
}

fn splitmix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

impl Solver {
    /// Solves every problem (the one-problem entry point its form calls for:
    /// [`Solver::solve`], [`Solver::solve_weighted`], [`Solver::solve_pixels`] or
    /// [`Solver::solve_pixels_weighted`]) in parallel; results in the order of `problems`.
    #[must_use]
    pub fn solve_batch(&self, problems: &[Problem<'_>]) -> Vec<Result<Solution, PnpError>> {
        problems.par_iter().map(|p| self.solve_problem(p)).collect()
    }

    /// One problem of a batch: what [`Solver::solve_batch`] computes for it. For callers that
    /// run their own parallel loop (e.g. building each problem inside its task, from memory
    /// the task reads itself).
    pub fn solve_problem(&self, p: &Problem<'_>) -> Result<Solution, PnpError> {
        match (p.observations, p.weights) {
            (Observations::Normalised { points, .. }, None) => self.solve(p.world, points),
            (Observations::Normalised { points, .. }, Some(w)) => {
                self.solve_weighted(p.world, points, w)
            }
            (Observations::Pixels { points, camera }, None) => {
                self.solve_pixels(p.world, points, camera)
            }
            (Observations::Pixels { points, camera }, Some(w)) => {
                self.solve_pixels_weighted(p.world, points, camera, w)
            }
        }
    }
}

impl Ransac {
    /// Robust estimation of every problem ([`Ransac::estimate`],
    /// [`Ransac::estimate_pixels`] or [`Ransac::estimate_pixels_weighted`]) in parallel,
    /// problem `i` with the seed [`problem_seed`]`(self.seed, i)`; results in the order of
    /// `problems`, each equal to the one-problem call with that seed.
    #[must_use]
    pub fn estimate_batch(
        &self,
        solver: &Solver,
        problems: &[Problem<'_>],
    ) -> Vec<Result<RansacSolution, PnpError>> {
        problems
            .par_iter()
            .enumerate()
            .map(|(i, p)| {
                self.seed(problem_seed(self.seed, i))
                    .estimate_problem(solver, p)
            })
            .collect()
    }

    /// One problem, with this configuration's seed: problem `i` of
    /// [`Ransac::estimate_batch`] is `ransac.seed(problem_seed(ransac.seed, i))
    /// .estimate_problem(solver, p)`. For callers that run their own parallel loop.
    pub fn estimate_problem(
        &self,
        solver: &Solver,
        p: &Problem<'_>,
    ) -> Result<RansacSolution, PnpError> {
        match (p.observations, p.weights) {
            (Observations::Normalised { points, focal }, w) => {
                self.estimate(solver, p.world, points, focal, w)
            }
            (Observations::Pixels { points, camera }, None) => {
                self.estimate_pixels(solver, camera, p.world, points)
            }
            (Observations::Pixels { points, camera }, Some(w)) => {
                self.estimate_pixels_weighted(solver, camera, p.world, points, w)
            }
        }
    }
}
