//! The public entry points: [`Solver`] (the options, as a builder) and [`solve`]. Every solve
//! runs the stages of [`crate::pipeline`]; pixel input first goes through the one undistortion
//! path (`undistort.rs`).

use nalgebra::{Isometry3, Matrix3, Point2, Point3};

use crate::camera::{Camera, Projector};
use crate::covariance::{pose_covariance, Metric, NoiseModel};
use crate::error::PnpError;
use crate::gravity::Gravity;
use crate::pipeline::refine_intrinsics::Free;
use crate::pipeline::vertical::Vertical;
use crate::pipeline::{
    self, Loss, Options, PixelInputs, PlanarDetection, Refinement, ReprojOptions, Solution,
    Solutions,
};
use crate::problem::{Observations, Problem};

mod intrinsics;
pub(crate) use intrinsics::FreeIntrinsics;
mod rig;
mod undistort;

pub(crate) use rig::{central_problem, in_rig};

pub(crate) use undistort::undistort_all;
use undistort::Undistorted;

/// Solver options, as a builder. `Solver::default()` is the recommended configuration: EOPnP
/// followed by the maximum-likelihood refinement of the reprojection error.
///
/// ```
/// use eopnp::{PlanarDetection, Problem, Refinement, Solver};
/// # use nalgebra::{Point2, Point3, Rotation3, Vector3};
/// # let r = Rotation3::from_euler_angles(0.1, -0.2, 0.3);
/// # let t = Vector3::new(0.1, -0.2, 6.0);
/// # let world = [
/// #     Point3::new(-1.0, -1.0, 0.5), Point3::new(1.0, -1.0, -0.5), Point3::new(1.0, 1.0, 0.2),
/// #     Point3::new(-1.0, 1.0, -0.1), Point3::new(0.3, 0.2, 1.0), Point3::new(-0.4, 0.6, -0.8),
/// # ];
/// # let image: Vec<Point2<f64>> = world
/// #     .iter()
/// #     .map(|x| { let p = r * x + t; Point2::new(p.x / p.z, p.y / p.z) })
/// #     .collect();
///
/// // The paper's algorithm alone, the planar branch chosen by the data, more Newton steps.
/// let solver = Solver::default()
///     .refinement(Refinement::Algebraic)
///     .planar_detection(PlanarDetection::Auto)
///     .newton_iterations(100);
/// let sol = solver.solve(&Problem::normalised(&world, &image))?;
/// assert!((sol.translation - t).norm() < 1e-9);
/// # Ok::<(), eopnp::PnpError>(())
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Solver {
    opts: Options,
    covariance: Option<NoiseModel>,
}

impl Solver {
    /// Fill [`Solution::covariance`] with the pose's 6 x 6 covariance under the given image
    /// noise (pycolmap's convention: [`crate::covariance`]); `None` (the default) leaves it
    /// empty. One extra O(N) pass per solve; for pixel input the noise is isotropic in pixels,
    /// through the camera model.
    ///
    /// ```
    /// use eopnp::covariance::NoiseModel;
    /// use eopnp::{Problem, Solver};
    /// # use nalgebra::{Point2, Point3, Vector3};
    /// # let t = Vector3::new(0.1, -0.2, 6.0);
    /// # let world = [
    /// #     Point3::new(-1.0, -1.0, 0.5), Point3::new(1.0, -1.0, -0.5), Point3::new(1.0, 1.0, 0.2),
    /// #     Point3::new(-1.0, 1.0, -0.1), Point3::new(0.3, 0.2, 1.0), Point3::new(-0.4, 0.6, -0.8),
    /// # ];
    /// # let image: Vec<Point2<f64>> = world
    /// #     .iter()
    /// #     .map(|x| { let p = x.coords + t; Point2::new(p.x / p.z, p.y / p.z) })
    /// #     .collect();
    ///
    /// // Image noise of 1 px at a focal length of 800 px, in normalised units.
    /// let sol = Solver::default().covariance(Some(NoiseModel::Sigma(1.0 / 800.0))).solve(&Problem::normalised(&world, &image))?;
    /// let cov = sol.covariance.unwrap().matrix;
    /// // Standard deviation of the depth, in world units.
    /// assert!(cov[(5, 5)].sqrt() < 0.05);
    /// # Ok::<(), eopnp::PnpError>(())
    /// ```
    #[must_use]
    pub fn covariance(mut self, noise: Option<NoiseModel>) -> Self {
        self.covariance = noise;
        self
    }

