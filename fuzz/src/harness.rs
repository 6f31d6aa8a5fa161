//! The fuzz harnesses: bytes in, the library exercised, every property checked with `assert!`.
//!
//! Shared by the cargo-fuzz targets (`fuzz/fuzz_targets/*.rs`, coverage-guided) and by the
//! stable test `tests/fuzz_corpus.rs`, which replays the committed corpus and the named
//! regression inputs through the same functions on every CI run.
//!
//! Properties (any input whatsoever):
//! - no panic, no hang (every call is bounded);
//! - `Ok` only for finite input, with a finite pose, an orthonormal rotation (det +1) equal to
//!   the quaternion's, finite non-negative costs, and a reprojection rmse that is finite or
//!   (algebraic mode, a point in the focal plane) +inf, never NaN;
//! - `Err` for every input with a NaN or infinity, with the matching typed error;
//! - on well-posed exact problems the pose reprojects exactly (`check_exact`): on the decoded
//!   problem when the fuzzer made it exact (rare: every noise value must be 0), and on an
//!   exact, well-conditioned problem derived from every input (`derive_exact`), so that the
//!   assertion runs on almost every input (`tests/fuzz_corpus.rs` asserts >= 90 % of the
//!   committed `solve` inputs; `fuzz/examples/exact_share.rs` prints the share for any corpus);
//! - RANSAC options out of range give `InvalidOption`; the inlier mask has one entry per point
//!   and agrees with the inlier count;
//! - parsers return a typed error with a message, never a panic; a parsed model or problem is
//!   then solved under the same properties;
//! - a parsed COLMAP model written (text and binary, in memory and to disk) reads back
//!   identical, bit for bit, with no temporary files left (`colmap_write`).

use eopnp::ransac::Ransac;
use eopnp::{Loss, PlanarDetection, PnpError, Refinement, Solution, Solver};
use nalgebra::{Matrix3, Point2, Point3, Rotation3, Vector3};

/// Largest N the decoder builds (N up to 10,000).
pub const MAX_POINTS: usize = 10_000;

/// A little-endian byte reader that yields zeros once the input is exhausted, so every input
/// decodes to something.
pub struct Reader<'a> {
    data: &'a [u8],
    pos: usize,
}

/// Values that break naive numerics, picked by one byte.
const SPECIAL: [f64; 16] = [
    0.0,
    -0.0,
    1.0,
    -1.0,
    f64::NAN,
    f64::INFINITY,
    f64::NEG_INFINITY,
    1e300,
    -1e300,
    1e-300,
    5e-324, // smallest subnormal
    f64::MAX,
    f64::MIN_POSITIVE,
    1e-8,
    1e8,
    0.5,
];

impl<'a> Reader<'a> {
    /// A reader over `data`.
    pub fn new(data: &'a [u8]) -> Self {
        Reader { data, pos: 0 }
    }

    /// The next byte (0 when exhausted).
    pub fn u8(&mut self) -> u8 {
        let b = self.data.get(self.pos).copied().unwrap_or(0);
        self.pos += 1;
        b
    }

    /// The next `n` bytes, zero-padded.
    fn bytes<const N: usize>(&mut self) -> [u8; N] {
        let mut out = [0; N];
        for b in &mut out {
            *b = self.u8();
        }
        out
    }

    /// A number: the tag byte's top three bits pick the encoding, so that small integers and
    /// quarters, special values, raw `f64`/`f32` bit patterns and wide-range magnitudes are
    /// all one mutation away from each other.
    pub fn f64(&mut self) -> f64 {
        let tag = self.u8();
        let low = f64::from(tag & 31);
        match tag >> 5 {
            0..=2 => (low - 16.0) / 4.0,
            3 => SPECIAL[usize::from(tag & 15)],
            4 => f64::from_le_bytes(self.bytes::<8>()),
            5 => f64::from(i16::from_le_bytes(self.bytes::<2>())) / 256.0,
            6 => (f64::from(self.u8()) - 128.0) / 16.0 * 10f64.powi(i32::from(tag & 31) - 16),
            _ => f64::from(f32::from_le_bytes(self.bytes::<4>())),
        }
    }

    /// Whether the input is exhausted.
    pub fn done(&self) -> bool {
        self.pos >= self.data.len()
    }
}

