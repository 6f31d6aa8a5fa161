//! Minimal P3P solver: the camera poses that map three world points onto three bearing
//! vectors, after Lambda Twist (Mikael Persson and Klas Nordberg, "Lambda Twist: An Accurate
//! Fast Robust Perspective Three Point (P3P) Solver", ECCV 2018).
//!
//! Used as the minimal solver of [`crate::ransac`], and by the small-N search of the default
//! solve (`search`, `pipeline/search.rs`), which is why it lives with the numerical building
//! blocks (`eopnp::p3p` re-exports it). Written here rather than taken from the
//! `lambda-twist` crate: its current release (0.7) is built on `cv-core` 0.15 and `nalgebra`
//! 0.21 (this crate uses nalgebra 0.35, so its poses would need converting between two
//! nalgebra versions and pull a second copy of nalgebra into every build), it allocates
//! nothing but also has no guard against degenerate triplets (collinear world points give
//! a NaN rotation), and it is about 300 lines: smaller to own than to wrap.
//!
//! # Method
//!
//! With unit bearings `y_i` and depths `l_i`, the camera points `l_i y_i` must keep the
//! squared distances `a_ij = |X_i - X_j|^2` of the world points:
//! `l_i^2 + l_j^2 + b_ij l_i l_j = a_ij`, `b_ij = -2 y_i . y_j`, i.e. `L^T M_ij L = a_ij` for
//! three 3x3 quadratic forms. Eliminating the unknown scale gives two homogeneous conics
//! `D1 = a23 M12 - a12 M23` and `D2 = a23 M13 - a13 M23` (`L^T D1 L = L^T D2 L = 0`). A
//! degenerate member `D0 = D1 + g D2` of their pencil (`det D0 = 0`, a cubic in `g`) is a pair
//! of planes through the origin, read off its eigen-decomposition
//! `D0 = s1 e1 e1^T + s2 e2 e2^T`: `(e1 +- sqrt(-s2/s1) e2) . L = 0`. On each plane the
//! remaining conic is a quadratic in one ratio; the scale follows from the sum of the three
//! distance equations (a positive definite form). Each depth triple is polished by
//! Gauss-Newton on the three distance equations, and the pose is the rigid motion between the
//! orthonormal frames of the two triangles.
//!
//! Differences from the paper's presentation (same mathematics): the cubic's coefficients are
//! `det D1`, `tr(adj(D1) D2)`, `tr(D1 adj(D2))`, `det D2` and its roots come from
//! the crate's real-root finder; every real root is tried and the most indefinite `D0` (the
//! best-conditioned plane pair) is used; the rotation is built from orthonormal frames, so it
//! is a rotation to rounding without a projection step.
//!
//! `p3p_unpolished` (crate-private: the solver's small-N starts, which `refine` refines) skips the
//! Gauss-Newton polish, takes `D0` from one real root of the cubic (`one_cubic_root`: every
//! real root gives a degenerate member whose plane pair, when real, holds every solution)
//! and its plane pair from the closed-form eigenvalues of `D0` (trace and principal minors,
//! the null one taken as 0) and cross products of the rows of `D0 - s I`; where that fails,
//! the polished solver's search over every root with the iterative decomposition decides.
//! Measured with `examples/small_n.rs` (500 general problems): 30.7M -> 28.5M instructions
//! at N = 4, 22.7M -> 20.0M at N = 5, no minimum missed in 6,000 problems per N and scene
//! type.
//!
//! Everything is fixed-size (no heap allocation) and every loop is bounded.
//!
//! ```
//! use eopnp::p3p::p3p;
//! use nalgebra::{Point3, Rotation3, Vector3};
//!
//! let r = Rotation3::from_euler_angles(0.2, -0.1, 0.3);
//! let t = Vector3::new(0.1, 0.2, 5.0);
//! let world = [Point3::new(1.0, 0.0, 0.0), Point3::new(0.0, 1.0, 0.5), Point3::new(-1.0, -0.5, 0.2)];
//! let bearing = world.map(|x| (r * x + t).coords.normalize());
//! // Up to four poses; the true one is among them.
//! let poses = p3p(&world, &bearing);
//! assert!(poses.iter().any(|p| (p.rotation - r.matrix()).norm() < 1e-9
//!     && (p.translation - t).norm() < 1e-9));
//! ```

