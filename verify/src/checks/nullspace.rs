//! The checks of the `nullspace` cases' kernels: the case 2 and case 3 cubics and resultants,
//! the case 3 quartic, the case 4 matrix and determinant, on random inputs and on systems with
//! a known root.

use crate::reference::{self as rf, gamma};
use crate::report::{Measurement, Tracker};
use crate::strategies as st;
use eopnp::internals::kernels as k;
use nalgebra::{DMatrix, Matrix3, SMatrix, SVector, Vector3};

use super::{g64, TOL_POLY};

/// Random case-2 inputs: `A` 6 x 3 with entries `N(0,1) 10^U(-2, 2)`, `b` random (half the
/// time the solver's `[1, 1, 1, 0, 0, 0]`).
fn case2_random(rng: &mut rand_pcg::Pcg64) -> ([f64; 6], [f64; 3]) {
    let a = SMatrix::<f64, 6, 3>::from_fn(|_, _| st::normal(rng) * st::log_uniform(rng, -2.0, 2.0));
    let b = if rand::Rng::random_bool(rng, 0.5) {
        SVector::<f64, 6>::from_column_slice(&[1.0, 1.0, 1.0, 0.0, 0.0, 0.0])
    } else {
        SVector::<f64, 6>::from_fn(|_, _| st::normal(rng))
    };
    rf::case2_inputs(&a, &b)
}

/// Random hidden variable: `+-10^U(-2, 2)`.
fn hidden(rng: &mut rand_pcg::Pcg64) -> f64 {
    let s = if rand::Rng::random_bool(rng, 0.5) {
        1.0
    } else {
        -1.0
    };
    s * st::log_uniform(rng, -2.0, 2.0)
}

/// Random case-3 coefficients: `H = Bm^T Bm` from a random 5 x 6 `Bm` (entries `N(0,1) 10^U(-2,2)`),
/// through `case3_quartic` (checked separately).
fn case3_random(rng: &mut rand_pcg::Pcg64) -> [f64; 15] {
    let b = SMatrix::<f64, 5, 6>::from_fn(|_, _| st::normal(rng) * st::log_uniform(rng, -2.0, 2.0));
    let h = b.transpose() * b;
    k::case3_quartic(&rf::h_upper21(&h))
}

/// Compare a resultant `sum_j res_j y^j` with `det` of the numeric Sylvester matrix of the
/// cubics `(p, q)` (absolute-value scales `pa`, `qa`) at `y`. Returns `(error / Hadamard(|S|_abs),
/// error / bound)`. The bound is the sum of the kernel rounding `gamma_64 per(|Bez|_abs)` (the
/// kernel evaluates the Bezout determinant by cofactor expansion; the absolute-value evaluation
/// of that route at `|y|` is bounded by the permanent of the Bezout matrix of the
/// absolute-value coefficients), the rounding of my Sylvester entries (each `<= gamma_4` of its
/// scale: `6 gamma_4 per(|S|_abs)` by Laplace expansion along every row) and nalgebra's LU
/// error (`det_with_bound`).
fn resultant_vs_sylvester(
    res_at_y: f64,
    p: &[f64; 4],
    q: &[f64; 4],
    pa: &[f64; 4],
    qa: &[f64; 4],
) -> (f64, f64) {
    let s = rf::sylvester(p, q);
    let sa = rf::sylvester(pa, qa);
    let (det, lu_bound) = rf::det_with_bound(&s);
    let bound =
        g64() * rf::bezout_abs_permanent(pa, qa) + 6.0 * gamma(4) * rf::permanent(&sa) + lu_bound;
    let err = (det - res_at_y).abs();
    (err / rf::hadamard(&sa), err / bound)
}

