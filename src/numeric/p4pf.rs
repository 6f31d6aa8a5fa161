//! The four-point pose with unknown focal length (P4Pf): the poses and focal lengths that
//! project four world points (not coplanar) to four image points. The minimal solver of RANSAC
//! when the focal length is unknown.
//!
//! # Method
//!
//! In the world's affine frame of the four points (`X = X_1 + A Y`, `A = [X_2 - X_1, X_3 - X_1,
//! X_4 - X_1]`) the camera is `P_Y = [l_2 m_2 - m_1, l_3 m_3 - m_1, l_4 m_4 - m_1 | m_1]` (`m_i`
//! the image points as `(u, v, 1)`, `l_1 = 1`), and its left block `M = M_Y A^-1` must be
//! `s diag(1, 1, w) R` (`w = 1 / f`): four quadrics in `(x, y, z) = (l_2, l_3, l_4)`, the
//! generated kernel `p4pf_quadrics` (`codegen/src/defs/p4pf.rs`). The first three are solved by
//! [`e3q3`]: `z` hidden, the constant 3 x 3 system of their `x^2, xy, y^2` coefficients solved
//! for those monomials, the generated kernel `e3q3_octic` gives the octic `det L(z)` and the
//! matrix `L(z)` whose null vector at a root is `(x, y, 1)`. Every `l_i` is `w` times the depth
//! of point `i` over that of point 1, so only roots and null vectors with every `mu_k = l_k - 1`
//! above -1 (positive `l_k`) are sought: the octic's roots on `(-1, bound)` only
//! (isolated by the Sturm sequence, [`real_roots_above`]; with the real parts of near-real
//! pairs, [`real_roots_near_above`], where the points are close to coplanar), the others' `x`
//! and `y` screened before the polish. Each
//! solution is polished by Newton's method on the three quadrics and Gauss-Newton on all four,
//! turned into `R` (from `M`'s first two rows, well determined, and their cross product), `f`
//! (from the third row's component along `R`'s third: that row is weak and noisy when the
//! perspective is faint) and `t` (linear least squares on the four projections), and kept if it
//! reprojects the four points to [`REPROJECTION_MAX`] of their spread (duplicates once).
//!
//! Image points are scaled by their mean distance from the principal point and the world's
//! edges by the longest, so the kernels' coefficients are O(1). Coplanar (or nearly coplanar,
//! `|det A| <= 1e-6` times the product of `A`'s column norms) world points have no affine frame:
//! no solution is returned (the planar case is a homography).
//!
//! Everything is fixed-size (no heap allocation) and every loop is bounded.

use arrayvec::ArrayVec;
use nalgebra::{Matrix3, Point2, Point3, Vector3};

use super::roots::{real_roots_above, real_roots_near_above};
use super::rotation::nearest_rotation;
use crate::kernels::{e3q3_octic, p4pf_quadrics, P4PF_QUADRIC_EXPONENTS};

/// At most 9 solutions: Bezout's bound for three quadrics, and the planar solution for nearly
/// coplanar points.
pub const MAX_P4PF_SOLUTIONS: usize = 9;

/// A pose `x_cam = R X + t` and the focal length `f` (pixels) that project the world points to
/// the image points: `(u, v) = f (x / z, y / z)` relative to the principal point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct P4pfSolution {
    /// The rotation `R`.
    pub rotation: Matrix3<f64>,
    /// The translation `t`.
    pub translation: Vector3<f64>,
    /// The focal length, pixels.
    pub focal: f64,
}

/// Up to [`MAX_P4PF_SOLUTIONS`] solutions (fixed capacity, no allocation).
pub type P4pfSolutions = ArrayVec<P4pfSolution, MAX_P4PF_SOLUTIONS>;

/// A solution is kept if it reprojects the four points to within this fraction of their mean
/// distance from the principal point. The truth of a noise-free sample reprojects them to the
/// rounding level, that of a noisy sample to about the noise (the problem is over-determined
/// by one equation); the solutions of the three quadrics that miss the fourth are typically
/// off by tens of per cent (on 4,000 random noise-free instances, with the first version of the
/// pose extraction, 613 of the 752 solutions that were not exact were off by more than 1 %, 433
/// by more than 10 %).
pub const REPROJECTION_MAX: f64 = 0.05;

