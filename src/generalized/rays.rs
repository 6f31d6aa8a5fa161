//! The rays of a rig problem: each pixel undistorted through its camera and turned into a ray of
//! the rig frame (its camera's centre and a unit direction), and the working frame the search
//! runs in.

use nalgebra::{Matrix3, Point2, Point3, Vector3};

use crate::error::{DegenerateKind, InputKind, PnpError};
use crate::numeric::lanes::dispatched;
use crate::numeric::mat3::sym_eigen3_closed;
use crate::pipeline::refine_rig::RigCamera;
use crate::rig::Rig;

/// Pixels undistorted at a time (a bit each in the failure mask).
const UNDISTORT_CHUNK: usize = 64;

/// A rig problem as the solver reads it.
#[derive(Clone, Copy)]
pub(crate) struct RigInput<'a> {
    pub world: &'a [Point3<f64>],
    pub pixels: &'a [Point2<f64>],
    pub cameras: &'a [u32],
    pub rig: &'a Rig,
    pub weights: Option<&'a [f64]>,
    /// The known vertical, in the rig's frame ([`crate::Problem::gravity`]).
    pub gravity: Option<crate::gravity::Gravity>,
}

/// One kept correspondence (its pixel undistorts): the indices into the input, the ray.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Ray {
    /// Index of the correspondence in the caller's slices.
    pub index: usize,
    /// Its camera.
    pub camera: usize,
    /// Its weight (the caller's, 1 without weights; > 0).
    pub weight: f64,
    /// The ray's centre (its camera's centre) in the rig frame.
    pub centre: Vector3<f64>,
    /// The ray's unit direction in the rig frame.
    pub direction: Vector3<f64>,
}

/// The kept correspondences' observations as the pixel refinement reads them, in the rays'
/// order (grouped by camera): world points, pixels, weights, and one [`RigCamera`] per run of
/// one camera's rays.
#[derive(Clone)]
pub(crate) struct Observations {
    pub world: Vec<Point3<f64>>,
    pub pixels: Vec<Point2<f64>>,
    /// The pixels undistorted: normalised image points (a camera without distortion refines
    /// on these, [`RigCamera::rows`]).
    pub normalised: Vec<Point2<f64>>,
    /// Empty when every weight is 1.
    pub weights: Vec<f64>,
    pub cameras: Vec<RigCamera>,
    /// The sum of the weights, in the rays' order.
    pub weight_sum: f64,
}

/// The rays of a problem and what the later stages need of it.
#[derive(Clone)]
pub(crate) struct Rays {
    /// Grouped by camera (in the input's order within each camera).
    pub rays: Vec<Ray>,
    /// Their observations, in the same order.
    pub obs: Observations,
    /// Correspondences left out: their pixel could not be undistorted.
    pub skipped: usize,
    /// The working frame: world points `(X - x_mean) / scale`, centres `(c - c_mean) / scale`.
    pub x_mean: Vector3<f64>,
    pub c_mean: Vector3<f64>,
    pub scale: f64,
    /// Each camera's centre in the working frame, by index.
    pub working_centres: Vec<Vector3<f64>>,
    /// The scatter of the centred world points, smallest eigenvalue over the largest: the
    /// planarity ratio of the central solver's `branch`.
    pub planarity: f64,
}

impl Rays {
    /// The rays `keep` selects (one flag per ray) with their observations, in the same
    /// working frame: RANSAC's inlier sets.
    pub(crate) fn subset(&self, rig: &Rig, keep: &[bool]) -> Rays {
        let pick = |k: &usize| keep[*k];
        let kept: Vec<usize> = (0..self.rays.len()).filter(pick).collect();
        let rays: Vec<Ray> = kept.iter().map(|&k| self.rays[k]).collect();
        let weighted = rays.iter().any(|r| r.weight != 1.0);
        let obs = Observations {
            world: kept.iter().map(|&k| self.obs.world[k]).collect(),
            pixels: kept.iter().map(|&k| self.obs.pixels[k]).collect(),
            normalised: kept.iter().map(|&k| self.obs.normalised[k]).collect(),
            weights: if weighted {
                rays.iter().map(|r| r.weight).collect()
            } else {
                Vec::new()
            },
            cameras: runs(&rays, rig),
            weight_sum: rays.iter().map(|r| r.weight).sum(),
        };
        Rays {
            rays,
            obs,
            working_centres: self.working_centres.clone(),
            ..*self
        }
    }
}