/// Check 4, case 2: `case2_resultant` vs nalgebra's determinant of the Sylvester matrix of the
/// `nullspace` case 2 cubics at random `y`: `k1 y + k3 y^3 + ... + k9 y^9 = det Syl(g1, g2)(y)`.
#[must_use]
pub fn case2_resultant(n: usize) -> Measurement {
    let seed = 101;
    let mut rng = st::rng(seed);
    let mut t = Tracker::new(
        "case2_resultant",
        "vs det of numeric 6x6 Sylvester (eq. 22)",
        "|dRes| / Hadamard(|Syl|)",
        "derived per sample".into(),
    );
    for i in 0..n {
        let (q, p) = case2_random(&mut rng);
        let y = hidden(&mut rng);
        let kk = k::case2_resultant(&q, &p);
        let odd = [0.0, kk[0], 0.0, kk[1], 0.0, kk[2], 0.0, kk[3], 0.0, kk[4]];
        let (r, _) = rf::poly_eval(&odd, y);
        let (g1, g2, g1a, g2a) = rf::case2_cubics(&q, &p, y);
        let (err, ratio) = resultant_vs_sylvester(r, &g1, &g2, &g1a, &g2a);
        t.record(err, err / ratio.max(f64::MIN_POSITIVE), || {
            format!("seed {seed} sample {i} q = {q:?} p = {p:?} y = {y:e}")
        });
    }
    t.finish()
}

/// `case2_cubics` vs the `nullspace` case 2 formulas: per coefficient
/// `|d a_n| / |a_n|_abs <= 1e-12`.
#[must_use]
pub fn case2_cubics(n: usize) -> Measurement {
    let seed = 102;
    let mut rng = st::rng(seed);
    let mut t = Tracker::new(
        "case2_cubics",
        "vs g1, g2 of docs/algorithm.md, `nullspace` case 2",
        "max_n |d a_n| / |a_n|_abs",
        format!("{TOL_POLY:.0e}"),
    );
    for i in 0..n {
        let (q, p) = case2_random(&mut rng);
        let y = hidden(&mut rng);
        let out = k::case2_cubics(&q, &p, y);
        let (g1, g2, g1a, g2a) = rf::case2_cubics(&q, &p, y);
        let mut err = 0.0f64;
        for j in 0..4 {
            err = err.max((out[j] - g1[j]).abs() / g1a[j]);
            err = err.max((out[4 + j] - g2[j]).abs() / g2a[j]);
        }
        t.record(err, TOL_POLY, || {
            format!("seed {seed} sample {i} q = {q:?} p = {p:?} y = {y:e}")
        });
    }
    t.finish()
}

/// Known root, case 2: integer `A` (entries in [-4, 4]), dyadic `(x0, y0)`, `b = A a(x0, y0)`:
/// every input is exact, `C2 = |A (a - a0)|^2` is stationary at `(x0, y0)`, so
/// `Res(y0) = y0 q(y0^2) = 0` and `g1(x0) = g2(x0) = 0` at `y0` exactly. Bound: the kernel's
/// own rounding only, `gamma_64 per(|Bez|_abs)` for the resultant, `gamma_64 sum |a_n|_abs |x0|^n`
/// for the cubics. Two measurements on the same samples, each with its own worst ratio (a
/// resultant error of exactly 0 must not hide the cubics' residual):
/// - `case2_resultant`: `|q(beta0)| / sum_j |k_j| beta0^j` (the coefficient scale);
/// - `case2_cubics`: `max_i |g_i(x0)| / sum_n |a_n|_abs |x0|^n`.
#[must_use]
pub fn case2_known_root(n: usize) -> [Measurement; 2] {
    let seed = 103;
    let mut rng = st::rng(seed);
    let mut t = Tracker::new(
        "case2_resultant",
        "known root beta0 = y0^2",
        "|q(beta0)| / sum |k_j| beta0^j",
        "derived per sample".into(),
    );
    let mut tc = Tracker::new(
        "case2_cubics",
        "known root x0 at y0 (the same systems)",
        "max_i |g_i(x0)| / sum |a_n|_abs |x0|^n",
        "derived per sample".into(),
    );
    for i in 0..n {
        let a = SMatrix::<f64, 6, 3>::from_fn(|_, _| st::small_int(&mut rng, 4));
        let (x0, y0) = (st::dyadic(&mut rng), st::dyadic(&mut rng));
        let a0 = Vector3::new(x0 * x0, x0 * y0, y0 * y0);
        let b = a * a0;
        let (q, p) = rf::case2_inputs(&a, &b);
        let kk = k::case2_resultant(&q, &p);
        let beta = y0 * y0;
        let (qv, qs) = rf::poly_eval(&kk, beta);
        let (_, _, g1a, g2a) = rf::case2_cubics(&q, &p, y0);
        let ratio = (qv * y0).abs() / (g64() * rf::bezout_abs_permanent(&g1a, &g2a));
        let input = || {
            format!(
                "seed {seed} sample {i} x0 = {x0} y0 = {y0} A = {:?}",
                a.as_slice()
            )
        };
        t.record_ratio(qv.abs() / qs, ratio, input);
        let cub = k::case2_cubics(&q, &p, y0);
        let (mut cerr, mut cratio) = (0.0f64, 0.0f64);
        for (off, ga) in [(0usize, g1a), (4, g2a)] {
            let (v, _) = rf::poly_eval(&cub[off..off + 4], x0);
            let (_, sa) = rf::poly_eval(&ga, x0.abs());
            cerr = cerr.max(v.abs() / sa);
            cratio = cratio.max(v.abs() / (g64() * sa));
        }
        tc.record_ratio(cerr, cratio, input);
    }
    [t.finish(), tc.finish()]
}

