//! The `refine_intrinsics` stage: Levenberg-Marquardt on the pixel error over the pose and the
//! camera's free intrinsics together, through the camera model: the focal length when it is
//! unknown ([`crate::Problem::unknown_focal`]), the principal point
//! ([`crate::Problem::refine_principal_point`]) and the distortion parameters
//! ([`crate::Problem::refine_distortion`]) when asked for. Its minimum is the maximum-likelihood
//! pose and intrinsics.
//!
//! Minimises `E(R, t, K) = sum_i w_i |m_i - K(pi(R (X_i - x0) + t))|^2`: `K` the camera's
//! projection (distortion included), `x0` the weighted centroid of the world points
//! (conditioning). Steps `R := Exp(w) R`, `t := t + dt`, the focal lengths `f := f exp(da)`
//! (all focal lengths of the camera scaled alike: square pixels stay square), the principal
//! point and the distortion parameters additively: at most [`MAX_FREE`] parameters, Marquardt's
//! scaling of the damping by the diagonal of `J^T W J`, a step accepted only if it lowers `E`,
//! keeps the sign of every depth (as `refine`'s) and leaves a valid camera. A pixel whose
//! distortion is outside the model's domain costs nothing here: the caller passes the
//! correspondences that undistort.
//!
//! The derivatives in the pose, the focal length and the principal point are analytic; those
//! in the distortion parameters are central differences of the projection (exact to rounding
//! for the parameters that enter it linearly, all but `FULL_OPENCV`'s denominator and the tilt
//! of `OPENCV_THIN_PRISM_TILTED`; `O(h^2)` with `h = 1e-4 max(1, |k|)` for those).
//!
//! O(N) per pass (the depth signs of the start kept in one vector); simpler than `refine`'s
//! vectorised pass (this stage runs once per solve with free intrinsics, after a search that
//! costs far more).

use arrayvec::ArrayVec;
use nalgebra::{Matrix3, Point2, Point3, SMatrix, SVector, Vector3};

use crate::camera::{Camera, Projector, MAX_PARAMS};
use crate::numeric::rotation::exp_so3;
use crate::pipeline::Loss;

/// The most distortion parameters of a model: those after two focal lengths and the principal
/// point (`OPENCV_THIN_PRISM_TILTED`'s 14).
const MAX_DISTORTION: usize = MAX_PARAMS - 4;
/// The most free parameters: the pose (6), the focal length (1), the principal point (2) and
/// the distortion.
pub(crate) const MAX_FREE: usize = 6 + 1 + 2 + MAX_DISTORTION;

type Normal = SMatrix<f64, MAX_FREE, MAX_FREE>;
type Gradient = SVector<f64, MAX_FREE>;

/// Which intrinsics are free (besides the pose).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct Free {
    /// The focal length (its scale: the camera's focal lengths alike).
    pub focal: bool,
    /// The principal point.
    pub principal_point: bool,
    /// The distortion parameters.
    pub distortion: bool,
}

impl Free {
    /// Whether any intrinsic is free.
    pub(crate) fn any(self) -> bool {
        self.focal || self.principal_point || self.distortion
    }
}

/// The result of [`refine_intrinsics`].
#[derive(Clone, Copy, Debug)]
pub(crate) struct IntrinsicsOutcome {
    /// The world-to-camera rotation.
    pub r: Matrix3<f64>,
    /// The translation, `x_cam = R X + t`.
    pub t: Vector3<f64>,
    /// The camera with the refined intrinsics.
    pub camera: Camera,
    /// `E` at the returned parameters (pixels^2, the caller's weights).
    pub cost: f64,
    /// Levenberg-Marquardt iterations.
    pub iterations: u32,
    /// Whether a convergence test stopped it (not the iteration cap).
    pub converged: bool,
}

/// Iteration cap of a refinement to convergence.
pub(crate) const MAX_ITERATIONS: u32 = 200;
/// Stop when the step is below this relative to the parameters (`|t| + 1` and 1 for the
/// rotation and the log-scale, `f` for the principal point, `max(1, |k|)` for a distortion
/// parameter).
const XTOL: f64 = 1e-12;
/// Stop when the relative decrease of the cost is below this.
const FTOL: f64 = 1e-15;