    /// Which cost to minimise. Default: [`Refinement::Reprojection`].
    #[must_use]
    pub fn refinement(mut self, r: Refinement) -> Self {
        self.opts.refinement = r;
        self
    }

    /// The cost this solver minimises (set by [`Solver::refinement`]).
    pub(crate) fn minimises(&self) -> Refinement {
        self.opts.refinement
    }

    /// Maximum damped-Newton iterations per candidate in `newton`. Default: `50`.
    #[must_use]
    pub fn newton_iterations(mut self, n: u32) -> Self {
        self.opts.newton.max_iterations = n;
        self
    }

    /// `newton` stops when the step norm (radians, roughly) falls to this. Default: `1e-12`. When
    /// `refine` follows (the default [`Refinement::Reprojection`]), `newton` uses at least `1e-6`
    /// (the minimum of the algebraic cost located to ~1e-9): `refine` then moves the pose on to the
    /// maximum-likelihood one and converges to its own tolerance.
    #[must_use]
    pub fn newton_step_tolerance(mut self, tol: f64) -> Self {
        self.opts.newton.step_tolerance = tol;
        self
    }

    /// Maximum Levenberg-Marquardt iterations of the reprojection refinement (`refine`, and
    /// `refine_pixels` through a camera). Default: `200` (a run from a start in a flat valley of
    /// the error can need more than 50: docs/algorithm.md, `search`; a run that converges sooner
    /// stops sooner).
    #[must_use]
    pub fn reprojection_iterations(mut self, n: u32) -> Self {
        self.opts.reproj.max_iterations = n;
        self
    }

    /// Planar branch selection. Default: [`PlanarDetection::Auto`].
    #[must_use]
    pub fn planar_detection(mut self, p: PlanarDetection) -> Self {
        self.opts.planar = p;
        self
    }

    /// `true` runs every candidate generator and refines every start to convergence for every
    /// problem (the stages `nullspace` to `newton` of docs/algorithm.md, literally: no certified
    /// early exit, no skipping of starts that lie near an already refined minimum). Default:
    /// `false`: the case-1 (planar: p1) start is refined first, and accepted without the rest of
    /// the search when a Lagrangian dual certificate proves it is the global minimum of the cost
    /// and more than half of the points are in front of it; `select` would select the same minimum.
    #[must_use]
    pub fn exhaustive(mut self, exhaustive: bool) -> Self {
        self.opts.exhaustive = exhaustive;
        self
    }