use crate::numeric::bounds::{converged, limit, Bound, Budget};
use arrayvec::ArrayVec;
use nalgebra::{Matrix3, Point3, Vector3};

/// Maximum number of P3P solutions.
pub const MAX_P3P_SOLUTIONS: usize = 4;

/// Gauss-Newton iterations polishing each depth triple (the paper reports no gain after 2-3;
/// each step is accepted only if it lowers the residual).
const GAUSS_NEWTON_ITERATIONS: usize = 5;

/// A world-to-camera pose `x_cam = R X + t` found by [`p3p`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct P3pPose {
    /// The rotation `R` (orthonormal to rounding, `det R = +1`).
    pub rotation: Matrix3<f64>,
    /// The translation `t`.
    pub translation: Vector3<f64>,
}

/// Up to [`MAX_P3P_SOLUTIONS`] poses (fixed capacity, no allocation).
pub type P3pSolutions = ArrayVec<P3pPose, MAX_P3P_SOLUTIONS>;

/// The poses with all three world points in front of the camera (positive depths) that map
/// `world[i]` onto the ray of `bearing[i]` (any non-zero direction; it is normalised here; for
/// a normalised image point `(x, y)` pass `(x, y, 1)`).
///
/// Returns no pose (never a NaN one) for degenerate triplets: coincident or collinear world
/// points, zero or parallel bearings, non-finite input. Solutions closer than `1e-9` (relative)
/// to a previous one are reported once.
#[must_use]
pub fn p3p(world: &[Point3<f64>; 3], bearing: &[Vector3<f64>; 3]) -> P3pSolutions {
    p3p_with::<true>(world, bearing)
}

/// [`p3p`] without the Gauss-Newton polish of the depths: starting poses for a refinement
/// that follows anyway (the solver's small-N starts, `search`), about as accurate as the
/// closed-form depths are.
pub(crate) fn p3p_unpolished(
    world: &[Point3<f64>; 3],
    bearing: &[Vector3<f64>; 3],
) -> P3pSolutions {
    p3p_with::<false>(world, bearing)
}

