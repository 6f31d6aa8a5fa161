//! Thin wrappers around internal pipeline stages, for the criterion benches (`benches/stages.rs`)
//! only. Not a stable API: the signatures follow the internals and may change at any time.
//!
//! Each hook does exactly one stage so that a bench measures that stage alone; the inputs of a
//! stage are produced once, outside the timed closure, by [`prepare`].

use super::frame::{self, WorkingFrame};
use super::moments::{self, System};
use super::newton::{self, NewtonOptions};
use super::nullspace::{self, Candidates};
use super::refine::{self, ReprojOptions};
use crate::numeric::bounds::M_EIGEN_MAX_ITER;
use nalgebra::{Matrix3, Point2, Point3, SMatrix, SVector, Vector3};

/// The intermediates of one problem that the later stages take as input.
#[derive(Clone, Debug)]
pub struct Prepared {
    fr: WorkingFrame,
    sys: System,
    m45: [f64; 45],
    v4: [SVector<f64, 9>; 4],
    start: Matrix3<f64>,
    refined: Matrix3<f64>,
    t: Vector3<f64>,
}

/// `frame` + `moments`: working frame and accumulation of `M` (9x9) and `G`. `None` on invalid
/// input.
#[must_use]
pub fn accumulate(world: &[Point3<f64>], image: &[Point2<f64>]) -> Option<SMatrix<f64, 9, 9>> {
    let fr = frame::working_frame(world, image, None, true).ok()?;
    let acc = fr.sums;
    acc.system(false).map(|s| s.m)
}

/// The 9x9 symmetric eigen-decomposition of `nullspace` (eigenvalues, eigenvectors), as the solver
/// calls it.
#[must_use]
pub fn eigen9(m: &SMatrix<f64, 9, 9>) -> Option<(SVector<f64, 9>, SMatrix<f64, 9, 9>)> {
    nalgebra::SymmetricEigen::try_new(*m, f64::EPSILON, M_EIGEN_MAX_ITER)
        .map(|e| (e.eigenvalues, e.eigenvectors))
}

/// The fast path's eigenvector of the smallest eigenvalue of `M` (inverse iteration,
/// `crate::numeric::linalg::smallest_eigenvector`), as the solver calls it with `scale = trace(M)`.
#[must_use]
pub fn smallest_eigenvector9(m: &SMatrix<f64, 9, 9>, scale: f64) -> Option<SVector<f64, 9>> {
    crate::numeric::linalg::smallest_eigenvector(m, scale)
}

/// The degeneracy test's count of eigenvalues of `M` below `tau` (Sturm count,
/// `crate::numeric::linalg::count_eigenvalues_below`).
#[must_use]
pub fn count_eigenvalues_below9(m: &SMatrix<f64, 9, 9>, tau: f64) -> usize {
    crate::numeric::linalg::count_eigenvalues_below(m, tau)
}

/// Every intermediate of one problem (`frame` to `newton`, non-planar branch): computed once,
/// outside the timed code. `None` on invalid input.
#[must_use]
pub fn prepare(world: &[Point3<f64>], image: &[Point2<f64>]) -> Option<Prepared> {
    let fr = frame::working_frame(world, image, None, true).ok()?;
    let sys = fr.sums.system(false)?;
    let (vals, vecs) = eigen9(&sys.m)?;
    let mut order: [usize; 9] = std::array::from_fn(|i| i);
    order.sort_by(|&a, &b| vals[a].total_cmp(&vals[b]));
    let v4: [SVector<f64, 9>; 4] = std::array::from_fn(|i| vecs.column(order[i]).into_owned());
    let v1: [f64; 9] = v4[0].into();
    let start = crate::numeric::rotation::candidate_to_rotation(&v1)?;
    let m45 = moments::m_upper(&sys.m);
    let refined = newton::refine_so3(&m45, sys.trace, &start, &NewtonOptions::default()).r;
    let rv = SVector::<f64, 9>::from_row_slice(refined.transpose().as_slice());
    let t = sys.g * rv;
    Some(Prepared {
        fr,
        sys,
        m45,
        v4,
        start,
        refined,
        t,
    })
}

impl Prepared {
    /// `M` of the problem.
    #[must_use]
    pub fn m(&self) -> &SMatrix<f64, 9, 9> {
        &self.sys.m
    }

    /// `trace(M)`, the solver's scale.
    #[must_use]
    pub fn scale(&self) -> f64 {
        self.sys.trace
    }
}

/// `nullspace`, all non-planar null-space cases (1-4) from the four smallest eigenvectors; returns
/// the number of candidates.
#[must_use]
pub fn nonplanar_candidates(p: &Prepared) -> usize {
    let mut cands = Candidates::new();
    nullspace::nonplanar_candidates(&p.v4, &mut cands);
    cands.len()
}

/// `newton`: damped Newton on SO(3) from the case-1 start (default options); returns f.
#[must_use]
pub fn newton(p: &Prepared) -> f64 {
    newton::refine_so3(&p.m45, p.sys.trace, &p.start, &NewtonOptions::default()).f
}

/// `refine`: Levenberg-Marquardt on the reprojection error from the refined case-1 minimum (default
/// options); returns the final cost.
#[must_use]
pub fn refine(world: &[Point3<f64>], image: &[Point2<f64>], p: &Prepared) -> f64 {
    refine::refine_reprojection(
        world,
        image,
        None,
        &p.fr,
        &p.refined,
        &p.t,
        &ReprojOptions::default(),
    )
    .e
}
