use super::*;
use crate::numeric::mat3::{singular_values3, smallest_right_singular_vector, svd3};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

/// CGR vector of a rotation: `s = [R32 - R23, R13 - R31, R21 - R12] / (1 + trace R)`.
///
/// Singular at 180 degrees (`1 + trace R = 0`: the result is infinite or NaN) and
/// ill-conditioned near it (trap T1); the refinement never uses it for that reason.
pub(crate) fn rotation_to_cgr(r: &Matrix3<f64>) -> Vector3<f64> {
    Vector3::new(
        r[(2, 1)] - r[(1, 2)],
        r[(0, 2)] - r[(2, 0)],
        r[(1, 0)] - r[(0, 1)],
    ) / (1.0 + r.trace())
}

fn rand_rot(rng: &mut Pcg64) -> Matrix3<f64> {
    // Haar-uniform via a random unit quaternion.
    let mut q = [0.0f64; 4];
    loop {
        for x in q.iter_mut() {
            *x = rng.random_range(-1.0..1.0);
        }
        let n = q.iter().map(|x| x * x).sum::<f64>();
        if n > 1e-3 && n <= 1.0 {
            break;
        }
    }
    let q = UnitQuaternion::new_normalize(nalgebra::Quaternion::new(q[0], q[1], q[2], q[3]));
    q.to_rotation_matrix().into_inner()
}

/// Orthonormality tolerance for products of computed orthogonal factors: each factor is
/// orthogonal to ~10 Jacobi rotations' rounding and the product adds 3-term dot products;
/// measured max 1.8e-15 (8 eps) over 2000 random inputs, allow 4e-15.
const ORTH_TOL: f64 = 4e-15;

fn orth_err(r: &Matrix3<f64>) -> f64 {
    (r.transpose() * r - Matrix3::identity()).amax()
}

#[test]
fn cgr_roundtrip_and_orthonormal() {
    let mut rng = Pcg64::seed_from_u64(1);
    for _ in 0..200 {
        let r = rand_rot(&mut rng);
        let s = rotation_to_cgr(&r);
        let r2 = cgr_to_rotation(&s);
        // Round trip through the CGR map: error grows like |s| ~ 1/(1 + tr R); random
        // rotations keep 1 + tr R well away from 0 except rarely, allow 1e-12.
        if 1.0 + r.trace() > 1e-2 {
            assert!((r - r2).amax() < 1e-12, "{}", (r - r2).amax());
        }
        // Rounding only: a few ulps.
        assert!(orth_err(&r2) < 1e-15);
        assert!((r2.determinant() - 1.0).abs() < 1e-15);
    }
    // Huge s (angle within 1e-12 rad of 180 deg) stays finite and orthonormal.
    let s = Vector3::new(1.0, -2.0, 0.5) * 1e200;
    let r = cgr_to_rotation(&s);
    assert!(orth_err(&r) < 1e-15);
    let n = Vector3::new(1.0, -2.0, 0.5).normalize();
    let expected = n * n.transpose() * 2.0 - Matrix3::identity();
    assert!((r - expected).amax() < 1e-15);
}

#[test]
fn cgr_matches_formula() {
    // Against the literal formula Rbar(s) / (1 + s's) from docs/algorithm.md section 1.
    let s = Vector3::new(0.3, -0.7, 1.9);
    let (s1, s2, s3) = (s.x, s.y, s.z);
    #[rustfmt::skip]
    let rbar = Matrix3::new(
        1.0 + s1 * s1 - s2 * s2 - s3 * s3, 2.0 * (s1 * s2 - s3), 2.0 * (s1 * s3 + s2),
        2.0 * (s1 * s2 + s3), 1.0 - s1 * s1 + s2 * s2 - s3 * s3, 2.0 * (s2 * s3 - s1),
        2.0 * (s1 * s3 - s2), 2.0 * (s1 + s2 * s3), 1.0 - s1 * s1 - s2 * s2 + s3 * s3,
    );
    let r = rbar / (1.0 + s.norm_squared());
    // Same formula, different grouping: a few ulps.
    assert!((cgr_to_rotation(&s) - r).amax() < 1e-15);
}