/// Newton iterations polishing each solution of the three quadrics (a step is kept only if it
/// lowers the residual).
const NEWTON_ITERATIONS: usize = 10;
/// The octic's near-real complex pairs (imaginary part at most this times `1 + |z|`) count as
/// roots: where two solutions of the three quadrics nearly coincide (points close to
/// coplanar), the rounding of the octic's coefficients can turn the pair next to the true
/// solution complex, and Newton's method on the three quadrics finds it from the pair's real
/// part (one of `verify`'s 5,000 instances).
const NEAR_REAL: f64 = 1e-2;
/// The screen of [`e3q3`]'s solutions in P4Pf: each `mu_k = l_k - 1` above this before the
/// polish (`l_k > 0`, what the solutions must have). The polish can move a root of a
/// near-double pair across it, so a looser screen (-2) was used first; measured against it:
/// on the unit test's 1,944 noisy samples one fewer gave a good hypothesis (1,663), `verify`'s
/// 5,000 instances all found the truth, and the focal RANSAC (`Ransac` with `unknown_focal`,
/// 200 problems at 0, 50 and 80 % outliers) drew the same samples to the same medians, at 80 %
/// a quarter faster (9.25 -> 6.90 ms a problem): most roots of outlier samples lie in between.
const SCREEN: f64 = -1.0;
/// [`polish`] stops where every residual is at most this times the sum of its terms' absolute
/// values (`4 eps`).
const ROUNDED: f64 = 4.0 * f64::EPSILON;
/// Gauss-Newton iterations on the four quadrics after that.
const GAUSS_NEWTON_ITERATIONS: usize = 10;

/// The general solver runs when the world points' planarity ratio (`|det A|` relative to the
/// product of its column norms) is at least this, the planar one when it is at most
/// [`PLANAR_MAX`]: both between. (Of the 3,988 instances with a ratio of at least 1e-3 among
/// the 4,000 of the unit tests' generator, the true pose was missed on 5, with ratios from
/// 1.1e-3 to 4.4e-3, and found on every other.)
const GENERAL_MIN: f64 = 1e-3;
/// See [`GENERAL_MIN`]: at a ratio of 3e-2 the points are out of their best-fit plane by a few
/// per cent of their spread, and the planar solution is a starting pose, not the pose.
const PLANAR_MAX: f64 = 3e-2;