/// [`p3p`] (`POLISH`) and [`p3p_unpolished`], each compiled for its own use.
fn p3p_with<const POLISH: bool>(
    world: &[Point3<f64>; 3],
    bearing: &[Vector3<f64>; 3],
) -> P3pSolutions {
    let mut out = P3pSolutions::new();
    let finite = world.iter().all(|p| p.coords.iter().all(|v| v.is_finite()))
        && bearing.iter().all(|b| b.iter().all(|v| v.is_finite()));
    if !finite {
        return out;
    }
    let mut y = [Vector3::zeros(); 3];
    for (yi, b) in y.iter_mut().zip(bearing) {
        let n = b.norm();
        if !(n > 0.0 && n.is_finite()) {
            return out;
        }
        *yi = b / n;
    }
    let d12 = world[0] - world[1];
    let d13 = world[0] - world[2];
    let d23 = world[1] - world[2];
    let (a12, a13, a23) = (d12.norm_squared(), d13.norm_squared(), d23.norm_squared());
    let amax = a12.max(a13).max(a23);
    // Collinear or coincident world points: |d12 x d13|^2 is 4 area^2; relative to the
    // squared side lengths it is sin^2 of the triangle's angle at X1.
    if !(amax > 0.0) || d12.cross(&d13).norm_squared() <= 1e-20 * a12 * a13 {
        return out;
    }
    // Parallel bearings cannot be told apart (|y_i x y_j| = sin of their angle).
    for (i, j) in [(0, 1), (0, 2), (1, 2)] {
        if y[i].cross(&y[j]).norm_squared() <= 1e-24 {
            return out;
        }
    }
    let b12 = -2.0 * y[0].dot(&y[1]);
    let b13 = -2.0 * y[0].dot(&y[2]);
    let b23 = -2.0 * y[1].dot(&y[2]);
    // Quadratic forms L^T M_ij L = l_i^2 + l_j^2 + b_ij l_i l_j, with h_ij = b_ij / 2 off the
    // diagonal: M12 = [[1, h12, 0], [h12, 1, 0], [0, 0, 0]], M13 and M23 alike. The conics
    // D1 = a23 M12 - a12 M23 and D2 = a23 M13 - a13 M23, scale-free (divided by amax to keep
    // the numbers O(1)), entry by entry.
    let (h12, h13, h23) = (0.5 * b12, 0.5 * b13, 0.5 * b23);
    let k = 1.0 / amax;
    let (ka12, ka13, ka23) = (a12 * k, a13 * k, a23 * k);
    let d1 = Matrix3::new(
        ka23,
        ka23 * h12,
        0.0,
        ka23 * h12,
        ka23 - ka12,
        -ka12 * h23,
        0.0,
        -ka12 * h23,
        -ka12,
    );
    let d2 = Matrix3::new(
        ka23,
        0.0,
        ka23 * h13,
        0.0,
        -ka13,
        -ka13 * h23,
        ka23 * h13,
        -ka13 * h23,
        ka23 - ka13,
    );

    let Some((e1, e2, ratio)) = degenerate_member(&d1, &d2, !POLISH) else {
        return out;
    };
    // M12 + M13 + M23.
    let sum_form = Matrix3::new(2.0, h12, h13, h12, 2.0, h23, h13, h23, 2.0);
    let asum = a12 + a13 + a23;
    let twist = ratio.max(0.0).sqrt();
    let mut lambdas: ArrayVec<Vector3<f64>, 4> = ArrayVec::new();
    for sign in [1.0, -1.0] {
        let n = e1 + e2 * (sign * twist);
        for l in depths_on_plane(&n, &d1, &d2, &sum_form, asum) {
            if !lambdas.is_full() {
                lambdas.push(l);
            }
        }
        if twist == 0.0 {
            break; // both planes are the same
        }
    }
    let xs = [world[0].coords, world[1].coords, world[2].coords];
    let Some(fw) = triangle_frame(&xs) else {
        return out;
    };
    let cw = (xs[0] + xs[1] + xs[2]) / 3.0;
    for l in lambdas {
        let l = if POLISH {
            gauss_newton(l, [a12, a13, a23], [b12, b13, b23])
        } else {
            l
        };
        if !(l.iter().all(|v| v.is_finite() && *v > 0.0)) {
            continue;
        }
        let ps = [y[0] * l[0], y[1] * l[1], y[2] * l[2]];
        let Some(fc) = triangle_frame(&ps) else {
            continue;
        };
        let rotation = fc * fw.transpose();
        let cc = (ps[0] + ps[1] + ps[2]) / 3.0;
        let translation = cc - rotation * cw;
        let pose = P3pPose {
            rotation,
            translation,
        };
        // Two plain loops, not a chained iterator (left out of line as a call of about 230
        // instructions per pose in some builds).
        let finite =
            rotation.iter().all(|v| v.is_finite()) && translation.iter().all(|v| v.is_finite());
        let scale = 1.0 + translation.norm();
        let duplicate = out.iter().any(|q| {
            (q.rotation - rotation).norm() <= 1e-9
                && (q.translation - translation).norm() <= 1e-9 * scale
        });
        if finite && !duplicate && !out.is_full() {
            out.push(pose);
        }
    }
    out
}