    /// The loss of the final refinement ([`Loss`]; default [`Loss::Squared`], the
    /// maximum-likelihood pose for Gaussian noise). A robust loss ([`Loss::Huber`],
    /// [`Loss::Cauchy`]) is applied by `refine_pixels` to the pixel residuals through the camera
    /// (pixel input: [`Problem::pixels`], RANSAC's fits) or to the normalised residuals
    /// (normalised input), after `refine`. An unusable scale (not positive, or with a square
    /// outside the normal f64 range) is [`PnpError::InvalidOption`] (`"loss"`) at solve time.
    ///
    /// ```
    /// use eopnp::{Loss, Problem, Solver};
    /// # use nalgebra::{Point2, Point3, Vector3};
    /// # let t = Vector3::new(0.1, -0.2, 6.0);
    /// # let mut world = vec![
    /// #     Point3::new(-1.0, -1.0, 0.5), Point3::new(1.0, -1.0, -0.5), Point3::new(1.0, 1.0, 0.2),
    /// #     Point3::new(-1.0, 1.0, -0.1), Point3::new(0.3, 0.2, 1.0), Point3::new(-0.4, 0.6, -0.8),
    /// #     Point3::new(0.5, -0.7, 0.3), Point3::new(-0.8, 0.1, 0.6),
    /// # ];
    /// # let mut image: Vec<Point2<f64>> = world
    /// #     .iter()
    /// #     .map(|x| { let p = x.coords + t; Point2::new(p.x / p.z, p.y / p.z) })
    /// #     .collect();
    /// // One gross outlier (0.05 normalised units, 40 px at f = 800).
    /// image[7].x += 0.05;
    /// let plain = Solver::default().solve(&Problem::normalised(&world, &image))?;
    /// let robust = Solver::default().loss(Loss::Cauchy(1e-3)).solve(&Problem::normalised(&world, &image))?;
    /// let err = |s: &eopnp::Solution| (s.translation - t).norm();
    /// assert!(err(&robust) < 0.1 * err(&plain));
    /// # Ok::<(), eopnp::PnpError>(())
    /// ```
    #[must_use]
    pub fn loss(mut self, loss: Loss) -> Self {
        self.opts.loss = loss;
        self
    }

    /// The pose of a [`Problem`]: EOPnP's global search, then (in the default mode) the
    /// maximum-likelihood refinement.
    ///
    /// In the default mode ([`Refinement::Reprojection`]) the returned pose minimises the
    /// (weighted) sum of squared reprojection residuals: of the normalised image points for
    /// [`Problem::normalised`], of the pixels through the camera model, distortion included,
    /// for [`Problem::pixels`] (with a robust [`Solver::loss`], the sum of the loss of the
    /// squared residuals). [`Solution::cost`] is that sum, [`Solution::reprojection_rmse`] the
    /// RMS residual in normalised units (for pixels: divided by `max(fx, fy)`).
    ///
    /// Pixels are first undistorted to normalised coordinates ([`Camera::undistort`]); a pixel
    /// that cannot be undistorted is left out and counted in [`Solution::skipped`]. The search
    /// on the undistorted points weights the x and y residual rows by `fx^2` and `fy^2`
    /// (normalised): exactly the pixel error for a pinhole camera. With distortion (or a robust
    /// loss) it gives the start of a last Levenberg-Marquardt refinement of the pixel error
    /// through the camera model itself (the `refine_pixels` stage of docs/algorithm.md). In
    /// [`Refinement::Algebraic`] mode, where the search's pose is the result, the residual of
    /// point `i` is also weighted by `|det J_i| / (fx fy)`, `J_i` the Jacobian of
    /// [`Camera::project`] at the point: to first order the pixel error.
    ///
    /// ```
    /// use eopnp::camera::Camera;
    /// use eopnp::{Problem, Solver};
    /// # use nalgebra::{Point2, Point3, Rotation3, Vector3};
    /// # let r = Rotation3::from_euler_angles(0.1, -0.2, 0.3);
    /// # let t = Vector3::new(0.1, -0.2, 6.0);
    /// # let world = [
    /// #     Point3::new(-1.0, -1.0, 0.5), Point3::new(1.0, -1.0, -0.5), Point3::new(1.0, 1.0, 0.2),
    /// #     Point3::new(-1.0, 1.0, -0.1), Point3::new(0.3, 0.2, 1.0), Point3::new(-0.4, 0.6, -0.8),
    /// # ];
    /// # let image: Vec<Point2<f64>> = world
    /// #     .iter()
    /// #     .map(|x| { let p = r * x + t; Point2::new(p.x / p.z, p.y / p.z) })
    /// #     .collect();
    ///
    /// let sol = Solver::default().solve(&Problem::normalised(&world, &image))?;
    /// assert!((sol.translation - t).norm() < 1e-9);
    /// assert!(sol.cheirality_ok && !sol.degenerate);
    ///
    /// // Pixels through a camera with lens distortion; a wrong seventh correspondence with
    /// // weight 0 changes nothing.
    /// let cam = Camera::from_colmap("SIMPLE_RADIAL", 640, 480, vec![800.0, 320.0, 240.0, -0.05])?;
    /// let mut pixels: Vec<Point2<f64>> = image.iter().map(|m| cam.project(*m)).collect();
    /// let mut world = world.to_vec();
    /// world.push(Point3::new(5.0, 5.0, 5.0));
    /// pixels.push(Point2::new(10.0, 470.0));
    /// let weights = [1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 0.0];
    /// let sol = Solver::default().solve(&Problem::pixels(&world, &pixels, &cam).weights(&weights))?;
    /// assert!((sol.translation - t).norm() < 1e-9);
    /// assert_eq!((sol.used, sol.skipped), (6, 0));
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    ///
    /// # Errors
    /// [`PnpError`] for too few points, mismatched lengths, non-finite values, bad weights
    /// (checked in that order, each with the correspondence's index), an unusable
    /// [`Solver::loss`] and degenerate configurations; see its variants.
    pub fn solve(&self, problem: &Problem<'_>) -> Result<Solution, PnpError> {
        self.solve_problem(problem, None)
    }

