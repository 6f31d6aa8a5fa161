//! The hard iteration bounds of every iterative routine: each bound's limit is owned here, and
//! nothing here imports the routines that use it.
//!
//! Every loop whose trip count depends on convergence runs under a [`Budget`] (or passes
//! [`limit`] to nalgebra's iterative eigen-decomposition). In normal builds a budget is a
//! plain counter against the bound's constant. In test builds the limit of any [`Bound`] can
//! be lowered for the current thread ([`hook::with_limit`]) and every exhausted budget is
//! counted, so that each routine's behaviour *at* its bound (a defined result, never a panic,
//! a hang or a silent wrong pose) has a test (`tests/unit/numeric/bounds.rs`).
//!
//! The user-configurable bounds (`newton_iterations` of the `newton` stage,
//! `reprojection_iterations` of `refine`, RANSAC `max_iterations`) are reached by setting the
//! option; their tests are there too.

/// Jacobi sweeps of the 3 x 3 symmetric eigen-decomposition (about 4-6 are used).
pub(crate) const SYM_EIGEN3_MAX_SWEEPS: usize = 40;
/// One-sided Jacobi sweeps of the 3 x 3 SVD (about 4-6 are used).
pub(crate) const SVD3_MAX_SWEEPS: usize = 40;
/// Jacobi sweeps of the smallest eigenvalue of a symmetric 3 x 3 matrix (about 4 are used).
pub(crate) const MIN_EIGEN3_MAX_SWEEPS: usize = 32;
/// Damping increases (trial steps) per Newton iteration (the `newton` stage).
pub(crate) const NEWTON_MAX_DAMPING_STEPS: u32 = 64;
/// QL iterations of nalgebra's symmetric eigen-decomposition of M (9 x 9) and M_p (6 x 6).
pub(crate) const M_EIGEN_MAX_ITER: usize = 1000;
/// QL iterations of nalgebra's 3 x 3 eigen-decomposition in Lambda Twist P3P.
pub(crate) const P3P_EIGEN_MAX_ITER: usize = 100;
/// Newton steps to the one root of the P3P cubic of the small-N starts (monotone from a bound
/// on the root; about 5-10 are used).
pub(crate) const P3P_CUBIC_MAX_ITER: usize = 100;
/// Safeguarded Newton/bisection iterations per root bracket.
pub(crate) const ROOT_MAX_BRACKET_ITERS: usize = 160;
/// Newton polishing steps per root.
pub(crate) const ROOT_POLISH_STEPS: usize = 4;
/// Newton steps of the lens undistortion.
pub(crate) const UNDISTORT_MAX_ITERATIONS: u32 = 100;

/// An iterative routine with a hard bound.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Bound {
    /// Jacobi sweeps of the 3x3 symmetric eigen-decomposition of the `frame` scatter
    /// (`mat3::sym_eigen3`).
    FrameEigenSweeps,
    /// One-sided Jacobi sweeps of the 3x3 SVD (`mat3::svd3`).
    Svd3Sweeps,
    /// Jacobi sweeps of the smallest eigenvalue of the 3x3 Newton Hessian
    /// (`mat3::min_eigenvalue_sym3`).
    HessianEigenSweeps,
    /// Damping increases per Newton iteration (the `newton` stage).
    NewtonDamping,
    /// QL iterations of nalgebra's symmetric eigen-decomposition of M (9x9) and M_p (6x6) in
    /// `nullspace`.
    MEigen,
    /// QL iterations of nalgebra's 3x3 eigen-decomposition in Lambda Twist P3P.
    P3pEigen,
    /// Newton steps to one root of the P3P cubic (`p3p::one_cubic_root`).
    P3pCubic,
    /// Safeguarded Newton/bisection iterations per root bracket (`roots`).
    RootBracket,
    /// Newton polishing steps per root (`roots`).
    RootPolish,
    /// Newton steps of the lens undistortion (`camera`).
    Undistort,
}