#[test]
fn exp_matches_nalgebra() {
    let mut rng = Pcg64::seed_from_u64(2);
    for k in 0..300 {
        let mag = 10f64.powi(-(k % 12)) * 3.0;
        let w = Vector3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        )
        .normalize()
            * mag;
        let r = exp_so3(&w);
        let rn = Rotation3::from_scaled_axis(w).into_inner();
        // Both are accurate to a few ulps of O(1) entries (measured max 8.9e-16 = 4 eps).
        assert!(
            (r - rn).amax() < 2e-15,
            "{} at |w| = {mag}",
            (r - rn).amax()
        );
        assert!(orth_err(&r) < 2e-15);
    }
    assert_eq!(exp_so3(&Vector3::zeros()), Matrix3::identity());
}

#[test]
fn svd3_converges_well_within_its_sweep_bound() {
    // An ordinary matrix (a candidate of the case-1 start) on which a 1-eps rotation
    // threshold kept rotating a pair whose inner product is rounding noise: all 40 sweeps.
    let a = Matrix3::from_column_slice(&[
        0.03165774668062224,
        0.06537362588744486,
        -0.0041840607448066815,
        0.023226095764420775,
        0.1598864994284672,
        -0.027021008617450003,
        -0.02359280146445423,
        -0.1725975064488418,
        0.05489997101597928,
    ]);
    use crate::numeric::bounds::{hook::with_limit, Bound};
    let (out, hit) = with_limit(Bound::Svd3Sweeps, 8, || svd3(&a));
    assert_eq!(hit, 0, "more than 8 sweeps");
    let svd = out.unwrap();
    let rec = svd.u * Matrix3::from_diagonal(&svd.s) * svd.v.transpose();
    assert!(
        (rec - a).amax() < 4.0 * f64::EPSILON * svd.s[0],
        "{:e}",
        (rec - a).amax()
    );
    assert!((svd.u.transpose() * svd.u - Matrix3::identity()).amax() < 1e-15);
    assert!((svd.v.transpose() * svd.v - Matrix3::identity()).amax() < 1e-15);
}

#[test]
fn svd3_accuracy() {
    let mut rng = Pcg64::seed_from_u64(3);
    for k in 0..200 {
        let u = rand_rot(&mut rng);
        let v = rand_rot(&mut rng);
        let sv = match k % 4 {
            0 => Vector3::new(1.0, 1e-8, 3e-9),
            1 => Vector3::new(2.0, 1.0, 0.0),
            2 => Vector3::new(1.0, 1.0, 1.0),
            _ => Vector3::new(5.0, 1e-12, 1e-20),
        };
        let a = u * Matrix3::from_diagonal(&sv) * v.transpose();
        let d = svd3(&a).unwrap();
        // Backward error: a few eps * |A|.
        let rec = d.u * Matrix3::from_diagonal(&d.s) * d.v.transpose();
        assert!((rec - a).amax() < 1e-14 * sv[0]);
        // Singular values: absolute error a few eps * s0 (1e-15 * s0 allows ~5 ulps).
        for i in 0..3 {
            assert!(
                (d.s[i] - sv[i]).abs() < 1e-15 * sv[0],
                "{k} {i} {:e}",
                d.s[i]
            );
        }
        assert!(orth_err(&d.u) < ORTH_TOL && orth_err(&d.v) < ORTH_TOL);
    }
    // Graded test of T9: relative accuracy of sv1 at 1e-8 must be far better than the
    // 5-25 % of the eigen-decomposition route.
    let u = Rotation3::from_scaled_axis(Vector3::new(0.3, 0.1, -0.2)).into_inner();
    let v = Rotation3::from_scaled_axis(Vector3::new(0.7, -0.4, 0.4)).into_inner();
    let a = u * Matrix3::from_diagonal(&Vector3::new(1.0, 1e-8, 3e-9)) * v.transpose();
    let d = svd3(&a).unwrap();
    // eps / 1e-8 relative: allow 1e-7.
    assert!((d.s[1] / 1e-8 - 1.0).abs() < 1e-7);
    // Extreme magnitudes, including subnormal entries: scaled internally.
    for scale in [1e300, 1e-300, 1e-310] {
        let d = svd3(&(a * scale)).unwrap();
        assert!((d.s[0] / scale - 1.0).abs() < 1e-14, "{scale}");
    }
    assert!(svd3(&Matrix3::from_element(f64::NAN)).is_none());
}

