//! The `solve` and `ransac` targets: the properties of a solution, the typed errors of
//! malformed input, and the exact-pose property on well-posed exact problems.

use eopnp::ransac::Ransac;
use eopnp::{PnpError, Solution};
use nalgebra::{Matrix3, Point2, Point3, Rotation3, Vector3};

use super::decode::{decode_problem, decode_solver, Problem, Reader};

/// The properties of a returned solution.
pub fn check_solution(s: &Solution) {
    let t = s.translation;
    assert!(
        t.iter().all(|x| x.is_finite()),
        "non-finite translation {t:?}"
    );
    let r = s.rotation;
    assert!(r.iter().all(|x| x.is_finite()), "non-finite rotation {r:?}");
    let orth = (r.transpose() * r - Matrix3::identity()).norm();
    assert!(
        orth < 1e-9,
        "rotation not orthonormal: |R^T R - I| = {orth:e}"
    );
    assert!(
        r.determinant() > 0.0,
        "reflection returned: det R = {}",
        r.determinant()
    );
    let q = s.pose().rotation.to_rotation_matrix().into_inner();
    let dq = (q - r).norm();
    assert!(dq < 1e-9, "pose.rotation and rotation differ by {dq:e}");
    // The rmse is +inf, never NaN, when a point lies in the focal plane of an algebraic-mode
    // pose (documented); the default mode never returns such a pose.
    assert!(
        s.reprojection_rmse.is_finite() || s.reprojection_rmse == f64::INFINITY,
        "reprojection_rmse = {}",
        s.reprojection_rmse
    );
    assert!(
        s.reprojection_rmse.is_finite() || s.reprojection_iterations == 0,
        "an infinite reprojection error after the reprojection refinement"
    );
    for (name, v) in [("cost", s.cost), ("algebraic_cost", s.algebraic_cost)] {
        // Costs are sums of squares; tiny negative values from rounding in f / trace(M) are
        // allowed.
        assert!(v.is_finite() && v >= -1e-9, "{name} = {v}");
    }
}

/// What the input checks must say about a problem, whatever the solver does afterwards: the
/// first error in the documented order, or `None` when the input is acceptable so far.
fn expected_input_error(p: &Problem) -> Option<PnpError> {
    if p.world.len() != p.image.len() {
        return Some(PnpError::LengthMismatch {
            world: p.world.len(),
            image: p.image.len(),
        });
    }
    if let Some(w) = &p.weights {
        if w.len() != p.world.len() {
            return Some(PnpError::WeightsLength {
                weights: w.len(),
                points: p.world.len(),
            });
        }
    }
    None
}

fn all_finite(p: &Problem) -> bool {
    p.world
        .iter()
        .all(|x| x.coords.iter().all(|v| v.is_finite()))
        && p.image
            .iter()
            .all(|x| x.coords.iter().all(|v| v.is_finite()))
        && p.weights.iter().flatten().all(|w| w.is_finite())
}

/// Checks a result against the input: typed errors for malformed input, properties for `Ok`.
fn check_result(p: &Problem, res: &Result<Solution, PnpError>) {
    if let Some(e) = expected_input_error(p) {
        assert_eq!(
            res.as_ref().err(),
            Some(&e),
            "wrong error for malformed input"
        );
        return;
    }
    match res {
        Ok(s) => {
            assert!(all_finite(p), "Ok for input with a NaN or infinity");
            check_solution(s);
        }
        Err(e) => {
            // Every error renders a message.
            assert!(!e.to_string().is_empty());
            // Input checks run in a documented order: lengths, weights length, N >= 4, then
            // finiteness.
            if !all_finite(p) && p.world.len() >= 4 {
                assert!(
                    matches!(e, PnpError::NonFinite { .. }),
                    "non-finite input gave {e:?}"
                );
            }
        }
    }
}

