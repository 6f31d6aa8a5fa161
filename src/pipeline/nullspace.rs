//! The `nullspace` stage of docs/algorithm.md: candidate rotations from the (approximate) null
//! space of M, and the algebra of constrained null-space combinations that the planar branch
//! (`planar`) shares.
//!
//! Non-planar branch (docs/algorithm.md, `nullspace`): `r` is sought in the span of the
//! eigenvectors of the four smallest eigenvalues of `M`, with the orthonormality constraints of a
//! rotation: case 1 (`r = v1`), case 2 (`r = x v1 + y v2`, quartic in `beta = y^2`), case 3
//! (`r = v1 + k1 v2 + k2 v3`, degree-9 resultant), case 4 (`r = v1 + k1 v2 + k2 v3 + k3 v4`, three
//! quadrics, degree-8 determinant). Planar branch (`planar`): the same for the first two columns of
//! `R` from the 6x6 planar system. The polynomial algebra is the generated code of
//! [`crate::kernels`]; the roots come from [`crate::roots`].
//!
//! Every function appends to a fixed-capacity list: no allocation.

use arrayvec::ArrayVec;
use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

use crate::error::PnpError;
use crate::kernels;
use crate::numeric::bounds::{converged, limit, Bound};
use crate::numeric::linalg;
use crate::numeric::mat3::{null_vector3, rcond3};
use crate::numeric::roots::{self, Roots};
use crate::numeric::rotation::candidate_to_rotation;

/// Which generator produced a candidate (reported in [`crate::Solution`]).
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum CandidateSource {
    /// `nullspace` case 1: the eigenvector of the smallest eigenvalue.
    Case1,
    /// `nullspace` case 2: two-dimensional null space (quartic in `beta`).
    Case2,
    /// `nullspace` case 3: three-dimensional null space (degree-9 resultant).
    Case3,
    /// `nullspace` case 4: four-dimensional null space (three quadrics, degree-8 determinant).
    Case4,
    /// `planar` case p1: planar, one null vector.
    Planar1,
    /// `planar` case p2: planar, two null vectors.
    Planar2,
    /// `nullspace`'s extra starts: one of the four fixed extra starting rotations.
    ExtraStart,
    /// The caller's initial pose ([`crate::Solver::refine`]).
    Initial,
    /// `search`: a P3P pose of three of the points (default mode, at most five points with a
    /// non-zero weight; docs/algorithm.md, `search`), refined by `refine` without `newton`.
    P3p,
    /// A rig (generalized EOPnP): the null vector of the generalized cost's homogenised matrix
    /// (docs/algorithm.md, generalized EOPnP).
    Generalized,
    /// A rig: a generalized three-point pose (gP3P) of three of the rays.
    Gp3p,
}

/// Upper bound on the number of candidates: 1 + 4 + 9 + 8 (`nullspace` cases 1-4) + 5
/// (`planar`) + 4 (`nullspace`'s extra starts) = 31.
pub const MAX_CANDIDATES: usize = 32;

/// A candidate rotation before refinement.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Candidate {
    pub r: Matrix3<f64>,
    pub source: CandidateSource,
}

pub(crate) type Candidates = ArrayVec<Candidate, MAX_CANDIDATES>;

/// Relative eigenvalue level below which an eigenvalue of `M` counts as zero for the
/// `degenerate` diagnostic (docs/algorithm.md, constants and tolerances).
const DEGENERATE_EIG: f64 = 1e-10;

/// The four fixed extra starting rotations (`nullspace`'s extra starts; working frame).
const EXTRA_STARTS: [[f64; 3]; 4] = [
    [1.0, 1.0, 1.0],
    [1.0, -1.0, -1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0],
];

/// How large the null space of `M` is, as far as the solver needs to know.
pub(crate) struct Probe {
    /// More than four eigenvalues of `M` at or below `DEGENERATE_EIG trace(M)`.
    pub degenerate: bool,
    /// The Cholesky factor of `M - tau I` when it exists (no eigenvalue below `tau`); the
    /// case-1 inverse iteration reuses it.
    shifted: Option<linalg::Factor<9>>,
}