/// `case3_quartic` vs `k^T H k` at random `(k1, k2)`: `|dC3| / (|k|^T |H| |k|) <= 1e-12`.
#[must_use]
pub fn case3_quartic(n: usize) -> Measurement {
    let seed = 111;
    let mut rng = st::rng(seed);
    let mut t = Tracker::new(
        "case3_quartic",
        "sum c_ij k1^i k2^j vs k^T H k",
        "|dC3| / |k|^T|H||k|",
        format!("{TOL_POLY:.0e}"),
    );
    let mons = rf::case3_monomials();
    for i in 0..n {
        let h = if rand::Rng::random_bool(&mut rng, 0.5) {
            let b = SMatrix::<f64, 5, 6>::from_fn(|_, _| {
                st::normal(&mut rng) * st::log_uniform(&mut rng, -2.0, 2.0)
            });
            b.transpose() * b
        } else {
            let x = SMatrix::<f64, 6, 6>::from_fn(|_, _| {
                st::normal(&mut rng) * st::log_uniform(&mut rng, -2.0, 2.0)
            });
            x + x.transpose()
        };
        let (k1, k2) = (hidden(&mut rng), hidden(&mut rng));
        let c = k::case3_quartic(&rf::h_upper21(&h));
        let v: f64 = c
            .iter()
            .zip(&mons)
            .map(|(ci, e)| ci * k1.powi(e[0] as i32) * k2.powi(e[1] as i32))
            .sum();
        let kv = rf::case3_k(k1, k2);
        let direct = kv.dot(&(h * kv));
        let scale = kv.abs().dot(&(h.abs() * kv.abs()));
        let err = (v - direct).abs() / scale;
        t.record(err, TOL_POLY, || {
            format!("seed {seed} sample {i} k = ({k1:e}, {k2:e})")
        });
    }
    t.finish()
}

/// `case3_cubics` vs the `nullspace` case 3 gradient cubics: per coefficient
/// `|d a_n| / |a_n|_abs <= 1e-12`.
#[must_use]
pub fn case3_cubics(n: usize) -> Measurement {
    let seed = 112;
    let mut rng = st::rng(seed);
    let mut t = Tracker::new(
        "case3_cubics",
        "vs dC3/dx, dC3/dy of docs/algorithm.md, `nullspace` case 3",
        "max_n |d a_n| / |a_n|_abs",
        format!("{TOL_POLY:.0e}"),
    );
    for i in 0..n {
        let c = case3_random(&mut rng);
        let y = hidden(&mut rng);
        let out = k::case3_cubics(&c, y);
        let (gx, gy, gxa, gya) = rf::case3_cubics(&c, y);
        let mut err = 0.0f64;
        for j in 0..4 {
            err = err.max((out[j] - gx[j]).abs() / gxa[j]);
            err = err.max((out[4 + j] - gy[j]).abs() / gya[j]);
        }
        t.record(err, TOL_POLY, || {
            format!("seed {seed} sample {i} c = {c:?} y = {y:e}")
        });
    }
    t.finish()
}

