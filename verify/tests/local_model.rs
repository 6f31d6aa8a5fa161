//! Check 3: `so3_local_model(m, r) -> [f, g0..g2, hc00, hc01, hc02, hc11, hc12, hc22]` at random
//! rotations (Haar-uniform, exact 180 deg rotations `2 a a^T - I`, exact axis flips), against
//! `vec(R)^T M vec(R)`, the explicit `newton` formulas with `M_k = D^T M D` (1e-12 of the
//! absolute-value scales), and against derivatives of `F(s) = f(R(s) R)`: `g = grad F(0)`,
//! `H_C - 4 f I = hess F(0)`, by central / second differences and by the complex step, with
//! per-sample bounds derived in `eopnp_verify::fd` (derivatives of `F` along one-parameter
//! subgroups `t -> Rot_u(2 atan t)`).

use eopnp::internals::kernels as k;
use eopnp_verify::checks::{self, LocalAgainst, N_COST, TOL_POLY};
use eopnp_verify::{reference as rf, strategies as st};
use nalgebra::{Matrix3, Vector3};
use proptest::prelude::*;

#[test]
fn value_vs_quadratic_form() {
    checks::local_model(LocalAgainst::Value, N_COST).assert_ok();
}

#[test]
fn explicit_formulas() {
    checks::local_model(LocalAgainst::Explicit, N_COST).assert_ok();
}

#[test]
fn gradient_vs_central_differences() {
    checks::local_model(LocalAgainst::FdGradient, N_COST).assert_ok();
}

#[test]
fn hessian_vs_second_differences() {
    checks::local_model(LocalAgainst::FdHessian, N_COST).assert_ok();
}

#[test]
fn gradient_vs_complex_step() {
    checks::local_model(LocalAgainst::CsGradient, N_COST).assert_ok();
}

#[test]
fn hessian_vs_complex_step_differences() {
    checks::local_model(LocalAgainst::CsHessian, N_COST).assert_ok();
}

/// Exactly 180 degrees about each coordinate axis and about a diagonal: finite outputs that
/// match the explicit formulas (1e-12 of the absolute-value scales).
#[test]
fn exact_half_turns() {
    let mut rng = st::rng(9);
    let m = st::cost_matrix(&mut rng);
    let a = Vector3::new(1.0, 1.0, 1.0) / 3f64.sqrt();
    let rs = [
        Matrix3::from_diagonal(&Vector3::new(1.0, -1.0, -1.0)),
        Matrix3::from_diagonal(&Vector3::new(-1.0, 1.0, -1.0)),
        Matrix3::from_diagonal(&Vector3::new(-1.0, -1.0, 1.0)),
        2.0 * a * a.transpose() - Matrix3::identity(),
    ];
    for r in rs {
        let r9: [f64; 9] = std::array::from_fn(|x| r[(x / 3, x % 3)]);
        let out = k::so3_local_model(&rf::m_upper45(&m), &r9);
        assert!(out.iter().all(|x| x.is_finite()));
        let lm = rf::local_model(&m, &r);
        assert!((out[0] - lm.f).abs() <= TOL_POLY * lm.sf);
        for i in 0..3 {
            assert!((out[1 + i] - lm.g[i]).abs() <= TOL_POLY * lm.sg[i]);
        }
    }
}

proptest! {
    #![proptest_config(st::proptest_config())]

    /// `f`, `g`, `H_C` vs the explicit formulas over proptest strategies (1e-12 of the scales).
    #[test]
    fn prop_explicit(m in st::psd_matrix_strategy(), r in st::rotation_strategy()) {
        let r9: [f64; 9] = std::array::from_fn(|x| r[(x / 3, x % 3)]);
        let out = k::so3_local_model(&rf::m_upper45(&m), &r9);
        let lm = rf::local_model(&m, &r);
        prop_assert!((out[0] - lm.f).abs() <= TOL_POLY * lm.sf);
        let hc = checks::sym3(&[out[4], out[5], out[6], out[7], out[8], out[9]]);
        for i in 0..3 {
            prop_assert!((out[1 + i] - lm.g[i]).abs() <= TOL_POLY * lm.sg[i]);
            for j in 0..3 {
                prop_assert!((hc[(i, j)] - lm.hc[(i, j)]).abs() <= TOL_POLY * lm.sh[(i, j)]);
            }
        }
    }
}