/// The problem's data: the correspondences and which intrinsics are free.
pub(crate) struct IntrinsicsInputs<'a> {
    pub world: &'a [Point3<f64>],
    pub pixels: &'a [Point2<f64>],
    pub weights: Option<&'a [f64]>,
    pub free: Free,
    /// With the focal length free: the range of the (first) focal length, pixels. A step
    /// that leaves it ends on its bound (a projected step), so the minimum returned is the
    /// range's.
    pub focal_range: (f64, f64),
    /// The robust loss of each point's squared pixel residual ([`Loss::Squared`]: least
    /// squares); the normal equations are then those of iteratively reweighted least squares.
    pub loss: Loss,
}

/// The free parameters' layout: the pose's 6, then the free intrinsics.
#[derive(Clone)]
struct Layout {
    /// Free parameters in all.
    len: usize,
    /// The focal log-scale's index.
    focal: Option<usize>,
    /// The principal point's first index.
    centre: Option<usize>,
    /// The first distortion parameter's index, and the distortion parameters' indices in
    /// [`Camera::params`].
    distortion: Option<(usize, core::ops::Range<usize>)>,
}

impl Layout {
    fn new(camera: &Camera, free: Free) -> Layout {
        let (_, dist) = camera.intrinsic_groups();
        let mut len = 6;
        let mut take = |on: bool, k: usize| {
            on.then(|| {
                len += k;
                len - k
            })
        };
        let focal = take(free.focal, 1);
        let centre = take(free.principal_point, 2);
        let distortion = take(free.distortion && !dist.is_empty(), dist.len()).map(|i| (i, dist));
        Layout {
            len,
            focal,
            centre,
            distortion,
        }
    }
}

/// The normal equations at one point of the parameter space: `E`, `J^T W J` and `J^T W r` (the
/// residuals `r = model - m`) over the layout's parameters, or `None` if the depth of a point
/// with a positive weight is 0 or has another sign than in `front` (`front[i]`: point `i` in
/// front at the start, recorded when `record`), or a residual is not finite.
fn normal(
    inp: &IntrinsicsInputs<'_>,
    lay: &Layout,
    x0: &Vector3<f64>,
    (r, t, cam): (&Matrix3<f64>, &Vector3<f64>, &Camera),
    front: &mut [bool],
    record: bool,
) -> Option<(f64, Normal, Gradient)> {
    let (cx, cy) = cam.principal_point();
    let proj = cam.projector();
    // The distortion parameters' central differences: the projections with each moved by +-h.
    let mut moved: ArrayVec<(Projector, Projector, f64), MAX_DISTORTION> = ArrayVec::new();
    if let Some((_, range)) = &lay.distortion {
        let mut params = [0.0; MAX_PARAMS];
        let n = cam.params().len();
        params[..n].copy_from_slice(cam.params());
        for j in range.clone() {
            let h = 1e-4 * params[j].abs().max(1.0);
            let k = params[j];
            params[j] = k + h;
            let plus = cam.with_params(&params[..n]);
            params[j] = k - h;
            let minus = cam.with_params(&params[..n]);
            params[j] = k;
            let (Some(plus), Some(minus)) = (plus, minus) else {
                return None;
            };
            moved.push((plus.projector(), minus.projector(), 0.5 / h));
        }
    }
    let m = lay.len;
    let mut e = 0.0;
    let mut h = Normal::zeros();
    let mut g = Gradient::zeros();
    let mut row = [[0.0; MAX_FREE]; 2];
    for (i, (x, px)) in inp.world.iter().zip(inp.pixels).enumerate() {
        let w = inp.weights.map_or(1.0, |w| w[i]);
        if !(w > 0.0) {
            continue;
        }
        let q = r * (x.coords - x0);
        let p = q + t;
        if !(p.z != 0.0) {
            return None;
        }
        if record {
            front[i] = p.z > 0.0;
        } else if front[i] != (p.z > 0.0) {
            return None;
        }
        let (nx, ny) = (p.x / p.z, p.y / p.z);
        let ((u, v), jc) = proj.project_with_jacobian(nx, ny);
        let res = [u - px.x, v - px.y];
        if !(res[0].is_finite() && res[1].is_finite()) {
            return None;
        }
        // The loss and its IRLS weight (1 for least squares).
        let (rho, drho) = inp.loss.eval(res[0] * res[0] + res[1] * res[1]);
        e += w * rho;
        let w = w * drho;
        // d pixel / d p = J_cam (1 / z) [[1, 0, -nx], [0, 1, -ny]].
        let iz = 1.0 / p.z;
        let dn = nalgebra::Matrix2x3::new(iz, 0.0, -nx * iz, 0.0, iz, -ny * iz);
        let dp = nalgebra::Matrix2::new(jc[0], jc[1], jc[2], jc[3]) * dn;
        // Rows: [dp (-[q]x), dp, the intrinsics].
        let dw = -(dp * q.cross_matrix());
        for k in 0..3 {
            row[0][k] = dw[(0, k)];
            row[1][k] = dw[(1, k)];
            row[0][3 + k] = dp[(0, k)];
            row[1][3 + k] = dp[(1, k)];
        }
        if let Some(j) = lay.focal {
            row[0][j] = u - cx;
            row[1][j] = v - cy;
        }
        if let Some(j) = lay.centre {
            (row[0][j], row[0][j + 1]) = (1.0, 0.0);
            (row[1][j], row[1][j + 1]) = (0.0, 1.0);
        }
        if let Some((j0, _)) = &lay.distortion {
            for (k, (plus, minus, s)) in moved.iter().enumerate() {
                let (up, vp) = plus.project(nx, ny);
                let (um, vm) = minus.project(nx, ny);
                row[0][j0 + k] = (up - um) * s;
                row[1][j0 + k] = (vp - vm) * s;
            }
        }
        // The pose and the focal length (RANSAC's fits): the same sums with the size known.
        if m == 7 {
            accumulate(7, &mut h, &mut g, &row, res, w);
        } else {
            accumulate(m, &mut h, &mut g, &row, res, w);
        }
    }
    for j in 0..m {
        for k in 0..j {
            h[(j, k)] = h[(k, j)];
        }
    }
    e.is_finite().then_some((e, h, g))
}