/// The probe's shift `tau = DEGENERATE_EIG trace(M) (1 + eps)`.
fn probe_shift(scale: f64) -> f64 {
    DEGENERATE_EIG * scale * (1.0 + f64::EPSILON)
}

/// A Cholesky factorisation of `M - tau I` proves that no eigenvalue is below `tau` (the
/// common case from N = 6 on) and is reused by the fast path's inverse iteration. One that
/// fails at pivot `j` has factored the leading `j x j` block, so at most `9 - j` eigenvalues
/// are below `tau` (interlacing): with `j >= 5` that settles the diagnostic too. So it does for
/// noise-free input and at N = 4 and 5 in general position, where M has a null space (of
/// dimension 1, 4 and 2: the factorisation fails at pivot 8, 5 and 7). The inertia count runs
/// otherwise.
#[inline(always)]
pub(crate) fn probe(m: &SMatrix<f64, 9, 9>, scale: f64) -> Probe {
    let tau = probe_shift(scale);
    let shifted = linalg::cholesky_shifted_or_pivot(m, tau);
    let degenerate = match shifted {
        Ok(_) => false,
        Err(j) => 9 - j > 4 && linalg::count_eigenvalues_below(m, tau) > 4,
    };
    Probe {
        degenerate,
        shifted: shifted.ok(),
    }
}

/// The case-1 start of the certified fast path: the rotation nearest to the eigenvector of the
/// smallest eigenvalue of `M`, by inverse iteration with the factor of `M - sigma I` (the
/// probe's, `sigma = tau`, or else [`linalg::cholesky_shifted_up`]'s), and `sigma`, below which
/// the factorisation proves no eigenvalue of `M` lies.
pub(crate) fn first_start(
    m: &SMatrix<f64, 9, 9>,
    probe: &Probe,
    scale: f64,
) -> Option<(Matrix3<f64>, f64)> {
    let (v1, sigma) = match &probe.shifted {
        Some(l) => (linalg::inverse_iteration(m, l)?, probe_shift(scale)),
        None => {
            let (l, sigma) = linalg::cholesky_shifted_up(m, scale)?;
            (linalg::inverse_iteration(m, &l)?, sigma)
        }
    };
    Some((candidate_to_rotation(&v1.into())?, sigma))
}

/// `nullspace`: the candidates of cases 1-4 from the eigenvectors of the four smallest eigenvalues
/// of `M`, appended to `out`.
pub(crate) fn candidates(m: &SMatrix<f64, 9, 9>, out: &mut Candidates) -> Result<(), PnpError> {
    let eig = nalgebra::SymmetricEigen::try_new(*m, f64::EPSILON, limit(Bound::MEigen));
    let eig = converged(eig, Bound::MEigen).ok_or(PnpError::NoSolution)?;
    let mut order: [usize; 9] = std::array::from_fn(|i| i);
    order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
    let v: [SVector<f64, 9>; 4] =
        std::array::from_fn(|i| eig.eigenvectors.column(order[i]).into_owned());
    nonplanar_candidates(&v, out);
    Ok(())
}

/// `nullspace`'s extra starts: the four fixed extra starting rotations, appended to `out` while
/// there is room.
pub(crate) fn extra_starts(out: &mut Candidates) {
    for d in EXTRA_STARTS {
        if !out.is_full() {
            out.push(Candidate {
                r: Matrix3::from_diagonal(&Vector3::from(d)),
                source: CandidateSource::ExtraStart,
            });
        }
    }
}

/// The row pairs (j, k) of R whose dot products are the constraints f1..f6 (docs/algorithm.md,
/// constants and tolerances).
const PAIRS: [(usize, usize); 6] = [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)];

/// Tolerance on the imaginary part of accepted near-real roots (docs/algorithm.md, constants and
/// tolerances, T8).
const IMAG_TOL: f64 = 1e-6;

