use super::*;
use crate::pipeline::frame::working_frame;
use crate::pipeline::frame::WorkingFrame;
use nalgebra::{DMatrix, Rotation3};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

/// Explicit `M = K^T K`, `G` from the stacked, weighted W and V (tests only).
fn explicit(p: &[Vector3<f64>], uv: &[Point2<f64>], w: &[f64]) -> (DMatrix<f64>, DMatrix<f64>) {
    let n = p.len();
    let mut wm = DMatrix::zeros(2 * n, 3);
    let mut vm = DMatrix::zeros(2 * n, 9);
    for i in 0..n {
        let sq = w[i].sqrt();
        let (u, v) = (uv[i].x, uv[i].y);
        wm[(2 * i, 0)] = sq;
        wm[(2 * i, 2)] = -u * sq;
        wm[(2 * i + 1, 1)] = sq;
        wm[(2 * i + 1, 2)] = -v * sq;
        for j in 0..3 {
            vm[(2 * i, j)] = -p[i][j] * sq;
            vm[(2 * i, 6 + j)] = u * p[i][j] * sq;
            vm[(2 * i + 1, 3 + j)] = -p[i][j] * sq;
            vm[(2 * i + 1, 6 + j)] = v * p[i][j] * sq;
        }
    }
    let wtw = wm.transpose() * &wm;
    let g = wtw.lu().solve(&(wm.transpose() * &vm)).unwrap();
    let k = &wm * &g - &vm;
    (k.transpose() * &k, g)
}

fn rel_diff(a: &SMatrix<f64, 9, 9>, b: &DMatrix<f64>) -> f64 {
    let mut num = 0.0f64;
    for i in 0..9 {
        for j in 0..9 {
            num = num.max((a[(i, j)] - b[(i, j)]).abs());
        }
    }
    num / a.amax()
}

struct Problem {
    world: Vec<Point3<f64>>,
    image: Vec<Point2<f64>>,
    r: Matrix3<f64>,
    t: Vector3<f64>,
}

fn problem(rng: &mut Pcg64, n: usize, noise: f64, planar: bool) -> Problem {
    let r = Rotation3::from_scaled_axis(Vector3::new(
        rng.random_range(-2.0..2.0),
        rng.random_range(-2.0..2.0),
        rng.random_range(-2.0..2.0),
    ))
    .into_inner();
    // Points in a box of half-size 2 around `offset`, the camera 8 units from its centre:
    // depths in [~4.5, ~11.5].
    let offset = Vector3::new(10.0, -4.0, 1.5);
    let t = Vector3::new(
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
        8.0,
    ) - r * offset;
    let world: Vec<Point3<f64>> = (0..n)
        .map(|_| {
            Point3::from(
                Vector3::new(
                    rng.random_range(-2.0..2.0),
                    rng.random_range(-2.0..2.0),
                    if planar {
                        0.0
                    } else {
                        rng.random_range(-2.0..2.0)
                    },
                ) + offset,
            )
        })
        .collect();
    let image = world
        .iter()
        .map(|x| {
            let pc = r * x.coords + t;
            Point2::new(
                pc.x / pc.z + noise * rng.random_range(-1.0..1.0),
                pc.y / pc.z + noise * rng.random_range(-1.0..1.0),
            )
        })
        .collect();
    Problem { world, image, r, t }
}

fn row_major(r: &Matrix3<f64>) -> SMatrix<f64, 9, 1> {
    SMatrix::<f64, 9, 1>::from_iterator((0..9).map(|k| r[(k / 3, k % 3)]))
}

