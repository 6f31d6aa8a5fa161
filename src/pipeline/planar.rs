//! The `planar` stage of docs/algorithm.md: the planar branch. For a (nearly) planar cloud the
//! working-frame z coordinates vanish, so only the first two columns of `R` are observable: the
//! flattened system's 6 x 6 `M_p` (the entries of `M` of those columns) gives candidate column
//! pairs `r6 = [R11, R12, R21, R22, R31, R32]` from its two smallest eigenvectors (cases p1 and p2,
//! with the case-2 algebra of [`super::nullspace`]), and each is completed to a rotation and
//! flipped by `diag(-1, -1, 1)` when most flattened points would lie behind the camera.

use nalgebra::{Matrix3, Point3, SMatrix, SVector, Vector3};

use super::frame::WorkingFrame;
use super::moments::System;
use super::nullspace::{
    case2_solutions, col_block, quad_form, Candidate, CandidateSource, Candidates,
};
use crate::numeric::bounds::{converged, limit, Bound};

/// `planar`: the planar candidates of the flattened system `sys_p`, appended to `out`. When the
/// eigen-decomposition of `M_p` fails (its iteration bound), only the p1 start, from the
/// smallest eigenvector by inverse iteration ([`first_start`]): without it the search would
/// go on from the remaining starts alone and could return a wrong local minimum.
pub(crate) fn candidates(
    sys_p: &System,
    world: &[Point3<f64>],
    weights: Option<&[f64]>,
    fr: &WorkingFrame,
    scale: f64,
    out: &mut Candidates,
) {
    let Some((_, vecs)) = planar_eigen(sys_p) else {
        if let Some(r) = first_start(sys_p, world, weights, fr, scale) {
            if !out.is_full() {
                out.push(Candidate {
                    r,
                    source: CandidateSource::Planar1,
                });
            }
        }
        return;
    };
    planar_vectors(&vecs, |r6, source| {
        if let Some(r) = start(&r6, sys_p, world, weights, fr) {
            if !out.is_full() {
                out.push(Candidate { r, source });
            }
        }
    });
}

/// The case-p1 start of the certified fast path: the rotation of the smallest eigenvector of
/// `M_p` (computed by inverse iteration, as the non-planar case 1).
pub(crate) fn first_start(
    sys_p: &System,
    world: &[Point3<f64>],
    weights: Option<&[f64]>,
    fr: &WorkingFrame,
    scale: f64,
) -> Option<Matrix3<f64>> {
    let v1 = crate::numeric::linalg::smallest_eigenvector(&planar_m(sys_p), scale)?;
    start(&v1, sys_p, world, weights, fr)
}

/// Eigen-decomposition of the 6x6 planar `M_p` (`planar` steps 2-3): the two smallest eigenvalues
/// (ascending) and their unit eigenvectors.
fn planar_eigen(sys_p: &System) -> Option<([f64; 2], [SVector<f64, 6>; 2])> {
    let mp = planar_m(sys_p);
    let eig = nalgebra::SymmetricEigen::try_new(mp, f64::EPSILON, limit(Bound::MEigen));
    let eig = converged(eig, Bound::MEigen)?;
    let mut order: [usize; 6] = std::array::from_fn(|i| i);
    order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
    Some((
        [eig.eigenvalues[order[0]], eig.eigenvalues[order[1]]],
        std::array::from_fn(|i| eig.eigenvectors.column(order[i]).into_owned()),
    ))
}

/// The 6x6 planar `M_p`: `M` of the flattened system restricted to the entries of the first two
/// columns of `R` (docs/algorithm.md, `planar` step 2).
fn planar_m(sys_p: &System) -> SMatrix<f64, 6, 6> {
    const IDX: [usize; 6] = [0, 1, 3, 4, 6, 7];
    SMatrix::<f64, 6, 6>::from_fn(|i, j| sys_p.m[(IDX[i], IDX[j])])
}

/// `planar` step 5: the rotation of a planar candidate `r6`, flipped by `diag(-1, -1, 1)` when the
/// majority of the flattened points would lie behind the camera.
fn start(
    r6: &SVector<f64, 6>,
    sys_p: &System,
    world: &[Point3<f64>],
    weights: Option<&[f64]>,
    fr: &WorkingFrame,
) -> Option<Matrix3<f64>> {
    let mut r = planar_rotation(r6)?;
    let t = sys_p.translation(&r);
    // Depths of the flattened working-frame points: z = R31 x + R32 y + t_z.
    let mut sum = 0i64;
    for (i, x) in world.iter().enumerate() {
        if weights.is_some_and(|w| w[i] == 0.0) {
            continue;
        }
        let p = fr.to_working(x);
        let z = r[(2, 0)] * p.x + r[(2, 1)] * p.y + t.z;
        sum += i64::from(z > 0.0) - i64::from(z < 0.0);
    }
    if sum < 0 {
        r *= Matrix3::from_diagonal(&Vector3::new(-1.0, -1.0, 1.0));
    }
    Some(r)
}

/// `planar` cases p1 and p2: candidate first-two-columns vectors
/// `r6 = [R11, R12, R21, R22, R31, R32]` from the two smallest eigenvectors of the 6x6 planar
/// `M_p`. Calls `emit(r6, source)`.
fn planar_vectors(
    v: &[SVector<f64, 6>; 2],
    mut emit: impl FnMut(SVector<f64, 6>, CandidateSource),
) {
    emit(v[0], CandidateSource::Planar1);
    let pairs = [(0, 0), (1, 1), (0, 1)];
    let qs: [SMatrix<f64, 2, 2>; 3] =
        std::array::from_fn(|p| quad_form(v, pairs[p].0, pairs[p].1, col_block));
    case2_solutions(&qs, &[1.0, 1.0, 0.0], |x, y| {
        emit(v[0] * x + v[1] * y, CandidateSource::Planar2)
    });
}

/// The rotation of a planar candidate (docs/algorithm.md, `planar` step 5, without the depth test):
/// `[c1 c2] = U V^T` of the 3x2 matrix of the two columns, `R = [c1, c2, c1 x c2]`.
fn planar_rotation(r6: &SVector<f64, 6>) -> Option<Matrix3<f64>> {
    if !r6.iter().all(|x| x.is_finite()) || r6.norm() == 0.0 {
        return None;
    }
    let a = SMatrix::<f64, 3, 2>::new(r6[0], r6[1], r6[2], r6[3], r6[4], r6[5]);
    let svd = a.svd(true, true);
    let c = svd.u? * svd.v_t?;
    let (c1, c2) = (c.column(0).into_owned(), c.column(1).into_owned());
    let r = Matrix3::from_columns(&[c1, c2, c1.cross(&c2)]);
    r.iter().all(|x| x.is_finite()).then_some(r)
}