/// `Q^{jk}[a][b]` for basis vectors `v` (docs/algorithm.md, `nullspace`):
/// `row_j(r) . row_k(r) = alpha^T Q alpha`. `block(v, j)` returns the j-th 3-block (a row of R, or
/// a column in the planar case).
pub(super) fn quad_form<const M: usize, const D: usize>(
    v: &[SVector<f64, D>; M],
    j: usize,
    k: usize,
    block: fn(&SVector<f64, D>, usize) -> Vector3<f64>,
) -> SMatrix<f64, M, M> {
    let bj: [Vector3<f64>; M] = std::array::from_fn(|a| block(&v[a], j));
    let bk: [Vector3<f64>; M] = std::array::from_fn(|a| block(&v[a], k));
    SMatrix::<f64, M, M>::from_fn(|a, b| 0.5 * (bj[a].dot(&bk[b]) + bj[b].dot(&bk[a])))
}

/// [`quad_form`] for the four non-planar basis vectors and row blocks: the upper triangle by
/// the same expression, mirrored (the expression is symmetric in a, b: the same values).
fn quad_form4(v: &[SVector<f64, 9>; 4], j: usize, k: usize) -> SMatrix<f64, 4, 4> {
    let bj: [Vector3<f64>; 4] = std::array::from_fn(|a| row_block(&v[a], j));
    let bk: [Vector3<f64>; 4] = std::array::from_fn(|a| row_block(&v[a], k));
    let mut q = SMatrix::<f64, 4, 4>::zeros();
    for a in 0..4 {
        for b in a..4 {
            let x = 0.5 * (bj[a].dot(&bk[b]) + bj[b].dot(&bk[a]));
            q[(a, b)] = x;
            q[(b, a)] = x;
        }
    }
    q
}

fn row_block(v: &SVector<f64, 9>, j: usize) -> Vector3<f64> {
    Vector3::new(v[3 * j], v[3 * j + 1], v[3 * j + 2])
}

/// Columns of R in the planar 6-vector `[R11, R12, R21, R22, R31, R32]`.
pub(super) fn col_block(v: &SVector<f64, 6>, j: usize) -> Vector3<f64> {
    Vector3::new(v[j], v[2 + j], v[4 + j])
}

fn sym3_upper(q: &Matrix3<f64>) -> [f64; 6] {
    [
        q[(0, 0)],
        q[(0, 1)],
        q[(0, 2)],
        q[(1, 1)],
        q[(1, 2)],
        q[(2, 2)],
    ]
}

/// Real roots of the cubic `c0 + c1 x + c2 x^2 + c3 x^3` for back-substitution.
fn cubic(c: &[f64]) -> Roots {
    roots::cubic_real_roots(&[c[0], c[1], c[2], c[3]])
}

/// The `x` minimising `cost(x)` among the real roots of the two gradient cubics.
fn best_x(cubics: &[f64; 8], cost: impl Fn(f64) -> f64) -> Option<f64> {
    let mut best: Option<(f64, f64)> = None;
    for x in cubic(&cubics[..4]).iter().chain(cubic(&cubics[4..]).iter()) {
        let c = cost(*x);
        if c.is_finite() && best.is_none_or(|(bc, _)| c < bc) {
            best = Some((c, *x));
        }
    }
    best.map(|(_, x)| x)
}

/// `nullspace` case 2 / `planar` p2: stationary points of `C2(x, y) = |A a - b|^2`,
/// `a = [x^2, x y, y^2]`, for the given constraint forms `qs` (rows of `A` are `[Q00, 2 Q01, Q11]`)
/// and right-hand sides `b`. Calls `emit(x, y)` for each (at most 4, `y > 0`).
pub(super) fn case2_solutions<const P: usize>(
    qs: &[SMatrix<f64, 2, 2>; P],
    b: &[f64; P],
    mut emit: impl FnMut(f64, f64),
) {
    let a = SMatrix::<f64, P, 3>::from_fn(|p, c| match c {
        0 => qs[p][(0, 0)],
        1 => 2.0 * qs[p][(0, 1)],
        _ => qs[p][(1, 1)],
    });
    let bv = SVector::<f64, P>::from_column_slice(b);
    let q = a.transpose() * a;
    let p = a.transpose() * bv;
    let q6 = sym3_upper(&q);
    let p3 = [p[0], p[1], p[2]];
    let quartic = kernels::case2_resultant(&q6, &p3);
    let c2 = |x: f64, y: f64| {
        let av = Vector3::new(x * x, x * y, y * y);
        (a * av - bv).norm_squared()
    };
    for beta in roots::real_roots_near(&quartic, IMAG_TOL).iter() {
        if !(*beta > 0.0) {
            continue;
        }
        let y = beta.sqrt();
        let cubics = kernels::case2_cubics(&q6, &p3, y);
        if let Some(x) = best_x(&cubics, |x| c2(x, y)) {
            emit(x, y);
        }
    }
}