/// The step `-hd^-1 g` by Cholesky's factorisation, or `None` if `hd` is not positive definite;
/// on the leading 7 x 7 block when `m` is 7 (the pose and the focal length: RANSAC's fits),
/// else on the whole matrix (the unused parameters' rows the identity).
fn solve_damped(hd: &Normal, g: &Gradient, m: usize) -> Option<Gradient> {
    if m == 7 {
        let chol = hd.fixed_view::<7, 7>(0, 0).into_owned().cholesky()?;
        let d = chol.solve(&(-g.fixed_rows::<7>(0).into_owned()));
        let mut delta = Gradient::zeros();
        delta.fixed_rows_mut::<7>(0).copy_from(&d);
        Some(delta)
    } else {
        Some(hd.cholesky()?.solve(&(-g)))
    }
}

/// Adds a point's two rows `row` (residuals `res`, weight `w`) to the upper triangle of `h` and
/// to `g`, over the first `m` parameters (inlined, so that a constant `m` is a size known at
/// compile time).
#[inline(always)]
fn accumulate(
    m: usize,
    h: &mut Normal,
    g: &mut Gradient,
    row: &[[f64; MAX_FREE]; 2],
    res: [f64; 2],
    w: f64,
) {
    for (rw, ri) in row.iter().zip(res) {
        for j in 0..m {
            g[j] += w * rw[j] * ri;
            for k in j..m {
                h[(j, k)] += w * rw[j] * rw[k];
            }
        }
    }
}

/// The camera `cam` moved by the intrinsics' part of the step `delta`, or `None` if that is not
/// a valid camera.
fn step_camera(
    cam: &Camera,
    lay: &Layout,
    delta: &Gradient,
    (lo, hi): (f64, f64),
) -> Option<Camera> {
    let base = match lay.focal {
        Some(j) => {
            let f = cam.focal_lengths().0;
            let to = (f * delta[j].exp()).clamp(lo, hi);
            cam.with_focal_scale(to / f)
        }
        None => *cam,
    };
    let n = base.params().len();
    let mut params = [0.0; MAX_PARAMS];
    params[..n].copy_from_slice(base.params());
    if let Some(j) = lay.centre {
        let [a, b] = cam.intrinsic_groups().0;
        params[a] += delta[j];
        params[b] += delta[j + 1];
    }
    if let Some((j0, range)) = &lay.distortion {
        for (k, i) in range.clone().enumerate() {
            params[i] += delta[j0 + k];
        }
    }
    cam.with_params(&params[..n])
}