/// A decoded PnP problem.
pub struct Problem {
    /// World points.
    pub world: Vec<Point3<f64>>,
    /// Normalised image points (one more or one fewer than `world` when lengths are fuzzed).
    pub image: Vec<Point2<f64>>,
    /// Per-point weights (`None`: unweighted).
    pub weights: Option<Vec<f64>>,
    /// The generating pose when the image points are its exact projections (no noise, no
    /// length change): a pose with zero reprojection error exists.
    pub exact_pose: Option<(Matrix3<f64>, Vector3<f64>)>,
}

/// Decodes a problem. Layout: a flags byte, a base count, a tiling count, then the base points
/// (and, when the flags say so, a pose that projects them, with per-point noise), then the tiling
/// offset. Tiling repeats the base set shifted by multiples of the offset up to
/// [`MAX_POINTS`], so that large N costs few input bytes.
pub fn decode_problem(r: &mut Reader) -> Problem {
    let flags = r.u8();
    let project = flags & 1 != 0;
    let weighted = flags & 2 != 0;
    let length_fuzz = flags & 4 != 0;
    let tile = flags & 8 != 0;
    let base = usize::from(r.u8() % 48);
    let reps = if tile {
        1 + usize::from(u16::from_le_bytes([r.u8(), r.u8()])) % MAX_POINTS
    } else {
        1
    };
    let mut world0 = Vec::with_capacity(base);
    for _ in 0..base {
        world0.push(Point3::new(r.f64(), r.f64(), r.f64()));
    }
    let mut image0 = Vec::with_capacity(base);
    let pose = if project {
        // Rotation from a (possibly huge or non-finite) rotation vector, translation as given.
        let rv = Vector3::new(r.f64(), r.f64(), r.f64());
        let t = Vector3::new(r.f64(), r.f64(), r.f64());
        let rot = if rv.iter().all(|x| x.is_finite()) && rv.norm().is_finite() {
            Rotation3::new(rv).into_inner()
        } else {
            Matrix3::identity()
        };
        Some((rot, t))
    } else {
        None
    };
    let mut noiseless = true;
    for x in &world0 {
        let p = match &pose {
            Some((rot, t)) => {
                let c = rot * x.coords + t;
                let noise = (r.f64(), r.f64());
                noiseless &= noise == (0.0, 0.0);
                let scale = 1e-3;
                Point2::new(c.x / c.z + scale * noise.0, c.y / c.z + scale * noise.1)
            }
            None => Point2::new(r.f64(), r.f64()),
        };
        image0.push(p);
    }
    let offset = Vector3::new(r.f64(), r.f64(), r.f64());
    let n = (base * reps).min(MAX_POINTS);
    let mut world = Vec::with_capacity(n);
    let mut image = Vec::with_capacity(n);
    for k in 0..n {
        let (i, rep) = (k % base.max(1), (k / base.max(1)) as f64);
        let x = world0[i] + rep * offset;
        let p = match &pose {
            Some((rot, t)) if rep > 0.0 => {
                let c = rot * x.coords + t;
                Point2::new(c.x / c.z, c.y / c.z)
            }
            _ => image0[i],
        };
        world.push(x);
        image.push(p);
    }
    let exact_pose = pose.filter(|_| noiseless && !length_fuzz);
    if length_fuzz {
        match r.u8() % 3 {
            0 => {
                image.pop();
            }
            1 => image.push(Point2::new(0.0, 0.0)),
            _ => {
                world.pop();
            }
        }
    }
    let weights = weighted.then(|| {
        let w: Vec<f64> = (0..base).map(|_| r.f64()).collect();
        let mut out: Vec<f64> = (0..world.len())
            .map(|k| if base == 0 { 1.0 } else { w[k % base] })
            .collect();
        if length_fuzz && r.u8() & 1 != 0 {
            out.pop();
        }
        out
    });
    Problem {
        world,
        image,
        weights,
        exact_pose,
    }
}

