use super::*;
use crate::numeric::rotation::{exp_so3, rotation_error_deg};
use crate::pipeline::frame::working_frame;
use crate::pipeline::moments::{m_symmetric, m_upper, tests::accumulate};
use nalgebra::{Point2, Point3, SMatrix};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

/// A working-frame problem: `align = false`, so the working-frame rotation is the true
/// rotation (T1 testing note). Returns (upper triangle of M, trace M).
fn problem(rng: &mut Pcg64, n: usize, noise: f64, r_true: &Matrix3<f64>) -> ([f64; 45], f64) {
    let t = Vector3::new(
        rng.random_range(-0.5..0.5),
        rng.random_range(-0.5..0.5),
        6.0,
    );
    let world: Vec<Point3<f64>> = (0..n)
        .map(|_| {
            Point3::new(
                rng.random_range(-2.0..2.0),
                rng.random_range(-2.0..2.0),
                rng.random_range(-2.0..2.0),
            )
        })
        .collect();
    let image: Vec<Point2<f64>> = world
        .iter()
        .map(|x| {
            let p = r_true * x.coords + t;
            Point2::new(
                p.x / p.z + noise * rng.random_range(-1.0..1.0),
                p.y / p.z + noise * rng.random_range(-1.0..1.0),
            )
        })
        .collect();
    let frame = working_frame(&world, &image, None, false).unwrap();
    assert_eq!(frame.rw, Matrix3::identity());
    let sys = accumulate(&world, &image, None, &frame)
        .system(false)
        .unwrap();
    (m_upper(&sys.m), sys.trace)
}

fn cost(m: &SMatrix<f64, 9, 9>, r: &Matrix3<f64>) -> f64 {
    let v = SMatrix::<f64, 9, 1>::from_iterator(row_major(r));
    (v.transpose() * m * v)[0]
}

fn rand_unit(rng: &mut Pcg64) -> Vector3<f64> {
    Vector3::new(
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
    )
    .normalize()
}

/// Central-difference gradient of F(s) = f(R(s) R) at s = 0.
fn fd_gradient(m: &SMatrix<f64, 9, 9>, r: &Matrix3<f64>, h: f64) -> Vector3<f64> {
    Vector3::from_fn(|i, _| {
        let mut e = Vector3::zeros();
        e[i] = h;
        (cost(m, &(cgr_to_rotation(&e) * r)) - cost(m, &(cgr_to_rotation(&-e) * r))) / (2.0 * h)
    })
}

#[test]
fn min_eigenvalue_jacobi() {
    let mut rng = Pcg64::seed_from_u64(32);
    for k in 0..500 {
        let q = exp_so3(&(rand_unit(&mut rng) * 2.0));
        let ev = match k % 4 {
            0 => Vector3::new(1.0, 1.0, 1.0),
            1 => Vector3::new(-3.0, 2.0, 2.0),
            2 => Vector3::new(1e-9, 5.0, -1e-9),
            _ => Vector3::new(
                rng.random_range(-5.0..5.0),
                rng.random_range(-5.0..5.0),
                rng.random_range(-5.0..5.0),
            ),
        };
        let a = q * Matrix3::from_diagonal(&ev) * q.transpose();
        let a = (a + a.transpose()) * 0.5;
        // Absolute error ~eps |A| (Weyl), also for near-double roots; allow 1e-14 |A|.
        let lmin = min_eigenvalue_sym3(&a);
        assert!(
            (lmin - ev.min()).abs() < 1e-14 * ev.amax(),
            "{k}: {lmin} {}",
            ev.min()
        );
    }
    assert_eq!(min_eigenvalue_sym3(&Matrix3::zeros()), 0.0);
}