    /// Every distinct local minimum of the cost, best first: cheirality-valid poses before the
    /// others, then by increasing reprojection error. For N <= 6 and for planar scenes several
    /// poses can explain the data about equally well; this lists them. Bounded (at most 32), no
    /// allocation of its own.
    ///
    /// ```
    /// use eopnp::{Problem, Solver};
    /// # use nalgebra::{Point2, Point3, Rotation3, Vector3};
    /// # let r = Rotation3::from_euler_angles(0.1, -0.2, 0.3);
    /// # let t = Vector3::new(0.1, -0.2, 6.0);
    /// # let world = [
    /// #     Point3::new(-1.0, -1.0, 0.5), Point3::new(1.0, -1.0, -0.5), Point3::new(1.0, 1.0, 0.2),
    /// #     Point3::new(-1.0, 1.0, -0.1), Point3::new(0.3, 0.2, 1.0), Point3::new(-0.4, 0.6, -0.8),
    /// # ];
    /// # let image: Vec<Point2<f64>> = world
    /// #     .iter()
    /// #     .map(|x| { let p = r * x + t; Point2::new(p.x / p.z, p.y / p.z) })
    /// #     .collect();
    ///
    /// let all = Solver::default().solve_all(&Problem::normalised(&world[..4], &image[..4]))?;
    /// // Four points: one or more poses fit them; the true one is among them.
    /// assert!(all.iter().any(|s| (s.translation - t).norm() < 1e-8));
    /// # Ok::<(), eopnp::PnpError>(())
    /// ```
    ///
    /// # Errors
    /// As [`Solver::solve`].
    pub fn solve_all(&self, problem: &Problem<'_>) -> Result<Solutions, PnpError> {
        let mut all = Solutions::new();
        self.solve_problem(problem, Some(&mut all))?;
        Ok(all)
    }