/// Camera `k` of the rig as the refinement reads it, with its observations `range`.
fn rig_camera(rig: &Rig, k: usize, range: core::ops::Range<usize>) -> RigCamera {
    let (rk, tk) = rig.pose(k);
    let camera = &rig.cameras()[k];
    let (fx, fy) = camera.focal_lengths();
    RigCamera {
        projector: *rig.projector(k),
        rows: (!camera.has_distortion()).then_some((fx * fx, fy * fy)),
        rotation: *rk,
        translation: *tk,
        range,
    }
}

/// One [`RigCamera`] per run of rays of one camera.
fn runs(rays: &[Ray], rig: &Rig) -> Vec<RigCamera> {
    let mut out: Vec<RigCamera> = Vec::new();
    let mut start = 0;
    while start < rays.len() {
        let cam = rays[start].camera;
        let end = start + rays[start..].iter().take_while(|r| r.camera == cam).count();
        out.push(rig_camera(rig, cam, start..end));
        start = end;
    }
    out
}

/// The camera every correspondence is in, if they are all in one (after checking the indices'
/// count and range, so that a bad index is reported as on the general path).
///
/// # Errors
/// [`PnpError::CameraIndicesLength`], [`PnpError::UnknownCamera`].
pub(crate) fn one_camera(input: &RigInput<'_>) -> Result<Option<usize>, PnpError> {
    if input.cameras.len() != input.world.len() {
        return Err(PnpError::CameraIndicesLength {
            indices: input.cameras.len(),
            points: input.world.len(),
        });
    }
    let n = input.rig.cameras().len();
    if let Some((index, &camera)) = input
        .cameras
        .iter()
        .enumerate()
        .find(|(_, &c)| c as usize >= n)
    {
        return Err(PnpError::UnknownCamera { index, camera });
    }
    let first = input.cameras.first().copied();
    Ok(first
        .filter(|f| input.cameras.iter().all(|c| c == f))
        .map(|f| f as usize))
}

