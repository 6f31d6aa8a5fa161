//! S1 of ALGORITHM.md: input validation and the normalised working frame.
//!
//! | symbol | meaning |
//! |---|---|
//! | `X_i`, `m_i`, `w_i` | world point, image point (normalised), weight (1 without weights) |
//! | `c` | weighted centroid `sum w_i X_i / sum w_i` |
//! | `Pc_i` | `X_i - c` |
//! | `Rw` | right singular vectors (rows) of the matrix with rows `sqrt(w_i) Pc_i^T` |
//! | `d` | weighted RMS distance `sqrt(sum w_i |Pc_i|^2 / sum w_i)` |
//! | `P_i` | working-frame point `Rw Pc_i / d` (centred, principal axes, unit RMS) |
//! | `ratio` | `sv2 / sv0` (planarity; plane normal = working-frame z) |
//!
//! Cost: three O(N) passes (validation and ranges; weighted means; a streamed Givens QR of the
//! centred rows), no allocation. The N x 3 SVD is the SVD of the 3 x 3 triangular factor R
//! (trap T9: the scatter matrix `sum Pc_i Pc_i^T` is never formed, it would square the
//! singular values). The 3 x 3 SVD is [`crate::rotation::svd3`] (one-sided Jacobi), not
//! nalgebra's `Matrix3::svd`, which in nalgebra 0.35 goes through the eigen-decomposition of
//! `A^T A` and so squares them again.
//!
//! Range safety: world coordinates, image coordinates and weights are divided by exact powers
//! of two near their largest magnitudes before any square is formed, so inputs from ~1e-300 to
//! ~1e300 give the same frame (up to the exact power-of-two factors) and nothing overflows.
//! Inputs whose normalisation would overflow (|X| above about 4e307) or whose spread is below
//! the normal `f64` range are rejected with [`DegenerateKind::ScaleOutOfRange`].
//!
//! Weights: a point with `w_i = 0` is skipped by every pass (it is still checked for
//! finiteness), so it gives results bit-identical to removing it.

use nalgebra::{Matrix3, Point2, Point3, Vector2, Vector3};

use crate::error::{DegenerateKind, InputKind, PnpError};
use crate::rotation::{pow2_scale, svd3};

/// Minimum number of correspondences (with a weight > 0).
pub(crate) const MIN_POINTS: usize = 4;
/// S1 collinearity test: collinear if `sv1 <= COLLINEAR_TOL * sv0`.
pub(crate) const COLLINEAR_TOL: f64 = 1e-8;
/// S1 image-spread test: coincident unless `spread > IMAGE_SPREAD_TOL * max(1, max |m|)`.
pub(crate) const IMAGE_SPREAD_TOL: f64 = 1e-12;

/// The normalised working frame of S1: `P = Rw (X - c) / d`.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct WorkingFrame {
    /// Weighted centroid of the world points.
    pub c: Vector3<f64>,
    /// Weighted RMS distance of the world points to `c` (> 0, a normal f64).
    pub d: f64,
    /// Principal axes as rows (singular values descending, det +1); identity if not aligned.
    pub rw: Matrix3<f64>,
    /// Planarity `sv2 / sv0` (computed even when not aligned).
    pub ratio: f64,
    /// Number of correspondences with a weight > 0 (N without weights).
    pub n_active: usize,
}

impl WorkingFrame {
    /// World point to the working frame: `Rw (x - c) / d`.
    #[inline]
    pub(crate) fn to_working(&self, x: &Point3<f64>) -> Vector3<f64> {
        (self.rw * (x.coords - self.c)) * (1.0 / self.d)
    }

    /// Working-frame pose to the world pose (S8): `(R Rw, d t - R Rw c)`.
    ///
    /// Both poses give the same projection of every point. The result can overflow only if
    /// the world coordinates themselves are near the f64 limit; callers check finiteness.
    pub(crate) fn to_world(
        &self,
        r_work: &Matrix3<f64>,
        t_work: &Vector3<f64>,
    ) -> (Matrix3<f64>, Vector3<f64>) {
        let r = r_work * self.rw;
        let t = t_work * self.d - r * self.c;
        (r, t)
    }