impl Bound {
    /// The bound in normal builds.
    pub(crate) const fn default_limit(self) -> usize {
        match self {
            Bound::FrameEigenSweeps => SYM_EIGEN3_MAX_SWEEPS,
            Bound::Svd3Sweeps => SVD3_MAX_SWEEPS,
            Bound::HessianEigenSweeps => MIN_EIGEN3_MAX_SWEEPS,
            Bound::NewtonDamping => NEWTON_MAX_DAMPING_STEPS as usize,
            Bound::MEigen => M_EIGEN_MAX_ITER,
            Bound::P3pEigen => P3P_EIGEN_MAX_ITER,
            Bound::P3pCubic => P3P_CUBIC_MAX_ITER,
            Bound::RootBracket => ROOT_MAX_BRACKET_ITERS,
            Bound::RootPolish => ROOT_POLISH_STEPS,
            Bound::Undistort => UNDISTORT_MAX_ITERATIONS as usize,
        }
    }
}

/// The limit of `b` (its constant; in tests, possibly lowered by [`hook::with_limit`]).
#[inline(always)]
pub(crate) fn limit(b: Bound) -> usize {
    #[cfg(test)]
    if let Some(l) = hook::override_of(b) {
        return l;
    }
    b.default_limit()
}

/// Records that an iterative routine stopped at its bound without converging (test builds).
#[inline(always)]
pub(crate) fn exhausted(_b: Bound) {
    #[cfg(test)]
    hook::record(_b);
}

/// `r`, recording the bound as reached when `r` is `None` (an iterative routine that signals
/// non-convergence within its bound by `None`, e.g. nalgebra's `SymmetricEigen::try_new`).
#[inline(always)]
pub(crate) fn converged<T>(r: Option<T>, b: Bound) -> Option<T> {
    if r.is_none() {
        exhausted(b);
    }
    r
}

/// A loop budget: `while budget.next() { ...; if converged { break } }` runs at most
/// `limit(bound)` times; when the budget runs out `next` returns `false` (and, in tests,
/// records the bound as reached).
pub(crate) struct Budget {
    left: usize,
    bound: Bound,
}

impl Budget {
    /// A fresh budget of `limit(bound)` iterations.
    #[inline(always)]
    pub(crate) fn new(bound: Bound) -> Self {
        Budget {
            left: limit(bound),
            bound,
        }
    }

    /// `true` while iterations are left (and uses one).
    #[inline(always)]
    #[allow(clippy::should_implement_trait)]
    pub(crate) fn next(&mut self) -> bool {
        if self.left > 0 {
            self.left -= 1;
            true
        } else {
            exhausted(self.bound);
            false
        }
    }
}

/// The test builds' hook: per-thread lowered limits and a count of exhausted budgets.
#[cfg(test)]
pub(crate) mod hook {
    use super::*;
    use std::cell::RefCell;

    thread_local! {
        static OVERRIDES: RefCell<Vec<(Bound, usize)>> = const { RefCell::new(Vec::new()) };
        static HITS: RefCell<Vec<Bound>> = const { RefCell::new(Vec::new()) };
    }

    pub(crate) fn override_of(b: Bound) -> Option<usize> {
        OVERRIDES.with(|o| {
            o.borrow()
                .iter()
                .rev()
                .find(|(x, _)| *x == b)
                .map(|&(_, l)| l)
        })
    }

    pub(crate) fn record(b: Bound) {
        HITS.with(|h| h.borrow_mut().push(b));
    }

    /// Runs `f` with the limit of `b` lowered to `l` on this thread; returns `f`'s result and
    /// how many times a budget of `b` ran out during the call.
    pub(crate) fn with_limit<T>(b: Bound, l: usize, f: impl FnOnce() -> T) -> (T, usize) {
        OVERRIDES.with(|o| o.borrow_mut().push((b, l)));
        let before = hits(b);
        let out = f();
        let after = hits(b);
        OVERRIDES.with(|o| o.borrow_mut().pop());
        (out, after - before)
    }

    /// Times a budget of `b` ran out on this thread so far.
    pub(crate) fn hits(b: Bound) -> usize {
        HITS.with(|h| h.borrow().iter().filter(|&&x| x == b).count())
    }
}

#[cfg(test)]
#[path = "../../tests/unit/numeric/bounds.rs"]
mod tests;