/// `nullspace` (non-planar branch): cases 1-4 from the eigenvectors `v[0..4]` of the four smallest
/// eigenvalues of M (ascending). Appends the candidate rotations.
pub(super) fn nonplanar_candidates(v: &[SVector<f64, 9>; 4], out: &mut Candidates) {
    let mut push = |r: SVector<f64, 9>, source: CandidateSource| {
        let arr: [f64; 9] = r.into();
        if let Some(rot) = candidate_to_rotation(&arr) {
            if !out.is_full() {
                out.push(Candidate { r: rot, source });
            }
        }
    };
    // Case 1.
    push(v[0], CandidateSource::Case1);

    // The forms of all six pairs over (v1..v4), once: the forms over (v1, v2) and (v1, v2, v3)
    // of cases 2 and 3 are their leading blocks (the same expressions, the same values).
    let q4: [SMatrix<f64, 4, 4>; 6] =
        std::array::from_fn(|p| quad_form4(v, PAIRS[p].0, PAIRS[p].1));

    // Case 2.
    let qs: [SMatrix<f64, 2, 2>; 6] =
        std::array::from_fn(|p| q4[p].fixed_view::<2, 2>(0, 0).into_owned());
    case2_solutions(&qs, &[1.0, 1.0, 1.0, 0.0, 0.0, 0.0], |x, y| {
        push(v[0] * x + v[1] * y, CandidateSource::Case2)
    });

    // Case 3: five equations g1 = f1 - f2, g2 = f1 - f3, f4, f5, f6 over (v1, v2, v3).
    let q3: [Matrix3<f64>; 6] =
        std::array::from_fn(|p| q4[p].fixed_view::<3, 3>(0, 0).into_owned());
    let forms = [q3[0] - q3[1], q3[0] - q3[2], q3[3], q3[4], q3[5]];
    // row = [F11, F22, 2 F12, 2 F01, 2 F02, F00] for k = [k1^2, k2^2, k1 k2, k1, k2, 1]
    let bm = SMatrix::<f64, 5, 6>::from_fn(|e, c| {
        let f = &forms[e];
        match c {
            0 => f[(1, 1)],
            1 => f[(2, 2)],
            2 => 2.0 * f[(1, 2)],
            3 => 2.0 * f[(0, 1)],
            4 => 2.0 * f[(0, 2)],
            _ => f[(0, 0)],
        }
    });
    let h = bm.transpose() * bm;
    let mut h21 = [0.0; 21];
    let mut n = 0;
    for i in 0..6 {
        for j in i..6 {
            h21[n] = h[(i, j)];
            n += 1;
        }
    }
    let c15 = kernels::case3_quartic(&h21);
    let res = kernels::case3_resultant(&c15);
    let c3 = |x: f64, y: f64| {
        let mut acc = 0.0;
        for (c, e) in c15.iter().zip(kernels::CASE3_MONOMIALS.iter()) {
            acc += c * x.powi(e[0] as i32) * y.powi(e[1] as i32);
        }
        acc
    };
    for y in roots::real_roots_near(&res, IMAG_TOL).iter() {
        let cubics = kernels::case3_cubics(&c15, *y);
        if let Some(x) = best_x(&cubics, |x| c3(x, *y)) {
            push(v[0] + v[1] * x + v[2] * *y, CandidateSource::Case3);
        }
    }

    // Case 4.
    case4(v, &[q4[3], q4[4], q4[5]], |r| {
        push(r, CandidateSource::Case4)
    });
}