/// A solver configuration from one byte.
pub fn decode_solver(b: u8) -> Solver {
    let mut s = Solver::default();
    if b & 1 != 0 {
        s = s.refinement(Refinement::Algebraic);
    }
    if b & 2 != 0 {
        s = s.exhaustive(true);
    }
    s = s.planar_detection(match (b >> 2) & 3 {
        1 => PlanarDetection::Planar,
        2 => PlanarDetection::NonPlanar,
        _ => PlanarDetection::Auto,
    });
    if b & 16 != 0 {
        // Tiny iteration budgets: the hard bounds must be honoured without a wrong Ok.
        s = s
            .newton_iterations(u32::from(b >> 5))
            .reprojection_iterations(u32::from(b >> 5));
    } else {
        // A robust loss for the final refinement (`refine_pixels`), at a small or a large scale.
        let scale = if b & 128 != 0 { 1e-2 } else { 1e-4 };
        s = s.loss(match (b >> 5) & 3 {
            1 => Loss::Huber(scale),
            2 => Loss::Cauchy(scale),
            _ => Loss::Squared,
        });
    }
    s
}

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

/// Splits the input into three files at the first two occurrences of the separator byte
/// sequence `\0\0\xff`.
fn three_files(data: &[u8]) -> [&[u8]; 3] {
    const SEP: &[u8] = b"\0\0\xff";
    let mut parts = [&data[..0]; 3];
    let mut rest = data;
    for (k, part) in parts.iter_mut().enumerate() {
        if k == 2 {
            *part = rest;
            break;
        }
        match rest.windows(SEP.len()).position(|w| w == SEP) {
            Some(at) => {
                *part = &rest[..at];
                rest = &rest[at + SEP.len()..];
            }
            None => {
                *part = rest;
                rest = &rest[rest.len()..];
            }
        }
    }
    parts
}

/// Registers (at most three of) the images of a parsed model, plain and with RANSAC.
fn exercise_model(model: &eopnp::colmap::Model) {
    let solver = Solver::default();
    let ransac = Ransac::default().seed(1).max_iterations(50);
    for &id in model.images.keys().take(3) {
        if let Ok(reg) = eopnp::colmap::register_image(model, id, &solver, None) {
            check_solution(&reg.solution);
        }
        if let Ok(reg) = eopnp::colmap::register_image(model, id, &solver, Some(&ransac)) {
            check_solution(&reg.solution);
            assert!(reg.ransac.is_some() && reg.inliers <= reg.n);
        }
    }
}

/// The COLMAP text reader (three files separated by `\0\0\xff`), then registration; and the
/// reading properties of [`check_model_reading`].
pub fn colmap_text(data: &[u8]) {
    let [c, i, p] = three_files(data);
    let whole = eopnp::colmap::parse_model(
        eopnp::colmap::ModelFormat::Text,
        [c, i, p],
        &eopnp::colmap::ReadOptions::default(),
    );
    check_model_reading(eopnp::colmap::ModelFormat::Text, [c, i, p], &whole);
    match whole {
        Ok(model) => exercise_model(&model),
        Err(e) => assert!(!e.to_string().is_empty()),
    }
}

/// The COLMAP binary reader (three files separated by `\0\0\xff`), then registration; and
/// the reading properties of [`check_model_reading`].
pub fn colmap_binary(data: &[u8]) {
    let [c, i, p] = three_files(data);
    let whole = eopnp::colmap::parse_model(
        eopnp::colmap::ModelFormat::Binary,
        [c, i, p],
        &eopnp::colmap::ReadOptions::default(),
    );
    check_model_reading(eopnp::colmap::ModelFormat::Binary, [c, i, p], &whole);
    match whole {
        Ok(model) => exercise_model(&model),
        Err(e) => assert!(!e.to_string().is_empty()),
    }
}

/// Limits small enough for fuzzed inputs to reach: 2 KiB files, 8 observations per image, 8
/// track elements per point.
const SMALL_FILE_BYTES: u64 = 2048;
const SMALL_OBSERVATIONS: usize = 8;
const SMALL_TRACK_LENGTH: usize = 8;

/// The reader options of [`SMALL_FILE_BYTES`], [`SMALL_OBSERVATIONS`] and
/// [`SMALL_TRACK_LENGTH`].
pub fn small_model_limits() -> eopnp::colmap::ReadOptions {
    eopnp::colmap::ReadOptions::default()
        .max_file_bytes(SMALL_FILE_BYTES)
        .max_observations(SMALL_OBSERVATIONS)
        .max_track_length(SMALL_TRACK_LENGTH)
}