/// `case3_resultant` vs nalgebra's determinant of the Sylvester matrix of the `nullspace` case 3
/// cubics.
#[must_use]
pub fn case3_resultant(n: usize) -> Measurement {
    let seed = 113;
    let mut rng = st::rng(seed);
    let mut t = Tracker::new(
        "case3_resultant",
        "vs det of numeric 6x6 Sylvester",
        "|dRes| / Hadamard(|Syl|)",
        "derived per sample".into(),
    );
    for i in 0..n {
        let c = case3_random(&mut rng);
        let y = hidden(&mut rng);
        let res = k::case3_resultant(&c);
        let (r, _) = rf::poly_eval(&res, y);
        let (gx, gy, gxa, gya) = rf::case3_cubics(&c, y);
        let (err, ratio) = resultant_vs_sylvester(r, &gx, &gy, &gxa, &gya);
        t.record(err, err / ratio.max(f64::MIN_POSITIVE), || {
            format!("seed {seed} sample {i} c = {c:?} y = {y:e}")
        });
    }
    t.finish()
}

/// Known root, case 3: dyadic `(x0, y0)`, integer rows `w` of `Bm` (5 x 6, entries in [-4, 4])
/// with the last entry set to `-(w . k0)` so that `Bm k(x0, y0) = 0` exactly; `H = Bm^T Bm`
/// exact. `C3 = |Bm k|^2` is stationary at `(x0, y0)`: `Res(y0) = 0` and both cubics vanish at
/// `x0`. Bound: kernel rounding only (`gamma_64` times the absolute-value scales, as for case 2).
/// Two measurements on the same samples, as for case 2: `case3_resultant` at `y0` and
/// `case3_cubics` at `x0`.
#[must_use]
pub fn case3_known_root(n: usize) -> [Measurement; 2] {
    let seed = 114;
    let mut rng = st::rng(seed);
    let mut t = Tracker::new(
        "case3_resultant",
        "known root y0",
        "|Res(y0)| / sum |r_j| |y0|^j",
        "derived per sample".into(),
    );
    let mut tc = Tracker::new(
        "case3_cubics",
        "known root x0 at y0 (the same systems)",
        "max_i |g_i(x0)| / sum |a_n|_abs |x0|^n",
        "derived per sample".into(),
    );
    for i in 0..n {
        let (x0, y0) = (st::dyadic(&mut rng), st::dyadic(&mut rng));
        let k0 = rf::case3_k(x0, y0);
        let mut bm = SMatrix::<f64, 5, 6>::from_fn(|_, _| st::small_int(&mut rng, 4));
        for row in 0..5 {
            let dot: f64 = (0..5).map(|j| bm[(row, j)] * k0[j]).sum();
            bm[(row, 5)] = -dot;
        }
        debug_assert!((bm * k0).amax() == 0.0);
        let h = bm.transpose() * bm;
        let c = k::case3_quartic(&rf::h_upper21(&h));
        let res = k::case3_resultant(&c);
        let (rv, rs) = rf::poly_eval(&res, y0);
        let (_, _, gxa, gya) = rf::case3_cubics(&c, y0);
        let ratio = rv.abs() / (g64() * rf::bezout_abs_permanent(&gxa, &gya));
        let input = || {
            format!(
                "seed {seed} sample {i} x0 = {x0} y0 = {y0} Bm = {:?}",
                bm.as_slice()
            )
        };
        t.record_ratio(rv.abs() / rs, ratio, input);
        let cub = k::case3_cubics(&c, y0);
        let (mut cerr, mut cratio) = (0.0f64, 0.0f64);
        for (off, ga) in [(0usize, gxa), (4, gya)] {
            let (v, _) = rf::poly_eval(&cub[off..off + 4], x0);
            let (_, sa) = rf::poly_eval(&ga, x0.abs());
            cerr = cerr.max(v.abs() / sa);
            cratio = cratio.max(v.abs() / (g64() * sa));
        }
        tc.record_ratio(cerr, cratio, input);
    }
    [t.finish(), tc.finish()]
}

/// Random case-4 inputs `t` (21 numbers, entries `N(0,1) 10^U(-1, 1)`).
fn case4_random(rng: &mut rand_pcg::Pcg64) -> [f64; 21] {
    std::array::from_fn(|_| st::normal(rng) * st::log_uniform(rng, -1.0, 1.0))
}