/// Whether the exact-pose property applies to an exact problem (image points that are the
/// exact projections of `(rot, t)`): N >= 6, no weight outside [1e-3, 1e3] (so every point
/// counts, none dominates), every point in front of the pose at a moderate depth (0.1..1e3),
/// moderate coordinates, and world points that span 3D well or lie exactly on a plane.
/// Near-degenerate inputs are excluded: there several poses fit and the conditioning, not the
/// solver, limits the answer.
fn exact_check_applies(
    world: &[Point3<f64>],
    image: &[Point2<f64>],
    weights: Option<&[f64]>,
    rot: &Matrix3<f64>,
    t: &Vector3<f64>,
) -> bool {
    if world.len() < 6 || world.len() != image.len() {
        return false;
    }
    if let Some(w) = weights {
        if w.len() != world.len() || !w.iter().all(|&w| (1e-3..=1e3).contains(&w)) {
            return false;
        }
    }
    let moderate = world.iter().all(|x| x.coords.amax() <= 1e3)
        && image.iter().all(|m| m.coords.amax() <= 2.0)
        && t.amax() <= 1e3;
    let depths = world.iter().map(|x| (rot * x.coords + t).z);
    let (zmin, zmax) = depths.fold((f64::INFINITY, 0.0f64), |(a, b), z| (a.min(z), b.max(z)));
    if !(moderate && zmin >= 0.1 && zmax <= 1e3) {
        return false;
    }
    // Spread of the world points: singular values of the centred cloud (of the N x 3 matrix
    // itself: those of its 3 x 3 scatter would put the rounding floor of an exactly planar
    // cloud at 1e-8, not 1e-16, of the largest).
    let n = world.len() as f64;
    let c = world.iter().fold(Vector3::zeros(), |a, x| a + x.coords) / n;
    let centred = nalgebra::DMatrix::from_fn(world.len(), 3, |i, j| world[i][j] - c[j]);
    let mut sv: Vec<f64> = centred.singular_values().iter().copied().collect();
    sv.sort_by(|a, b| b.total_cmp(a));
    sv[0] >= 0.1 && sv[1] >= 0.1 * sv[0] && (sv[2] >= 0.1 * sv[0] || sv[2] <= 1e-12 * sv[0])
}

/// The accuracy property on well-posed exact problems ([`exact_check_applies`]): the returned
/// pose must reproject (nearly) exactly. A pose with a visible reprojection error while an
/// exact one exists is a silently wrong answer. `what` names the problem in the message.
/// Returns whether the assertion ran (a solution flagged `degenerate` is not checked).
fn check_exact(
    world: &[Point3<f64>],
    image: &[Point2<f64>],
    weights: Option<&[f64]>,
    (rot, t): (&Matrix3<f64>, &Vector3<f64>),
    s: &Solution,
    what: &str,
) -> bool {
    if s.degenerate || !exact_check_applies(world, image, weights, rot, t) {
        return false;
    }
    assert!(
        s.reprojection_rmse <= 1e-6,
        "{what}: exact well-posed problem (N = {}), but the pose reprojects with rmse {:e} \
         (source {:?})",
        world.len(),
        s.reprojection_rmse,
        s.source
    );
    true
}

/// Maps any `f64` into (-2, 2), continuously and monotonically (`2 x / (1 + |x|)`); NaN and
/// infinities to 0 and +-2.
fn squash(x: f64) -> f64 {
    if x.is_nan() {
        0.0
    } else if x.is_infinite() {
        2.0 * x.signum()
    } else {
        2.0 * (x / (1.0 + x.abs()))
    }
}

/// A fixed pseudo-random number in [-1, 1) for index `k` and salt `s` (splitmix64).
fn jitter(k: u64, s: u64) -> f64 {
    let mut z = k
        .wrapping_mul(0x9E37_79B9_7F4A_7C15)
        .wrapping_add(s.wrapping_mul(0xD1B5_4A32_D192_ED03))
        .wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 52) as f64 - 1.0
}

/// An exact, well-conditioned problem derived from a decoded one, so that the exact-pose
/// property runs on almost every `solve` input, whatever the fuzzer made of the numbers.
pub struct ExactProblem {
    /// World points: the decoded ones (the first 6..=1000; fewer are padded) squashed into
    /// (-2, 2) ([`squash`]), plus a fixed jitter in [-1, 1) per coordinate (so that repeated,
    /// tiny or exhausted inputs still span 3D), times 0.75; on the plane `z = a x + b y + c`
    /// when planar.
    pub world: Vec<Point3<f64>>,
    /// Their exact projections through the pose.
    pub image: Vec<Point2<f64>>,
    /// The decoded weights squashed into [0.1, 10] (when the decoded problem has weights).
    pub weights: Option<Vec<f64>>,
    /// The pose: any rotation (from the decoded projecting pose, else from the bytes after the
    /// problem), the point cloud's origin 8..40 units in front of the camera and at most 0.2
    /// of that depth off its axis.
    pub pose: (Matrix3<f64>, Vector3<f64>),
    /// Whether the points are exactly planar.
    pub planar: bool,
}