/// `(e1, e2, -s2/s1)` of the most indefinite singular member `D0` of the pencil of `d1`, `d2`
/// (`|s1| >= |s2|`, `e1`, `e2` unit eigenvectors), or `None`.
fn degenerate_member(
    d1: &Matrix3<f64>,
    d2: &Matrix3<f64>,
    closed_form: bool,
) -> Option<(Vector3<f64>, Vector3<f64>, f64)> {
    // det(D1 + g D2) = det D1 + tr(adj(D1) D2) g + tr(D1 adj(D2)) g^2 + det D2 g^3; the
    // matrices are symmetric, so tr(A B) is the sum of the entrywise products.
    let (adj1, adj2) = (adjugate(d1), adjugate(d2));
    let c0 = d1.determinant();
    let c1 = adj1.component_mul(d2).sum();
    let c2 = d1.component_mul(&adj2).sum();
    let c3 = d2.determinant();
    // det(D1 + g D2) = c0 + c1 g + c2 g^2 + c3 g^3; with |c3| < |c0| solve the reversed
    // polynomial det(m D1 + D2) instead, so a root near infinity (D2 singular) is found as m ~ 0.
    let reversed = c3.abs() < c0.abs();
    let coeffs = if reversed {
        [c3, c2, c1, c0]
    } else {
        [c0, c1, c2, c3]
    };
    if closed_form {
        // The unpolished starts: one real root of the cubic (every real root of it gives a
        // degenerate member whose plane pair, when real, holds every solution), its plane
        // pair in closed form; the search over all roots below only if that fails.
        if let Some(pair) = one_cubic_root(&coeffs)
            .map(|g| if reversed { d1 * g + d2 } else { d1 + d2 * g })
            .and_then(|d0| plane_pair_closed(&d0))
        {
            return Some(pair);
        }
    }
    let roots = crate::numeric::roots::real_roots(&coeffs);
    let mut best: Option<(Vector3<f64>, Vector3<f64>, f64)> = None;
    let consider = |best: &mut Option<(Vector3<f64>, Vector3<f64>, f64)>, d0: Matrix3<f64>| {
        let pair = if closed_form {
            plane_pair_closed(&d0).or_else(|| plane_pair(&d0))
        } else {
            plane_pair(&d0)
        };
        if let Some(c) = pair {
            if best.is_none_or(|b| c.2 > b.2) {
                *best = Some(c);
            }
        }
    };
    for &g in roots.iter() {
        consider(&mut best, if reversed { d1 * g + d2 } else { d1 + d2 * g });
    }
    if best.is_none() {
        // No real root survived the normalisation (both conics nearly singular): use the more
        // singular one directly.
        let r1 = c0.abs() / d1.norm().powi(3).max(f64::MIN_POSITIVE);
        let r2 = c3.abs() / d2.norm().powi(3).max(f64::MIN_POSITIVE);
        consider(&mut best, if r1 <= r2 { *d1 } else { *d2 });
    }
    best
}

/// A real root of the cubic `c[0] + c[1] g + c[2] g^2 + c[3] g^3`, or `None` if `c[3]` is 0
/// or not finite or the iteration fails. With `p` monic and `y = g - g_i` measured from its
/// inflection point `g_i`, `p = y^3 + P y + Q`: if `Q < 0` a root lies at `y > 0`, where `p` is
/// convex, and Newton's iteration from any point above it decreases monotonically to it; if
/// `Q > 0`, symmetrically, from below. The start is such a point: `|Q| / P` (the Newton step
/// from `y = 0`, beyond the root by convexity) when `P > 0`, else `max(cbrt(2 |Q|), sqrt(2
/// |P|))` (there `|y|^3 > |Q| + |P| |y|`).
fn one_cubic_root(c: &[f64; 4]) -> Option<f64> {
    if !(c[3] != 0.0 && c[3].is_finite()) {
        return None;
    }
    let (a, b, k) = (c[2] / c[3], c[1] / c[3], c[0] / c[3]);
    let gi = -a / 3.0;
    // p(g_i) and p'(g_i) of the monic cubic g^3 + a g^2 + b g + k.
    let q = ((gi + a) * gi + b) * gi + k;
    let pp = (3.0 * gi + 2.0 * a) * gi + b;
    if !(q.is_finite() && pp.is_finite()) {
        return None;
    }
    if q == 0.0 {
        return Some(gi);
    }
    // The side of the root: y > 0 if q < 0.
    let side = if q < 0.0 { 1.0 } else { -1.0 };
    let y = if pp > 0.0 {
        q.abs() / pp
    } else {
        (2.0 * q.abs()).cbrt().max((-2.0 * pp).sqrt())
    };
    // Newton on g itself (not on y, whose offset g_i would bound the root's precision by
    // the ulp of g_i): every step moves towards g_i, by `side`.
    let mut g = gi + side * y;
    let mut budget = Budget::new(Bound::P3pCubic);
    while budget.next() {
        let f = ((g + a) * g + b) * g + k;
        let df = (3.0 * g + 2.0 * a) * g + b;
        let next = g - f / df;
        // Monotone in exact arithmetic: stop where rounding ends the progress.
        if !(side * (g - next) > 0.0) {
            return Some(g);
        }
        g = next;
    }
    None
}

