//! The synthetic problem generator of docs/algorithm.md section 7 (synth.py).

use nalgebra::{Matrix3, Point2, Point3, Vector3};
use rand::Rng;
use rand_pcg::Pcg64;

use crate::lm::{lm_refine, LmResult, PIXEL_CAMERA};
use crate::metrics::{rot_err_deg, trans_err_rel};
use crate::rotation::{haar_rotation, rotation_near_180};
use crate::seed::{gauss, rng_from_seed};
use crate::{CX, CY, F, NEAR180_MAX_DEV_DEG};

/// Scene type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scene {
    /// Camera-frame points uniform in [-2,2] x [-2,2] x [4,8]; world origin at their centroid.
    General,
    /// Points uniform on a plane ([-2,2]^2) seen from distance 6, at an arbitrary pose in the
    /// world (random world similarity), so the plane is not Z = 0 in the world frame.
    Planar,
    /// Camera-frame points uniform in [1,2] x [1,2] x [4,8] (narrow, off-axis); world origin at
    /// their centroid.
    QuasiSingular,
}

/// Distribution of the ground-truth (world -> camera) rotation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RotationKind {
    /// Haar-uniform on SO(3).
    Uniform,
    /// Within [`NEAR180_MAX_DEV_DEG`] of 180 degrees (exactly 180 in 5 % of draws).
    Near180,
}

/// What to generate; `seed` alone determines the problem.
#[derive(Clone, Copy, Debug)]
pub struct ProblemOptions {
    /// Number of correspondences.
    pub n: usize,
    /// Gaussian pixel noise per coordinate, pixels.
    pub sigma_px: f64,
    /// Scene type.
    pub scene: Scene,
    /// Ground-truth rotation distribution.
    pub rotation: RotationKind,
    /// The trial seed.
    pub seed: u64,
}

/// A synthetic PnP problem with ground truth (x_cam = r_gt X + t_gt).
#[derive(Clone, Debug)]
pub struct Problem {
    /// The options it was generated from (including the seed).
    pub opts: ProblemOptions,
    /// World points.
    pub world: Vec<Point3<f64>>,
    /// Noisy pixel coordinates (f = 800, principal point (320, 240)).
    pub pixels: Vec<Point2<f64>>,
    /// Normalised image coordinates (pixels - (320, 240)) / 800.
    pub image: Vec<Point2<f64>>,
    /// Ground-truth rotation.
    pub r_gt: Matrix3<f64>,
    /// Ground-truth translation.
    pub t_gt: Vector3<f64>,
}

/// Draws the ground-truth world rotation of the requested kind.
fn draw_rotation(rng: &mut Pcg64, kind: RotationKind) -> Matrix3<f64> {
    match kind {
        RotationKind::Uniform => haar_rotation(rng),
        RotationKind::Near180 => rotation_near_180(rng, NEAR180_MAX_DEV_DEG),
    }
}

impl Problem {
    /// Generates the problem determined by `opts` (in particular by `opts.seed`).
    ///
    /// General / QuasiSingular follow synth.py `make_problem`: R drawn first, camera-frame
    /// points, t = their centroid, X = R^T (x_cam - t). Planar: as synth.py, plane Z = 0 with
    /// points in [-2,2]^2, plane pose (Rp Haar, redrawn until |Rp33| > cos 75 deg; t_p =
    /// (U(-.5,.5), U(-.5,.5), 6)); then a world similarity X = s Q Y + b with s log-uniform in
    /// [0.1, 10], b = s U(-5,5)^3 and Q = R_gt^T Rp, where R_gt is drawn with `opts.rotation`,
    /// so the world-frame ground truth has the requested distribution while the plane has an
    /// arbitrary world pose; t_gt = s t_p - R_gt b. Pixel noise last.
    pub fn generate(opts: &ProblemOptions) -> Problem {
        let mut rng = rng_from_seed(opts.seed);
        let n = opts.n;
        let (world, cam, r_gt, t_gt) = match opts.scene {
            Scene::General | Scene::QuasiSingular => {
                let r = draw_rotation(&mut rng, opts.rotation);
                let (lo, hi) = if opts.scene == Scene::General {
                    (-2.0, 2.0)
                } else {
                    (1.0, 2.0)
                };
                let cam: Vec<Vector3<f64>> = (0..n)
                    .map(|_| {
                        Vector3::new(
                            rng.random_range(lo..hi),
                            rng.random_range(lo..hi),
                            rng.random_range(4.0..8.0),
                        )
                    })
                    .collect();
                let t = if n == 0 {
                    Vector3::new(0.0, 0.0, 6.0)
                } else {
                    cam.iter().sum::<Vector3<f64>>() / n as f64
                };
                let world = cam
                    .iter()
                    .map(|p| Point3::from(r.transpose() * (p - t)))
                    .collect();
                (world, cam, r, t)
            }
            Scene::Planar => {
                let plane: Vec<Vector3<f64>> = (0..n)
                    .map(|_| {
                        Vector3::new(
                            rng.random_range(-2.0..2.0),
                            rng.random_range(-2.0..2.0),
                            0.0,
                        )
                    })
                    .collect();
                let tp = Vector3::new(
                    rng.random_range(-0.5..0.5),
                    rng.random_range(-0.5..0.5),
                    6.0,
                );
                let cos75 = 75f64.to_radians().cos();
                let mut rp = haar_rotation(&mut rng);
                // Acceptance probability ~0.74 per draw: 200 draws never all fail in practice.
                for _ in 0..200 {
                    if rp[(2, 2)].abs() > cos75 {
                        break;
                    }
                    rp = haar_rotation(&mut rng);
                }
                assert!(
                    rp[(2, 2)].abs() > cos75,
                    "seed {}: plane pose draw",
                    opts.seed
                );
                let r_gt = draw_rotation(&mut rng, opts.rotation);
                let s = 10f64.powf(rng.random_range(-1.0..1.0));
                let b = Vector3::new(
                    rng.random_range(-5.0..5.0),
                    rng.random_range(-5.0..5.0),
                    rng.random_range(-5.0..5.0),
                ) * s;
                let q = r_gt.transpose() * rp;
                let world = plane.iter().map(|y| Point3::from(q * y * s + b)).collect();
                // Camera frame scaled by s (the image is scale invariant).
                let cam: Vec<Vector3<f64>> = plane.iter().map(|y| (rp * y + tp) * s).collect();
                (world, cam, r_gt, tp * s - r_gt * b)
            }
        };
        let pixels: Vec<Point2<f64>> = cam
            .iter()
            .map(|p| {
                let u = p.x / p.z * F + CX + opts.sigma_px * gauss(&mut rng);
                let v = p.y / p.z * F + CY + opts.sigma_px * gauss(&mut rng);
                Point2::new(u, v)
            })
            .collect();
        let image = pixels
            .iter()
            .map(|p| Point2::new((p.x - CX) / F, (p.y - CY) / F))
            .collect();
        Problem {
            opts: *opts,
            world,
            pixels,
            image,
            r_gt,
            t_gt,
        }
    }

    /// Rotation error (deg) and relative translation error of a pose w.r.t. the ground truth.
    pub fn errors(&self, r: &Matrix3<f64>, t: &Vector3<f64>) -> (f64, f64) {
        (rot_err_deg(r, &self.r_gt), trans_err_rel(t, &self.t_gt))
    }

    /// Maximum-likelihood floor: LM on the pixel residuals started at the ground truth.
    pub fn lm_from_gt(&self) -> LmResult {
        lm_refine(
            &self.world,
            &self.pixels,
            &self.r_gt,
            &self.t_gt,
            PIXEL_CAMERA,
        )
    }
}