    /// Inverse of [`WorkingFrame::to_world`]: `(R_world Rw^T, (t_world + R_world c) / d)`.
    #[cfg(test)]
    pub(crate) fn to_work_pose(
        &self,
        r_world: &Matrix3<f64>,
        t_world: &Vector3<f64>,
    ) -> (Matrix3<f64>, Vector3<f64>) {
        let r = r_world * self.rw.transpose();
        let t = (t_world + r_world * self.c) * (1.0 / self.d);
        (r, t)
    }
}

/// Weight of point `i` (1 without weights).
#[inline]
fn weight(weights: Option<&[f64]>, i: usize) -> f64 {
    match weights {
        Some(w) => w[i],
        None => 1.0,
    }
}

/// `sqrt(a^2 + b^2)` without spurious underflow/overflow; fast path for ordinary magnitudes.
#[inline]
fn hyp(a: f64, b: f64) -> f64 {
    let m = a.abs().max(b.abs());
    if m > 1e-150 && m < 1e150 {
        (a * a + b * b).sqrt()
    } else {
        a.hypot(b)
    }
}

/// Upper-triangular factor of a QR factorisation, updated one row at a time with Givens
/// rotations. A zero row leaves it bit-identical (every rotation is skipped).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct TriangularFactor {
    /// The factor; only the upper triangle is used (the strict lower triangle stays 0).
    pub r: Matrix3<f64>,
}

impl TriangularFactor {
    /// The factor of an empty matrix (zero).
    pub(crate) fn new() -> Self {
        Self {
            r: Matrix3::zeros(),
        }
    }

    /// Append the row `y`: `R^T R := R^T R + y y^T`, keeping R upper triangular with a
    /// non-negative diagonal. 3 rotations, at most 3 square roots.
    #[inline]
    pub(crate) fn add_row(&mut self, y: &Vector3<f64>) {
        let mut y = *y;
        for k in 0..3 {
            if y[k] == 0.0 {
                continue;
            }
            let a = self.r[(k, k)];
            let rho = hyp(a, y[k]);
            let c = a / rho;
            let s = y[k] / rho;
            self.r[(k, k)] = rho;
            y[k] = 0.0;
            for j in (k + 1)..3 {
                let rkj = self.r[(k, j)];
                self.r[(k, j)] = c * rkj + s * y[j];
                y[j] = c * y[j] - s * rkj;
            }
        }
    }
}