#[test]
fn matches_explicit_k_t_k() {
    let mut rng = Pcg64::seed_from_u64(21);
    for trial in 0..60 {
        let n = 4 + trial % 30;
        let pr = problem(&mut rng, n, 0.01, trial % 4 == 0);
        let w: Vec<f64> = if trial % 2 == 0 {
            vec![1.0; n]
        } else {
            (0..n).map(|_| rng.random_range(0.0..3.0)).collect()
        };
        let wopt = if trial % 2 == 0 { None } else { Some(&w[..]) };
        let frame = working_frame(&pr.world, &pr.image, wopt, true).unwrap();
        let acc = accumulate(&pr.world, &pr.image, wopt, &frame);
        let p: Vec<Vector3<f64>> = pr.world.iter().map(|x| frame.to_working(x)).collect();
        for flatten in [false, true] {
            let sys = acc.system(flatten).unwrap();
            let pf: Vec<Vector3<f64>> = if flatten {
                p.iter().map(|x| Vector3::new(x.x, x.y, 0.0)).collect()
            } else {
                p.clone()
            };
            let (m, g) = explicit(&pf, &pr.image, &w);
            // Cancellation in V^T V - (W^T V)^T G; measured ~1e-15 relative to max |M|
            // (docs/algorithm.md, `moments` quotes 9e-16); 1e-13 leaves room for N up to 33.
            assert!(
                rel_diff(&sys.m, &m) < 1e-13,
                "{trial} {flatten}: {:e}",
                rel_diff(&sys.m, &m)
            );
            let gd = (0..27)
                .map(|k| (sys.g[(k / 9, k % 9)] - g[(k / 9, k % 9)]).abs())
                .fold(0.0, f64::max);
            assert!(gd < 1e-13 * sys.g.amax().max(1.0));
            assert_eq!(sys.m, sys.m.transpose());
            assert!((sys.trace - sys.m.trace()).abs() == 0.0);
            if flatten {
                for k in [2usize, 5, 8] {
                    assert!(sys.m.row(k).iter().all(|&x| x == 0.0));
                }
            }
        }
    }
}

/// The centred pass as a sequential loop (the scalar formulas of [`centred_pass`], one
/// running sum each, in point order): the reference of the vectorised pass.
fn centred_sequential(
    world: &[Point3<f64>],
    image: &[Point2<f64>],
    weights: Option<&[f64]>,
    map: &CentredMap,
    a: Option<&Matrix3<f64>>,
) -> (Sums, f64) {
    let mut s: Sums = [[0.0; 4]; 10];
    let mut spread = 0.0;
    for i in 0..world.len().min(image.len()) {
        let w = weights.map_or(1.0, |ws| ws[i]);
        if w <= 0.0 {
            continue;
        }
        let w = w * map.inv_weight;
        let x = &world[i];
        let y = Vector3::new(
            x.x * map.inv_unit - map.centre.x,
            x.y * map.inv_unit - map.centre.y,
            x.z * map.inv_unit - map.centre.z,
        );
        let p = match a {
            Some(a) => {
                Vector3::from_fn(|r, _| a[(r, 0)] * y[0] + a[(r, 1)] * y[1] + a[(r, 2)] * y[2])
            }
            None => y,
        };
        let (u, v) = (image[i].x, image[i].y);
        let du = u * map.inv_image - map.image_mean.x;
        let dv = v * map.inv_image - map.image_mean.y;
        spread += w * (du * du + dv * dv);
        let q = u * u + v * v;
        let f = [w, w * u, w * v, w * q];
        let mono = [
            1.0,
            p[0],
            p[1],
            p[2],
            p[0] * p[0],
            p[0] * p[1],
            p[0] * p[2],
            p[1] * p[1],
            p[1] * p[2],
            p[2] * p[2],
        ];
        for k in 0..10 {
            for j in 0..4 {
                s[k][j] += f[j] * mono[k];
            }
        }
    }
    (s, spread)
}

/// Random points for [`accumulate_centred`]: world coordinates in a box off the origin,
/// image coordinates within (-1, 1).
fn centred_problem(rng: &mut Pcg64, n: usize) -> (Vec<Point3<f64>>, Vec<Point2<f64>>) {
    let world = (0..n)
        .map(|_| {
            Point3::new(
                rng.random_range(2.0..6.0),
                rng.random_range(-3.0..1.0),
                rng.random_range(-1.0..1.5),
            )
        })
        .collect();
    let image = (0..n)
        .map(|_| Point2::new(rng.random_range(-0.7..0.9), rng.random_range(-0.8..0.6)))
        .collect();
    (world, image)
}