/// The poses and focal lengths projecting `world[i]` to `image[i]` (pixels relative to the
/// principal point, square pixels), with every point in front of the camera and `f > 0`.
///
/// Returns no solution (never a NaN one) for coplanar or coincident world points, coincident
/// image points at the principal point, or non-finite input.
#[must_use]
pub fn p4pf(world: &[Point3<f64>; 4], image: &[Point2<f64>; 4]) -> P4pfSolutions {
    let mut out = P4pfSolutions::new();
    let finite = world.iter().all(|p| p.coords.iter().all(|v| v.is_finite()))
        && image.iter().all(|p| p.x.is_finite() && p.y.is_finite());
    if !finite {
        return out;
    }
    // Image scale: the mean distance from the principal point.
    let si = image.iter().map(|p| p.coords.norm()).sum::<f64>() / 4.0;
    if !(si > 0.0 && si.is_finite()) {
        return out;
    }
    let m: [Vector3<f64>; 4] = image.map(|p| Vector3::new(p.x / si, p.y / si, 1.0));
    // World: the affine frame, edges scaled by the longest.
    let d = [1, 2, 3].map(|k| world[k].coords - world[0].coords);
    let sw = d.iter().map(|v| v.norm()).fold(0.0, f64::max);
    if !(sw > 0.0 && sw.is_finite()) {
        return out;
    }
    let a = Matrix3::from_columns(&d.map(|v| v / sw));
    let norms = a.column(0).norm() * a.column(1).norm() * a.column(2).norm();
    let ratio = a.determinant().abs() / norms;
    if !(ratio.is_finite() && norms > 0.0) {
        return out;
    }
    if ratio <= PLANAR_MAX {
        if let Some(s) = planar(world, &m, si) {
            keep(&mut out, s, world, image, si);
        }
    }
    if ratio < GENERAL_MIN {
        return out;
    }
    let Some(a_inv) = a.try_inverse() else {
        return out;
    };
    let g = a_inv * a_inv.transpose();
    let uv = [
        m[0].x, m[0].y, m[1].x, m[1].y, m[2].x, m[2].y, m[3].x, m[3].y,
    ];
    let q = p4pf_quadrics(
        &uv,
        &[
            g[(0, 0)],
            g[(0, 1)],
            g[(0, 2)],
            g[(1, 1)],
            g[(1, 2)],
            g[(2, 2)],
        ],
    );
    let quadric = |n: usize| -> [f64; 10] { core::array::from_fn(|i| q[10 * n + i]) };
    let four = [quadric(0), quadric(1), quadric(2), quadric(3)];
    let three = [four[0], four[1], four[2]];
    // Roots whose depth ratios are clearly negative (l_k < -1 before the polish; the polish can
    // move a root of a near-double pair far, so the screen is loose) are neither sought nor
    // polished: on noisy samples, 6.4 -> 5.4 us per call (the polish), and the octic's roots
    // searched above the screen only (module docs).
    // Near-real pairs of the octic are sought only where the points are close to coplanar
    // (below [`PLANAR_MAX`]): there two solutions of the three quadrics can nearly coincide and
    // the rounding turn their pair complex; elsewhere the Sturm sequence isolates the real roots.
    let near_real = if ratio < PLANAR_MAX { NEAR_REAL } else { 0.0 };
    for mu in e3q3(&three, SCREEN, near_real) {
        // Gauss-Newton on all four: two solutions of the three close together (a near-double
        // root of the octic, where Newton on the three converges slowly) are told apart by the
        // fourth.
        let mu = gauss_newton4(&four, mu);
        // l_k = 1 + mu_k, positive for points in front.
        let l = mu.map(|v| 1.0 + v);
        if !l.iter().all(|v| *v > 0.0 && v.is_finite()) {
            continue;
        }
        // M_Y's columns l_k m_k - m_1; M = M_Y A^-1 (world units: / sw).
        let my = Matrix3::from_columns(&[1, 2, 3].map(|k| m[k] * l[k - 1] - m[0]));
        let mm = my * a_inv / sw;
        let (ra, rb, rc) = (mm.row(0), mm.row(1), mm.row(2));
        let (na, nb) = (ra.norm(), rb.norm());
        if !(na > 0.0 && nb > 0.0) {
            continue;
        }
        // R from the first two rows (well determined), the third their cross product; the
        // third row of M (weak when the perspective is faint, and noisy) gives only `w`, its
        // component along R's third row.
        let r1 = (ra / na).transpose();
        let r2 = (rb / nb).transpose();
        let Some(rotation) = orthonormal_pair(&r1, &r2) else {
            continue;
        };
        let s = (na + nb) / 2.0;
        let w = rc.transpose().dot(&rotation.row(2).transpose()) / s;
        if !(w > 0.0 && w.is_finite()) {
            continue;
        }
        let focal = si / w;
        // t by least squares from the four projections at (R, f): linear in t.
        let Some(translation) = translation_at(world, image, &rotation, focal) else {
            continue;
        };
        let ok = rotation.iter().all(|v| v.is_finite())
            && translation.iter().all(|v| v.is_finite())
            && focal.is_finite();
        let sol = P4pfSolution {
            rotation,
            translation,
            focal,
        };
        if ok {
            keep(&mut out, sol, world, image, si);
        }
    }
    out
}

