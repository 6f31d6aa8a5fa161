//! The checks of the upright two-point pose: its generated quadratic against the 4 x 4
//! determinant computed numerically, the true rotation as a root, and the solver's poses (on
//! their rays, the true one among them, as many as an independent scan of the determinant over
//! the angle finds).
//!
//! Random instances: two rays, through one centre (a camera) on even samples and from two
//! centres spread up to 1 unit (a rig) on odd ones, each through a world point 0.2 to 5 units
//! away, the pose a rotation about the vertical `y` by any angle and a translation of a few
//! units.

use crate::reference::{det_with_bound, hadamard};
use crate::report::{Measurement, Tracker};
use crate::strategies as st;
use eopnp::internals::kernels as k;
use eopnp::internals::up2p::up2p;
use nalgebra::{DMatrix, Matrix3, Point3, Vector3};

/// A random instance: the kernel's inputs (rows `a`, points `p`, offsets `e`) formed as the
/// solver forms them, the geometry, and the true pose.
struct Instance {
    a: [f64; 12],
    p: [f64; 6],
    e: [f64; 4],
    world: [Point3<f64>; 2],
    centres: [Point3<f64>; 2],
    directions: [Vector3<f64>; 2],
    theta: f64,
    r: Matrix3<f64>,
    t: Vector3<f64>,
}

/// `R_y(theta)`.
fn rotation_y(theta: f64) -> Matrix3<f64> {
    let (s, c) = theta.sin_cos();
    Matrix3::new(c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c)
}

/// Two unit vectors orthogonal to `v` (any: the check does not depend on the solver's choice).
fn complement(v: &Vector3<f64>, rng: &mut rand_pcg::Pcg64) -> (Vector3<f64>, Vector3<f64>) {
    let a = loop {
        let w = st::unit_vector(rng);
        let a = v.cross(&w);
        if a.norm() > 0.1 {
            break a.normalize();
        }
    };
    (a, v.cross(&a))
}

fn instance(rng: &mut rand_pcg::Pcg64, rig: bool) -> Instance {
    let theta = std::f64::consts::PI * (2.0 * rand::Rng::random::<f64>(rng) - 1.0);
    let r = rotation_y(theta);
    let t = Vector3::new(st::normal(rng), st::normal(rng), st::normal(rng)) * 2.0;
    let mut world = [Point3::origin(); 2];
    let mut centres = [Point3::origin(); 2];
    let mut directions = [Vector3::zeros(); 2];
    for i in 0..2 {
        let c = if rig {
            st::unit_vector(rng) * rand::Rng::random::<f64>(rng)
        } else {
            Vector3::zeros()
        };
        let v = st::unit_vector(rng);
        let l = 0.2 + 4.8 * rand::Rng::random::<f64>(rng);
        world[i] = Point3::from(r.transpose() * (c + v * l - t));
        centres[i] = Point3::from(c);
        directions[i] = v;
    }
    let (a0, a1) = complement(&directions[0], rng);
    let (a2, a3) = complement(&directions[1], rng);
    let rows = [a0, a1, a2, a3];
    let x = [world[0].coords, world[1].coords];
    Instance {
        a: std::array::from_fn(|i| rows[i / 3][i % 3]),
        p: [x[0].x, x[0].y, x[0].z, x[1].x, x[1].y, x[1].z],
        e: std::array::from_fn(|k| rows[k].dot(&centres[k / 2].coords)),
        world,
        centres,
        directions,
        theta,
        r,
        t,
    }
}

/// The 4 x 4 matrix `[A | (1 + s^2) (b(R_y) - e)]` at `s = tan(theta / 2)`, formed from the
/// rotation matrix itself (no Cayley algebra), scaled by `cos^2(theta / 2)`: `[A | b - e]` at
/// the angle `theta`.
fn constraint_matrix(inst: &Instance, theta: f64) -> DMatrix<f64> {
    let r = rotation_y(theta);
    DMatrix::from_fn(4, 4, |row, col| {
        if col < 3 {
            inst.a[3 * row + col]
        } else {
            let a = Vector3::new(inst.a[3 * row], inst.a[3 * row + 1], inst.a[3 * row + 2]);
            let x = Vector3::new(
                inst.p[3 * (row / 2)],
                inst.p[3 * (row / 2) + 1],
                inst.p[3 * (row / 2) + 2],
            );
            a.dot(&(r * x)) - inst.e[row]
        }
    })
}