#[test]
fn centred_pass_matches_sequential() {
    // The vectorised pass against the sequential loop: every sum within the bound of the
    // rounding of either summation order (2 N eps times the sum of the magnitudes of its
    // terms); `sum w` without weights exactly (N times the unit).
    let mut rng = Pcg64::seed_from_u64(31);
    let rot = Rotation3::from_scaled_axis(Vector3::new(0.4, -0.9, 1.3)).into_inner() * 0.7;
    for trial in 0..48 {
        let n = [1usize, 3, 4, 5, 7, 8, 9, 50, 203][trial % 9];
        let (world, image) = centred_problem(&mut rng, n);
        let w: Vec<f64> = (0..n)
            .map(|i| {
                if i % 3 == 1 {
                    0.0
                } else {
                    rng.random_range(0.1..2.0)
                }
            })
            .collect();
        let wopt = if trial % 2 == 0 { None } else { Some(&w[..]) };
        let map = CentredMap {
            inv_unit: [0.125, 1.0, 0.25][trial % 3],
            centre: Vector3::new(0.5, -0.25, 0.125),
            // Without weights also a unit other than 1 (not from `frame`): exact scaling.
            inv_weight: if wopt.is_some() {
                0.5
            } else {
                [1.0, 0.25][trial / 12 % 2]
            },
            inv_image: [1.0, 0.5][trial / 3 % 2],
            image_mean: Vector2::new(0.1, -0.05),
        };
        let a = if trial / 6 % 2 == 0 { None } else { Some(&rot) };
        let got = accumulate_centred(&world, &image, wopt, &map, a);
        let (want, spread) = centred_sequential(&world, &image, wopt, &map, a);
        let (mag, mag_spread) = {
            let abs_w: Vec<f64> = w.iter().map(|x| x.abs()).collect();
            let abs_world: Vec<Point3<f64>> = world
                .iter()
                .map(|x| {
                    let y = Vector3::new(
                        x.x * map.inv_unit - map.centre.x,
                        x.y * map.inv_unit - map.centre.y,
                        x.z * map.inv_unit - map.centre.z,
                    );
                    let p = a.map_or(y, |a| a * y);
                    Point3::from(p.abs())
                })
                .collect();
            let abs_image: Vec<Point2<f64>> =
                image.iter().map(|m| Point2::from(m.coords.abs())).collect();
            let abs_map = CentredMap {
                inv_unit: 1.0,
                centre: Vector3::zeros(),
                ..map
            };
            let abs_weights = wopt.map(|_| &abs_w[..]);
            centred_sequential(&abs_world, &abs_image, abs_weights, &abs_map, None)
        };
        let acc = &got.acc;
        let vec3 = |v: &Vector3<f64>| [v[0], v[1], v[2]];
        let row = |m: &Matrix3<f64>| {
            [
                m[(0, 0)],
                m[(0, 1)],
                m[(0, 2)],
                m[(1, 1)],
                m[(1, 2)],
                m[(2, 2)],
            ]
        };
        let mut flat = [[0.0; 4]; 10];
        let scalars = [acc.sw, acc.su, acc.sv, acc.sq];
        let vecs = [vec3(&acc.a), vec3(&acc.a_u), vec3(&acc.a_v), vec3(&acc.a_q)];
        let mats = [row(&acc.s), row(&acc.s_u), row(&acc.s_v), row(&acc.s_q)];
        for j in 0..4 {
            flat[0][j] = scalars[j];
            for r in 0..3 {
                flat[1 + r][j] = vecs[j][r];
            }
            for r in 0..6 {
                flat[4 + r][j] = mats[j][r];
            }
        }
        for k in 0..10 {
            for j in 0..4 {
                let tol = 2.0 * n as f64 * f64::EPSILON * mag[k][j];
                assert!(
                    (flat[k][j] - want[k][j]).abs() <= tol,
                    "{trial} {k} {j}: {:e} {:e}",
                    flat[k][j],
                    want[k][j]
                );
            }
        }
        assert!((got.spread - spread).abs() <= 2.0 * n as f64 * f64::EPSILON * mag_spread);
        if wopt.is_none() {
            assert_eq!(acc.sw, n as f64 * map.inv_weight, "{trial}");
        }
    }
}

#[test]
fn centred_pass_zero_weights_bit_identical() {
    // Points of weight 0 anywhere (before, inside and after blocks) give the sums of the
    // remaining points to the bit.
    let mut rng = Pcg64::seed_from_u64(32);
    let rot = Rotation3::from_scaled_axis(Vector3::new(-0.3, 1.1, 0.2)).into_inner();
    for n in [4usize, 5, 9, 13, 40] {
        let (world, image) = centred_problem(&mut rng, n);
        let w: Vec<f64> = (0..n).map(|_| rng.random_range(0.1..2.0)).collect();
        let map = CentredMap {
            inv_unit: 0.25,
            centre: Vector3::new(0.9, -0.3, 0.05),
            inv_weight: 0.5,
            inv_image: 1.0,
            image_mean: Vector2::new(0.05, 0.1),
        };
        for a in [None, Some(&rot)] {
            let base = accumulate_centred(&world, &image, Some(&w), &map, a);
            for at in [0, 1, n / 2, n] {
                for count in [1usize, 3, 4] {
                    let (mut world2, mut image2, mut w2) =
                        (world.clone(), image.clone(), w.clone());
                    for c in 0..count {
                        world2.insert(at, Point3::new(1e3 + c as f64, -7.0, 2.0));
                        image2.insert(at, Point2::new(-9.0, 0.3));
                        w2.insert(at, 0.0);
                    }
                    let got = accumulate_centred(&world2, &image2, Some(&w2), &map, a);
                    assert_eq!(got, base, "{n} {at} {count}");
                }
            }
        }
    }
}