#[test]
fn singular_values3_and_null_vector_match_svd3_bitwise() {
    let mut rng = Pcg64::seed_from_u64(6);
    for k in 0..300 {
        let mut a = Matrix3::from_fn(|_, _| rng.random_range(-1.0..1.0));
        if k % 3 == 1 {
            // rank 2
            let c = a.column(0) * 0.3 - a.column(1) * 1.7;
            a.set_column(2, &c);
        }
        if k % 3 == 2 {
            a *= 1e-310;
        }
        let s = singular_values3(&a).unwrap();
        let d = svd3(&a).unwrap();
        let y = smallest_right_singular_vector(&a).unwrap();
        for i in 0..3 {
            assert_eq!(y[i].to_bits(), d.v[(i, 2)].to_bits(), "{k} {i}");
        }
        for i in 0..3 {
            assert_eq!(s[i].to_bits(), d.s[i].to_bits(), "{k} {i}");
        }
    }
    assert_eq!(
        singular_values3(&Matrix3::zeros()).unwrap(),
        Vector3::zeros()
    );
    assert!(singular_values3(&Matrix3::from_element(f64::NAN)).is_none());
    assert_eq!(
        smallest_right_singular_vector(&Matrix3::zeros()).unwrap(),
        svd3(&Matrix3::zeros()).unwrap().v.column(2)
    );
    assert!(smallest_right_singular_vector(&Matrix3::from_element(f64::NAN)).is_none());
}

#[test]
fn pow2_scale_brackets() {
    for x in [
        1.0,
        1.5,
        2.0,
        3.999,
        1e-300,
        5e-324,
        1e-310,
        3e-320,
        f64::MAX,
        f64::MIN_POSITIVE,
    ] {
        let p = pow2_scale(x);
        assert!(p <= x && x < 2.0 * p, "{x} {p}");
        // A power of two: no mantissa bits (normal) or a single bit (subnormal).
        if p >= f64::MIN_POSITIVE {
            assert_eq!(p.to_bits() & 0x000f_ffff_ffff_ffff, 0, "{x}");
        } else {
            assert_eq!(p.to_bits().count_ones(), 1, "{x}");
        }
    }
}

#[test]
fn nearest_rotation_properties() {
    let mut rng = Pcg64::seed_from_u64(4);
    for _ in 0..200 {
        let r = rand_rot(&mut rng);
        // Projection of a rotation is itself (to the orthonormality rounding).
        let p = nearest_rotation(&r).unwrap();
        assert!((p - r).amax() < ORTH_TOL);
        // Scale invariant, and a reflection maps to a rotation (det +1).
        let p = nearest_rotation(&(r * 3.7)).unwrap();
        assert!((p - r).amax() < ORTH_TOL);
        let refl = r * Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, -1.0));
        let p = nearest_rotation(&refl).unwrap();
        assert!((p.determinant() - 1.0).abs() < ORTH_TOL && orth_err(&p) < ORTH_TOL);
        // Perturbed rotation: result is a rotation close to r.
        let noise = Matrix3::from_fn(|_, _| rng.random_range(-1e-3..1e-3));
        let p = nearest_rotation(&(r + noise)).unwrap();
        assert!(orth_err(&p) < ORTH_TOL && (p.determinant() - 1.0).abs() < ORTH_TOL);
        assert!(rotation_error_deg(&p, &r) < 0.5);
    }
    // Rank deficient input still gives a rotation.
    let p = nearest_rotation(&Matrix3::from_diagonal(&Vector3::new(1.0, 0.0, 0.0))).unwrap();
    assert!(orth_err(&p) < ORTH_TOL && (p.determinant() - 1.0).abs() < ORTH_TOL);
    assert!(nearest_rotation(&Matrix3::zeros()).is_none());
    assert!(nearest_rotation(&Matrix3::from_element(f64::INFINITY)).is_none());
}

#[test]
fn polar_rotation_is_the_nearest_rotation() {
    let mut rng = Pcg64::seed_from_u64(5);
    let mut settled = 0;
    for k in 0..2000 {
        // Rotations times a scale plus noise from 1e-9 to 1 relative: condition numbers up
        // to about 1e3 (and some matrices with det <= 0, which it must refuse).
        let r = rand_rot(&mut rng);
        let size = 10f64.powf(-9.0 + 9.0 * (k as f64 / 2000.0));
        let noise = Matrix3::from_fn(|_, _| rng.random_range(-size..size));
        let a = (r + noise) * rng.random_range(0.1..10.0);
        let Some(p) = polar_rotation(&a) else {
            continue;
        };
        settled += 1;
        assert!(a.determinant() > 0.0, "{k}");
        assert!(
            orth_err(&p) < ORTH_TOL && (p.determinant() - 1.0).abs() < ORTH_TOL,
            "{k}"
        );
        // The same rotation as the SVD's, to the rounding of the two computations.
        let q = nearest_rotation(&a).unwrap();
        assert!((p - q).amax() < 1e-13, "{k}: {:e}", (p - q).amax());
    }
    // Refused only near singularity or with det <= 0 (large noise).
    assert!(settled >= 1900, "{settled}");
    assert!(polar_rotation(&Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, 1e-9))).is_none());
    assert!(polar_rotation(&Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, -1.0))).is_none());
}