/// The quadratic in homogeneous form at the half-angle `h`, `c2 sin^2 h + c1 sin h cos h +
/// c0 cos^2 h` (`det [A | b - e]` at `theta = 2 h`), and the sum of its terms' absolute values.
fn quadratic_at(c: &[f64; 3], h: f64) -> (f64, f64) {
    let (sh, ch) = h.sin_cos();
    let terms = [c[0] * ch * ch, c[1] * sh * ch, c[2] * sh * sh];
    (terms.iter().sum(), terms.iter().map(|x| x.abs()).sum())
}

/// Tolerance of the determinant comparison, relative to the Hadamard bound of the 4 x 4
/// absolute-value matrix: the kernel is a straight-line polynomial of depth below 16, the
/// reference a 4 x 4 LU determinant; both are a few `u` of that scale; 1e-12 leaves a factor
/// above 10^2.
const TOL_DET: f64 = 1e-12;

/// `up2p_quadratic` at a random angle against `det [A | b - e]` by LU (times `1 / cos^2 h`,
/// the kernel's Cayley scaling, applied to the kernel's side as `cos^2 h`).
#[must_use]
pub fn up2p_determinant(n: usize) -> Measurement {
    let seed = 401;
    let mut rng = st::rng(seed);
    let mut t = Tracker::new(
        "up2p_quadratic",
        "quadratic vs det [A, b(R_y) - e] (LU) at a random angle",
        "|dD| / Hadamard(|M|)",
        format!("{TOL_DET:e}"),
    );
    for i in 0..n {
        let inst = instance(&mut rng, i % 2 == 1);
        let theta = std::f64::consts::PI * (2.0 * rand::Rng::random::<f64>(&mut rng) - 1.0);
        let c = k::up2p_quadratic(&inst.a, &inst.p, &inst.e);
        let (kernel, _) = quadratic_at(&c, theta / 2.0);
        let m = constraint_matrix(&inst, theta);
        let (reference, _) = det_with_bound(&m);
        let scale = hadamard(&m.map(f64::abs));
        let err = (kernel - reference).abs() / scale;
        t.record(err, TOL_DET, || {
            format!(
                "seed {seed} sample {i}: theta {theta:e}, a {:?}, p {:?}, e {:?}",
                inst.a, inst.p, inst.e
            )
        });
    }
    t.finish()
}

/// Tolerance of the known-root check, relative to the Hadamard bound of the absolute-value
/// constraint matrix at the root (the scale of the determinant's rounding, as in
/// [`up2p_determinant`]; not the coefficients' own size, which cancels near the root: at
/// `theta* = 0` the quadratic's `c0` is the determinant itself): the inputs are rounded once from
/// the geometry and the kernel evaluates a polynomial of depth below 16; 1e-12 leaves a factor
/// above 10^2.
const TOL_ROOT: f64 = 1e-12;

/// The true rotation is a root: `|q(h*)| / Hadamard(|M(theta*)|)`, `h* = theta* / 2`.
#[must_use]
pub fn up2p_known_root(n: usize) -> Measurement {
    let seed = 402;
    let mut rng = st::rng(seed);
    let mut t = Tracker::new(
        "up2p_quadratic",
        "known root theta*",
        "|q(theta* / 2)| / Hadamard(|M(theta*)|)",
        format!("{TOL_ROOT:e}"),
    );
    for i in 0..n {
        let inst = instance(&mut rng, i % 2 == 1);
        let c = k::up2p_quadratic(&inst.a, &inst.p, &inst.e);
        let (v, _) = quadratic_at(&c, inst.theta / 2.0);
        let scale = hadamard(&constraint_matrix(&inst, inst.theta).map(f64::abs));
        t.record(v.abs() / scale, TOL_ROOT, || {
            format!("seed {seed} sample {i}: theta {:e}", inst.theta)
        });
    }
    t.finish()
}

/// Grid points of the independent root count over `theta in (-pi, pi]`.
const SCAN: usize = 4096;