    /// Refines a prior pose (tracking: the previous frame's pose) to the maximum-likelihood pose
    /// of the basin it starts in, without EOPnP's global search (OpenCV's `solvePnPRefineLM`,
    /// PoseLib's `refine_absolute_pose`): damped Newton on the algebraic cost from `initial`'s
    /// rotation, then the Levenberg-Marquardt refinement of the reprojection error (through the
    /// camera for pixels). `initial` maps world to camera, `x_cam = R X + t`. The problem is
    /// validated as by [`Solver::solve`]; [`Solution::converged`] says whether the refinement
    /// reached a minimum, [`Solution::source`] is [`crate::CandidateSource::Initial`].
    ///
    /// ```
    /// use eopnp::{Problem, Solver};
    /// use nalgebra::{Isometry3, Point2, Point3, Translation3, UnitQuaternion, Vector3};
    ///
    /// let t = Vector3::new(0.1, -0.2, 6.0);
    /// let world = [
    ///     Point3::new(-1.0, -1.0, 0.5), Point3::new(1.0, -1.0, -0.5), Point3::new(1.0, 1.0, 0.2),
    ///     Point3::new(-1.0, 1.0, -0.1), Point3::new(0.3, 0.2, 1.0), Point3::new(-0.4, 0.6, -0.8),
    /// ];
    /// let image: Vec<Point2<f64>> = world
    ///     .iter()
    ///     .map(|x| { let p = x.coords + t; Point2::new(p.x / p.z, p.y / p.z) })
    ///     .collect();
    /// // The previous frame's pose, a little off.
    /// let prior = Isometry3::from_parts(
    ///     Translation3::new(0.12, -0.18, 5.9),
    ///     UnitQuaternion::from_euler_angles(0.02, -0.01, 0.03),
    /// );
    /// let sol = Solver::default().refine(&Problem::normalised(&world, &image), &prior)?;
    /// assert!(sol.converged);
    /// assert!((sol.translation - t).norm() < 1e-9);
    /// # Ok::<(), eopnp::PnpError>(())
    /// ```
    ///
    /// # Errors
    /// As [`Solver::solve`], and [`PnpError::InvalidOption`] (`"initial"`) for an initial pose
    /// that is not finite.
    pub fn refine(
        &self,
        problem: &Problem<'_>,
        initial: &Isometry3<f64>,
    ) -> Result<Solution, PnpError> {
        let this = self.for_problem(problem);
        let (world, weights) = (problem.world, problem.weights);
        if let Some((points, camera, free)) = intrinsics_input(problem)? {
            return this.refine_pixels_intrinsics(world, points, camera, weights, free, initial);
        }
        match problem.observations {
            Observations::Normalised { points, .. } => {
                this.refine_normalised(world, points, weights, initial)
            }
            Observations::Pixels { points, camera } => {
                this.refine_pixels(world, points, camera, weights, initial)
            }
            Observations::Rig {
                points,
                cameras,
                rig,
            } => this.refine_rig(
                &rig_problem(world, points, cameras, rig, weights, problem.gravity),
                initial,
            ),
        }
    }

    /// This solver with `problem`'s known vertical (the `vertical` stage's prior) or without
    /// one.
    pub(crate) fn for_problem(&self, problem: &Problem<'_>) -> Solver {
        self.with_gravity(problem.gravity)
    }

    /// This solver with the known vertical `gravity` (the `vertical` stage's prior) or without
    /// one.
    pub(crate) fn with_gravity(&self, gravity: Option<Gravity>) -> Solver {
        let mut s = *self;
        s.opts.reproj.vertical = gravity.as_ref().map(Vertical::new);
        s
    }

    /// [`Solver::solve`] (`all: None`) and [`Solver::solve_all`].
    fn solve_problem(
        &self,
        problem: &Problem<'_>,
        all: Option<&mut Solutions>,
    ) -> Result<Solution, PnpError> {
        let this = self.for_problem(problem);
        let (world, weights) = (problem.world, problem.weights);
        if let Some((points, camera, free)) = intrinsics_input(problem)? {
            let sol = this.pixels_intrinsics(world, points, camera, weights, free)?;
            if let Some(all) = all {
                all.clear();
                all.push(sol);
            }
            return Ok(sol);
        }
        match problem.observations {
            Observations::Normalised { points, .. } => this.normalised(world, points, weights, all),
            Observations::Pixels { points, camera } => {
                this.pixels(world, points, camera, weights, all)
            }
            Observations::Rig {
                points,
                cameras,
                rig,
            } => this.rig(
                &rig_problem(world, points, cameras, rig, weights, problem.gravity),
                all,
            ),
        }
    }