/// `case4_matrix` evaluated at random `k1` vs `M(k1)` from the `nullspace` case 4 row formulas with
/// numeric `T(k1)`: per entry `|dM_ij| / |M|_abs,ij <= 1e-12`.
#[must_use]
pub fn case4_matrix(n: usize) -> Measurement {
    let seed = 121;
    let mut rng = st::rng(seed);
    let mut t = Tracker::new(
        "case4_matrix",
        "vs row_i, row_ii, row_iii of docs/algorithm.md, `nullspace` case 4",
        "max_ij |dM_ij| / |M|_abs,ij",
        format!("{TOL_POLY:.0e}"),
    );
    for i in 0..n {
        let tt = case4_random(&mut rng);
        let k1 = hidden(&mut rng);
        let out = k::case4_matrix(&tt);
        let mk = rf::case4_layout_at(&out, k1);
        let (tv, ta) = rf::case4_t_at(&tt, k1);
        let mf = rf::case4_m_from_t(&tv, false);
        let ma = rf::case4_m_from_t(&ta, true);
        let err = (mk - mf).component_div(&ma).amax();
        t.record(err, TOL_POLY, || {
            format!("seed {seed} sample {i} t = {tt:?} k1 = {k1:e}")
        });
    }
    t.finish()
}

/// `case4_determinant` at random `k1` vs nalgebra's determinant of the numeric `M(k1)` (the
/// 45-number layout of `case4_matrix` evaluated at `k1`). Bound: `(gamma_64 + 3 gamma_32)
/// per(|M|_abs)` (kernel cofactor route, and the rounding of the numeric entries by Laplace
/// expansion) + nalgebra's LU bound.
#[must_use]
pub fn case4_determinant(n: usize) -> Measurement {
    let seed = 122;
    let mut rng = st::rng(seed);
    let mut t = Tracker::new(
        "case4_determinant",
        "vs det of numeric M(k1)",
        "|d det| / Hadamard(|M|_abs)",
        "derived per sample".into(),
    );
    for i in 0..n {
        let tt = case4_random(&mut rng);
        let k1 = hidden(&mut rng);
        let d = k::case4_determinant(&tt);
        let (dv, _) = rf::poly_eval(&d, k1);
        let mk = rf::case4_layout_at(&k::case4_matrix(&tt), k1);
        let (_, ta) = rf::case4_t_at(&tt, k1);
        let ma = DMatrix::from_iterator(3, 3, rf::case4_m_from_t(&ta, true).iter().copied());
        let (det, lu_bound) = rf::det_with_bound(&DMatrix::from_iterator(3, 3, mk.iter().copied()));
        let bound = (g64() + 3.0 * gamma(32)) * rf::permanent(&ma) + lu_bound;
        let errabs = (dv - det).abs();
        let err = errabs / rf::hadamard(&ma);
        t.record(err, err * bound / errabs.max(f64::MIN_POSITIVE), || {
            format!("seed {seed} sample {i} t = {tt:?} k1 = {k1:e}")
        });
    }
    t.finish()
}

/// The known-root system of case 4 (see [`case4_known_root`]): returns `t` (21 inputs) and
/// `(k1*, k2*, k3*)`.
pub fn case4_known_system(rng: &mut rand_pcg::Pcg64) -> ([f64; 21], [f64; 3]) {
    let ks = [st::dyadic(rng), st::dyadic(rng), st::dyadic(rng)];
    let v = nalgebra::Vector4::new(1.0, ks[0], ks[1], ks[2]);
    // Mm = L U, unit triangular integer factors: det Mm = 1, Mm^-1 = adj(Mm) exact.
    let mut l = Matrix3::identity();
    let mut u = Matrix3::identity();
    for i in 0..3 {
        for j in 0..i {
            l[(i, j)] = st::small_int(rng, 2);
            u[(j, i)] = st::small_int(rng, 2);
        }
    }
    let mm = l * u;
    let mut n0 = Matrix3::zeros();
    let mut n1 = Matrix3::zeros();
    let mut n2 = Matrix3::zeros();
    for e in 0..3 {
        // the symmetric 4 x 4 form of equation e over (1, k1, k2, k3)
        let mut f = nalgebra::Matrix4::<f64>::zeros();
        for a in 0..4 {
            for b in a..4 {
                let x = st::small_int(rng, 4);
                f[(a, b)] = x;
                f[(b, a)] = x;
            }
        }
        f[(2, 2)] = mm[(e, 0)];
        f[(3, 3)] = mm[(e, 1)];
        f[(2, 3)] = mm[(e, 2)] / 2.0;
        f[(3, 2)] = mm[(e, 2)] / 2.0;
        f[(0, 0)] -= v.dot(&(f * v)); // exact: dyadic arithmetic
        debug_assert_eq!(v.dot(&(f * v)), 0.0);
        // [2 F02 + 2 F12 k1, 2 F03 + 2 F13 k1, F00 + 2 F01 k1 + F11 k1^2]
        n0[(e, 0)] = 2.0 * f[(0, 2)];
        n1[(e, 0)] = 2.0 * f[(1, 2)];
        n0[(e, 1)] = 2.0 * f[(0, 3)];
        n1[(e, 1)] = 2.0 * f[(1, 3)];
        n0[(e, 2)] = f[(0, 0)];
        n1[(e, 2)] = 2.0 * f[(0, 1)];
        n2[(e, 2)] = f[(1, 1)];
    }
    let adj = Matrix3::from_fn(|i, j| {
        // adj_ij = (-1)^(i+j) minor_ji
        let rows: Vec<usize> = (0..3).filter(|&x| x != j).collect();
        let cols: Vec<usize> = (0..3).filter(|&x| x != i).collect();
        let minor = mm[(rows[0], cols[0])] * mm[(rows[1], cols[1])]
            - mm[(rows[0], cols[1])] * mm[(rows[1], cols[0])];
        if (i + j) % 2 == 0 {
            minor
        } else {
            -minor
        }
    });
    debug_assert_eq!(adj * mm, Matrix3::identity());
    let tn = [-adj * n0, -adj * n1, -adj * n2];
    let layout = rf::case4_layout();
    let t: [f64; 21] = std::array::from_fn(|x| {
        let e = layout[x];
        tn[e[2] as usize][(e[0] as usize, e[1] as usize)]
    });
    (t, ks)
}