/// The nearest rotation (Frobenius norm) to the matrix of rows `a`, `b`, `a x b` (`a`, `b` unit
/// vectors), in closed form: its rows are orthogonal to `a x b` and `a x b` to them, so the
/// polar factor is the symmetric orthonormalisation of the pair, `(a, b) G^-1/2` with `G` their
/// Gram matrix `[1 c; c 1]` (`c = a . b`), and the unit `a x b`. `None` if the pair is
/// (nearly) parallel or not finite.
fn orthonormal_pair(a: &Vector3<f64>, b: &Vector3<f64>) -> Option<Matrix3<f64>> {
    let c = a.dot(b);
    if !(c.abs() < 1.0 - 1e-12) {
        return None;
    }
    // G^-1/2 = [[p, q], [q, p]]: the eigenvalues 1 +- c, eigenvectors (1, +-1) / sqrt(2).
    let (sp, sm) = (1.0 / (1.0 + c).sqrt(), 1.0 / (1.0 - c).sqrt());
    let (p, q) = ((sp + sm) / 2.0, (sp - sm) / 2.0);
    let r1 = a * p + b * q;
    let r2 = a * q + b * p;
    let r3 = r1.cross(&r2);
    let m = Matrix3::from_rows(&[r1.transpose(), r2.transpose(), r3.transpose()]);
    m.iter().all(|v| v.is_finite()).then_some(m)
}

/// The translation that projects the four points closest to their images at the rotation
/// `r` and focal length `f`, by linear least squares on `f (r_k . X + t_k) = u_k (r_3 . X + t_z)`
/// (`k` = x, y): eight equations in `t`.
fn translation_at(
    world: &[Point3<f64>; 4],
    image: &[Point2<f64>; 4],
    r: &Matrix3<f64>,
    f: f64,
) -> Option<Vector3<f64>> {
    let mut ata = Matrix3::zeros();
    let mut atb = Vector3::zeros();
    for (x, m) in world.iter().zip(image) {
        let q = r * x.coords;
        for (row, rhs) in [
            (Vector3::new(f, 0.0, -m.x), m.x * q.z - f * q.x),
            (Vector3::new(0.0, f, -m.y), m.y * q.z - f * q.y),
        ] {
            ata += row * row.transpose();
            atb += row * rhs;
        }
    }
    ata.try_inverse().map(|inv| inv * atb)
}

/// The largest distance of the four points' projections under `s` from their image points,
/// over the image scale `si`; infinite if a point is not in front.
fn reprojection(
    s: &P4pfSolution,
    world: &[Point3<f64>; 4],
    image: &[Point2<f64>; 4],
    si: f64,
) -> f64 {
    world.iter().zip(image).fold(0.0, |worst, (x, m)| {
        let p = s.rotation * x.coords + s.translation;
        if !(p.z > 0.0) {
            return f64::INFINITY;
        }
        let (du, dv) = (s.focal * p.x / p.z - m.x, s.focal * p.y / p.z - m.y);
        worst.max((du * du + dv * dv).sqrt() / si)
    })
}

/// Adds `s` to `out` if every point is in front and it reprojects the four points to
/// [`REPROJECTION_MAX`], unless a solution within `1e-6` of it is there already (then the one
/// that reprojects better stays).
fn keep(
    out: &mut P4pfSolutions,
    s: P4pfSolution,
    world: &[Point3<f64>; 4],
    image: &[Point2<f64>; 4],
    si: f64,
) {
    let err = reprojection(&s, world, image, si);
    if !(err <= REPROJECTION_MAX) {
        return;
    }
    let near = |o: &P4pfSolution| {
        (o.rotation - s.rotation).norm() <= 1e-6
            && (o.focal / s.focal - 1.0).abs() <= 1e-6
            && (o.translation - s.translation).norm() <= 1e-6 * (1.0 + s.translation.norm())
    };
    if let Some(o) = out.iter_mut().find(|o| near(o)) {
        if err < reprojection(o, world, image, si) {
            *o = s;
        }
    } else if !out.is_full() {
        out.push(s);
    }
}