    /// The solve of normalised image points.
    fn normalised(
        &self,
        world: &[Point3<f64>],
        image: &[Point2<f64>],
        weights: Option<&[f64]>,
        mut all: Option<&mut Solutions>,
    ) -> Result<Solution, PnpError> {
        let px = self.normalised_loss(image, weights);
        let sol = self.run(
            world,
            image,
            weights,
            &self.opts.reproj,
            px.as_ref(),
            all.as_deref_mut(),
        )?;
        let weight = |i: usize| weights.map_or(1.0, |w| w[i]);
        let finish = |s: Solution| self.with_covariance(s, world, image, &weight, Metric::Identity);
        for s in all.into_iter().flatten() {
            *s = finish(*s);
        }
        Ok(finish(sol))
    }

    /// [`Solver::refine`] of normalised image points.
    fn refine_normalised(
        &self,
        world: &[Point3<f64>],
        image: &[Point2<f64>],
        weights: Option<&[f64]>,
        initial: &Isometry3<f64>,
    ) -> Result<Solution, PnpError> {
        let r = check_initial(initial)?;
        let t = initial.translation.vector;
        self.check_loss()?;
        let px = self.normalised_loss(image, weights);
        let sol = pipeline::run_from_prior(
            &self.opts,
            world,
            image,
            weights,
            &self.opts.reproj,
            px.as_ref(),
            (&r, &t),
        )?;
        let weight = |i: usize| weights.map_or(1.0, |w| w[i]);
        Ok(self.with_covariance(sol, world, image, &weight, Metric::Identity))
    }

    /// [`Solver::refine`] of pixels through a camera.
    fn refine_pixels(
        &self,
        world: &[Point3<f64>],
        pixels: &[Point2<f64>],
        camera: &Camera,
        user_weights: Option<&[f64]>,
        initial: &Isometry3<f64>,
    ) -> Result<Solution, PnpError> {
        let r = check_initial(initial)?;
        let t = initial.translation.vector;
        let u = self.undistort(world, pixels, camera, user_weights)?;
        let mut reproj = self.opts.reproj;
        reproj.row_weights = u.rows;
        let px = self.camera_loss(&u, camera);
        let mut sol = pipeline::run_from_prior(
            &self.opts,
            &u.world,
            &u.image,
            u.solve_weights(),
            &reproj,
            Some(&px),
            (&r, &t),
        )?;
        sol.skipped = world.len() - u.image.len();
        // The covariance through the camera with the caller's weights, as `Solver::pixels`.
        let weight = |k: usize| user_weights.map_or(1.0, |uw| uw[u.index(k)]);
        Ok(self.with_covariance(sol, &u.world, &u.image, &weight, Metric::Camera(camera)))
    }

    /// The solve of normalised image points (weights optional) with the x and y residual rows
    /// of the reprojection refinement weighted by `row_weights` (e.g. `(fx^2, fy^2)`
    /// normalised, as for pixels through a camera). Used by RANSAC's fits. Non-finite or
    /// non-positive row weights fall back to `(1, 1)`.
    pub(crate) fn solve_with_row_weights(
        &self,
        world: &[Point3<f64>],
        image: &[Point2<f64>],
        weights: Option<&[f64]>,
        row_weights: (f64, f64),
        pixel: Option<&PixelInputs<'_>>,
        all: Option<&mut Solutions>,
    ) -> Result<Solution, PnpError> {
        let mut opts = self.opts.reproj;
        let ok = |w: f64| w.is_finite() && w > 0.0;
        if ok(row_weights.0) && ok(row_weights.1) {
            opts.row_weights = row_weights;
        }
        self.run(world, image, weights, &opts, pixel, all)
    }