/// The size of the intrinsics' part of a step, relative to the parameters.
fn step_size(cam: &Camera, lay: &Layout, delta: &Gradient) -> f64 {
    let mut s = 0.0;
    if let Some(j) = lay.focal {
        s += delta[j].abs();
    }
    if let Some(j) = lay.centre {
        s += (delta[j].abs() + delta[j + 1].abs()) / cam.focal_lengths().0;
    }
    if let Some((j0, range)) = &lay.distortion {
        for (k, i) in range.clone().enumerate() {
            s += delta[j0 + k].abs() / cam.params()[i].abs().max(1.0);
        }
    }
    s
}

/// Levenberg-Marquardt over the pose and `inp.free`'s intrinsics (the focal length within
/// `inp.focal_range`, the start's moved into it) from `(r0, t0, camera)`
/// (`x_cam = R X + t`), at most `max_iterations` iterations ([`MAX_ITERATIONS`] to
/// convergence; RANSAC's local fits take a few, their result only re-scored). Returns `None`
/// if the start has a point at depth 0 (or a non-finite residual).
pub(crate) fn refine_intrinsics(
    inp: &IntrinsicsInputs<'_>,
    r0: &Matrix3<f64>,
    t0: &Vector3<f64>,
    camera: &Camera,
    max_iterations: u32,
) -> Option<IntrinsicsOutcome> {
    // Conditioning: world points relative to their weighted centroid.
    let (mut sum, mut wsum) = (Vector3::zeros(), 0.0);
    for (i, x) in inp.world.iter().enumerate() {
        let w = inp.weights.map_or(1.0, |w| w[i]);
        if w > 0.0 {
            sum += x.coords * w;
            wsum += w;
        }
    }
    if !(wsum > 0.0) {
        return None;
    }
    let lay = Layout::new(camera, inp.free);
    let m = lay.len;
    let x0 = sum / wsum;
    let mut r = *r0;
    let mut t = t0 + r0 * x0;
    // The start within the focal range.
    let mut cam = *camera;
    if lay.focal.is_some() {
        let (f, (lo, hi)) = (cam.focal_lengths().0, inp.focal_range);
        if !(lo <= hi) {
            return None;
        }
        cam = cam.with_focal_scale(f.clamp(lo, hi) / f);
    }
    // The depth signs at the start, which no accepted step changes (as `refine`'s).
    let mut front = vec![false; inp.world.len()];
    let (mut e, mut h, mut g) = normal(inp, &lay, &x0, (&r, &t, &cam), &mut front, true)?;
    let mut lam = 1e-6;
    let mut converged = false;
    let mut iterations = 0;
    for it in 1..=max_iterations {
        iterations = it;
        // Marquardt: the damping scaled by the diagonal (a parameter the points do not
        // constrain, a zero column, damped at a tiny fraction of the largest); the unused
        // parameters' rows the identity.
        let big = (0..m).map(|j| h[(j, j)]).fold(0.0, f64::max);
        let mut hd = h;
        for j in 0..MAX_FREE {
            if j < m {
                hd[(j, j)] += lam * h[(j, j)].max(1e-12 * big).max(1e-300);
            } else {
                hd[(j, j)] = 1.0;
            }
        }
        let Some(delta) = solve_damped(&hd, &g, m) else {
            lam *= 10.0;
            if lam > 1e16 {
                break;
            }
            continue;
        };
        let w = Vector3::new(delta[0], delta[1], delta[2]);
        let dt = Vector3::new(delta[3], delta[4], delta[5]);
        let scale = t.norm() + 1.0;
        if w.norm() + dt.norm() / scale + step_size(&cam, &lay, &delta) <= XTOL {
            converged = true;
            break;
        }
        let r_new = exp_so3(&w) * r;
        let t_new = t + dt;
        let next = step_camera(&cam, &lay, &delta, inp.focal_range).and_then(|c| {
            normal(inp, &lay, &x0, (&r_new, &t_new, &c), &mut front, false).map(|n| (c, n))
        });
        match next {
            Some((c, (e_new, h_new, g_new))) if e_new < e => {
                let small = (e - e_new) <= FTOL * e;
                (r, t, cam, e, h, g) = (r_new, t_new, c, e_new, h_new, g_new);
                lam = (lam / 10.0).max(1e-12);
                if small {
                    converged = true;
                    break;
                }
            }
            _ => {
                lam *= 10.0;
                if lam > 1e16 {
                    // No step lowers the cost: a minimum to working precision.
                    converged = true;
                    break;
                }
            }
        }
    }
    Some(IntrinsicsOutcome {
        r,
        t: t - r * x0,
        camera: cam,
        cost: e,
        iterations,
        converged,
    })
}