/// The `newton` local model as the solver assembles it (`f`, `g`, `H = H_C - 4 f I` from the
/// kernel) on the `M` of realistic problems (8 points, 0.02 image noise, any rotation), at random
/// rotations, against central and second differences of `F(s) = f(R(s) R_k)` with fixed tolerances
/// relative to `trace(M)`. (Formerly a unit test of the solver's Newton stage.)
#[test]
fn solver_local_model_on_realistic_problems() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_pcg::Pcg64::seed_from_u64(31);
    let rand_unit = |rng: &mut rand_pcg::Pcg64| {
        Vector3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        )
        .normalize()
    };
    let exp = |w: Vector3<f64>| nalgebra::Rotation3::from_scaled_axis(w).into_inner();
    // Cayley (CGR) rotation of a small s.
    let cgr = |s: &Vector3<f64>| {
        let ss = s.norm_squared();
        (Matrix3::identity() * (1.0 - ss) + s.cross_matrix() * 2.0 + s * s.transpose() * 2.0)
            / (1.0 + ss)
    };
    for _ in 0..50 {
        let r_true = exp(rand_unit(&mut rng) * rng.random_range(0.0..3.1));
        let t = Vector3::new(
            rng.random_range(-0.5..0.5),
            rng.random_range(-0.5..0.5),
            6.0,
        );
        let world: Vec<nalgebra::Point3<f64>> = (0..8)
            .map(|_| {
                nalgebra::Point3::new(
                    rng.random_range(-2.0..2.0),
                    rng.random_range(-2.0..2.0),
                    rng.random_range(-2.0..2.0),
                )
            })
            .collect();
        let image: Vec<nalgebra::Point2<f64>> = world
            .iter()
            .map(|x| {
                let p = r_true * x.coords + t;
                nalgebra::Point2::new(
                    p.x / p.z + 0.02 * rng.random_range(-1.0..1.0),
                    p.y / p.z + 0.02 * rng.random_range(-1.0..1.0),
                )
            })
            .collect();
        let m = explicit_m(&world, &image);
        let trace = m.trace();
        let m45 = rf::m_upper45(&m);
        let cost = |r: &Matrix3<f64>| {
            let v = rf::vec_r(r);
            (v.transpose() * m * v)[0]
        };
        let rk = exp(rand_unit(&mut rng) * 3.0);
        let r9: [f64; 9] = std::array::from_fn(|x| rk[(x / 3, x % 3)]);
        let o = k::so3_local_model(&m45, &r9);
        let (f, g) = (o[0], Vector3::new(o[1], o[2], o[3]));
        #[rustfmt::skip]
        let hess = Matrix3::new(o[4], o[5], o[6], o[5], o[7], o[8], o[6], o[8], o[9])
            - Matrix3::identity() * (4.0 * f);
        // f: same quadratic form, different evaluation order.
        assert!((f - cost(&rk)).abs() < 1e-13 * trace);
        // Central differences, step 1e-4: truncation h^2 |F'''| ~ 1e-8 trace, rounding
        // eps trace / h ~ 1e-12 trace; allow 1e-7 trace.
        let h = 1e-4;
        let fk = |s: &Vector3<f64>| cost(&(cgr(s) * rk));
        let gfd = Vector3::from_fn(|i, _| {
            let mut e = Vector3::zeros();
            e[i] = h;
            (fk(&e) - fk(&-e)) / (2.0 * h)
        });
        assert!((gfd - g).amax() < 1e-7 * trace, "{:e}", (gfd - g).amax());
        // Fixed-chart Hessian by second differences of F: error h^2 ~ 1e-8, rounding
        // eps trace / h^2 ~ 1e-8 trace; allow 1e-6 trace.
        for i in 0..3 {
            for j in 0..3 {
                let mut ei = Vector3::zeros();
                ei[i] = h;
                let mut ej = Vector3::zeros();
                ej[j] = h;
                let d2 = (fk(&(ei + ej)) - fk(&(ei - ej)) - fk(&(ej - ei)) + fk(&(-ei - ej)))
                    / (4.0 * h * h);
                assert!(
                    (d2 - hess[(i, j)]).abs() < 1e-6 * trace,
                    "{i}{j}: {d2} {}",
                    hess[(i, j)]
                );
            }
        }
    }
}

/// `M = V^T V - (W^T V)^T (W^T W)^-1 W^T V` of the problem, from the explicit rows of each point
/// (`W_i = [[1, 0, -u], [0, 1, -v]]`, `V_i = [[X^T, 0, -u X^T], [0, X^T, -v X^T]]`) in the user's
/// frame: an independent `moments` stage, for realistic (rank-deficient, structured) matrices.
fn explicit_m(world: &[nalgebra::Point3<f64>], image: &[nalgebra::Point2<f64>]) -> rf::M9 {
    let n = world.len();
    let mut w = nalgebra::DMatrix::<f64>::zeros(2 * n, 3);
    let mut v = nalgebra::DMatrix::<f64>::zeros(2 * n, 9);
    for (i, (x, m)) in world.iter().zip(image).enumerate() {
        let (u, vv) = (m.x, m.y);
        w[(2 * i, 0)] = 1.0;
        w[(2 * i, 2)] = -u;
        w[(2 * i + 1, 1)] = 1.0;
        w[(2 * i + 1, 2)] = -vv;
        for k in 0..3 {
            v[(2 * i, k)] = x[k];
            v[(2 * i, 6 + k)] = -u * x[k];
            v[(2 * i + 1, 3 + k)] = x[k];
            v[(2 * i + 1, 6 + k)] = -vv * x[k];
        }
    }
    let wtv = w.transpose() * &v;
    let g = (w.transpose() * &w)
        .try_inverse()
        .expect("W^T W invertible")
        * &wtv;
    let m = v.transpose() * &v - wtv.transpose() * g;
    let m = (&m + m.transpose()) * 0.5;
    rf::M9::from_fn(|i, j| m[(i, j)])
}