#[test]
fn zero_weight_bit_identical() {
    let mut rng = Pcg64::seed_from_u64(22);
    let pr = problem(&mut rng, 9, 0.01, false);
    let w: Vec<f64> = (0..9).map(|_| rng.random_range(0.5..2.0)).collect();
    let f = working_frame(&pr.world, &pr.image, Some(&w), true).unwrap();
    let a = accumulate(&pr.world, &pr.image, Some(&w), &f);
    let mut world = pr.world.clone();
    let mut image = pr.image.clone();
    let mut w2 = w.clone();
    world.insert(4, Point3::new(3.0, 1e4, -2.0));
    image.insert(4, Point2::new(-9.0, 0.3));
    w2.insert(4, 0.0);
    let f2 = working_frame(&world, &image, Some(&w2), true).unwrap();
    let b = accumulate(&world, &image, Some(&w2), &f2);
    assert_eq!(a, b);
    assert_eq!(a.system(false), b.system(false));
}

#[test]
fn sign_check_at_noise_free_truth() {
    let mut rng = Pcg64::seed_from_u64(23);
    for trial in 0..40 {
        let pr = problem(&mut rng, 6 + trial % 10, 0.0, trial % 3 == 0);
        let frame = working_frame(&pr.world, &pr.image, None, true).unwrap();
        let sys = accumulate(&pr.world, &pr.image, None, &frame)
            .system(false)
            .unwrap();
        let (rw, tw) = frame.to_work_pose(&pr.r, &pr.t);
        let r = row_major(&rw);
        let t = sys.g * r;
        // t = G r exactly at the truth: rounding of O(1) quantities, ~1e-16 (`moments`).
        assert!((t - tw).amax() < 1e-14 * tw.norm(), "{:e}", (t - tw).amax());
        // f(R_true) = 0 to rounding relative to trace(M).
        let f = (r.transpose() * sys.m * r)[0];
        assert!(f.abs() < 1e-14 * sys.trace);
    }
}

#[test]
fn matches_python_reference() {
    // general_N6_sigma2 of the reference prototype's test vectors: inputs, the stored
    // working-frame M, G and Rw.
    let r = crate::test_data::vector("general_N6_sigma2");
    let frame = working_frame(&r.world, &r.image, None, true).unwrap();
    let sys = accumulate(&r.world, &r.image, None, &frame)
        .system(false)
        .unwrap();
    // Align the working frames: D = Rw Rw_ref^T is diagonal +-1 (section 8).
    let dm = frame.rw * r.rw.transpose();
    // Off-diagonal of D: rounding of the SVDs, ~1e-15.
    assert!((dm.abs() - Matrix3::identity()).amax() < 1e-13);
    let mut bd = SMatrix::<f64, 9, 9>::zeros();
    for b in 0..3 {
        for k in 0..3 {
            bd[(3 * b + k, 3 * b + k)] = dm[(k, k)].signum();
        }
    }
    let m_al = bd * r.m * bd.transpose();
    let g_al = r.g * bd.transpose();
    // Section 8: M, G within 1e-12 relative.
    assert!(
        (sys.m - m_al).amax() < 1e-12 * m_al.amax(),
        "{:e}",
        (sys.m - m_al).amax()
    );
    assert!((sys.g - g_al).amax() < 1e-12 * g_al.amax());
}

#[test]
fn image_scatter_keeps_its_accuracy_on_nearly_coincident_images() {
    // Image points within 1e-10 of (0.3, -0.2): `sq - (su^2 + sv^2) / sw` is left with the
    // rounding of sums of size 0.13 (about 1e-17 each) against a true value of about 1e-20
    // per point, so it is noise (of either sign); the scatter about the mean keeps its
    // relative accuracy, and the system exists.
    let mut rng = Pcg64::seed_from_u64(31);
    for trial in 0..50 {
        let pr = problem(&mut rng, 6 + trial % 10, 0.0, false);
        let image: Vec<Point2<f64>> = (0..pr.world.len())
            .map(|_| {
                Point2::new(
                    0.3 + 1e-10 * rng.random_range(-1.0..1.0),
                    -0.2 + 1e-10 * rng.random_range(-1.0..1.0),
                )
            })
            .collect();
        let frame = working_frame(&pr.world, &image, None, true).unwrap();
        let n = image.len() as f64;
        let mean = image
            .iter()
            .fold((0.0, 0.0), |a, m| (a.0 + m.x / n, a.1 + m.y / n));
        // Deviations of 1e-10 are exact to about 1e-17 / 1e-10 = 1e-7 relative.
        let exact: f64 = image
            .iter()
            .map(|m| (m.x - mean.0).powi(2) + (m.y - mean.1).powi(2))
            .sum();
        let got = frame.sums.image_scatter;
        assert!(
            (got / exact - 1.0).abs() < 1e-5,
            "{trial}: {got:e} {exact:e}"
        );
        assert!(frame.sums.system(false).is_some(), "{trial}");
    }
}