#[test]
fn matches_python_reference() {
    // general_N4_sigma2 of the reference prototype's test vectors: the stored working-frame
    // M, refined by the prototype's refine_so3 from each of the four extra starts (R, f,
    // iterations printed by the prototype). Two different local minima are reached.
    let m45 = m_upper(&crate::test_data::vector("general_N4_sigma2").m);
    let reference = crate::test_data::newton_reference();
    let expected: Vec<(Vec<f64>, f64, u32)> = reference["minima"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| {
            let it = e["iterations"].as_u64().unwrap();
            (
                crate::test_data::numbers(&e["R"]),
                e["f"].as_f64().unwrap(),
                it as u32,
            )
        })
        .collect();
    assert_eq!(expected.len(), 4);
    let trace = m_symmetric(&m45).trace();
    let starts = [
        Vector3::new(1.0, 1.0, 1.0),
        Vector3::new(1.0, -1.0, -1.0),
        Vector3::new(-1.0, 1.0, -1.0),
        Vector3::new(-1.0, -1.0, 1.0),
    ];
    for (s, (r_ref, f_ref, it_ref)) in starts.iter().zip(expected.iter()) {
        let out = refine_so3(
            &m45,
            trace,
            &Matrix3::from_diagonal(s),
            &NewtonOptions::default(),
        );
        let r_ref = Matrix3::from_row_slice(r_ref);
        // Same local minimum of the same cost: rotations agree to ~1e-12 deg (both
        // converged to machine precision); f to rounding relative to trace.
        assert!(
            rotation_error_deg(&out.r, &r_ref) < 1e-9,
            "{}",
            rotation_error_deg(&out.r, &r_ref)
        );
        assert!((out.f - f_ref).abs() < 1e-13 * trace);
        // Iteration counts may differ by a step where rounding decides the last accept.
        assert!(
            out.iterations.abs_diff(*it_ref) <= 1,
            "{} vs {it_ref}",
            out.iterations
        );
        assert!(!out.hit_limit);
    }
}

#[test]
fn noise_free_reaches_machine_precision() {
    let mut rng = Pcg64::seed_from_u64(33);
    let mut worst = 0.0f64;
    let mut max_it = 0;
    for trial in 0..200 {
        let n = 6 + trial % 10;
        let r_true = exp_so3(&(rand_unit(&mut rng) * rng.random_range(0.0..3.1)));
        let (m45, trace) = problem(&mut rng, n, 0.0, &r_true);
        let r0 = exp_so3(&(rand_unit(&mut rng) * 0.3)) * r_true;
        let out = refine_so3(&m45, trace, &r0, &NewtonOptions::default());
        worst = worst.max(rotation_error_deg(&out.r, &r_true));
        max_it = max_it.max(out.iterations);
        assert!(!out.hit_limit);
    }
    // docs/algorithm.md, `newton`: the prototype reaches max 9.8e-14 deg (N = 6) and 7.3e-14 deg
    // (N = 10) over 300 trials; without the acceptance floor it would be ~2e-7 deg.
    // Allow 1e-12 deg (10x the measured prototype maximum).
    assert!(worst < 1e-12, "worst {worst:e} deg");
    assert!(max_it < 50);
}

#[test]
fn converges_to_stationary_point_and_never_increases() {
    let mut rng = Pcg64::seed_from_u64(34);
    for trial in 0..60 {
        let n = 4 + trial % 8;
        let r_true = exp_so3(&(rand_unit(&mut rng) * rng.random_range(0.0..3.1)));
        let (m45, trace) = problem(&mut rng, n, 0.005, &r_true);
        let m = m_symmetric(&m45);
        let r0 = exp_so3(&(rand_unit(&mut rng) * rng.random_range(0.0..3.1)));
        let opts = NewtonOptions::default();
        let out = refine_so3(&m45, trace, &r0, &opts);
        assert!(!out.hit_limit, "{trial}");
        // Stationary point of f (not of the chart-dependent C): the finite-difference
        // gradient of f(R(s) R) vanishes. Step 1e-5: truncation ~1e-10 trace, rounding
        // ~1e-11 trace; allow 1e-9 trace. (At r0 it is O(trace).)
        let gfd = fd_gradient(&m, &out.r, 1e-5);
        assert!(
            gfd.amax() < 1e-9 * trace,
            "{trial}: {:e}",
            gfd.amax() / trace
        );
        assert!((out.f - cost(&m, &out.r)).abs() < 1e-13 * trace);
        // Monotone up to the floor: replay with every iteration cap (the iteration is
        // deterministic, so the cap-k run is the state after k iterations).
        let mut prev = cost(&m, &r0);
        for k in 1..=out.iterations {
            let step = refine_so3(
                &m45,
                trace,
                &r0,
                &NewtonOptions {
                    max_iterations: k,
                    ..opts
                },
            );
            assert!(step.f <= prev + opts.accept_floor * trace, "{trial} {k}");
            prev = step.f;
        }
        assert_eq!(prev, out.f);
        // Orthonormal to rounding after all iterations.
        assert!((out.r.transpose() * out.r - Matrix3::identity()).amax() < 1e-14);
    }
}