/// Derives the [`ExactProblem`] of a decoded problem; reads (after it) a control byte (bit 0:
/// planar; bits 1-7: the depth), three numbers (the rotation vector, when the decoded problem
/// has no projecting pose) and three more (the lateral offset and the plane).
pub fn derive_exact(p: &Problem, r: &mut Reader) -> ExactProblem {
    let control = r.u8();
    let planar = control & 1 != 0;
    let depth = 8.0 + 32.0 * f64::from(control >> 1) / 127.0;
    let rv = Vector3::new(r.f64(), r.f64(), r.f64());
    let extra = Vector3::new(r.f64(), r.f64(), r.f64());
    let rot = match &p.exact_pose {
        Some((rot, _)) if rot.iter().all(|x| x.is_finite()) => *rot,
        _ => Rotation3::new(rv.map(|x| 4.0 * squash(x))).into_inner(),
    };
    let t = Vector3::new(
        0.1 * depth * squash(extra.x),
        0.1 * depth * squash(extra.y),
        depth,
    );
    let (pa, pb, pc) = (
        0.5 * squash(extra.x),
        0.5 * squash(extra.y),
        0.5 * squash(extra.z),
    );
    let n = p.world.len().clamp(6, 1000);
    let salt = u64::from(control);
    let world: Vec<Point3<f64>> = (0..n)
        .map(|k| {
            let x = p.world.get(k).copied().unwrap_or_else(Point3::origin);
            let kk = 3 * k as u64;
            let mut q = Point3::new(
                0.75 * (squash(x.x) + jitter(kk, salt)),
                0.75 * (squash(x.y) + jitter(kk + 1, salt)),
                0.75 * (squash(x.z) + jitter(kk + 2, salt)),
            );
            if planar {
                q.z = pa * q.x + pb * q.y + pc;
            }
            q
        })
        .collect();
    let image = world
        .iter()
        .map(|x| {
            let c = rot * x.coords + t;
            Point2::new(c.x / c.z, c.y / c.z)
        })
        .collect();
    let weights = p.weights.as_ref().map(|w| {
        (0..n)
            .map(|k| {
                let v = w.get(k).copied().unwrap_or(1.0);
                10f64.powf(0.5 * squash(v.abs().log10()))
            })
            .collect()
    });
    ExactProblem {
        world,
        image,
        weights,
        pose: (rot, t),
        planar,
    }
}

/// What one `solve` input exercised (for the corpus replay's statistics).
#[derive(Clone, Copy, Debug, Default)]
pub struct SolveReport {
    /// The decoded problem is exact and the exact-pose assertion ran on it.
    pub exact_decoded: bool,
    /// The exact-pose assertion ran on the derived problem ([`derive_exact`]).
    pub exact_derived: bool,
}

/// `Solver::solve` (weighted or not) and `solve_all` on an arbitrary problem.
pub fn solve(data: &[u8]) {
    solve_report(data);
}

