//! Many independent problems at once, in parallel (feature `rayon`).
//!
//! [`Solver::solve_batch`] and [`Ransac::estimate_batch`] run one problem per task on rayon's
//! current thread pool (the global one, or the pool of an enclosing
//! `rayon::ThreadPool::install`, which sets the thread count). Each result is exactly what
//! the one-problem call returns: the solver is deterministic, and problem `i` of a RANSAC
//! batch uses the seed [`problem_seed`]`(seed, i)` whatever the thread count or the order in
//! which the tasks run.
//!
//! ```
//! use eopnp::{Problem, Solver};
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
//! assert!((results[7].as_ref().unwrap().translation.z - 5.07).abs() < 1e-9);
//! ```

use rayon::prelude::*;

use crate::ransac::{problem_seed, Ransac, RansacSolution};
use crate::{PnpError, Problem, Solution, Solver};

impl Solver {
    /// Solves every problem ([`Solver::solve`]) in parallel, one per task on rayon's current
    /// thread pool; results in the order of `problems`, each exactly what [`Solver::solve`]
    /// returns for it.
    #[must_use]
    pub fn solve_batch(&self, problems: &[Problem<'_>]) -> Vec<Result<Solution, PnpError>> {
        problems.par_iter().map(|p| self.solve(p)).collect()
    }
}

impl Ransac {
    /// Robust estimation of every problem ([`Ransac::estimate`]) in parallel, problem `i` with
    /// the seed [`problem_seed`]`(seed, i)` (`seed` this configuration's); results in the order
    /// of `problems`, each equal to the one-problem call with that seed.
    #[must_use]
    pub fn estimate_batch(
        &self,
        solver: &Solver,
        problems: &[Problem<'_>],
    ) -> Vec<Result<RansacSolution, PnpError>> {
        problems
            .par_iter()
            .enumerate()
            .map(|(i, p)| self.seed(problem_seed(self.seed, i)).estimate(solver, p))
            .collect()
    }
}