#[test]
fn near_180_in_the_solver_frame() {
    // T1: rotations within 1e-4 deg of 180 deg in the working frame (align = false).
    // CGR(R) of such a start is ~1e6 in size; the moving chart never uses it.
    let mut rng = Pcg64::seed_from_u64(35);
    for trial in 0..40 {
        let axis = rand_unit(&mut rng);
        let angle = core::f64::consts::PI - (1e-4f64).to_radians() * rng.random::<f64>();
        let r_true = exp_so3(&(axis * angle));
        let (m45, trace) = problem(&mut rng, 6 + trial % 6, 0.0, &r_true);
        // Starts: 5 deg off the truth, and a start at exactly 180 deg about the true axis.
        let r_exact = axis * axis.transpose() * 2.0 - Matrix3::identity();
        for r0 in [
            exp_so3(&(rand_unit(&mut rng) * 5f64.to_radians())) * r_true,
            r_exact,
        ] {
            let out = refine_so3(&m45, trace, &r0, &NewtonOptions::default());
            let err = rotation_error_deg(&out.r, &r_true);
            // Noise-free: machine precision as in the generic test (`newton` max 1.6e-12 deg
            // near 180 in the prototype's re-run of test_near180.py).
            assert!(err < 1e-11, "{trial}: {err:e}");
            assert!(!out.hit_limit);
        }
    }
}

#[test]
fn iteration_cap_is_reported() {
    let mut rng = Pcg64::seed_from_u64(36);
    let r_true = exp_so3(&Vector3::new(0.3, -0.2, 1.0));
    let (m45, trace) = problem(&mut rng, 10, 0.01, &r_true);
    let r0 = exp_so3(&Vector3::new(0.0, 0.9, 0.0)) * r_true;
    let out = refine_so3(
        &m45,
        trace,
        &r0,
        &NewtonOptions {
            max_iterations: 1,
            ..NewtonOptions::default()
        },
    );
    assert!(out.hit_limit);
    assert_eq!(out.iterations, 1);
    let out0 = refine_so3(
        &m45,
        trace,
        &r0,
        &NewtonOptions {
            max_iterations: 0,
            ..NewtonOptions::default()
        },
    );
    assert_eq!((out0.r, out0.iterations, out0.hit_limit), (r0, 0, true));
    let full_run = refine_so3(&m45, trace, &r0, &NewtonOptions::default());
    assert!(!full_run.hit_limit && full_run.iterations > 1);
    // Degenerate options still terminate (bounded inner loop).
    let odd = refine_so3(
        &m45,
        trace,
        &r0,
        &NewtonOptions {
            mu0: 0.0,
            ..NewtonOptions::default()
        },
    );
    assert!(odd.f.is_finite() && odd.iterations <= 50);
    // M = 0: every rotation is optimal; stops at once.
    let zero = refine_so3(&[0.0; 45], 0.0, &r0, &NewtonOptions::default());
    assert_eq!(zero.r, r0);
    assert!(!zero.hit_limit);
}