/// The streaming readers' properties on one input (`whole`: its result with the default
/// limits):
/// - read through a buffer of 1 to 13 bytes (tokens, names and records cut anywhere), the
///   result is the same;
/// - with [`small_model_limits`], a model within them reads the same, one beyond them fails
///   with an error of kind `Limit`, and input that fails still fails.
fn check_model_reading(
    format: eopnp::colmap::ModelFormat,
    files: [&[u8]; 3],
    whole: &Result<eopnp::colmap::Model, eopnp::colmap::ModelError>,
) {
    use eopnp::colmap::{parse_model, parse_model_buffered, ModelErrorKind};
    let len: usize = files.iter().map(|f| f.len()).sum();
    let capacity = 1 + len % 13;
    let buffered = parse_model_buffered(format, files, &Default::default(), capacity);
    match (whole, &buffered) {
        (Ok(a), Ok(b)) => assert_same_model(a, b, "buffered"),
        (Err(a), Err(b)) => assert_eq!(a, b, "buffered through {capacity} bytes"),
        (a, b) => panic!("buffered through {capacity} bytes: {b:?}, whole: {a:?}"),
    }
    let small = small_model_limits();
    let limited = parse_model(format, files, &small);
    match (whole, limited) {
        (Ok(a), Ok(b)) => assert_same_model(a, &b, "limited"),
        (Ok(m), Err(e)) => {
            assert!(matches!(e.kind, ModelErrorKind::Limit(_)), "{e}");
            let within = files.iter().all(|f| f.len() as u64 <= SMALL_FILE_BYTES)
                && m.images
                    .values()
                    .all(|i| i.points2d.len() <= SMALL_OBSERVATIONS)
                && m.points
                    .values()
                    .all(|p| p.track.len() <= SMALL_TRACK_LENGTH);
            assert!(!within, "a model within the limits is refused: {e}");
        }
        (Err(e), Ok(_)) => panic!("bad input read under smaller limits: {e}"),
        (Err(_), Err(_)) => {}
    }
}

/// Whether two `f64` are the same value bit for bit (`-0.0` differs from `0.0`), any NaN
/// matching any NaN (text prints every NaN as `NaN`).
fn same_f64(a: f64, b: f64) -> bool {
    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
}

fn same_f64s<'a>(
    a: impl IntoIterator<Item = &'a f64>,
    b: impl IntoIterator<Item = &'a f64>,
) -> bool {
    let (a, b): (Vec<f64>, Vec<f64>) = (
        a.into_iter().copied().collect(),
        b.into_iter().copied().collect(),
    );
    a.len() == b.len() && a.iter().zip(&b).all(|(x, y)| same_f64(*x, *y))
}

/// Asserts that two models are identical, every number bit for bit (NaN for NaN).
pub fn assert_same_model(a: &eopnp::colmap::Model, b: &eopnp::colmap::Model, what: &str) {
    assert_eq!(a.cameras.len(), b.cameras.len(), "{what}: cameras");
    for ((ia, ca), (ib, cb)) in a.cameras.iter().zip(&b.cameras) {
        assert_eq!(ia, ib, "{what}: camera ids");
        assert_eq!(
            (ca.model(), ca.width(), ca.height()),
            (cb.model(), cb.width(), cb.height()),
            "{what}: camera {ia}"
        );
        assert!(
            same_f64s(ca.params(), cb.params()),
            "{what}: camera {ia} params"
        );
    }
    assert_eq!(a.images.len(), b.images.len(), "{what}: images");
    for ((ka, ia), (kb, ib)) in a.images.iter().zip(&b.images) {
        assert_eq!(
            (ka, ia.id, ia.camera_id, &ia.name),
            (kb, ib.id, ib.camera_id, &ib.name),
            "{what}"
        );
        assert!(same_f64s(&ia.q, &ib.q), "{what}: image {ka} q");
        assert!(same_f64s(ia.t.iter(), ib.t.iter()), "{what}: image {ka} t");
        assert_eq!(
            ia.points2d.len(),
            ib.points2d.len(),
            "{what}: image {ka} observations"
        );
        for ((pa, ida), (pb, idb)) in ia.points2d.iter().zip(&ib.points2d) {
            assert_eq!(ida, idb, "{what}: image {ka} observation point id");
            assert!(same_f64s(pa.iter(), pb.iter()), "{what}: image {ka} pixel");
        }
    }
    assert_eq!(a.points.len(), b.points.len(), "{what}: points");
    for ((ka, pa), (kb, pb)) in a.points.iter().zip(&b.points) {
        assert_eq!(
            (ka, pa.id, pa.rgb, &pa.track),
            (kb, pb.id, pb.rgb, &pb.track),
            "{what}"
        );
        assert!(
            same_f64s(pa.xyz.iter(), pb.xyz.iter()),
            "{what}: point {ka} xyz"
        );
        assert!(same_f64(pa.error, pb.error), "{what}: point {ka} error");
    }
}