    /// `refine_pixels`' inputs for normalised input: only with a robust loss (the identity camera,
    /// residuals in normalised units); `refine` alone minimises the squared loss.
    pub(crate) fn normalised_loss<'a>(
        &self,
        image: &'a [Point2<f64>],
        weights: Option<&'a [f64]>,
    ) -> Option<PixelInputs<'a>> {
        (self.opts.loss != Loss::Squared).then(|| PixelInputs {
            pixels: image,
            weights,
            projector: Projector::identity(),
            loss: self.opts.loss,
            refine: true,
            scale: 1.0,
        })
    }

    /// `refine_pixels`' inputs for pixel input through `camera` (the used correspondences of `u`):
    /// it runs for a camera with distortion or a robust loss.
    pub(crate) fn camera_loss<'a>(
        &self,
        u: &'a Undistorted<'_>,
        camera: &Camera,
    ) -> PixelInputs<'a> {
        PixelInputs {
            pixels: &u.pixels,
            weights: u.user_weights.as_deref(),
            projector: camera.projector(),
            loss: self.opts.loss,
            refine: self.refine_pixels_runs(camera),
            scale: u.focal.0.max(u.focal.1),
        }
    }

    /// Whether `refine_pixels` refines a solve through `camera` in the default mode: a camera with
    /// distortion, or a robust loss.
    fn refine_pixels_runs(&self, camera: &Camera) -> bool {
        camera.has_distortion() || self.opts.loss != Loss::Squared
    }

    /// [`PnpError::InvalidOption`] (`"loss"`) for a loss whose scale is not usable.
    pub(crate) fn check_loss(&self) -> Result<(), PnpError> {
        if self.opts.loss.is_valid() {
            Ok(())
        } else {
            Err(PnpError::InvalidOption { option: "loss" })
        }
    }

    /// The solve of pixels through a camera.
    fn pixels(
        &self,
        world: &[Point3<f64>],
        pixels: &[Point2<f64>],
        camera: &Camera,
        user_weights: Option<&[f64]>,
        mut all: Option<&mut Solutions>,
    ) -> Result<Solution, PnpError> {
        let u = self.undistort(world, pixels, camera, user_weights)?;
        let px = self.camera_loss(&u, camera);
        let sol = self.solve_with_row_weights(
            &u.world,
            &u.image,
            u.solve_weights(),
            u.rows,
            Some(&px),
            all.as_deref_mut(),
        )?;
        let skipped = world.len() - u.image.len();
        // The covariance through the camera: the caller's weights, not the first-order
        // distortion weights of the solve.
        let weight = |k: usize| user_weights.map_or(1.0, |uw| uw[u.index(k)]);
        let finish = |mut s: Solution| {
            s.skipped = skipped;
            self.with_covariance(s, &u.world, &u.image, &weight, Metric::Camera(camera))
        };
        for s in all.into_iter().flatten() {
            *s = finish(*s);
        }
        Ok(finish(sol))
    }

    /// `sol` with its covariance when [`Solver::covariance`] asks for it (also RANSAC's, from
    /// its inliers).
    pub(crate) fn with_covariance(
        &self,
        mut sol: Solution,
        world: &[Point3<f64>],
        image: &[Point2<f64>],
        weight: &dyn Fn(usize) -> f64,
        metric: Metric<'_>,
    ) -> Solution {
        if let Some(noise) = self.covariance {
            let pose = (&sol.rotation, &sol.translation);
            sol.covariance = pose_covariance(world, image, weight, pose, metric, noise);
        }
        sol
    }

    fn run(
        &self,
        world: &[Point3<f64>],
        image: &[Point2<f64>],
        weights: Option<&[f64]>,
        reproj: &ReprojOptions,
        pixel: Option<&PixelInputs<'_>>,
        all: Option<&mut Solutions>,
    ) -> Result<Solution, PnpError> {
        self.check_loss()?;
        pipeline::run(&self.opts, world, image, weights, reproj, pixel, all)
    }
}