/// The roots of `D(theta) = det [A | b(R_y(theta)) - e]` by an independent route: its sign on a
/// grid of [`SCAN`] angles (the LU determinant), each sign change refined by bisection; `None`
/// when a grid value is within `1e-9` of its Hadamard scale (a nearly double root, or a root on a
/// grid point, which a scan cannot count reliably).
fn scanned_roots(inst: &Instance) -> Option<Vec<f64>> {
    let pi = std::f64::consts::PI;
    let at = |theta: f64| {
        let m = constraint_matrix(inst, theta);
        (det_with_bound(&m).0, hadamard(&m.map(f64::abs)))
    };
    let grid: Vec<f64> = (0..=SCAN)
        .map(|j| -pi + 2.0 * pi * j as f64 / SCAN as f64)
        .collect();
    let mut values = Vec::with_capacity(grid.len());
    for &g in &grid {
        let (d, s) = at(g);
        if d.abs() <= 1e-9 * s {
            return None;
        }
        values.push(d);
    }
    let mut roots = Vec::new();
    for j in 0..SCAN {
        if (values[j] > 0.0) != (values[j + 1] > 0.0) {
            let (mut lo, mut hi, mut flo) = (grid[j], grid[j + 1], values[j]);
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                let fm = at(mid).0;
                if (fm > 0.0) == (flo > 0.0) {
                    lo = mid;
                    flo = fm;
                } else {
                    hi = mid;
                }
            }
            roots.push(0.5 * (lo + hi));
        }
    }
    Some(roots)
}

/// The pose at the angle `theta` by least squares on the four equations, and whether both
/// points are in front of their centres.
fn in_front_at(inst: &Instance, theta: f64) -> bool {
    let r = rotation_y(theta);
    let m = constraint_matrix(inst, theta);
    let a = m.columns(0, 3).into_owned();
    let rhs = -m.column(3).into_owned();
    let Some(tt) = (a.transpose() * &a).lu().solve(&(a.transpose() * rhs)) else {
        return false;
    };
    let t = Vector3::new(tt[0], tt[1], tt[2]);
    (0..2).all(|i| {
        (r * inst.world[i].coords + t - inst.centres[i].coords).dot(&inst.directions[i]) > 0.0
    })
}

/// The solver: every pose puts both points on their rays, in front, to 1e-10 (the sine of the
/// angle between `R X + t - c` and the ray), the true pose is among them (1e-8), and their
/// number equals that of the roots of the scanned determinant with both points in front
/// (instances the scan cannot count are reported, not compared).
#[must_use]
pub fn up2p_solutions(n: usize) -> Measurement {
    let seed = 403;
    let mut rng = st::rng(seed);
    let mut t = Tracker::new(
        "up2p_quadratic",
        "solver: poses on their rays, the true one found, as many as a scan of det [A, b - e] finds in front",
        "max ray sine; count mismatch = inf",
        "1e-10".into(),
    );
    let mut unscanned = 0usize;
    for i in 0..n {
        let inst = instance(&mut rng, i % 2 == 1);
        let sols = up2p(&inst.world, &inst.centres, &inst.directions);
        let rays = (&inst.world[..], &inst.centres[..], &inst.directions[..]);
        let (mut worst, found) = super::poses_on_rays(&sols, rays, (&inst.r, &inst.t));
        if !found {
            worst = f64::INFINITY;
        }
        let mut count = None;
        if i % 10 == 0 {
            // The scan is 4,096 LU determinants: every tenth instance.
            match scanned_roots(&inst) {
                Some(roots) => {
                    let c = roots.iter().filter(|&&th| in_front_at(&inst, th)).count();
                    count = Some(c);
                    if c != sols.len() {
                        worst = f64::INFINITY;
                    }
                }
                None => unscanned += 1,
            }
        }
        t.record(worst, 1e-10, || {
            format!(
                "seed {seed} sample {i}: {} poses, scanned count {count:?}, found {found}",
                sols.len()
            )
        });
    }
    let mut m = t.finish();
    if unscanned > 0 {
        m.worst_input = format!(
            "{} ({unscanned} instances the scan could not count)",
            m.worst_input
        );
    }
    m
}