/// Adjugate (transposed cofactor matrix) of a 3x3 matrix.
fn adjugate(m: &Matrix3<f64>) -> Matrix3<f64> {
    let c = |r0: usize, r1: usize, c0: usize, c1: usize| {
        m[(r0, c0)] * m[(r1, c1)] - m[(r0, c1)] * m[(r1, c0)]
    };
    Matrix3::new(
        c(1, 2, 1, 2),
        -c(0, 2, 1, 2),
        c(0, 1, 1, 2),
        -c(1, 2, 0, 2),
        c(0, 2, 0, 2),
        -c(0, 1, 0, 2),
        c(1, 2, 0, 1),
        -c(0, 2, 0, 1),
        c(0, 1, 0, 1),
    )
}

/// For a (numerically) rank-2 symmetric `d0`: its two non-null eigenvectors, larger
/// eigenvalue magnitude first, and `-s2/s1` (positive when `d0` is indefinite, i.e. a real
/// plane pair). `None` if the decomposition fails or `d0` is not a real plane pair.
fn plane_pair(d0: &Matrix3<f64>) -> Option<(Vector3<f64>, Vector3<f64>, f64)> {
    let eig = nalgebra::SymmetricEigen::try_new(*d0, f64::EPSILON, limit(Bound::P3pEigen));
    let eig = converged(eig, Bound::P3pEigen)?;
    let ev = eig.eigenvalues;
    // The null eigenvalue is the one of smallest magnitude.
    let mut idx = [0usize, 1, 2];
    idx.sort_by(|&a, &b| ev[b].abs().total_cmp(&ev[a].abs()));
    let (s1, s2) = (ev[idx[0]], ev[idx[1]]);
    if !(s1.abs() > 0.0) || !s1.is_finite() {
        return None;
    }
    let ratio = -s2 / s1;
    // A slightly positive-definite pair (ratio a rounding error below 0) is a double plane.
    if ratio < -1e-12 {
        return None;
    }
    let e1 = eig.eigenvectors.column(idx[0]).into_owned();
    let e2 = eig.eigenvectors.column(idx[1]).into_owned();
    Some((e1, e2, ratio))
}

