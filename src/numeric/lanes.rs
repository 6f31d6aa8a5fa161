//! Blocks of points for the passes vectorised across points (`moments` in `accumulate`, `refine` in
//! `reproj`): active points are gathered, in order, into blocks of [`LANES`], every quantity
//! is kept per lane, and the lanes are added pairwise at the end ([`lane_sum`]). The compiler
//! then runs the per-point code on packed registers: two 128-bit SSE2 registers per quantity
//! in the baseline x86-64 build, one 256-bit register in the AVX2 build that [`dispatched`]
//! adds and picks at run time.

use core::ops::ControlFlow;

use nalgebra::{Point2, Point3};

/// Points per block: one AVX2 register (two SSE2 registers) per quantity.
pub(crate) const LANES: usize = 4;

/// Sum of the lanes, pairwise: `(0 + 1) + (2 + 3)`.
#[inline(always)]
pub(crate) fn lane_sum(v: &[f64; LANES]) -> f64 {
    const _: () = assert!(LANES == 4);
    (v[0] + v[1]) + (v[2] + v[3])
}

/// Up to [`LANES`] active points, transposed: world coordinates, image coordinates and the
/// weight. Aligned (every field is a multiple of 32 bytes) so that SSE2 and AVX2 can use its
/// operands in place.
#[repr(C, align(32))]
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

/// The weighted form of a pass's loop: the points with non-zero weight, in order, gathered
/// into blocks of [`LANES`] with their weights times `scale`; `full(&block)` for each full
/// block, in order, until it breaks. Then the last, partial block and the number of its
/// filled lanes (0 to `LANES - 1`), which the pass adds itself. The weights must be validated
/// (finite, non-negative). The sequence of active points, and so a pass's result to the bit,
/// does not depend on the points of weight 0.
#[inline(always)]
pub(crate) fn weighted_blocks<B>(
    world: &[Point3<f64>],
    image: &[Point2<f64>],
    weights: &[f64],
    scale: f64,
    mut full: impl FnMut(&Block) -> ControlFlow<B>,
) -> ControlFlow<B, (Block, usize)> {
    let mut blk = Block::new();
    let mut filled = 0;
    let n = world.len().min(image.len()).min(weights.len());
    let (world, image, weights) = (&world[..n], &image[..n], &weights[..n]);
    let mut cw = world.chunks_exact(LANES);
    let mut cm = image.chunks_exact(LANES);
    let mut cws = weights.chunks_exact(LANES);
    for ((xs, ms), ws) in (&mut cw).zip(&mut cm).zip(&mut cws) {
        if filled == 0 && ws.iter().all(|&w| w != 0.0) {
            // A whole block of active points at a block boundary (the common case): the
            // same lanes as point by point, without a test per point.
            for l in 0..LANES {
                blk.set(l, &xs[l], &ms[l]);
                blk.w[l] = ws[l] * scale;
            }
            full(&blk)?;
            continue;
        }
        for l in 0..LANES {
            add_active(
                &mut blk,
                &mut filled,
                &xs[l],
                &ms[l],
                ws[l],
                scale,
                &mut full,
            )?;
        }
    }
    for ((x, m), &w) in cw
        .remainder()
        .iter()
        .zip(cm.remainder())
        .zip(cws.remainder())
    {
        add_active(&mut blk, &mut filled, x, m, w, scale, &mut full)?;
    }
    ControlFlow::Continue((blk, filled))
}

/// One point of [`weighted_blocks`]' point-by-point loop: skipped if its weight is 0, else put
/// in the next lane, and the block handed to `full` when that fills it.
#[inline(always)]
fn add_active<B>(
    blk: &mut Block,
    filled: &mut usize,
    x: &Point3<f64>,
    m: &Point2<f64>,
    w: f64,
    scale: f64,
    full: &mut impl FnMut(&Block) -> ControlFlow<B>,
) -> ControlFlow<B> {
    if w == 0.0 {
        return ControlFlow::Continue(());
    }
    let l = *filled;
    blk.set(l, x, m);
    blk.w[l] = w * scale;
    *filled = l + 1;
    if *filled == LANES {
        *filled = 0;
        full(blk)?;
    }
    ControlFlow::Continue(())
}

/// A pass's loop over the points with or without weights: [`weighted_blocks`] or
/// [`unweighted_blocks`], for a pass whose per-point code reads the weight from the block.
#[inline(always)]
pub(crate) fn blocks<B>(
    world: &[Point3<f64>],
    image: &[Point2<f64>],
    weights: Option<&[f64]>,
    scale: f64,
    full: impl FnMut(&Block) -> ControlFlow<B>,
) -> ControlFlow<B, (Block, usize)> {
    // `full` moved into one arm, not borrowed: a `&mut F` call shim is not always inlined
    // into the AVX2 build.
    match weights {
        None => unweighted_blocks(world, image, full),
        Some(w) => weighted_blocks(world, image, w, scale, full),
    }
}