/// The planar solution (module docs): the homography of the plane that fits the world points
/// best, its focal length from the two constraints of an orthonormal pair of columns (least
/// squares), and its pose. `m` are the scaled image points, `si` their scale.
fn planar(world: &[Point3<f64>; 4], m: &[Vector3<f64>; 4], si: f64) -> Option<P4pfSolution> {
    let mean = world.iter().map(|p| p.coords).sum::<Vector3<f64>>() / 4.0;
    let scatter = world
        .iter()
        .map(|p| (p.coords - mean) * (p.coords - mean).transpose())
        .sum::<Matrix3<f64>>();
    let (_, vecs) = super::mat3::sym_eigen3_closed(&scatter)?;
    // The plane's frame: e1, e2 across it, n = e1 x e2 (a rotation, rows e1, e2, n).
    let (e1, e2) = (vecs.column(0).into_owned(), vecs.column(1).into_owned());
    let n = e1.cross(&e2);
    let frame = Matrix3::from_rows(&[e1.transpose(), e2.transpose(), n.transpose()]);
    let scale = world
        .iter()
        .map(|p| (p.coords - mean).norm())
        .fold(0.0, f64::max);
    if !(scale > 0.0) {
        return None;
    }
    let y: [Vector3<f64>; 4] = world.map(|p| frame * (p.coords - mean) / scale);
    // The homography `m ~ H (y1, y2, 1)`, scaled to `h33 = 1` (the plane's centroid is in
    // front): the one projective map of four points in general position, `H = B A^-1` with `A`
    // and `B` the maps of the canonical basis and `(1, 1, 1)` to the four points on each side.
    let hm = frame4(&y.map(|p| Vector3::new(p.x, p.y, 1.0)))
        .and_then(|a| a.try_inverse())
        .zip(frame4(m))
        .map(|(a_inv, b)| b * a_inv)?;
    let hm = hm / hm[(2, 2)];
    if !hm.iter().all(|v| v.is_finite()) {
        return None;
    }
    let (h1, h2) = (hm.column(0), hm.column(1));
    // k = w^2: k (h11 h12 + h21 h22) + h31 h32 = 0, k (|h1_xy|^2 - |h2_xy|^2) + h31^2 - h32^2 = 0.
    let (a1, b1) = (h1.x * h2.x + h1.y * h2.y, h1.z * h2.z);
    let (a2, b2) = (
        h1.x * h1.x + h1.y * h1.y - h2.x * h2.x - h2.y * h2.y,
        h1.z * h1.z - h2.z * h2.z,
    );
    let k = -(a1 * b1 + a2 * b2) / (a1 * a1 + a2 * a2);
    if !(k > 0.0 && k.is_finite()) {
        return None;
    }
    let w = k.sqrt();
    let b = Matrix3::from_diagonal(&Vector3::new(w, w, 1.0)) * hm;
    let mut lambda = (b.column(0).norm() + b.column(1).norm()) / 2.0;
    if b[(2, 2)] < 0.0 {
        lambda = -lambda;
    }
    let (r1, r2) = (b.column(0) / lambda, b.column(1) / lambda);
    let raw = Matrix3::from_columns(&[r1, r2, r1.cross(&r2)]);
    let r_plane = nearest_rotation(&raw)?;
    let t_plane = b.column(2) / lambda * scale;
    let rotation = r_plane * frame;
    let translation = t_plane - rotation * mean;
    let focal = si / w;
    let ok = rotation
        .iter()
        .chain(translation.iter())
        .all(|v| v.is_finite())
        && focal.is_finite();
    ok.then_some(P4pfSolution {
        rotation,
        translation,
        focal,
    })
}

/// The projective frame of four points (homogeneous, three of them, and the fourth, in general
/// position): the matrix that takes the canonical basis to the first three (up to scale) and
/// `(1, 1, 1)` to the fourth. `None` if three of them are collinear (it is singular).
fn frame4(p: &[Vector3<f64>; 4]) -> Option<Matrix3<f64>> {
    let b = Matrix3::from_columns(&[p[0], p[1], p[2]]);
    let l = b.try_inverse()? * p[3];
    let f = b * Matrix3::from_diagonal(&l);
    (l.iter().all(|v| *v != 0.0) && f.iter().all(|v| v.is_finite())).then_some(f)
}

/// The exponents of a quadric's coefficients `[xx, xy, yy, xz, yz, zz, x, y, z, 1]` (the
/// order of `p4pf_quadrics`, whose table it is).
const EXPONENTS: [[u8; 3]; 10] = P4PF_QUADRIC_EXPONENTS;

/// The monomials `[xx, xy, yy, xz, yz, zz, x, y, z, 1]` at `v` (the order of [`EXPONENTS`],
/// checked by a unit test).
#[inline]
fn monomials(v: &[f64; 3]) -> [f64; 10] {
    let [x, y, z] = *v;
    [x * x, x * y, y * y, x * z, y * z, z * z, x, y, z, 1.0]
}