/// [`solve`], reporting which exact-pose assertions ran.
///
/// The decoded problem is solved as given; the exact problem derived from it
/// ([`derive_exact`]) is solved with the same options, except that an iteration budget is
/// the default one (tiny budgets are for the decoded problem: a bounded answer, no wrong
/// `Ok`) and a planar detection that contradicts the derived points is `Auto`.
pub fn solve_report(data: &[u8]) -> SolveReport {
    let mut report = SolveReport::default();
    let mut r = Reader::new(data);
    let solver_byte = r.u8();
    let solver = decode_solver(solver_byte);
    let full_budget = solver_byte & 16 == 0;
    let p = decode_problem(&mut r);
    let res = match &p.weights {
        Some(w) => solver.solve(&eopnp::Problem::normalised(&p.world, &p.image).weights(w)),
        None => solver.solve(&eopnp::Problem::normalised(&p.world, &p.image)),
    };
    check_result(&p, &res);
    if let (Ok(s), Some((rot, t)), true) = (&res, &p.exact_pose, full_budget) {
        report.exact_decoded = check_exact(
            &p.world,
            &p.image,
            p.weights.as_deref(),
            (rot, t),
            s,
            "decoded problem",
        );
    }
    // The derived exact problem.
    let e = derive_exact(&p, &mut r);
    let contradicts = match (solver_byte >> 2) & 3 {
        1 => !e.planar,
        2 => e.planar,
        _ => false,
    };
    let exact_solver = decode_solver(solver_byte & if contradicts { 0x03 } else { 0x0f });
    let eres = match &e.weights {
        Some(w) => exact_solver.solve(&eopnp::Problem::normalised(&e.world, &e.image).weights(w)),
        None => exact_solver.solve(&eopnp::Problem::normalised(&e.world, &e.image)),
    };
    match &eres {
        Ok(s) => {
            check_solution(s);
            report.exact_derived = check_exact(
                &e.world,
                &e.image,
                e.weights.as_deref(),
                (&e.pose.0, &e.pose.1),
                s,
                "derived problem",
            );
        }
        Err(err) => {
            if exact_check_applies(
                &e.world,
                &e.image,
                e.weights.as_deref(),
                &e.pose.0,
                &e.pose.1,
            ) {
                panic!("derived problem: exact well-posed problem, but {err:?}");
            }
        }
    }
    // solve_all on small problems: every minimum satisfies the same properties, the best
    // equals solve's answer in exhaustive mode, and the list is non-empty exactly when Ok.
    if p.weights.is_none() && p.world.len() <= 64 {
        let all = solver.solve_all(&eopnp::Problem::normalised(&p.world, &p.image));
        match (&all, &res) {
            (Ok(all), Ok(_)) => {
                assert!(!all.is_empty(), "solve_all: Ok with no solution");
                all.iter().for_each(check_solution);
            }
            (Err(e), Err(f)) => {
                // Input errors are the same whatever the mode; NoSolution may differ.
                if !matches!(f, PnpError::NoSolution) && !matches!(e, PnpError::NoSolution) {
                    assert_eq!(e, f, "solve and solve_all disagree on the error");
                }
            }
            (Ok(all), Err(e)) => {
                assert!(
                    matches!(e, PnpError::NoSolution),
                    "solve: {e:?}, solve_all: Ok"
                );
                all.iter().for_each(check_solution);
            }
            (Err(e), Ok(_)) => {
                assert!(
                    matches!(e, PnpError::NoSolution),
                    "solve_all: {e:?}, solve: Ok"
                );
            }
        }
    }
    report
}

/// `Ransac::estimate` on an arbitrary problem with arbitrary options.
pub fn ransac(data: &[u8]) {
    let mut r = Reader::new(data);
    let solver = decode_solver(r.u8() & 0x0f);
    let threshold = r.f64();
    let confidence = r.f64();
    let focal = (r.f64(), r.f64());
    let seed = u64::from(r.u8());
    let max_iter = u32::from(r.u8()) * 4;
    let lo = r.u8() & 1 != 0;
    let min_iter = u32::from(r.u8());
    let factor = r.f64();
    let p = decode_problem(&mut r);
    // Every option as given (the fields are public: a user can set anything).
    let ransac = Ransac::default()
        .seed(seed)
        .max_iterations(max_iter)
        .min_iterations(min_iter)
        .local_optimisation(lo)
        .threshold_px(threshold)
        .confidence(confidence)
        .final_threshold_factor(factor);
    let mut problem = eopnp::Problem::normalised(&p.world, &p.image).focal(focal.0, focal.1);
    if let Some(w) = p.weights.as_deref() {
        problem = problem.weights(w);
    }
    let res = ransac.estimate(&solver, &problem);
    let options_ok = threshold.is_finite()
        && threshold > 0.0
        && confidence > 0.0
        && confidence < 1.0
        && max_iter > 0
        && factor.is_finite()
        && factor >= 1.0;
    if !options_ok {
        assert!(
            matches!(res, Err(PnpError::InvalidOption { .. })),
            "options out of range gave {res:?}"
        );
        return;
    }
    match &res {
        Ok(sol) => {
            assert!(all_finite(&p), "RANSAC Ok for non-finite input");
            assert!(
                focal.0 > 0.0 && focal.1 > 0.0 && focal.0.is_finite() && focal.1.is_finite(),
                "RANSAC Ok with focal lengths {focal:?}"
            );
            check_solution(&sol.solution);
            assert_eq!(sol.inliers.len(), p.world.len(), "inlier mask length");
            let count = sol.inliers.iter().filter(|&&b| b).count();
            assert_eq!(count, sol.num_inliers, "inlier count vs mask");
        }
        Err(e) => assert!(!e.to_string().is_empty()),
    }
}