fn parse_as(
    format: eopnp::colmap::ModelFormat,
    [c, i, p]: [&[u8]; 3],
) -> Result<eopnp::colmap::Model, eopnp::colmap::ModelError> {
    eopnp::colmap::parse_model(format, [c, i, p], &eopnp::colmap::ReadOptions::default())
}

/// A fresh scratch directory of this process (removed by the caller).
fn scratch_dir() -> std::path::PathBuf {
    use std::sync::atomic::{AtomicU64, Ordering};
    static N: AtomicU64 = AtomicU64::new(0);
    let d = std::env::temp_dir().join(format!(
        "eopnp-fuzz-colmap-write-{}-{}",
        std::process::id(),
        N.fetch_add(1, Ordering::Relaxed)
    ));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("scratch directory");
    d
}

fn sorted_entries(dir: &std::path::Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .expect("list directory")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// The COLMAP writer: the input (three files separated by `\0\0\xff`) is parsed as a text
/// and as a binary model; each model that parses is encoded in both formats and parsed back,
/// and written to a fresh directory with `colmap::write_model` and read back. Properties:
/// - a model always writes in the format it was read from; in the other format the only
///   failure is `InvalidInput` (a name text cannot hold, a 3D point id binary cannot hold);
/// - what is written reads back identical, every number bit for bit (NaN for NaN), and
///   encoding the model read back gives the same bytes;
/// - the directory written holds exactly the three files (no temporaries left).
pub fn colmap_write(data: &[u8]) {
    use eopnp::colmap::{
        encode_model, read_model, write_model, ModelFormat, ReadOptions, WriteOptions,
    };
    let files = three_files(data);
    for source in [ModelFormat::Text, ModelFormat::Binary] {
        let Ok(model) = parse_as(source, files) else {
            continue;
        };
        for format in [ModelFormat::Text, ModelFormat::Binary] {
            let what = format!("{source:?} -> {format:?}");
            let encoded = match encode_model(&model, format) {
                Ok(e) => e,
                Err(e) => {
                    assert_ne!(
                        source, format,
                        "{what}: a parsed model writes in its own format: {e}"
                    );
                    assert_eq!(e.kind(), std::io::ErrorKind::InvalidInput, "{what}: {e}");
                    assert!(!e.to_string().is_empty());
                    continue;
                }
            };
            let [c, i, p] = &encoded;
            let back = parse_as(format, [c, i, p])
                .unwrap_or_else(|e| panic!("{what}: written model does not parse: {e}"));
            assert_same_model(&model, &back, &what);
            let again = encode_model(&back, format).expect("re-encode");
            assert!(again == encoded, "{what}: re-encoding differs");

            let base = scratch_dir();
            let dir = base.join("model");
            write_model(&model, &dir, &WriteOptions::default().format(format))
                .unwrap_or_else(|e| panic!("{what}: write: {e}"));
            assert_eq!(sorted_entries(&base), ["model"], "{what}: leftovers");
            let mut names = format.file_names().map(String::from).to_vec();
            names.sort();
            assert_eq!(sorted_entries(&dir), names, "{what}: files written");
            let read = read_model(&dir, &ReadOptions::default().format(format));
            let _ = std::fs::remove_dir_all(&base);
            assert_same_model(
                &model,
                &read.unwrap_or_else(|e| panic!("{what}: read back: {e}")),
                &what,
            );
        }
    }
}

/// The CLI's problem-file parser (CSV or JSON) and its pose output. The first byte picks the
/// extension and whether a `--camera` argument (the first line) is given.
///
/// Properties: a parse failure is an input error (exit code 2) with a message that shows no raw
/// control character, whatever the input mode (CSV, JSON, `--camera`: what it echoes of the
/// input is escaped); a parsed
/// problem solves or fails with code 1 or 2, and a pose is JSON with a translation. The seeds cover the CSV dialects the csv crate reads
/// (byte-order mark, quotes, `;` and tab, reordered columns, comments).
pub fn cli_input(data: &[u8]) {
    let Some((&mode, rest)) = data.split_first() else {
        return;
    };
    let ext = match mode & 3 {
        0 => Some("json"),
        1 => Some("csv"),
        2 => Some("txt"),
        _ => None,
    };
    let (camera, body) = if mode & 4 != 0 {
        let end = rest.iter().position(|&b| b == b'\n').unwrap_or(rest.len());
        let cam = std::str::from_utf8(&rest[..end]).ok();
        (cam, rest.get(end + 1..).unwrap_or(&[]))
    } else {
        (None, rest)
    };
    let whole = eopnp_cli::input::parse_problem("fuzz", body, ext, camera);
    check_problem_reading(body, ext, camera, &whole);
    match whole {
        Ok(problem) => match eopnp_cli::solve::solve(&problem, &Solver::default()) {
            Ok(json) => {
                let v: serde_json::Value = serde_json::from_str(&json).expect("output is JSON");
                assert!(v["translation"].is_array(), "pose JSON without translation");
            }
            Err(f) => {
                assert!(!f.message.is_empty());
                assert!(f.code == 1 || f.code == 2, "exit code {}", f.code);
            }
        },
        Err(f) => {
            assert!(!f.message.is_empty());
            assert_eq!(f.code, 2, "a parse failure is bad input (exit code 2)");
            // Every input mode (CSV, JSON, no or another extension, the `--camera` argument):
            // what the message echoes of the input is escaped.
            assert!(
                !f.message.chars().any(char::is_control),
                "raw control character in the error of a {} input{}: {:?}",
                ext.unwrap_or("extensionless"),
                if camera.is_some() {
                    " with --camera"
                } else {
                    ""
                },
                f.message
            );
        }
    }
}

/// Limits small enough for fuzzed inputs to reach: 1 KiB of input, lines (and JSON strings
/// and numbers) of 48 bytes.
pub fn small_input_limits() -> eopnp_cli::input::Limits {
    eopnp_cli::input::Limits {
        max_input_bytes: 1024,
        max_line_bytes: 48,
    }
}

/// The streaming properties of `solve`'s reader on one input (`whole`: its result read from
/// the slice with the default limits):
/// - read through a buffer of 1 to 7 bytes (a stream that delivers little at a time: a
///   byte-order mark, lines, tokens cut anywhere), the result is the same;
/// - with [`small_input_limits`], a problem that is read is the same, and one that is
///   refused although it reads with the default limits is refused for a limit, which the
///   message names.
fn check_problem_reading(
    body: &[u8],
    ext: Option<&str>,
    camera: Option<&str>,
    whole: &Result<eopnp_cli::input::Problem, eopnp_cli::Failure>,
) {
    use eopnp_cli::input::{read_problem_from, Limits};
    let capacity = 1 + body.len() % 7;
    let src = || std::io::BufReader::with_capacity(capacity, body);
    let buffered = read_problem_from("fuzz", src(), ext, camera, &Limits::default());
    match (whole, &buffered) {
        (Ok(a), Ok(b)) => assert_eq!(a, b, "buffered through {capacity} bytes"),
        (Err(a), Err(b)) => assert_eq!(
            (a.code, &a.message),
            (b.code, &b.message),
            "buffered through {capacity} bytes"
        ),
        (a, b) => panic!(
            "buffered through {capacity} bytes: {:?}, whole: {:?}",
            b.as_ref().map_err(|f| &f.message),
            a.as_ref().map_err(|f| &f.message)
        ),
    }
    match (
        whole,
        read_problem_from("fuzz", src(), ext, camera, &small_input_limits()),
    ) {
        (Ok(a), Ok(b)) => assert_eq!(*a, b, "limited"),
        (Ok(_), Err(f)) => {
            assert_eq!(f.code, 2, "{}", f.message);
            assert!(f.message.contains("limit"), "limited: {}", f.message);
        }
        (Err(a), Ok(_)) => panic!("bad input read under smaller limits: {}", a.message),
        (Err(_), Err(f)) => assert_eq!(f.code, 2, "{}", f.message),
    }
}