/// `inp` with the least-squares loss.
fn squared<'a>(inp: &IntrinsicsInputs<'a>) -> IntrinsicsInputs<'a> {
    IntrinsicsInputs {
        world: inp.world,
        pixels: inp.pixels,
        weights: inp.weights,
        free: inp.free,
        focal_range: inp.focal_range,
        loss: Loss::Squared,
    }
}

/// The (weighted) sum of squared pixel residuals at `out`, without the loss (`None` if a
/// point of weight > 0 is at depth 0).
pub(crate) fn squared_cost(inp: &IntrinsicsInputs<'_>, out: &IntrinsicsOutcome) -> Option<f64> {
    let inp = squared(inp);
    let lay = Layout::new(&out.camera, inp.free);
    let mut front = vec![false; inp.world.len()];
    let zero = Vector3::zeros();
    normal(
        &inp,
        &lay,
        &zero,
        (&out.r, &out.t, &out.camera),
        &mut front,
        true,
    )
    .map(|n| n.0)
}

/// The covariance of the pose and the free intrinsics at `out` (the same normal equations
/// without the loss, as the pose's covariance with a loss is, at the world's origin so that
/// the translation is `t`'s): `sigma^2 (J^T W J)^-1` over the
/// layout's parameters, the noise `sigma` given or estimated as `sqrt(E / (2 n - p))` (`n` the
/// points of weight > 0, `p` the free parameters). Returns the pose's marginal covariance
/// of `[w, dt]` (`R = Exp(w) R_hat`), the focal length's standard deviation (pixels, the first
/// focal length; `None` when it is not free) and `sigma`, or `None` if the normal equations are
/// not positive definite or the noise is not finite.
pub(crate) fn covariance(
    inp: &IntrinsicsInputs<'_>,
    out: &IntrinsicsOutcome,
    sigma: Option<f64>,
) -> Option<(SMatrix<f64, 6, 6>, Option<f64>, f64)> {
    let inp = &squared(inp);
    let lay = Layout::new(&out.camera, inp.free);
    let m = lay.len;
    let mut front = vec![false; inp.world.len()];
    let (e, h, _) = normal(
        inp,
        &lay,
        &Vector3::zeros(),
        (&out.r, &out.t, &out.camera),
        &mut front,
        true,
    )?;
    let n = (0..inp.world.len())
        .filter(|&i| inp.weights.is_none_or(|w| w[i] > 0.0))
        .count();
    if 2 * n <= m {
        return None;
    }
    let sigma = sigma.unwrap_or_else(|| (e / (2 * n - m) as f64).sqrt());
    if !(sigma.is_finite() && sigma >= 0.0) {
        return None;
    }
    let mut hm = h;
    for j in m..MAX_FREE {
        hm[(j, j)] = 1.0;
    }
    let inv = hm.cholesky()?.inverse() * (sigma * sigma);
    let pose = inv.fixed_view::<6, 6>(0, 0).into_owned();
    let focal_sigma = lay
        .focal
        .map(|j| out.camera.focal_lengths().0 * inv[(j, j)].max(0.0).sqrt());
    Some((pose, focal_sigma, sigma))
}

#[cfg(test)]
#[path = "../../tests/unit/pipeline/refine_intrinsics.rs"]
mod tests;