/// A quadric `[xx, xy, yy, xz, yz, zz, x, y, z, 1]` at `v`.
#[inline]
fn eval(q: &[f64; 10], v: &[f64; 3]) -> f64 {
    let [x, y, z] = *v;
    (q[0] * x + q[1] * y + q[3] * z + q[6]) * x
        + (q[2] * y + q[4] * z + q[7]) * y
        + (q[5] * z + q[8]) * z
        + q[9]
}

/// The gradient of a quadric at `v`.
fn gradient(q: &[f64; 10], v: &[f64; 3]) -> Vector3<f64> {
    let [x, y, z] = *v;
    Vector3::new(
        2.0 * q[0] * x + q[1] * y + q[3] * z + q[6],
        q[1] * x + 2.0 * q[2] * y + q[4] * z + q[7],
        q[3] * x + q[4] * y + 2.0 * q[5] * z + q[8],
    )
}

/// The variable orders tried by [`e3q3`]: each hides its last variable (`z`, `x`, `y`).
const PERMS: [[usize; 3]; 3] = [[0, 1, 2], [1, 2, 0], [2, 0, 1]];

/// `PERMUTED[p][i]`: where coefficient `i` of a quadric goes when its variables are renamed by
/// `PERMS[p]` (variable `k` of the result is variable `PERMS[p][k]` of the quadric).
const PERMUTED: [[usize; 10]; 3] = {
    let mut table = [[0usize; 10]; 3];
    let mut p = 0;
    while p < 3 {
        let mut i = 0;
        while i < 10 {
            let e = EXPONENTS[i];
            let new = [e[PERMS[p][0]], e[PERMS[p][1]], e[PERMS[p][2]]];
            let mut j = 0;
            while !(EXPONENTS[j][0] == new[0]
                && EXPONENTS[j][1] == new[1]
                && EXPONENTS[j][2] == new[2])
            {
                j += 1;
            }
            table[p][i] = j;
            i += 1;
        }
        p += 1;
    }
    table
};

/// `PERMUTED_INVERSE[p][j]`: the coefficient of a quadric that lands at `j` when its variables
/// are renamed by `PERMS[p]`.
const PERMUTED_INVERSE: [[usize; 10]; 3] = {
    let mut table = [[0usize; 10]; 3];
    let mut p = 0;
    while p < 3 {
        let mut i = 0;
        while i < 10 {
            table[p][PERMUTED[p][i]] = i;
            i += 1;
        }
        p += 1;
    }
    table
};

/// The quadric `q` with its variables renamed by `PERMS[p]`.
fn permuted(q: &[f64; 10], p: usize) -> [f64; 10] {
    let mut out = [0.0; 10];
    for (i, c) in q.iter().enumerate() {
        out[PERMUTED[p][i]] = *c;
    }
    out
}