/// `local_model` (factored, 4-wide) computes what the generated kernel `so3_local_model`
/// defines: the gradient and `H_C - 4 f I`, to rounding, on noisy and noise-free M at
/// rotations near and far from the minimum.
#[test]
fn local_model_matches_the_generated_kernel() {
    let mut rng = Pcg64::seed_from_u64(5);
    let mut worst = 0.0_f64;
    for n in [6, 10, 50] {
        for trial in 0..60 {
            let r_true = exp_so3(&(rand_unit(&mut rng) * rng.random_range(0.0..3.1)));
            let (m45, _) = problem(&mut rng, n, 1e-2 * (trial % 3) as f64, &r_true);
            let away = exp_so3(&(rand_unit(&mut rng) * rng.random_range(0.0..3.1)));
            let r = if trial % 2 == 0 {
                r_true
            } else {
                away * r_true
            };
            let m = m_symmetric(&m45);
            let r9: [f64; 9] = std::array::from_fn(|a| r[(a / 3, a % 3)]);
            let k = crate::kernels::so3_local_model(&m45, &r9);
            let g_ref = Vector3::new(k[1], k[2], k[3]);
            #[rustfmt::skip]
            let h_ref = Matrix3::new(
                k[4], k[5], k[6],
                k[5], k[7], k[8],
                k[6], k[8], k[9],
            ) - Matrix3::identity() * (4.0 * k[0]);
            let (g, h) = local_model(&m.data.0, &r);
            // The AVX2 and the baseline builds round alike (no fused multiply-add).
            let baseline = crate::numeric::lanes::with_baseline(|| local_model(&m.data.0, &r));
            assert_eq!((g, h), baseline);
            // Every output is a sum of products of entries of M with entries of R (|R| <= 1).
            let err = (g - g_ref).amax().max((h - h_ref).amax()) / m.amax();
            worst = worst.max(err);
            assert!(err <= 1e-13, "n {n} trial {trial}: {err:e}");
            assert_eq!(h, h.transpose());
        }
    }
    eprintln!("local model vs kernel: worst {worst:e} of max |M|");
}

/// `newton`'s 3 x 3 `L D L^T` (`mat3::ldl3`): the solve's residual at the level of the rounding
/// over condition numbers up to 1e12, and `None` exactly where Cholesky's test fails (a
/// pivot not positive, a NaN or infinite entry).
#[test]
fn ldl3_solves_positive_definite_systems_and_refuses_the_others() {
    use crate::numeric::mat3::{ldl3, ldl3_solve};
    let mut rng = Pcg64::seed_from_u64(37);
    let mut next = || rng.random::<f64>() * 2.0 - 1.0;
    for trial in 0..1000 {
        let q = Matrix3::from_fn(|_, _| next()).qr().q();
        let decades = 12.0 * (trial as f64 / 1000.0);
        let lam = Vector3::new(1.0, 10f64.powf(-decades / 2.0), 10f64.powf(-decades));
        let a = q * Matrix3::from_diagonal(&lam) * q.transpose();
        let a = (a + a.transpose()) * 0.5;
        let b = Vector3::new(next(), next(), next());
        let x = ldl3_solve(&ldl3(&a).expect("positive definite"), &b);
        let res = (a * x - b).norm();
        let scale = a.norm() * x.norm() + b.norm();
        assert!(res <= 1e-14 * scale, "trial {trial}: {res:e} vs {scale:e}");
    }
    let mut a = Matrix3::identity();
    a[(1, 1)] = -1.0;
    assert!(ldl3(&a).is_none());
    a[(1, 1)] = 0.0;
    assert!(ldl3(&a).is_none());
    let mut a = Matrix3::identity();
    a[(2, 2)] = f64::INFINITY;
    assert!(ldl3(&a).is_none());
    a[(2, 2)] = 1.0;
    a[(2, 0)] = f64::NAN;
    assert!(ldl3(&a).is_none());
    // Positive definite but with a large off-diagonal entry: still factored.
    let a = Matrix3::new(4.0, 1.9, 0.0, 1.9, 1.0, 0.0, 0.0, 0.0, 1e-300);
    assert!(ldl3(&a).is_some());
}