/// Checks a rig problem (the documented error order: lengths, weights, non-finite values,
/// camera indices), undistorts every pixel through its camera and forms the rays; a pixel that
/// cannot be undistorted is left out (counted in `skipped`), a point of weight 0 too.
///
/// # Errors
/// [`PnpError`] for mismatched lengths, bad weights, non-finite input, unknown cameras, fewer
/// than four usable correspondences, coincident or collinear world points.
pub(crate) fn rays(input: &RigInput<'_>) -> Result<Rays, PnpError> {
    let n = input.world.len();
    if input.pixels.len() != n {
        return Err(PnpError::LengthMismatch {
            world: n,
            image: input.pixels.len(),
        });
    }
    if input.cameras.len() != n {
        return Err(PnpError::CameraIndicesLength {
            indices: input.cameras.len(),
            points: n,
        });
    }
    if let Some(w) = input.weights {
        if w.len() != n {
            return Err(PnpError::WeightsLength {
                weights: w.len(),
                points: n,
            });
        }
    }
    if !all_valid(input) {
        if let Some(e) = first_invalid(input) {
            return Err(e);
        }
    }
    let n_cams = input.rig.cameras().len();
    // The correspondences grouped by camera (in their order within each camera) by a counting
    // sort: `end[k]` ends camera k's run and starts camera k + 1's.
    let mut end = vec![0usize; n_cams + 1];
    for &c in input.cameras {
        end[c as usize + 1] += 1;
    }
    for k in 0..n_cams {
        end[k + 1] += end[k];
    }
    let mut order = vec![0usize; n];
    for (i, &c) in input.cameras.iter().enumerate() {
        let at = &mut end[c as usize];
        order[*at] = i;
        *at += 1;
    }
    // Camera by camera, a chunk of its pixels at a time: gathered in the grouped order,
    // undistorted, turned into unit directions of the rig frame, then written at the end of
    // the kept ones (each entry written, the count advanced only for a kept one: a pixel that
    // does not undistort, or of weight 0, is overwritten by the next).
    let zero_ray = Ray {
        index: 0,
        camera: 0,
        weight: 0.0,
        centre: Vector3::zeros(),
        direction: Vector3::zeros(),
    };
    let mut rays = vec![zero_ray; n];
    let mut world = vec![Point3::origin(); n];
    let mut pixels = vec![Point2::origin(); n];
    let mut normalised = vec![Point2::origin(); n];
    let mut weights = if input.weights.is_some() {
        vec![0.0; n]
    } else {
        Vec::new()
    };
    let (mut kept, mut skipped) = (0usize, 0usize);
    // The weighted sums of the centroids, in the rays' order.
    let (mut wsum, mut xw, mut cw) = (0.0f64, Vector3::zeros(), Vector3::zeros());
    let mut src = [Point2::origin(); UNDISTORT_CHUNK];
    let mut points = [Point2::origin(); UNDISTORT_CHUNK];
    let mut dirs = [[0.0f64; UNDISTORT_CHUNK]; 3];
    let mut cameras = Vec::with_capacity(n_cams);
    for k in 0..n_cams {
        let (begin, stop) = (if k == 0 { 0 } else { end[k - 1] }, end[k]);
        let first = kept;
        let (rk, _) = input.rig.pose(k);
        let centre = input.rig.centre(k).coords;
        for chunk in order[begin..stop].chunks(UNDISTORT_CHUNK) {
            let len = chunk.len();
            for (s, &i) in src.iter_mut().zip(chunk) {
                *s = input.pixels[i];
            }
            let mut failed = 0u64;
            input
                .rig
                .projector(k)
                .undistort_into(&src[..len], &mut points[..len], None, |j| {
                    failed |= 1 << j;
                });
            unit_directions(rk, &points[..len], &mut dirs);
            for (j, &i) in chunk.iter().enumerate() {
                let ok = failed >> j & 1 == 0;
                skipped += usize::from(!ok);
                let weight = input.weights.map_or(1.0, |w| w[i]);
                let keep = ok & (weight > 0.0);
                let wk = if keep { weight } else { 0.0 };
                wsum += wk;
                xw += input.world[i].coords * wk;
                cw += centre * wk;
                world[kept] = input.world[i];
                pixels[kept] = src[j];
                normalised[kept] = points[j];
                if let Some(w) = weights.get_mut(kept) {
                    *w = weight;
                }
                rays[kept] = Ray {
                    index: i,
                    camera: k,
                    weight,
                    centre,
                    direction: Vector3::new(dirs[0][j], dirs[1][j], dirs[2][j]),
                };
                kept += usize::from(keep);
            }
        }
        if kept > first {
            cameras.push(rig_camera(input.rig, k, first..kept));
        }
    }
    rays.truncate(kept);
    world.truncate(kept);
    weights.truncate(kept);
    pixels.truncate(kept);
    normalised.truncate(kept);
    if weights.iter().all(|&w| w == 1.0) {
        weights = Vec::new();
    }
    if rays.len() < 4 {
        return Err(PnpError::TooFewPoints {
            got: rays.len(),
            need: 4,
        });
    }
    let first = world[0];
    if world.iter().all(|x| *x == first) {
        return Err(PnpError::Degenerate(DegenerateKind::CoincidentWorldPoints));
    }
    // The working frame: weighted centroids, the RMS distance of the world points.
    let x_mean = xw / wsum;
    let c_mean = cw / wsum;
    let mut sc = [0.0f64; 6];
    for (x, r) in world.iter().zip(&rays) {
        let d = x.coords - x_mean;
        let wd = d * r.weight;
        sc[0] += wd.x * d.x;
        sc[1] += wd.x * d.y;
        sc[2] += wd.x * d.z;
        sc[3] += wd.y * d.y;
        sc[4] += wd.y * d.z;
        sc[5] += wd.z * d.z;
    }
    let scatter = Matrix3::new(
        sc[0], sc[1], sc[2], sc[1], sc[3], sc[4], sc[2], sc[4], sc[5],
    ) / wsum;
    let scale = scatter.trace().sqrt();
    if !(scale > 0.0 && scale.is_finite()) {
        return Err(PnpError::Degenerate(if scale == 0.0 {
            DegenerateKind::CoincidentWorldPoints
        } else {
            DegenerateKind::ScaleOutOfRange
        }));
    }
    // Eigenvalues descending, each to about u times the largest (1).
    let (vals, vecs) = sym_eigen3_closed(&(scatter / (scale * scale)))
        .ok_or(PnpError::Degenerate(DegenerateKind::ScaleOutOfRange))?;
    let ev = [vals[2], vals[1], vals[0]];
    // Collinear: every centred point within 1e-8 of its distance from the centroid of the
    // principal line, as the central solver's `frame` (its second singular value at most
    // 1e-8 times the first). Measured on the points themselves (one O(N) pass), not on the
    // scatter's small eigenvalue, whose rounding is u times the largest. The pass is not
    // needed when the second eigenvalue alone rules it out: the largest squared distance off
    // the line is at least the weighted mean, `(ev[0] + ev[1]) scale^2`, and the largest along
    // it at most `sum w |d|^2 / w_min = wsum scale^2 / w_min`; the eigenvalues' rounding (u
    // times the largest, 1) is far below the margin of 1e-12.
    let w_min = weights.iter().copied().fold(1.0f64, f64::min);
    if !(ev[1] > 1e-12 * (wsum / w_min)) {
        let axis = vecs.column(0).into_owned();
        // (Squared distances: no square root per point.)
        let (mut off_line2, mut along2) = (0.0f64, 0.0f64);
        for x in &world {
            let d = x.coords - x_mean;
            let a = d.dot(&axis);
            off_line2 = off_line2.max((d - axis * a).norm_squared());
            along2 = along2.max(a * a);
        }
        if off_line2 <= 1e-16 * along2 {
            return Err(PnpError::Degenerate(DegenerateKind::CollinearWorldPoints));
        }
    }
    let obs = Observations {
        cameras,
        weight_sum: wsum,
        world,
        pixels,
        normalised,
        weights,
    };
    let working_centres = (0..n_cams)
        .map(|k| (input.rig.centre(k).coords - c_mean) / scale)
        .collect();
    Ok(Rays {
        rays,
        obs,
        working_centres,
        skipped,
        x_mean,
        c_mean,
        scale,
        planarity: ev[0].max(0.0) / ev[2],
    })
}