/// The real solutions of three quadrics in `(x, y, z)` (coefficients
/// `[xx, xy, yy, xz, yz, zz, x, y, z, 1]`), by the E3Q3 elimination (module docs): the hidden
/// variable is the one whose other two's `x^2, xy, y^2` coefficients form the best-conditioned
/// 3 x 3 system (by Hadamard's ratio). Each solution is polished by Newton's method on the three, kept if it then
/// solves them (to `1e-8` of each one's terms) and reported once.
///
/// Only solutions whose every coordinate exceeds `above` are sought (P4Pf: the depth ratios
/// loosely positive; `f64::NEG_INFINITY` for all): the octic's roots on `(above, bound)` only,
/// the others' coordinates screened before their polish. With `near_real > 0` the real parts of
/// the octic's near-real complex pairs are tried too ([`real_roots_near_above`]'s `imag_tol`);
/// with 0, the real roots alone, isolated by the Sturm sequence when `above` is finite
/// ([`real_roots_above`]).
#[must_use]
pub fn e3q3(
    quadrics: &[[f64; 10]; 3],
    above: f64,
    near_real: f64,
) -> ArrayVec<[f64; 3], MAX_P4PF_SOLUTIONS> {
    let mut out = ArrayVec::new();
    // Hide each variable in turn: the best-conditioned 3 x 3 system of the other two's squares,
    // by the ratio of its determinant to the product of its rows' norms (Hadamard's bound: 1 for
    // orthogonal rows, 0 for a singular system).
    // (Squared, without the square roots: the same order.)
    let mut best: Option<(usize, f64)> = None;
    for p in 0..3 {
        let c = Matrix3::from_fn(|i, j| quadrics[i][PERMUTED_INVERSE[p][j]]);
        let rows = c.row(0).norm_squared() * c.row(1).norm_squared() * c.row(2).norm_squared();
        let det = c.determinant();
        let ratio2 = det * det / rows;
        if best.is_none_or(|b| ratio2 > b.1) {
            best = Some((p, ratio2));
        }
    }
    let Some((p, ratio2)) = best else {
        return out;
    };
    if !(ratio2 > 1e-24) {
        return out;
    }
    let qs = quadrics.map(|q| permuted(&q, p));
    let c = Matrix3::from_fn(|i, j| qs[i][j]);
    let perm = PERMS[p];
    let Some(ci) = c.try_inverse() else {
        return out;
    };
    // [x^2, xy, y^2] = -C^-1 (lx(z) x + ly(z) y + k(z)).
    let mut mcoef = [0.0; 21];
    for i in 0..3 {
        let mut row = [0.0; 7];
        for j in 0..3 {
            let (q, cij) = (&qs[j], -ci[(i, j)]);
            row[0] += cij * q[6]; // A: x, constant
            row[1] += cij * q[3]; // A: xz
            row[2] += cij * q[7]; // B: y
            row[3] += cij * q[4]; // B: yz
            row[4] += cij * q[9]; // C: 1
            row[5] += cij * q[8]; // C: z
            row[6] += cij * q[5]; // C: zz
        }
        mcoef[7 * i..7 * i + 7].copy_from_slice(&row);
    }
    let k = e3q3_octic(&mcoef);
    let octic = &k[0..9];
    // L's entries: coefficient slices row by row (lengths 3, 3, 4 / 3, 3, 4 / 4, 4, 5).
    let lens = [3, 3, 4, 3, 3, 4, 4, 4, 5];
    let mut starts = [0usize; 9];
    let mut at = 9;
    for (s, len) in starts.iter_mut().zip(lens) {
        *s = at;
        at += len;
    }
    let roots = if near_real > 0.0 {
        real_roots_near_above(octic, near_real, above)
    } else {
        real_roots_above(octic, above)
    };
    for &z in roots.iter() {
        let l = Matrix3::from_fn(|r, col| {
            let n = 3 * r + col;
            horner(&k[starts[n]..starts[n] + lens[n]], z)
        });
        // The null vector: the largest cross product of two rows.
        let crosses = [
            l.row(0).cross(&l.row(1)),
            l.row(0).cross(&l.row(2)),
            l.row(1).cross(&l.row(2)),
        ];
        let v = crosses
            .iter()
            .max_by(|a, b| a.norm_squared().total_cmp(&b.norm_squared()))
            .expect("three");
        if !(v[2].abs() > 0.0) {
            continue;
        }
        let sol = [v[0] / v[2], v[1] / v[2], z];
        let mut orig = [0.0; 3];
        for kk in 0..3 {
            orig[perm[kk]] = sol[kk];
        }
        if !orig.iter().all(|x| *x > above) {
            continue;
        }
        let sol = polish(&qs, sol);
        if !solves(&qs, &sol) {
            continue;
        }
        // Back to the caller's variables.
        let mut orig = [0.0; 3];
        for kk in 0..3 {
            orig[perm[kk]] = sol[kk];
        }
        let scale = 1.0 + orig.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let duplicate = out
            .iter()
            .any(|o: &[f64; 3]| (0..3).all(|i| (o[i] - orig[i]).abs() <= 1e-9 * scale));
        if orig.iter().all(|x| x.is_finite()) && !duplicate && !out.is_full() {
            out.push(orig);
        }
    }
    out
}