/// `nullspace` case 4 with the hidden variable chosen at run time: each of k1, k2, k3 is tried as
/// the hidden one and the choice whose constant matrix `Mm` is best conditioned is used
/// (docs/algorithm.md, `nullspace` case 4, "Robustness"); skipped if even that one is numerically
/// singular. `q4` are the forms of f4, f5, f6 over (v1..v4).
fn case4(
    v: &[SVector<f64, 9>; 4],
    q4: &[SMatrix<f64, 4, 4>; 3],
    mut emit: impl FnMut(SVector<f64, 9>),
) {
    const RCOND_MIN: f64 = 1e-10;
    // perm[h] = order of the basis (1, hidden, a, b) in terms of the original indices 0..3.
    let perms = [[0usize, 1, 2, 3], [0, 2, 1, 3], [0, 3, 1, 2]];
    let mm_of = |perm: &[usize; 4]| {
        Matrix3::from_fn(|e, c| {
            let f = &q4[e];
            let (a, b) = (perm[2], perm[3]);
            match c {
                0 => f[(a, a)],
                1 => f[(b, b)],
                _ => 2.0 * f[(a, b)],
            }
        })
    };
    let mut best: Option<(f64, usize)> = None;
    for (i, perm) in perms.iter().enumerate() {
        let rc = rcond3(&mm_of(perm));
        if best.is_none_or(|(b, _)| rc > b) {
            best = Some((rc, i));
        }
    }
    let Some((rc, pi)) = best else { return };
    if !(rc >= RCOND_MIN) {
        return;
    }
    let perm = perms[pi];
    let mm = mm_of(&perm);
    let Some(mm_inv) = mm.try_inverse() else {
        return;
    };
    // N(k1) per equation e: columns [deg 1, deg 1, deg 2] in the hidden variable (index perm[1]).
    let (o, hv, a, b) = (perm[0], perm[1], perm[2], perm[3]);
    let ncoef = |e: usize, j: usize, n: usize| -> f64 {
        let f = &q4[e];
        match (j, n) {
            (0, 0) => 2.0 * f[(o, a)],
            (0, 1) => 2.0 * f[(hv, a)],
            (1, 0) => 2.0 * f[(o, b)],
            (1, 1) => 2.0 * f[(hv, b)],
            (2, 0) => f[(o, o)],
            (2, 1) => 2.0 * f[(o, hv)],
            (2, 2) => f[(hv, hv)],
            _ => 0.0,
        }
    };
    // T = -Mm^-1 N, laid out as kernels::CASE4_T_LAYOUT.
    let mut t = [0.0; 21];
    for (slot, lay) in kernels::CASE4_T_LAYOUT.iter().enumerate() {
        let (i, j, n) = (lay[0] as usize, lay[1] as usize, lay[2] as usize);
        t[slot] = -(0..3).map(|l| mm_inv[(i, l)] * ncoef(l, j, n)).sum::<f64>();
    }
    let det = kernels::case4_determinant(&t);
    let mat = kernels::case4_matrix(&t);
    for k in roots::real_roots_near(&det, IMAG_TOL).iter() {
        let mk = Matrix3::from_fn(|i, j| {
            let c = &mat[(3 * i + j) * 5..(3 * i + j) * 5 + 5];
            c.iter().rev().fold(0.0, |acc, x| acc * k + x)
        });
        let Some(y) = null_vector3(&mk) else {
            continue;
        };
        if !(y[2].abs() >= 1e-12 * y.norm()) {
            continue;
        }
        let (ka, kb) = (y[0] / y[2], y[1] / y[2]);
        let mut coef = [0.0; 4];
        coef[o] = 1.0;
        coef[hv] = *k;
        coef[a] = ka;
        coef[b] = kb;
        emit(v[0] * coef[0] + v[1] * coef[1] + v[2] * coef[2] + v[3] * coef[3]);
    }
}

#[cfg(test)]
#[path = "../../tests/unit/pipeline/nullspace.rs"]
mod tests;