#[test]
fn singular_wtw_gives_none() {
    let acc = Accumulator {
        sw: 4.0,
        su: 4.0,
        sv: -8.0,
        sq: 4.0 * 5.0, // all four image points at (1, -2): W^T W singular
        a: Vector3::zeros(),
        a_u: Vector3::zeros(),
        a_v: Vector3::zeros(),
        a_q: Vector3::zeros(),
        s: Matrix3::identity(),
        s_u: Matrix3::identity(),
        s_v: Matrix3::identity(),
        s_q: Matrix3::identity(),
        image_scatter: 0.0,
    };
    assert!(acc.system(false).is_none());
    let mut bad = acc;
    bad.sq = f64::INFINITY;
    assert!(bad.system(false).is_none());
}

#[test]
fn m_upper_order() {
    let m = SMatrix::<f64, 9, 9>::from_fn(|i, j| (i.min(j) * 10 + i.max(j)) as f64);
    let u = m_upper(&m);
    assert_eq!(u[0], 0.0);
    assert_eq!(u[8], 8.0);
    assert_eq!(u[9], 11.0);
    assert_eq!(u[16], 18.0);
    assert_eq!(u[17], 22.0);
    assert_eq!(u[44], 88.0);
}

/// The reference of the tests: the `moments` sums over the points with weight > 0, transforming
/// each world point to the working frame on the fly ([`WorkingFrame::to_working`]). Weights must
/// already be validated ([`crate::pipeline::frame::working_frame`]); a point with weight 0 is
/// skipped, so it gives bit-identical sums to removing it.
pub(crate) fn accumulate(
    world: &[Point3<f64>],
    image: &[Point2<f64>],
    weights: Option<&[f64]>,
    frame: &WorkingFrame,
) -> Accumulator {
    let mut sw = 0.0;
    let mut su = 0.0;
    let mut sv = 0.0;
    let mut sq = 0.0;
    let mut a = Vector3::zeros();
    let mut a_u = Vector3::zeros();
    let mut a_v = Vector3::zeros();
    let mut a_q = Vector3::zeros();
    let mut s = [0.0f64; 6];
    let mut s_u = [0.0f64; 6];
    let mut s_v = [0.0f64; 6];
    let mut s_q = [0.0f64; 6];
    let n = world.len().min(image.len());
    for i in 0..n {
        let w = match weights {
            Some(ws) => ws[i],
            None => 1.0,
        };
        if w <= 0.0 {
            continue;
        }
        let p = frame.to_working(&world[i]);
        let (u, v) = (image[i].x, image[i].y);
        let q = u * u + v * v;
        let (wu, wv, wq) = (w * u, w * v, w * q);
        sw += w;
        su += wu;
        sv += wv;
        sq += wq;
        let wp = p * w;
        a += wp;
        a_u += p * wu;
        a_v += p * wv;
        a_q += p * wq;
        for (k, &(r, c)) in SYM6.iter().enumerate() {
            let pp = wp[r] * p[c];
            s[k] += pp;
            s_u[k] += u * pp;
            s_v[k] += v * pp;
            s_q[k] += q * pp;
        }
    }
    let full = |x: &[f64; 6]| {
        Matrix3::new(
            x[0], x[1], x[2], //
            x[1], x[3], x[4], //
            x[2], x[4], x[5],
        )
    };
    // The image scatter about the weighted mean, in a second loop.
    let mean = (su / sw, sv / sw);
    let mut image_scatter = 0.0;
    for (i, m) in image.iter().enumerate() {
        let w = weights.map_or(1.0, |w| w[i]);
        if w > 0.0 {
            image_scatter += w * ((m.x - mean.0).powi(2) + (m.y - mean.1).powi(2));
        }
    }
    Accumulator {
        image_scatter,
        sw,
        su,
        sv,
        sq,
        a,
        a_u,
        a_v,
        a_q,
        s: full(&s),
        s_u: full(&s_u),
        s_v: full(&s_v),
        s_q: full(&s_q),
    }
}