dispatched! {
/// The unit directions `R_k^T (m, 1) / |R_k^T (m, 1)|` of a chunk's points `m` (in the rig
/// frame, camera `k`'s rotation `R_k`), coordinate by coordinate in `out`: vectorised across
/// points, built for the processor ([`crate::numeric::lanes::dispatched`]). The same operations
/// as nalgebra's `normalize` (the norm, then each coordinate divided by it).
fn unit_directions[][](
        rk: &Matrix3<f64>,
        points: &[Point2<f64>],
        out: &mut [[f64; UNDISTORT_CHUNK]; 3],
    ) -> () = unit_directions_body;
}

#[inline(always)]
fn unit_directions_body(
    rk: &Matrix3<f64>,
    points: &[Point2<f64>],
    out: &mut [[f64; UNDISTORT_CHUNK]; 3],
) {
    let [ox, oy, oz] = out;
    for (((m, x), y), z) in points.iter().zip(ox).zip(oy).zip(oz) {
        // R^T (m.x, m.y, 1): column a of R dotted with (m.x, m.y, 1).
        let d = rk.tr_mul(&Vector3::new(m.x, m.y, 1.0));
        let norm = d.norm();
        (*x, *y, *z) = (d.x / norm, d.y / norm, d.z / norm);
    }
}

/// Every value finite, every weight at least 0, every camera index known: one pass without
/// branches or a dependency chain longer than a bitwise `and`.
fn all_valid(input: &RigInput<'_>) -> bool {
    let mut ok = true;
    for (x, m) in input.world.iter().zip(input.pixels) {
        ok &=
            x.x.is_finite() & x.y.is_finite() & x.z.is_finite() & m.x.is_finite() & m.y.is_finite();
    }
    if let Some(w) = input.weights {
        for &v in w {
            ok &= v.is_finite() & (v >= 0.0);
        }
    }
    let n_cams = input.rig.cameras().len();
    let highest = input
        .cameras
        .iter()
        .copied()
        .max()
        .map_or(0, |c| c as usize + 1);
    ok && highest <= n_cams
}

/// The error of the first invalid correspondence (in the order of the checks: a non-finite
/// world point, pixel or weight, a negative weight, an unknown camera), if any.
fn first_invalid(input: &RigInput<'_>) -> Option<PnpError> {
    for i in 0..input.world.len() {
        if !input.world[i].coords.iter().all(|v| v.is_finite()) {
            return Some(PnpError::NonFinite {
                index: i,
                input: InputKind::World,
            });
        }
        let p = input.pixels[i];
        if !(p.x.is_finite() && p.y.is_finite()) {
            return Some(PnpError::NonFinite {
                index: i,
                input: InputKind::Image,
            });
        }
        if let Some(w) = input.weights {
            if !w[i].is_finite() {
                return Some(PnpError::NonFinite {
                    index: i,
                    input: InputKind::Weight,
                });
            }
            if w[i] < 0.0 {
                return Some(PnpError::InvalidWeight { index: i });
            }
        }
        if input.cameras[i] as usize >= input.rig.cameras().len() {
            return Some(PnpError::UnknownCamera {
                index: i,
                camera: input.cameras[i],
            });
        }
    }
    None
}