/// [`plane_pair`] in closed form, for the unpolished starts: with the null eigenvalue taken
/// as 0, the other two are the roots of `s^2 - tr(d0) s + m2(d0)` (`m2` the sum of the
/// principal 2 x 2 minors), and the eigenvector of each is the largest cross product of two
/// rows of `d0 - s I`. `None` (the caller falls back to the iterative decomposition) when the
/// two eigenvalues are not well separated or a cross product is tiny.
fn plane_pair_closed(d0: &Matrix3<f64>) -> Option<(Vector3<f64>, Vector3<f64>, f64)> {
    let tr = d0.trace();
    let m2 = d0[(0, 0)] * d0[(1, 1)] - d0[(0, 1)] * d0[(1, 0)] + d0[(0, 0)] * d0[(2, 2)]
        - d0[(0, 2)] * d0[(2, 0)]
        + d0[(1, 1)] * d0[(2, 2)]
        - d0[(1, 2)] * d0[(2, 1)];
    let disc = tr * tr - 4.0 * m2;
    let scale = d0.norm();
    if !(disc > 1e-6 * scale * scale) || !disc.is_finite() {
        return None;
    }
    let sq = disc.sqrt();
    // Roots without cancellation; s1 the one of larger magnitude.
    let big = 0.5 * (tr + tr.signum() * sq);
    if big == 0.0 {
        return None;
    }
    let (s1, s2) = (big, m2 / big);
    let vector = |s: f64| -> Option<Vector3<f64>> {
        // The rows of d0 - s I (d0 is symmetric: its columns).
        let r0 = Vector3::new(d0[(0, 0)] - s, d0[(1, 0)], d0[(2, 0)]);
        let r1 = Vector3::new(d0[(0, 1)], d0[(1, 1)] - s, d0[(2, 1)]);
        let r2 = Vector3::new(d0[(0, 2)], d0[(1, 2)], d0[(2, 2)] - s);
        let (c0, c1, c2) = (r0.cross(&r1), r0.cross(&r2), r1.cross(&r2));
        let (n0, n1, n2) = (c0.norm_squared(), c1.norm_squared(), c2.norm_squared());
        // The largest (the last of equal ones).
        let (best, nb) = if n2 >= n1 && n2 >= n0 {
            (c2, n2)
        } else if n1 >= n0 {
            (c1, n1)
        } else {
            (c0, n0)
        };
        let n = nb.sqrt();
        (n > 1e-8 * scale * scale && n.is_finite()).then(|| best / n)
    };
    let (e1, e2) = (vector(s1)?, vector(s2)?);
    let ratio = -s2 / s1;
    if ratio < -1e-12 {
        return None;
    }
    Some((e1, e2, ratio))
}

/// The depth triples with `n . L = 0` on the conics `d1`, `d2`, scaled so that
/// `L^T sum_form L = asum`, all depths positive.
fn depths_on_plane(
    n: &Vector3<f64>,
    d1: &Matrix3<f64>,
    d2: &Matrix3<f64>,
    sum_form: &Matrix3<f64>,
    asum: f64,
) -> ArrayVec<Vector3<f64>, 2> {
    let mut out = ArrayVec::new();
    let nn = n.norm();
    if !(nn > 0.0 && nn.is_finite()) {
        return out;
    }
    let n = n / nn;
    // Orthonormal basis (p, q) of the plane.
    let helper = if n.x.abs() < 0.6 {
        Vector3::x()
    } else if n.y.abs() < 0.6 {
        Vector3::y()
    } else {
        Vector3::z()
    };
    let p = n.cross(&helper).normalize();
    let q = n.cross(&p);
    // The conics restricted to the plane, `[[p.Dp, p.Dq], [p.Dq, q.Dq]]` (D symmetric), and
    // the one of larger Frobenius norm.
    let restrict = |d: &Matrix3<f64>| {
        let dq = d * q;
        (p.dot(&(d * p)), p.dot(&dq), q.dot(&dq))
    };
    let squared_norm = |(a, b, c): (f64, f64, f64)| a * a + 2.0 * b * b + c * c;
    let (r1, r2) = (restrict(d1), restrict(d2));
    let (q11, q12, q22) = if squared_norm(r1) >= squared_norm(r2) {
        r1
    } else {
        r2
    };
    // q11 u^2 + 2 q12 u v + q22 v^2 = 0 for L = u p + v q: solve for the ratio with the
    // larger leading coefficient.
    let swap = q11.abs() < q22.abs();
    let (a, b, c) = if swap {
        (q22, q12, q11)
    } else {
        (q11, q12, q22)
    };
    if !(a.abs() > 0.0) {
        return out;
    }
    let disc = b * b - a * c;
    let tol = 1e-12 * (b * b).max((a * c).abs());
    if disc < -tol {
        return out;
    }
    let sq = disc.max(0.0).sqrt();
    // Stable quadratic formula: roots of a t^2 + 2 b t + c.
    let big = -(b + b.signum() * sq);
    let mut ts: ArrayVec<f64, 2> = ArrayVec::new();
    if big != 0.0 {
        ts.push(big / a);
        ts.push(c / big);
    } else {
        ts.push(0.0);
    }
    for t in ts {
        // L = u p + v q with (u, v) = (1, t) or (t, 1).
        let l = if swap { p + q * t } else { p * t + q };
        let form = l.dot(&(sum_form * l));
        if !(form > 0.0 && form.is_finite()) {
            continue;
        }
        let mut l = l * (asum / form).sqrt();
        if l.sum() < 0.0 {
            l = -l;
        }
        if l.iter().all(|v| *v > 0.0) && !out.is_full() {
            out.push(l);
        }
    }
    out
}