/// The pose from world points and their normalised image points `(x/z, y/z)` with the
/// default [`Solver`]: `Solver::default().solve(&Problem::normalised(world, image))`, the
/// shortest way in.
///
/// ```
/// # use nalgebra::{Point2, Point3, Rotation3, Vector3};
/// # let r = Rotation3::from_euler_angles(0.1, -0.2, 0.3);
/// # let t = Vector3::new(0.1, -0.2, 6.0);
/// # let world = [
/// #     Point3::new(-1.0, -1.0, 0.5), Point3::new(1.0, -1.0, -0.5), Point3::new(1.0, 1.0, 0.2),
/// #     Point3::new(-1.0, 1.0, -0.1), Point3::new(0.3, 0.2, 1.0), Point3::new(-0.4, 0.6, -0.8),
/// # ];
/// # let image: Vec<Point2<f64>> = world
/// #     .iter()
/// #     .map(|x| { let p = r * x + t; Point2::new(p.x / p.z, p.y / p.z) })
/// #     .collect();
///
/// let sol = eopnp::solve(&world, &image)?;
/// assert!((sol.rotation - r.matrix()).norm() < 1e-9);
/// # Ok::<(), eopnp::PnpError>(())
/// ```
///
/// # Errors
/// See [`Solver::solve`].
pub fn solve(world: &[Point3<f64>], image: &[Point2<f64>]) -> Result<Solution, PnpError> {
    Solver::default().solve(&Problem::normalised(world, image))
}

/// The rotation of a finite initial pose, or [`PnpError::InvalidOption`] (`"initial"`).
/// A rig problem's parts.
fn rig_problem<'a>(
    world: &'a [Point3<f64>],
    pixels: &'a [Point2<f64>],
    cameras: &'a [u32],
    rig: &'a crate::rig::Rig,
    weights: Option<&'a [f64]>,
    gravity: Option<Gravity>,
) -> crate::generalized::RigInput<'a> {
    crate::generalized::RigInput {
        world,
        pixels,
        cameras,
        rig,
        weights,
        gravity,
    }
}

/// A problem's pixels, camera and free intrinsics ([`intrinsics_input`]).
pub(crate) type IntrinsicsInput<'a> = (&'a [Point2<f64>], &'a Camera, FreeIntrinsics);

/// The pixels, the camera and the free intrinsics of a problem that estimates intrinsics
/// ([`Problem::unknown_focal`], [`Problem::refine_principal_point`],
/// [`Problem::refine_distortion`]); `None` when it estimates none;
/// [`PnpError::InvalidOption`] (naming the first option asked for) unless its input is pixels
/// through a camera, without a known vertical.
pub(crate) fn intrinsics_input<'a>(
    problem: &Problem<'a>,
) -> Result<Option<IntrinsicsInput<'a>>, PnpError> {
    let free = Free {
        focal: problem.unknown_focal.is_some(),
        principal_point: problem.refine_principal_point,
        distortion: problem.refine_distortion,
    };
    if !free.any() {
        return Ok(None);
    }
    match problem.observations {
        Observations::Pixels { points, camera } if problem.gravity.is_none() => Ok(Some((
            points,
            camera,
            FreeIntrinsics {
                free,
                range: problem.unknown_focal,
            },
        ))),
        _ => Err(PnpError::InvalidOption {
            option: if free.focal {
                "unknown_focal"
            } else if free.principal_point {
                "refine_principal_point"
            } else {
                "refine_distortion"
            },
        }),
    }
}

fn check_initial(initial: &Isometry3<f64>) -> Result<Matrix3<f64>, PnpError> {
    let finite = initial.translation.vector.iter().all(|x| x.is_finite())
        && initial.rotation.coords.iter().all(|x| x.is_finite());
    if !finite {
        return Err(PnpError::InvalidOption { option: "initial" });
    }
    Ok(initial.rotation.to_rotation_matrix().into_inner())
}