/// Whether `v` solves the three quadrics: each residual at most `1e-8` times the sum of its
/// terms' absolute values (the rounding of the octic's coefficients leaves the roots it gives
/// far less accurate than that; Newton's polish brings a real solution to the rounding level,
/// and the real part of a complex pair, which solves nothing, stays far above it).
fn solves(qs: &[[f64; 10]; 3], v: &[f64; 3]) -> bool {
    residuals_within(qs, v, &values3(qs, v), 1e-8)
}

/// The three quadrics at `v`.
#[inline]
fn values3(qs: &[[f64; 10]; 3], v: &[f64; 3]) -> [f64; 3] {
    [eval(&qs[0], v), eval(&qs[1], v), eval(&qs[2], v)]
}

/// Whether each quadric's value `f` at `v` is at most `tol` times the sum of its terms'
/// absolute values there.
fn residuals_within(qs: &[[f64; 10]; 3], v: &[f64; 3], f: &[f64; 3], tol: f64) -> bool {
    let m = monomials(v).map(f64::abs);
    qs.iter().zip(f).all(|(q, fk)| {
        let terms: f64 = q.iter().zip(&m).map(|(c, mi)| c.abs() * mi).sum();
        fk.abs() <= tol * terms
    })
}

/// Newton's method on the three quadrics from `v` (a step kept only if it lowers the largest
/// residual), until every residual is at the rounding level (at most [`ROUNDED`] times the sum
/// of its terms' absolute values: the Sturm sequence's roots mostly start there, and a step
/// from there only chases rounding noise).
fn polish(qs: &[[f64; 10]; 3], mut v: [f64; 3]) -> [f64; 3] {
    let values = |v: &[f64; 3]| values3(qs, v);
    let largest = |f: &[f64; 3]| f[0].abs().max(f[1].abs()).max(f[2].abs());
    let mut f = values(&v);
    let mut r = largest(&f);
    for _ in 0..NEWTON_ITERATIONS {
        if residuals_within(qs, &v, &f, ROUNDED) {
            break;
        }
        let j = Matrix3::from_rows(&[
            gradient(&qs[0], &v).transpose(),
            gradient(&qs[1], &v).transpose(),
            gradient(&qs[2], &v).transpose(),
        ]);
        let Some(step) = j
            .try_inverse()
            .map(|ji| ji * Vector3::new(f[0], f[1], f[2]))
        else {
            break;
        };
        let cand = [v[0] - step[0], v[1] - step[1], v[2] - step[2]];
        let fc = values(&cand);
        let rc = largest(&fc);
        if rc < r {
            v = cand;
            f = fc;
            r = rc;
        } else {
            break;
        }
    }
    v
}

/// Gauss-Newton on the four quadrics from `v` (a step kept only if it lowers the sum of
/// squared residuals).
fn gauss_newton4(qs: &[[f64; 10]; 4], mut v: [f64; 3]) -> [f64; 3] {
    let values = |v: &[f64; 3]| {
        [
            eval(&qs[0], v),
            eval(&qs[1], v),
            eval(&qs[2], v),
            eval(&qs[3], v),
        ]
    };
    let cost = |f: &[f64; 4]| f.iter().map(|x| x * x).sum::<f64>();
    let mut f = values(&v);
    let mut c = cost(&f);
    for _ in 0..GAUSS_NEWTON_ITERATIONS {
        // The normal equations J^T J step = J^T f, accumulated row by row.
        let mut jtj = Matrix3::zeros();
        let mut jtf = Vector3::zeros();
        for (q, fi) in qs.iter().zip(&f) {
            let g = gradient(q, &v);
            jtj += g * g.transpose();
            jtf += g * *fi;
        }
        let Some(step) = jtj.try_inverse().map(|n| n * jtf) else {
            break;
        };
        let cand = [v[0] - step[0], v[1] - step[1], v[2] - step[2]];
        let fc = values(&cand);
        let cc = cost(&fc);
        if cc < c {
            v = cand;
            f = fc;
            c = cc;
        } else {
            break;
        }
    }
    v
}

/// `c[0] + c[1] x + ...` at `x`.
fn horner(c: &[f64], x: f64) -> f64 {
    c.iter().rev().fold(0.0, |acc, &ci| acc * x + ci)
}

#[cfg(test)]
#[path = "../../tests/unit/numeric/p4pf.rs"]
mod tests;
