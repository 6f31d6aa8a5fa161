//! Blocks of points for the passes vectorised across points (S2 in `accumulate`, S9 in
//! `reproj`): active points are gathered, in order, into blocks of [`LANES`], every quantity
//! is kept per lane, and the lanes are added pairwise at the end ([`lane_sum`]). With the
//! baseline x86-64 target the compiler then uses packed SSE2 operations.

use nalgebra::{Point2, Point3};

/// Points per block: two SSE2 registers per quantity on the baseline x86-64 target.
pub(crate) const LANES: usize = 4;

/// Sum of the lanes, pairwise: `(0 + 1) + (2 + 3)`.
#[inline(always)]
pub(crate) fn lane_sum(v: &[f64; LANES]) -> f64 {
    const _: () = assert!(LANES == 4);
    (v[0] + v[1]) + (v[2] + v[3])
}

/// Up to [`LANES`] active points, transposed: world coordinates, image coordinates and the
/// weight. Aligned (every field is a multiple of 16 bytes) so that SSE2 can use its operands
/// in place.
#[repr(C, align(16))]
pub(crate) struct Block {
    pub x: [[f64; LANES]; 3],
    pub m: [[f64; LANES]; 2],
    pub w: [f64; LANES],
}

impl Block {
    /// An empty block; weights 1 (the unweighted passes never set them).
    #[inline(always)]
    pub(crate) fn new() -> Self {
        Block {
            x: [[0.0; LANES]; 3],
            m: [[0.0; LANES]; 2],
            w: [1.0; LANES],
        }
    }

    /// Puts the point `(x, m)` in lane `l` (the weight is set separately, when there is one).
    #[inline(always)]
    pub(crate) fn set(&mut self, l: usize, x: &Point3<f64>, m: &Point2<f64>) {
        self.x[0][l] = x.x;
        self.x[1][l] = x.y;
        self.x[2][l] = x.z;
        self.m[0][l] = m.x;
        self.m[1][l] = m.y;
    }

    /// The point in lane `l`: world coordinates, image coordinates, weight.
    #[inline(always)]
    pub(crate) fn point(&self, l: usize) -> ([f64; 3], [f64; 2], f64) {
        (
            [self.x[0][l], self.x[1][l], self.x[2][l]],
            [self.m[0][l], self.m[1][l]],
            self.w[l],
        )
    }
}