/// The unweighted form of a pass's loop ([`weighted_blocks`] without weights): every point,
/// in order, gathered into blocks of [`LANES`] (weights 1); `full(&block)` for each full block,
/// in order, until it breaks. Then the last, partial block and the number of its filled lanes
/// (0 to `LANES - 1`), which the pass adds itself.
#[inline(always)]
pub(crate) fn unweighted_blocks<B>(
    world: &[Point3<f64>],
    image: &[Point2<f64>],
    mut full: impl FnMut(&Block) -> ControlFlow<B>,
) -> ControlFlow<B, (Block, usize)> {
    let mut blk = Block::new();
    let mut cw = world.chunks_exact(LANES);
    let mut cm = image.chunks_exact(LANES);
    for (xs, ms) in (&mut cw).zip(&mut cm) {
        blk.x = [
            core::array::from_fn(|l| xs[l].x),
            core::array::from_fn(|l| xs[l].y),
            core::array::from_fn(|l| xs[l].z),
        ];
        blk.m = [
            core::array::from_fn(|l| ms[l].x),
            core::array::from_fn(|l| ms[l].y),
        ];
        full(&blk)?;
    }
    let mut filled = 0;
    for (l, (x, m)) in cw.remainder().iter().zip(cm.remainder()).enumerate() {
        blk.set(l, x, m);
        filled = l + 1;
    }
    ControlFlow::Continue((blk, filled))
}

/// Whether the vectorised passes run their AVX2 + FMA build: the processor has both
/// (`is_x86_feature_detected!`, a cached atomic load after the first call). Always `false`
/// off x86-64, and in the library's unit tests inside [`with_baseline`].
// Off x86-64 only the unit test asks (`dispatched!` compiles the baseline build alone there).
#[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
#[inline(always)]
pub(crate) fn wide() -> bool {
    #[cfg(test)]
    if FORCE_BASELINE.with(core::cell::Cell::get) {
        return false;
    }
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

#[cfg(test)]
std::thread_local! {
    static FORCE_BASELINE: core::cell::Cell<bool> = const { core::cell::Cell::new(false) };
}

/// Runs `f` with the vectorised passes on their baseline build (unit tests: both builds must
/// give the same bits).
#[cfg(test)]
pub(crate) fn with_baseline<R>(f: impl FnOnce() -> R) -> R {
    FORCE_BASELINE.with(|c| c.set(true));
    let r = f();
    FORCE_BASELINE.with(|c| c.set(false));
    r
}

/// Defines a vectorised pass twice from one `#[inline(always)]` body: the baseline build (SSE2
/// on x86-64), and on x86-64 a build with `#[target_feature(enable = "avx2,fma")]`, where
/// each quantity of a block of [`LANES`] points fills one 256-bit register instead of two
/// 128-bit ones. The defined function picks one at run time ([`wide`]).
///
/// Both builds compute the same operations in the same order: Rust never contracts `a * b + c`
/// into a fused multiply-add (that needs an explicit `mul_add`, which the passes do not use),
/// so they return the same bits (tested).
///
/// Generics go in brackets, their parameters and then the arguments that pass them on:
/// `pub(crate) fn name[const K: bool, M: Trait][K, M](a: &A, m: &M) -> R = body_fn;`.
macro_rules! dispatched {
    (
        $(#[$meta:meta])*
        $vis:vis fn $name:ident [$($gp:tt)*] [$($ga:tt)*] ($($arg:ident: $ty:ty),* $(,)?) -> $ret:ty
        = $body:ident;
    ) => {
        $(#[$meta])*
        $vis fn $name<$($gp)*>($($arg: $ty),*) -> $ret {
            #[cfg(target_arch = "x86_64")]
            if $crate::numeric::lanes::wide() {
                #[target_feature(enable = "avx2,fma")]
                fn avx2<$($gp)*>($($arg: $ty),*) -> $ret {
                    $body::<$($ga)*>($($arg),*)
                }
                // SAFETY: `wide()` has just checked that this processor supports AVX2 and FMA,
                // the only requirement of a `#[target_feature]` function.
                return unsafe { avx2::<$($ga)*>($($arg),*) };
            }
            $body::<$($ga)*>($($arg),*)
        }
    };
}
pub(crate) use dispatched;

#[cfg(test)]
#[path = "../../tests/unit/numeric/lanes.rs"]
mod tests;