/// The polar route is the SVD's nearest rotation for every matrix, with a negative determinant
/// (the SVD's fallback, no sign taken away; distinct singular values there, so that the
/// nearest rotation is unique) and at scales the determinant would not survive.
#[test]
fn nearest_rotation_polar_is_the_nearest_rotation() {
    let mut rng = Pcg64::seed_from_u64(11);
    for k in 0..2000 {
        let r = rand_rot(&mut rng);
        let size = 10f64.powf(-9.0 + 9.0 * (k as f64 / 2000.0));
        let noise = Matrix3::from_fn(|_, _| rng.random_range(-size..size));
        let shape = if k % 3 == 0 {
            Matrix3::from_diagonal(&Vector3::new(3.0, 2.0, -1.0))
        } else {
            Matrix3::identity()
        };
        let scale = 10f64.powi(rng.random_range(-200..200));
        let a = (r * shape + noise) * scale;
        let p = nearest_rotation_polar(&a).expect("finite and nonzero");
        let q = nearest_rotation(&(a / scale)).unwrap();
        assert!(
            orth_err(&p) < ORTH_TOL && (p.determinant() - 1.0).abs() < ORTH_TOL,
            "{k}"
        );
        assert!((p - q).amax() < 1e-12, "{k}: {:e}", (p - q).amax());
    }
    assert!(nearest_rotation_polar(&Matrix3::zeros()).is_none());
    let mut bad = Matrix3::identity();
    bad[(1, 2)] = f64::INFINITY;
    assert!(nearest_rotation_polar(&bad).is_none());
}

#[test]
fn candidate_to_rotation_sign_and_skip() {
    let r = Rotation3::from_scaled_axis(Vector3::new(0.2, -1.0, 2.0)).into_inner();
    let mut v = [0.0; 9];
    for i in 0..3 {
        for j in 0..3 {
            v[3 * i + j] = -2.5e-200 * r[(i, j)]; // row-major, negative scale
        }
    }
    let p = candidate_to_rotation(&v).unwrap();
    // Orthonormality-level rounding (see ORTH_TOL).
    assert!((p - r).amax() < ORTH_TOL);
    assert!(candidate_to_rotation(&[0.0; 9]).is_none());
    let mut bad = v;
    bad[4] = f64::NAN;
    assert!(candidate_to_rotation(&bad).is_none());
}

#[test]
fn quaternion_at_180_degrees() {
    let axes = [
        Vector3::x(),
        Vector3::y(),
        Vector3::z(),
        Vector3::new(1.0, 1.0, 0.0),
        Vector3::new(1.0, -1.0, 1.0),
        Vector3::new(0.0, 0.3, -2.0),
        Vector3::new(-0.4, 0.1, 0.2),
    ];
    for a in &axes {
        let n = a.normalize();
        // Exactly 180 degrees: R = 2 n n' - I.
        let r = n * n.transpose() * 2.0 - Matrix3::identity();
        let q = to_unit_quaternion(&r);
        let back = q.to_rotation_matrix().into_inner();
        // Closed form: entries to a few ulps.
        assert!((back - r).amax() < 1e-15, "{a:?}: {}", (back - r).amax());
        assert!(q.w.abs() < 1e-15);
        assert!((q.angle() - std::f64::consts::PI).abs() < 1e-7);
        assert!(rotation_error_deg(&back, &r) < 1e-12);
    }
    // Random rotations and near-180 ones.
    let mut rng = Pcg64::seed_from_u64(5);
    for k in 0..300 {
        let r = if k % 2 == 0 {
            rand_rot(&mut rng)
        } else {
            let n = Vector3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            )
            .normalize();
            exp_so3(&(n * (std::f64::consts::PI - 1e-9 * rng.random::<f64>())))
        };
        let back = to_unit_quaternion(&r).to_rotation_matrix().into_inner();
        assert!((back - r).amax() < 2e-15);
    }
}