/// Residuals of the three distance equations `l_i^2 + l_j^2 + b_ij l_i l_j - a_ij`.
fn residuals(l: &Vector3<f64>, a: [f64; 3], b: [f64; 3]) -> Vector3<f64> {
    Vector3::new(
        l[0] * l[0] + l[1] * l[1] + b[0] * l[0] * l[1] - a[0],
        l[0] * l[0] + l[2] * l[2] + b[1] * l[0] * l[2] - a[1],
        l[1] * l[1] + l[2] * l[2] + b[2] * l[1] * l[2] - a[2],
    )
}

/// Gauss-Newton on the distance equations (`a = [a12, a13, a23]`, `b = [b12, b13, b23]`);
/// a step is kept only if it lowers the residual norm.
fn gauss_newton(mut l: Vector3<f64>, a: [f64; 3], b: [f64; 3]) -> Vector3<f64> {
    let mut r = residuals(&l, a, b);
    for _ in 0..GAUSS_NEWTON_ITERATIONS {
        let rn = r.norm();
        if rn == 0.0 {
            break;
        }
        let j = Matrix3::new(
            2.0 * l[0] + b[0] * l[1],
            2.0 * l[1] + b[0] * l[0],
            0.0,
            2.0 * l[0] + b[1] * l[2],
            0.0,
            2.0 * l[2] + b[1] * l[0],
            0.0,
            2.0 * l[1] + b[2] * l[2],
            2.0 * l[2] + b[2] * l[1],
        );
        let Some(ji) = j.try_inverse() else {
            break;
        };
        let cand = l - ji * r;
        let rc = residuals(&cand, a, b);
        if !(rc.norm() < rn) {
            break;
        }
        l = cand;
        r = rc;
    }
    l
}

/// Orthonormal frame (columns) of a triangle: the first edge, the normal, their cross product.
///
/// The normal, a cross product of two edges, is orthogonal to the first edge only to about
/// `eps / sin(angle)` when the triangle is nearly flat (1e-9 at an angle of 1e-7, which the
/// degeneracy cut lets through): it is re-orthogonalised against the edge (one Gram-Schmidt
/// step), so the frame, and the rotation built from two frames, is orthonormal to rounding.
pub(super) fn triangle_frame(p: &[Vector3<f64>; 3]) -> Option<Matrix3<f64>> {
    let u = p[0] - p[1];
    let n = u.cross(&(p[0] - p[2]));
    let (un, nn) = (u.norm(), n.norm());
    if !(un > 0.0 && nn > 0.0 && un.is_finite() && nn.is_finite()) {
        return None;
    }
    let e1 = u / un;
    let n1 = n / nn;
    let n2 = n1 - e1 * e1.dot(&n1);
    let n2n = n2.norm();
    if !(n2n > 0.0) {
        return None;
    }
    let e2 = n2 / n2n;
    let e3 = e1.cross(&e2);
    Some(Matrix3::from_columns(&[e1, e2, e3]))
}

#[cfg(test)]
#[path = "../../tests/unit/numeric/p3p.rs"]
mod tests;