/// Known root, case 4: three symmetric integer 4 x 4 forms over `(1, k1, k2, k3)` with the
/// `(k2, k3)` block an integer unimodular `Mm` and `F00` adjusted so that every form vanishes
/// at a dyadic `(k1*, k2*, k3*)`; `T = -Mm^-1 N(k1)` exactly (adjugate). Then `det M(k1*) = 0`
/// and `M(k1*) [k2*, k3*, 1] = 0` exactly; bounds: kernel rounding `gamma_64 per(|M|_abs)` and
/// `gamma_64 (|M|_abs |y*|)_i`. Two measurements on the same samples, as for case 2:
/// - `case4_determinant`: `|det M(k1*)| / Hadamard(|M|_abs)`;
/// - `case4_matrix`: `max_i |(M(k1*) y*)_i| / (|M|_abs |y*|)_i`.
#[must_use]
pub fn case4_known_root(n: usize) -> [Measurement; 2] {
    let seed = 123;
    let mut rng = st::rng(seed);
    let mut t = Tracker::new(
        "case4_determinant",
        "known root k1*",
        "|det M(k1*)| / Hadamard(|M|_abs)",
        "derived per sample".into(),
    );
    let mut tm = Tracker::new(
        "case4_matrix",
        "known root: M(k1*) y* = 0 (the same systems)",
        "max_i |(M(k1*) y*)_i| / (|M|_abs |y*|)_i",
        "derived per sample".into(),
    );
    for i in 0..n {
        let (tt, ks) = case4_known_system(&mut rng);
        let (_, ta) = rf::case4_t_at(&tt, ks[0]);
        let ma = rf::case4_m_from_t(&ta, true);
        let mad = DMatrix::from_iterator(3, 3, ma.iter().copied());
        let (dv, _) = rf::poly_eval(&k::case4_determinant(&tt), ks[0]);
        let ratio = dv.abs() / (g64() * rf::permanent(&mad));
        let input = || format!("seed {seed} sample {i} k* = {ks:?} t = {tt:?}");
        t.record_ratio(dv.abs() / rf::hadamard(&mad), ratio, input);
        let mk = rf::case4_layout_at(&k::case4_matrix(&tt), ks[0]);
        let y = Vector3::new(ks[1], ks[2], 1.0);
        let resid = mk * y;
        let rscale = ma * y.abs();
        let (mut merr, mut mratio) = (0.0f64, 0.0f64);
        for r in 0..3 {
            merr = merr.max(resid[r].abs() / rscale[r]);
            mratio = mratio.max(resid[r].abs() / (g64() * rscale[r]));
        }
        tm.record_ratio(merr, mratio, input);
    }
    [t.finish(), tm.finish()]
}