/// S1: validate the input and compute the working frame.
///
/// Checks, in this order (the first failing one is reported): lengths of world and image
/// ([`PnpError::LengthMismatch`]); length of the weights ([`PnpError::WeightsLength`]);
/// N >= 4 ([`PnpError::TooFewPoints`] with `got = N`); every coordinate and weight finite,
/// scanning index by index, world before image before weight ([`PnpError::NonFinite`]); no
/// negative weight ([`PnpError::InvalidWeight`]); at least 4 points with a weight > 0
/// ([`PnpError::TooFewPoints`] with `got` = that count); world range
/// ([`DegenerateKind::ScaleOutOfRange`] if a coordinate exceeds `f64::MAX / 4`); coincident
/// world points; collinear world points (`sv1 <= 1e-8 sv0`); world spread below the normal
/// range ([`DegenerateKind::ScaleOutOfRange`]); coincident image points (weighted RMS spread
/// `<= 1e-12 max(1, max |m|)`). All range quantities are taken over points with weight > 0.
///
/// `align = false` keeps the user's axes (`rw = I`; a test option, valid for non-planar
/// input only); every check still runs and `ratio` is still computed.
pub(crate) fn working_frame(
    world: &[Point3<f64>],
    image: &[Point2<f64>],
    weights: Option<&[f64]>,
    align: bool,
) -> Result<WorkingFrame, PnpError> {
    let n = world.len();
    if image.len() != n {
        return Err(PnpError::LengthMismatch {
            world: n,
            image: image.len(),
        });
    }
    if let Some(w) = weights {
        if w.len() != n {
            return Err(PnpError::WeightsLength {
                weights: w.len(),
                points: n,
            });
        }
    }
    if n < MIN_POINTS {
        return Err(PnpError::TooFewPoints {
            got: n,
            need: MIN_POINTS,
        });
    }

    // Pass 1: finiteness, weight signs, active count, ranges (over active points).
    let mut first_negative: Option<usize> = None;
    let mut n_active = 0usize;
    let mut xmax = 0.0f64;
    let mut mmax = 0.0f64;
    let mut wmax = 0.0f64;
    for i in 0..n {
        let x = &world[i];
        if !(x.x.is_finite() && x.y.is_finite() && x.z.is_finite()) {
            return Err(PnpError::NonFinite {
                index: i,
                input: InputKind::World,
            });
        }
        let m = &image[i];
        if !(m.x.is_finite() && m.y.is_finite()) {
            return Err(PnpError::NonFinite {
                index: i,
                input: InputKind::Image,
            });
        }
        let w = weight(weights, i);
        if !w.is_finite() {
            return Err(PnpError::NonFinite {
                index: i,
                input: InputKind::Weight,
            });
        }
        if w < 0.0 && first_negative.is_none() {
            first_negative = Some(i);
        }
        if w > 0.0 {
            n_active += 1;
            xmax = xmax.max(x.coords.amax());
            mmax = mmax.max(m.coords.amax());
            wmax = wmax.max(w);
        }
    }
    if let Some(index) = first_negative {
        return Err(PnpError::InvalidWeight { index });
    }
    if n_active < MIN_POINTS {
        return Err(PnpError::TooFewPoints {
            got: n_active,
            need: MIN_POINTS,
        });
    }
    if xmax > f64::MAX / 4.0 {
        return Err(PnpError::Degenerate(DegenerateKind::ScaleOutOfRange));
    }
    if xmax == 0.0 {
        return Err(PnpError::Degenerate(DegenerateKind::CoincidentWorldPoints));
    }
    // Exact power-of-two units: scaled world coordinates in [-2, 2], the largest weight in
    // [1, 2), scaled image coordinates in [-2, 2].
    let sx = pow2_scale(xmax);
    let sw = pow2_scale(wmax);
    let sm = if mmax > 0.0 { pow2_scale(mmax) } else { 1.0 };

    // Pass 2: weighted means (scaled units).
    let mut wsum = 0.0f64;
    let mut xsum = Vector3::<f64>::zeros();
    let mut msum = Vector2::<f64>::zeros();
    for i in 0..n {
        let w = weight(weights, i);
        if w <= 0.0 {
            continue;
        }
        let w = w / sw;
        wsum += w;
        xsum += (world[i].coords / sx) * w;
        msum += (image[i].coords / sm) * w;
    }
    let cs = xsum / wsum;
    let ms = msum / wsum;

    // Pass 3: streamed QR of the rows sqrt(w_i) (X_i - c) (scaled) and the image spread.
    let mut qr = TriangularFactor::new();
    let mut mspread = 0.0f64;
    for i in 0..n {
        let w = weight(weights, i);
        if w <= 0.0 {
            continue;
        }
        let w = w / sw;
        let y = world[i].coords / sx - cs;
        if weights.is_some() {
            qr.add_row(&(y * w.sqrt()));
        } else {
            qr.add_row(&y);
        }
        mspread += (image[i].coords / sm - ms).norm_squared() * w;
    }

    let rmax = qr.r.amax();
    if rmax == 0.0 {
        return Err(PnpError::Degenerate(DegenerateKind::CoincidentWorldPoints));
    }
    let svd = svd3(&qr.r).ok_or(PnpError::NoSolution)?;
    let sv = svd.s;
    if sv[0] == 0.0 {
        return Err(PnpError::Degenerate(DegenerateKind::CoincidentWorldPoints));
    }
    if sv[1] <= COLLINEAR_TOL * sv[0] {
        return Err(PnpError::Degenerate(DegenerateKind::CollinearWorldPoints));
    }
    // |R|_F^2 = sum w |Pc|^2 (scaled units); evaluate the norm in units of rmax.
    let fro = rmax * (qr.r / rmax).norm();
    let d = fro / wsum.sqrt() * sx;
    if !(d.is_finite() && d >= f64::MIN_POSITIVE) {
        return Err(PnpError::Degenerate(DegenerateKind::ScaleOutOfRange));
    }
    let spread = (mspread / wsum).sqrt();
    // (`spread` is finite here; written so that a NaN would also be rejected.)
    if spread.is_nan() || spread <= IMAGE_SPREAD_TOL * mmax.max(1.0) / sm {
        return Err(PnpError::Degenerate(DegenerateKind::CoincidentImagePoints));
    }

    let rw = if align {
        let mut rw = svd.v.transpose();
        if rw.determinant() < 0.0 {
            rw.row_mut(2).neg_mut();
        }
        rw
    } else {
        Matrix3::identity()
    };
    Ok(WorkingFrame {
        c: cs * sx,
        d,
        rw,
        ratio: sv[2] / sv[0],
        n_active,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, Rotation3};
    use rand::{Rng, SeedableRng};
    use rand_pcg::Pcg64;

    fn cloud(rng: &mut Pcg64, n: usize, planar: bool) -> (Vec<Point3<f64>>, Vec<Point2<f64>>) {
        let world: Vec<Point3<f64>> = (0..n)
            .map(|_| {
                Point3::new(
                    rng.random_range(-2.0..2.0),
                    rng.random_range(-1.0..1.0),
                    if planar {
                        0.0
                    } else {
                        rng.random_range(-0.5..0.5)
                    },
                )
            })
            .collect();
        let image = (0..n)
            .map(|_| Point2::new(rng.random_range(-0.5..0.5), rng.random_range(-0.5..0.5)))
            .collect();
        (world, image)
    }

    /// Reference frame from a dense Golub-Kahan SVD of the N x 3 matrix (nalgebra DMatrix,
    /// not the 3 x 3 special case).
    fn dense_reference(world: &[Point3<f64>], w: &[f64]) -> (Vector3<f64>, f64, Matrix3<f64>, f64) {
        let wsum: f64 = w.iter().sum();
        let c = world
            .iter()
            .zip(w)
            .fold(Vector3::zeros(), |acc, (x, &wi)| acc + x.coords * wi)
            / wsum;
        let a = DMatrix::from_fn(world.len(), 3, |i, j| {
            (world[i].coords[j] - c[j]) * w[i].sqrt()
        });
        let svd = a.clone().svd(false, true);
        let vt = svd.v_t.unwrap();
        let mut rw = Matrix3::from_fn(|i, j| vt[(i, j)]);
        if rw.determinant() < 0.0 {
            rw.row_mut(2).neg_mut();
        }
        let d = (a.norm_squared() / wsum).sqrt();
        let s = svd.singular_values;
        (c, d, rw, s[2] / s[0])
    }

    /// Rows of Rw agree up to sign (the sign of each right singular vector is arbitrary).
    fn rows_agree(a: &Matrix3<f64>, b: &Matrix3<f64>, tol: f64) -> bool {
        (0..3).all(|i| {
            let s = a.row(i).dot(&b.row(i)).signum();
            (a.row(i) - b.row(i) * s).amax() < tol
        })
    }

    #[test]
    fn matches_dense_svd() {
        let mut rng = Pcg64::seed_from_u64(11);
        for trial in 0..50 {
            let n = 4 + trial % 20;
            let (world, image) = cloud(&mut rng, n, trial % 5 == 0);
            let f = working_frame(&world, &image, None, true).unwrap();
            let (c, d, rw, ratio) = dense_reference(&world, &vec![1.0; n]);
            // Centroid and RMS: sums of O(1) values, rounding ~N eps.
            assert!((f.c - c).amax() < 1e-14);
            assert!((f.d / d - 1.0).abs() < 1e-14);
            // Singular vectors: eps / relative gap; the generated clouds have gaps >= ~0.1.
            assert!(rows_agree(&f.rw, &rw, 1e-12), "{trial}");
            assert!((f.rw.determinant() - 1.0).abs() < 1e-14);
            // ratio: absolute error ~eps (exact planar clouds give ~1e-17).
            assert!((f.ratio - ratio).abs() < 1e-14, "{} {}", f.ratio, ratio);
            assert_eq!(f.n_active, n);
            // Working-frame points: centred, unit RMS, principal axes.
            let p: Vec<Vector3<f64>> = world.iter().map(|x| f.to_working(x)).collect();
            let mean = p.iter().fold(Vector3::zeros(), |a, b| a + b) / n as f64;
            let rms = (p.iter().map(|v| v.norm_squared()).sum::<f64>() / n as f64).sqrt();
            assert!(mean.amax() < 1e-14 && (rms - 1.0).abs() < 1e-14);
            let scatter = p
                .iter()
                .fold(Matrix3::zeros(), |a, v| a + v * v.transpose());
            // Off-diagonal scatter vanishes in principal axes (relative to trace, ~1e-15).
            assert!(
                scatter[(0, 1)].abs() + scatter[(0, 2)].abs() + scatter[(1, 2)].abs()
                    < 1e-13 * n as f64
            );
            assert!(scatter[(0, 0)] >= scatter[(1, 1)] && scatter[(1, 1)] >= scatter[(2, 2)]);
        }
    }

    #[test]
    fn matches_python_reference() {
        // general_N6_sigma2 of shared/reference/test_vectors.json: inputs and the stored
        // intermediates c, d, Rw, ratio (copied verbatim).
        let pw = [
            [1.0868021275186281, -1.3378125690946359, -0.3716971277257549],
            [
                -0.08262245175874146,
                2.1404394422295856,
                0.09475780416357736,
            ],
            [0.9837802860864412, 0.6486714833868172, -1.163831730906571],
            [
                -0.16408937546260566,
                -0.6368367668076029,
                1.5540718637475532,
            ],
            [-1.281369717191685, -0.9806899121263071, 0.6735257094982209],
            [-0.5425008691920372, 0.1662283224121397, -0.7868265187770254],
        ];
        let uv = [
            [-0.0016570055124605432, -0.3422231017892266],
            [0.15776340718902354, -0.02316152452382859],
            [0.07176707780774506, -0.2872221288450443],
            [0.12902243078389844, 0.1406703442626368],
            [0.4194096267170485, 0.024480318873897174],
            [0.296668343841841, -0.20472434279129387],
        ];
        let c_ref = Vector3::new(
            3.700743415417188e-17,
            -5.551115123125783e-16,
            1.850371707708594e-17,
        );
        let d_ref = 1.6978117265587764;
        #[rustfmt::skip]
        let rw_ref = Matrix3::new(0.2536263214851283, 0.8370144007505782, -0.48485109259036724, -0.6427153944048016, 0.5204188954652214, 0.562210899074217, 0.7229042888550342, 0.16902977897077642, 0.6699539707891041);
        let ratio_ref = 0.4743882145350797;
        let world: Vec<Point3<f64>> = pw.iter().map(|p| Point3::new(p[0], p[1], p[2])).collect();
        let image: Vec<Point2<f64>> = uv.iter().map(|p| Point2::new(p[0], p[1])).collect();
        let f = working_frame(&world, &image, None, true).unwrap();
        // Same quantities from different summation orders / SVD algorithms: ~10 eps.
        assert!((f.c - c_ref).amax() < 1e-14);
        assert!((f.d - d_ref).abs() < 1e-14);
        assert!(rows_agree(&f.rw, &rw_ref, 1e-13));
        assert!((f.ratio - ratio_ref).abs() < 1e-14);
    }

    #[test]
    fn zero_weight_is_bit_identical_to_dropping() {
        let mut rng = Pcg64::seed_from_u64(12);
        for trial in 0..30 {
            let n = 8;
            let (mut world, mut image) = cloud(&mut rng, n, trial % 3 == 0);
            let mut w: Vec<f64> = (0..n).map(|_| rng.random_range(0.1..3.0)).collect();
            let reference = working_frame(&world, &image, Some(&w), true).unwrap();
            // Insert zero-weight points (far away, at various indices).
            for k in [0usize, 3, 9] {
                world.insert(k, Point3::new(1e5, -3e4, 7.0));
                image.insert(k, Point2::new(40.0, -1e3));
                w.insert(k, 0.0);
            }
            let f = working_frame(&world, &image, Some(&w), true).unwrap();
            assert_eq!(f, reference);
        }
        // A weight of 1 everywhere equals no weights, bit for bit.
        let (world, image) = cloud(&mut rng, 9, false);
        let a = working_frame(&world, &image, None, true).unwrap();
        let b = working_frame(&world, &image, Some(&[1.0; 9]), true).unwrap();
        assert_eq!(a, b);
        // Integer weights equal repeated points (up to rounding).
        let w = [2.0, 1.0, 1.0, 3.0, 1.0, 1.0, 1.0, 1.0, 1.0];
        let mut wr = Vec::new();
        let mut mr = Vec::new();
        for i in 0..9 {
            for _ in 0..(w[i] as usize) {
                wr.push(world[i]);
                mr.push(image[i]);
            }
        }
        let a = working_frame(&world, &image, Some(&w), true).unwrap();
        let b = working_frame(&wr, &mr, None, true).unwrap();
        assert!((a.c - b.c).amax() < 1e-14 && (a.d - b.d).abs() < 1e-14);
        assert!(rows_agree(&a.rw, &b.rw, 1e-12) && (a.ratio - b.ratio).abs() < 1e-14);
        assert_eq!(b.n_active, 12);
    }

    #[test]
    fn zero_row_leaves_factor_unchanged() {
        let mut f = TriangularFactor::new();
        f.add_row(&Vector3::new(1.0, 2.0, 3.0));
        f.add_row(&Vector3::new(-0.5, 0.25, 4.0));
        let before = f;
        f.add_row(&Vector3::zeros());
        assert_eq!(f, before);
        // R^T R equals the Gram matrix of the rows.
        f.add_row(&Vector3::new(0.3, -7.0, 0.1));
        let g = Vector3::new(1.0, 2.0, 3.0) * Vector3::new(1.0, 2.0, 3.0).transpose()
            + Vector3::new(-0.5, 0.25, 4.0) * Vector3::new(-0.5, 0.25, 4.0).transpose()
            + Vector3::new(0.3, -7.0, 0.1) * Vector3::new(0.3, -7.0, 0.1).transpose();
        // Entries up to ~50: rounding ~1e-14.
        assert!((f.r.transpose() * f.r - g).amax() < 1e-13);
        assert!(f.r[(1, 0)] == 0.0 && f.r[(2, 0)] == 0.0 && f.r[(2, 1)] == 0.0);
    }

    #[test]
    fn validation_errors_in_order() {
        let mut rng = Pcg64::seed_from_u64(13);
        let (world, image) = cloud(&mut rng, 6, false);
        let e = |r: Result<WorkingFrame, PnpError>| r.unwrap_err();
        assert_eq!(
            e(working_frame(&world, &image[..5], None, true)),
            PnpError::LengthMismatch { world: 6, image: 5 }
        );
        assert_eq!(
            e(working_frame(&world, &image, Some(&[1.0; 5]), true)),
            PnpError::WeightsLength {
                weights: 5,
                points: 6
            }
        );
        assert_eq!(
            e(working_frame(&world[..3], &image[..3], None, true)),
            PnpError::TooFewPoints { got: 3, need: 4 }
        );
        // Finiteness: first index, world before image before weight.
        let mut wb = world.clone();
        let mut ib = image.clone();
        wb[4].y = f64::NAN;
        ib[2].x = f64::INFINITY;
        assert_eq!(
            e(working_frame(&wb, &ib, None, true)),
            PnpError::NonFinite {
                index: 2,
                input: InputKind::Image
            }
        );
        ib[4].x = f64::NAN;
        ib[2].x = 0.0;
        assert_eq!(
            e(working_frame(&wb, &ib, None, true)),
            PnpError::NonFinite {
                index: 4,
                input: InputKind::World
            }
        );
        let mut w = [1.0; 6];
        w[1] = -1.0;
        w[3] = f64::NAN;
        assert_eq!(
            e(working_frame(&world, &image, Some(&w), true)),
            PnpError::NonFinite {
                index: 3,
                input: InputKind::Weight
            }
        );
        w[3] = 1.0;
        assert_eq!(
            e(working_frame(&world, &image, Some(&w), true)),
            PnpError::InvalidWeight { index: 1 }
        );
        let w = [1.0, 0.0, 1.0, 0.0, 1.0, 1e-300];
        assert!(working_frame(&world, &image, Some(&w), true).is_ok());
        let w = [1.0, 0.0, 1.0, 0.0, 1.0, 0.0];
        assert_eq!(
            e(working_frame(&world, &image, Some(&w), true)),
            PnpError::TooFewPoints { got: 3, need: 4 }
        );
        // Coincident world points (also at a non-zero location, and all at the origin).
        for p in [Point3::new(1.0, 2.0, 3.0), Point3::origin()] {
            let same = vec![p; 6];
            assert_eq!(
                e(working_frame(&same, &image, None, true)),
                PnpError::Degenerate(DegenerateKind::CoincidentWorldPoints)
            );
        }
        // Collinear beats coincident image points.
        let line: Vec<Point3<f64>> = (0..6)
            .map(|i| Point3::new(i as f64, 2.0 * i as f64, 1.0))
            .collect();
        let one = vec![Point2::new(0.1, 0.2); 6];
        assert_eq!(
            e(working_frame(&line, &one, None, true)),
            PnpError::Degenerate(DegenerateKind::CollinearWorldPoints)
        );
        assert_eq!(
            e(working_frame(&world, &one, None, true)),
            PnpError::Degenerate(DegenerateKind::CoincidentImagePoints)
        );
        // Image spread threshold is relative to max(1, max |m|).
        let mut far = vec![Point2::new(1e6, -2e6); 6];
        far[0].x += 1e-7; // spread ~4e-8 < 1e-12 * 2e6 = 2e-6
        assert_eq!(
            e(working_frame(&world, &far, None, true)),
            PnpError::Degenerate(DegenerateKind::CoincidentImagePoints)
        );
        far[0].x += 1e-4; // spread ~4e-5 > 2e-6
        assert!(working_frame(&world, &far, None, true).is_ok());
    }

    #[test]
    fn collinearity_threshold() {
        // ALGORITHM.md section 6: offset 0 to 1e-8 of the extent -> collinear error;
        // offset 1e-7 and above -> solvable.
        let mut rng = Pcg64::seed_from_u64(14);
        let image: Vec<Point2<f64>> = (0..10)
            .map(|_| Point2::new(rng.random_range(-0.5..0.5), rng.random_range(-0.5..0.5)))
            .collect();
        for (offset, ok) in [
            (0.0, false),
            (1e-9, false),
            (1e-8, false),
            (1e-7, true),
            (1e-3, true),
        ] {
            let world: Vec<Point3<f64>> = (0..10)
                .map(|i| {
                    let t = i as f64 / 9.0 * 2.0 - 1.0;
                    let e = Vector3::new(
                        rng.random_range(-1.0..1.0),
                        rng.random_range(-1.0..1.0),
                        rng.random_range(-1.0..1.0),
                    );
                    Point3::from(
                        Vector3::new(1.0, 2.0, -0.5) * t + e * offset + Vector3::new(3.0, 0.0, 1.0),
                    )
                })
                .collect();
            let r = working_frame(&world, &image, None, true);
            assert_eq!(r.is_ok(), ok, "offset {offset}: {r:?}");
        }
    }

    #[test]
    fn extreme_scales() {
        let mut rng = Pcg64::seed_from_u64(15);
        let (world, image) = cloud(&mut rng, 10, false);
        let base = working_frame(&world, &image, None, true).unwrap();
        // Power-of-two scaling is exact: identical frame up to the exact factor. (The image
        // is not scaled: the image-spread rule is deliberately not scale invariant.)
        for e in [-1000i32, -500, 500, 1000] {
            let s = 2f64.powi(e);
            let ws: Vec<Point3<f64>> = world.iter().map(|x| Point3::from(x.coords * s)).collect();
            let f = working_frame(&ws, &image, None, true).unwrap();
            assert_eq!(f.rw, base.rw);
            assert_eq!(f.ratio, base.ratio);
            assert_eq!(f.d, base.d * s);
            assert_eq!(f.c, base.c * s);
        }
        // Decimal scales and a large offset (millimetres at 1e6): same frame to rounding.
        for (s, off) in [(1e300, 0.0), (1e-300, 0.0), (1.0, 1e6), (1e-3, 1e6)] {
            let ws: Vec<Point3<f64>> = world
                .iter()
                .map(|x| Point3::from(x.coords * s + Vector3::repeat(off)))
                .collect();
            let f = working_frame(&ws, &image, None, true).unwrap();
            // Rounding of the inputs: off * eps / 2 absolute, i.e. off * eps / (2 s) relative to
            // the extent ~s; the principal axes amplify it by 1 / (relative gap) (~4 here).
            let tol = 1e-14 + 10.0 * off * f64::EPSILON / s;
            assert!(rows_agree(&f.rw, &base.rw, tol), "{s} {off}");
            assert!((f.d / (base.d * s) - 1.0).abs() < tol);
            assert!((f.ratio - base.ratio).abs() < tol);
        }
        // Large weights, tiny weights: invariant to the weight scale.
        let w: Vec<f64> = (0..10).map(|i| 1.0 + i as f64).collect();
        let a = working_frame(&world, &image, Some(&w), true).unwrap();
        for s in [1e300, 1e-300] {
            let ws: Vec<f64> = w.iter().map(|x| x * s).collect();
            let b = working_frame(&world, &image, Some(&ws), true).unwrap();
            // Decimal scaling rounds every weight once: ~eps relative.
            assert!((a.c - b.c).amax() < 1e-14 && (a.d / b.d - 1.0).abs() < 1e-14);
            assert!(rows_agree(&a.rw, &b.rw, 1e-13));
        }
        // Out of range: coordinates near f64::MAX, spread in the subnormal range.
        let huge: Vec<Point3<f64>> = world
            .iter()
            .map(|x| Point3::from(x.coords * 4e307))
            .collect(); // |X| up to 8e307 > f64::MAX / 4
        assert_eq!(
            working_frame(&huge, &image, None, true).unwrap_err(),
            PnpError::Degenerate(DegenerateKind::ScaleOutOfRange)
        );
        let tiny: Vec<Point3<f64>> = world
            .iter()
            .map(|x| Point3::from(x.coords * 1e-310 + Vector3::repeat(1e-300)))
            .collect();
        let r = working_frame(&tiny, &image, None, true);
        assert!(r.is_err(), "{r:?}");
        let tiny: Vec<Point3<f64>> = world
            .iter()
            .map(|x| Point3::from(x.coords * 1e-310))
            .collect();
        assert_eq!(
            working_frame(&tiny, &image, None, true).unwrap_err(),
            PnpError::Degenerate(DegenerateKind::ScaleOutOfRange)
        );
    }

    #[test]
    fn pose_maps_roundtrip_and_preserve_projection() {
        let mut rng = Pcg64::seed_from_u64(16);
        let (world, image) = cloud(&mut rng, 12, false);
        let world: Vec<Point3<f64>> = world
            .iter()
            .map(|x| Point3::from(x.coords * 7.0 + Vector3::new(100.0, -50.0, 30.0)))
            .collect();
        let f = working_frame(&world, &image, None, true).unwrap();
        let r = Rotation3::from_scaled_axis(Vector3::new(0.4, -1.2, 2.0)).into_inner();
        let t = Vector3::new(0.3, -0.1, 4.0);
        let (rwld, twld) = f.to_world(&r, &t);
        let (r2, t2) = f.to_work_pose(&rwld, &twld);
        // Round trip through O(100) world coordinates: ~1e-14 relative.
        assert!((r2 - r).amax() < 1e-14 && (t2 - t).amax() < 1e-13);
        for x in &world {
            let pw = f.to_working(x);
            let a = r * pw + t;
            let b = rwld * x.coords + twld;
            // Same projection; b = d a.
            assert!((b / f.d - a).amax() < 1e-12);
        }
        let (ri, ti) = f.to_world(&Matrix3::identity(), &Vector3::zeros());
        assert_eq!(ri, f.rw);
        assert!((ti + f.rw * f.c).amax() == 0.0);
    }

    #[test]
    fn align_false_keeps_axes() {
        let mut rng = Pcg64::seed_from_u64(17);
        let (world, image) = cloud(&mut rng, 7, false);
        let a = working_frame(&world, &image, None, true).unwrap();
        let b = working_frame(&world, &image, None, false).unwrap();
        assert_eq!(b.rw, Matrix3::identity());
        assert_eq!((a.c, a.d, a.ratio), (b.c, b.d, b.ratio));
    }
}
