use super::*;
use crate::numeric::mat3::svd3;
use nalgebra::{DMatrix, Rotation3};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

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
/// rotations. A zero row leaves it bit-identical (every rotation is skipped). (Used by the
/// reference implementation of the tests.)
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

/// The previous `frame` implementation (three passes, the streamed Givens QR of the centred rows
/// and [`svd3`] of its triangular factor), kept as the reference of the tests; its `sums` are
/// those of [`crate::pipeline::moments::accumulate`] in its frame.
///
/// Same checks in the same order as [`working_frame`], whose documentation applies.
pub(crate) fn working_frame_qr(
    world: &[Point3<f64>],
    image: &[Point2<f64>],
    weights: Option<&[f64]>,
    align: bool,
) -> Result<WorkingFrame, PnpError> {
    check_lengths(world.len(), image.len(), weights)?;
    let n = world.len();

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
    let mut frame = WorkingFrame {
        c: cs * sx,
        d,
        rw,
        ratio: sv[2] / sv[0],
        small_image: false,
        n_active,
        weight_unit: sw,
        weight_sum: wsum,
        sums: crate::pipeline::moments::Accumulator::default(),
    };
    // The sums in the weight unit, as `frame`'s.
    let mut w_unit: Vec<f64> = Vec::new();
    let weights = weights.map(|w| {
        w_unit = w.iter().map(|x| x / sw).collect();
        &w_unit[..]
    });
    frame.sums = crate::pipeline::moments::tests::accumulate(world, image, weights, &frame);
    Ok(frame)
}

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
    // general_N6_sigma2 of the reference prototype's test vectors: inputs and the stored
    // intermediates c, d, Rw, ratio.
    let r = crate::test_data::vector("general_N6_sigma2");
    let f = working_frame(&r.world, &r.image, None, true).unwrap();
    // Same quantities from different summation orders / SVD algorithms: ~10 eps.
    assert!((f.c - r.c).amax() < 1e-14);
    assert!((f.d - r.d).abs() < 1e-14);
    assert!(rows_agree(&f.rw, &r.rw, 1e-13));
    assert!((f.ratio - r.ratio).abs() < 1e-14);
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
fn image_spread_threshold_is_relative() {
    // (The other validation checks are tested through the solver: tests/validation.rs.)
    let mut rng = Pcg64::seed_from_u64(13);
    let (world, _) = cloud(&mut rng, 6, false);
    // Image spread threshold is relative to max(1, max |m|).
    let mut far = vec![Point2::new(1e6, -2e6); 6];
    far[0].x += 1e-7; // spread ~4e-8 < 1e-12 * 2e6 = 2e-6
    assert_eq!(
        working_frame(&world, &far, None, true).unwrap_err(),
        PnpError::Degenerate(DegenerateKind::CoincidentImagePoints)
    );
    far[0].x += 1e-4; // spread ~4e-5 > 2e-6
    assert!(working_frame(&world, &far, None, true).is_ok());
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
    // (Out of range scales: tests/validation.rs.)
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

/// `M`, `G` of the frame's sums, with the rows of `rw` sign-aligned to `rw_ref` (the
/// signs of the principal axes are arbitrary: `D = Rw Rw_ref^T = diag(+-1)`).
fn aligned_system(
    f: &WorkingFrame,
    rw_ref: &Matrix3<f64>,
) -> (nalgebra::SMatrix<f64, 9, 9>, nalgebra::SMatrix<f64, 3, 9>) {
    let sys = f.sums.system(false).unwrap();
    let dm = f.rw * rw_ref.transpose();
    let mut bd = nalgebra::SMatrix::<f64, 9, 9>::zeros();
    for b in 0..3 {
        for k in 0..3 {
            bd[(3 * b + k, 3 * b + k)] = dm[(k, k)].signum();
        }
    }
    (bd * sys.m * bd, sys.g * bd)
}

/// Clouds of every shape the frame distinguishes: general, near-planar with
/// `sv2 / sv0 ~ thin`, near-collinear with `sv1 / sv0 ~ thin`, optionally far from the
/// origin; image points of a camera looking at them (plus noise).
fn shaped(
    rng: &mut Pcg64,
    n: usize,
    thin: f64,
    collinear: bool,
    offset: f64,
) -> (Vec<Point3<f64>>, Vec<Point2<f64>>) {
    let r = Rotation3::from_scaled_axis(Vector3::new(
        rng.random_range(-2.0..2.0),
        rng.random_range(-2.0..2.0),
        rng.random_range(-2.0..2.0),
    ));
    let world: Vec<Point3<f64>> = (0..n)
        .map(|_| {
            let e = Vector3::new(
                rng.random_range(-2.0..2.0),
                rng.random_range(-1.0..1.0) * if collinear { thin } else { 1.0 },
                rng.random_range(-1.0..1.0) * thin,
            );
            Point3::from(r * e + Vector3::repeat(offset))
        })
        .collect();
    let image = world
        .iter()
        .map(|x| {
            let p = x.coords - Vector3::repeat(offset) + Vector3::new(0.1, -0.2, 8.0);
            Point2::new(
                p.x / p.z + 1e-3 * rng.random_range(-1.0..1.0),
                p.y / p.z + 1e-3 * rng.random_range(-1.0..1.0),
            )
        })
        .collect();
    (world, image)
}

#[test]
fn min_unit_is_two_to_minus_1000() {
    assert_eq!(MIN_UNIT, 2f64.powi(-1000));
}

/// The 3 x 3 symmetric eigen-decompositions: the cyclic Jacobi iteration and the closed form.
type Eigen3 = fn(&Matrix3<f64>) -> Option<(Vector3<f64>, Matrix3<f64>)>;
const EIGEN3: [(&str, Eigen3); 2] = [("jacobi", sym_eigen3), ("closed", sym_eigen3_closed)];

#[test]
fn sym_eigen3_accuracy() {
    // Both methods, backward stable: eigenvalues within a few eps |A| (the test matrix
    // Q L Q^T itself carries ~3 eps |A| of rounding, so 4e-15 |A|, ~18 ulps, in all),
    // orthogonal eigenvectors (a few rotations: ~10 eps, as crate::rotation's ORTH_TOL) and
    // A V = V L to rounding, including nearly coincident eigenvalues (1 and 1 +- 1e-9, where
    // the closed form's trigonometric eigenvalues alone are off by about sqrt(eps)).
    let mut rng = Pcg64::seed_from_u64(18);
    for k in 0..700 {
        let q = Rotation3::from_scaled_axis(Vector3::new(
            rng.random_range(-2.0..2.0),
            rng.random_range(-2.0..2.0),
            rng.random_range(-2.0..2.0),
        ))
        .into_inner();
        let l = match k % 7 {
            0 => Vector3::new(3.0, 2.0, 1.0),
            1 => Vector3::new(1.0, 1.0, 1e-3),
            2 => Vector3::new(1.0, 1.0, 1.0),
            3 => Vector3::new(2.0, 0.0, 0.0),
            4 => Vector3::new(1.0, 1.0 + 1e-9, 0.5),
            5 => Vector3::new(1.0, 1.0 - 1e-9, 1.0 + 2e-9),
            _ => Vector3::new(1.0, -0.5, 1e-12),
        } * 10f64.powi(k % 11 * 30 - 150);
        let a = q * Matrix3::from_diagonal(&l) * q.transpose();
        let mut sorted = l;
        sorted.as_mut_slice().sort_by(|x, y| y.total_cmp(x));
        for (name, eigen) in EIGEN3 {
            let (vals, vecs) = eigen(&a).unwrap();
            assert!(
                (vals - sorted).amax() <= 4e-15 * l.amax(),
                "{name} {k}: {vals} {sorted}"
            );
            assert!(
                (vecs.transpose() * vecs - Matrix3::identity()).amax() < 4e-15,
                "{name} {k}"
            );
            let res = a * vecs - vecs * Matrix3::from_diagonal(&vals);
            assert!(
                res.amax() <= 4e-15 * l.amax(),
                "{name} {k}: {:e}",
                res.amax() / l.amax()
            );
        }
    }
    for (name, eigen) in EIGEN3 {
        assert_eq!(
            eigen(&Matrix3::zeros()).unwrap().0,
            Vector3::zeros(),
            "{name}"
        );
        let d = eigen(&Matrix3::from_diagonal(&Vector3::new(1.0, 3.0, 2.0))).unwrap();
        assert_eq!(d.0, Vector3::new(3.0, 2.0, 1.0), "{name}");
        let mut bad = Matrix3::identity();
        bad[(0, 2)] = f64::NAN;
        assert!(eigen(&bad).is_none(), "{name}");
    }
}

#[test]
fn sym_eigen3_relative_accuracy() {
    // Relative accuracy for a graded, nearly diagonal positive definite matrix (the
    // scatter of the third pass): eigenvalues 1, 1e-8, 1e-16 with couplings 1e-16 relative
    // to the largest entry; each eigenvalue to a few eps relative.
    #[rustfmt::skip]
    let a = Matrix3::new(
        1.0, 1e-16, -2e-16,
        1e-16, 1e-8, 3e-20,
        -2e-16, 3e-20, 1e-16,
    );
    let (vals, _) = sym_eigen3(&a).unwrap();
    // Exact eigenvalues to first order: a_ii - a_1i^2 / a_11 (shifts 1e-24 and 4e-32).
    assert!((vals[1] / (1e-8 - 1e-32) - 1.0).abs() < 1e-14);
    assert!(
        (vals[2] / (1e-16 - 4e-32) - 1.0).abs() < 1e-14,
        "{}",
        vals[2]
    );
}

#[test]
fn scatter_path_matches_streamed_qr_and_forced_pass3() {
    // The fast path (frame from the scatter), the forced third pass and the previous
    // streamed-QR implementation (with the direct `moments` pass in its frame) on the same data.
    let mut rng = Pcg64::seed_from_u64(19);
    let mut fast = 0;
    for trial in 0..240 {
        let n = [4usize, 5, 9, 30, 200][trial % 5];
        let thin = [1.0, 0.3, 0.05, 1e-2, 3e-3, 1e-3, 1e-4, 1e-6, 1e-7, 0.0][trial / 5 % 10];
        let collinear = trial / 50 % 2 == 1 && thin > 0.0;
        let offset = [0.0, 1e3][trial / 100 % 2];
        let (world, image) = shaped(&mut rng, n, thin, collinear, offset);
        let w: Vec<f64> = (0..n).map(|_| rng.random_range(0.2..3.0)).collect();
        let wopt = if trial % 3 == 0 { Some(&w[..]) } else { None };
        let old = working_frame_qr(&world, &image, wopt, true);
        let new = working_frame(&world, &image, wopt, true);
        let forced = frame_impl(&world, &image, wopt, true, true);
        let (old, new, forced) = match (old, new, forced) {
            (Ok(a), Ok(b), Ok(c)) => (a, b, c),
            (a, b, c) => {
                // Same decision (the collinearity threshold is far from these shapes).
                assert_eq!(a.clone().err(), b.clone().err(), "{trial}");
                assert_eq!(a.err(), c.err(), "{trial}");
                continue;
            }
        };
        // The scatter path is taken exactly when sv2 / sv0 >= 1e-2.
        let took_fast = new != forced;
        fast += usize::from(took_fast);
        assert!(!took_fast || old.ratio > 0.9e-2, "{trial} {}", old.ratio);
        // Centroid, d: same sums (d from the trace of the scatter vs the Frobenius norm
        // of the QR factor): rounding of O(N) terms, ~N eps relative.
        let tol = 1e-13;
        let scale = 1.0 + offset;
        for f in [&new, &forced] {
            assert!((f.c - old.c).amax() <= tol * scale, "{trial}");
            assert!((f.d / old.d - 1.0).abs() <= tol, "{trial}");
            assert_eq!(f.n_active, old.n_active);
            // ratio: the QR route is accurate to ~eps / gap absolute; the scatter route to
            // ~eps / ratio (taken only for ratio >= 1e-2); the third pass like the QR.
            assert!(
                (f.ratio - old.ratio).abs() <= 1e-13 * (1.0 + offset) / thin.max(1e-3),
                "{trial}: {} {}",
                f.ratio,
                old.ratio
            );
            // M, G in the (sign-aligned) frames: within 1e-13 relative to max |M|, |G|,
            // the level of the reference check (1e-12) with a margin. The frames agree up to
            // eps / (relative eigen-gap) (the sampled clouds have gaps >= ~0.05 in the
            // first two axes; for exactly planar clouds the in-plane axes matter).
            let m_old = old.sums.system(false).unwrap();
            let (m, g) = aligned_system(f, &old.rw);
            let gold = old.sums.system(false).unwrap().g;
            let axes_tol = if offset > 0.0 { 1e-11 } else { 1e-12 };
            if rows_agree(&f.rw, &old.rw, axes_tol) {
                assert!(
                    (m - m_old.m).amax() <= 1e-12 * m_old.m.amax(),
                    "{trial}: {:e}",
                    (m - m_old.m).amax() / m_old.m.amax()
                );
                assert!((g - gold).amax() <= 1e-12 * gold.amax().max(1.0), "{trial}");
            }
            assert!((f.rw.determinant() - 1.0).abs() < 1e-14);
        }
        // Fast path vs forced third pass (same centroid and d bit for bit).
        assert_eq!((new.c, new.d), (forced.c, forced.d));
        if took_fast && rows_agree(&new.rw, &forced.rw, 1e-12) {
            let (m1, g1) = aligned_system(&new, &forced.rw);
            let s2 = forced.sums.system(false).unwrap();
            assert!(
                (m1 - s2.m).amax() <= 1e-13 * s2.m.amax(),
                "{trial}: {:e} {:e} {:e}",
                (m1 - s2.m).amax() / s2.m.amax(),
                s2.m.amax(),
                new.sums.s_q.amax()
            );
            assert!(
                (g1 - s2.g).amax() <= 1e-13 * s2.g.amax().max(1.0),
                "{trial}"
            );
            assert!((new.ratio - forced.ratio).abs() <= 1e-13, "{trial}");
        }
    }
    assert!(fast > 40, "{fast}");
}

#[test]
fn thin_clouds_resolved_like_the_svd() {
    // T9: near the collinearity threshold (sv1 / sv0 = 1e-8) and the planarity thresholds
    // (sv2 / sv0 = 1e-6, 1e-3) the frame must see the singular values of the points, not
    // those of the scatter. Exact singular values: points on a grid, rotated.
    let mut rng = Pcg64::seed_from_u64(20);
    let image: Vec<Point2<f64>> = (0..16)
        .map(|_| Point2::new(rng.random_range(-0.5..0.5), rng.random_range(-0.5..0.5)))
        .collect();
    let r = Rotation3::from_scaled_axis(Vector3::new(0.3, -1.1, 0.7));
    // +-1 patterns with zero mean and orthogonal columns: sv_k = 4 * scale_k.
    let pat = |i: usize, b: usize| if (i >> b) & 1 == 1 { 1.0 } else { -1.0 };
    for (s1, s2) in [
        (1.0, 1e-6),
        (1.0, 1.001e-6),
        (1.0, 0.999e-6),
        (1.0, 1e-3),
        (0.5, 1e-7),
        // At the threshold itself the outcome is the rounding's: sv1 / sv0 came out
        // 1e-8 (1 - 4.9e-10) with the scatter summed in point order, 1e-8 (1 + 5.1e-10) with
        // every sum in lanes. 1e-6 relative either side of it is resolved.
        (1e-8 * (1.0 - 1e-6), 1e-9),
        (1e-8 * (1.0 + 1e-6), 1e-9),
        (1.01e-8, 1e-9),
        (0.99e-8, 1e-9),
        (3e-8, 3e-8),
    ] {
        let world: Vec<Point3<f64>> = (0..16)
            .map(|i| {
                let e = Vector3::new(pat(i, 0), s1 * pat(i, 1), s2 * pat(i, 2) * pat(i, 3));
                Point3::from(r * e + Vector3::new(3.0, -2.0, 1.0))
            })
            .collect();
        let f = working_frame(&world, &image, None, true);
        let q = working_frame_qr(&world, &image, None, true);
        if s1 < 1e-8 {
            // sv1 / sv0 = s1 (up to the rounding of the inputs, ~1e-16 / 1e-8).
            assert_eq!(
                f.clone().err(),
                Some(PnpError::Degenerate(DegenerateKind::CollinearWorldPoints)),
                "{s1}"
            );
            assert_eq!(f, q);
            continue;
        }
        let (f, q) = (f.unwrap(), q.unwrap());
        let want = s2 / 1.0;
        // Rounding of the inputs (offset 3: ~4e-16 absolute) relative to sv2.
        let tol = 2e-15 / s2;
        assert!((f.ratio / want - 1.0).abs() < tol, "{s1} {s2}: {}", f.ratio);
        assert!((q.ratio / want - 1.0).abs() < tol, "{s1} {s2}: {}", q.ratio);
    }
}

#[test]
fn sums_match_direct_accumulation() {
    // The sums carried to the working frame equal the direct per-point `moments` pass in that frame
    // (the previous implementation of `moments`), weights in the frame's unit: 1e-13 relative to
    // max |M| (rounding of O(N) sums, N <= 200).
    let mut rng = Pcg64::seed_from_u64(21);
    for trial in 0..60 {
        let n = [4usize, 7, 50, 200][trial % 4];
        let thin = [1.0, 0.2, 1e-3, 1e-5][trial / 4 % 4];
        let (world, image) = shaped(&mut rng, n, thin, false, [0.0, 50.0][trial / 16 % 2]);
        let w: Vec<f64> = (0..n).map(|_| rng.random_range(0.0..3.0)).collect();
        let wopt = if trial % 2 == 0 { Some(&w[..]) } else { None };
        let Ok(f) = working_frame(&world, &image, wopt, trial % 7 != 3 || thin < 0.1) else {
            continue;
        };
        // The frame's sums are in its weight unit.
        let w_unit: Vec<f64> = w.iter().map(|x| x / f.weight_unit).collect();
        let wopt = wopt.map(|_| &w_unit[..]);
        let direct = crate::pipeline::moments::tests::accumulate(&world, &image, wopt, &f);
        for flatten in [false, true] {
            let a = f.sums.system(flatten).unwrap();
            let b = direct.system(flatten).unwrap();
            assert!(
                (a.m - b.m).amax() <= 1e-13 * b.m.amax(),
                "{trial} {flatten}: {:e}",
                (a.m - b.m).amax() / b.m.amax()
            );
            assert!((a.g - b.g).amax() <= 1e-13 * b.g.amax().max(1.0), "{trial}");
        }
        // Thin clouds: the sums of the small coordinate z are accurate relative to
        // themselves, as in the direct pass (the third pass computes z per point): both
        // carry ~eps / ratio relative error; allow 50 eps / ratio (the scatter alone would
        // give ~eps / ratio^2, 1e-6 at ratio 1e-5).
        if thin < 0.1 && f.rw != Matrix3::identity() {
            let tol = 50.0 * f64::EPSILON / f.ratio;
            // Signed sums are compared with the sums of their magnitudes (Cauchy-Schwarz
            // bounds; |u| < 1 here).
            let (szz, sxx) = (direct.s[(2, 2)], direct.s[(0, 0)]);
            for (x, y, mag) in [
                (f.sums.s[(2, 2)], szz, szz),
                (f.sums.s_q[(2, 2)], direct.s_q[(2, 2)], direct.s_q[(2, 2)]),
                (f.sums.s_u[(0, 2)], direct.s_u[(0, 2)], (sxx * szz).sqrt()),
                (f.sums.a_u[2], direct.a_u[2], (direct.sw * szz).sqrt()),
            ] {
                assert!((x - y).abs() <= tol * mag, "{trial}: {x:e} {y:e}");
            }
        }
    }
}

impl WorkingFrame {
    /// Inverse of [`WorkingFrame::to_world`]: `(R_world Rw^T, (t_world + R_world c) / d)`.
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
