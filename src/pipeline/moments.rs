//! The `moments` stage of docs/algorithm.md: O(N) accumulation of the sums that give `M` (9 x 9)
//! and `G` (3 x 9); `W`, `V` and `K` are never formed.
//!
//! | symbol | meaning (sums over points with weight `w > 0`; `w = 1` without weights) |
//! |---|---|
//! | `P = (x, y, z)` | working-frame point `Rw (X - c) / d` |
//! | `u, v, q` | image point, `q = u^2 + v^2` |
//! | `sw` | `sum w` (N without weights) |
//! | `su, sv, sq` | `sum w u`, `sum w v`, `sum w q` |
//! | `a, a_u, a_v, a_q` | `sum w P`, `sum w u P`, `sum w v P`, `sum w q P` |
//! | `S, S_u, S_v, S_q` | `sum w P P^T`, `sum w u P P^T`, `sum w v P P^T`, `sum w q P P^T` |
//!
//! Then (weighted rows `sqrt(w) W_i`, `sqrt(w) V_i`):
//! `W^T W = [[sw, 0, -su], [0, sw, -sv], [-su, -sv, sq]]`,
//! `W^T V = [[-a^T, 0, a_u^T], [0, -a^T, a_v^T], [a_u^T, a_v^T, -a_q^T]]`,
//! `V^T V = [[S, 0, -S_u], [0, S, -S_v], [-S_u, -S_v, S_q]]`,
//! `G = (W^T W)^-1 W^T V`, `M = V^T V - (W^T V)^T G`, symmetrised.
//!
//! Cost per point: 12 multiply-adds and 1 division for the transform to the working frame,
//! then 48 multiply-adds for the sums (q: 2, w u / w v / w q: 3, su/sv/sq: 3, w P: 3, a: 3,
//! a_u/a_v/a_q: 9, w P P^T: 6, S/S_u/S_v/S_q: 6 + 18): 60 in all, no allocation.

use nalgebra::{Matrix3, Point2, Point3, SMatrix, Vector2, Vector3};

use core::convert::Infallible;
use core::ops::ControlFlow;

use crate::numeric::lanes::{dispatched, lane_sum, weighted_blocks, Block, LANES};

/// The weighted sums of `moments` (symmetric matrices stored in full).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Accumulator {
    /// `sum w` (the N of the unweighted formulas).
    pub sw: f64,
    /// `sum w u`.
    pub su: f64,
    /// `sum w v`.
    pub sv: f64,
    /// `sum w (u^2 + v^2)`.
    pub sq: f64,
    /// `sum w P` (0 in exact arithmetic: the points are centred; kept).
    pub a: Vector3<f64>,
    /// `sum w u P`.
    pub a_u: Vector3<f64>,
    /// `sum w v P`.
    pub a_v: Vector3<f64>,
    /// `sum w q P`.
    pub a_q: Vector3<f64>,
    /// `sum w P P^T`.
    pub s: Matrix3<f64>,
    /// `sum w u P P^T`.
    pub s_u: Matrix3<f64>,
    /// `sum w v P P^T`.
    pub s_v: Matrix3<f64>,
    /// `sum w q P P^T`.
    pub s_q: Matrix3<f64>,
    /// `sum w |m - mean|^2` about the weighted image mean: `sq - (su^2 + sv^2) / sw` in exact
    /// arithmetic, the last pivot of `W^T W`, but accumulated about the mean (`frame`'s image
    /// spread) so that it keeps its relative accuracy when the image points nearly coincide,
    /// where the difference of the sums is left with their rounding alone.
    pub image_scatter: f64,
}

/// `M` (9 x 9, symmetric PSD) and `G` (3 x 9) of `moments`, with `f(R) = r^T M r` and `t = G r`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct System {
    /// `M = V^T V - (W^T V)^T G`, symmetrised.
    pub m: SMatrix<f64, 9, 9>,
    /// `G = (W^T W)^-1 W^T V`.
    pub g: SMatrix<f64, 3, 9>,
    /// `trace(M)`, the natural scale of the cost.
    pub trace: f64,
}

/// Index pairs of the 6 unique entries of a symmetric 3 x 3 matrix.
const SYM6: [(usize, usize); 6] = [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)];

/// Parameters of [`accumulate_centred`]: the point map `Y = X * inv_unit - centre` (exact
/// power-of-two units, then centred), the optional linear map applied to `Y`, the weight unit
/// and the image map used for the image spread.
#[derive(Clone, Copy, Debug)]
pub(crate) struct CentredMap {
    /// `1 / sx`, an exact power of two (world unit).
    pub inv_unit: f64,
    /// Weighted centroid in world units of `sx`.
    pub centre: Vector3<f64>,
    /// `1 / sw`, an exact power of two (weight unit).
    pub inv_weight: f64,
    /// `1 / sm`, an exact power of two (image unit; spread only).
    pub inv_image: f64,
    /// Weighted image mean in image units of `sm` (spread only).
    pub image_mean: Vector2<f64>,
}

/// Output of [`accumulate_centred`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct CentredSums {
    /// The `moments` sums of the mapped points `p = A Y` (or `Y`), with weights `w / sw`.
    pub acc: Accumulator,
    /// `sum (w / sw) |m / sm - image_mean|^2` (the `frame` image spread, before dividing by the
    /// weight sum).
    pub spread: f64,
}

/// The `moments` sums of [`accumulate_centred`] as a flat array: row `k` holds the monomial `k` of
/// `p` = `1, x, y, z, xx, xy, xz, yy, yz, zz` times `[w, w u, w v, w q]`.
type Sums = [[f64; 4]; 10];

/// What the centred pass needs of [`CentredMap`] and `A`, as plain scalars.
struct PassInputs {
    /// `1 / sx`.
    isx: f64,
    /// The centre (world units of `sx`).
    c: [f64; 3],
    /// `A`, row-major (unused without `A`).
    a: [[f64; 3]; 3],
    /// `1 / sm`.
    ism: f64,
    /// The image mean (image units of `sm`).
    mm: [f64; 2],
}

/// LaneSums sums of the centred pass. Lane `l` of `s` and `spread` sums the points
/// `l, l + LANES, ...` of the sequence of active points. Aligned (every field is a multiple of
/// 32 bytes) so that SSE2 and AVX2 can use the sums as operands in place.
#[repr(C, align(32))]
struct LaneSums {
    /// `s[k][j][l]`: lane `l` of the sum `k, j` of [`Sums`].
    s: [[[f64; LANES]; 4]; 10],
    /// The image spread.
    spread: [f64; LANES],
}

impl LaneSums {
    /// The sums (each lane-wise sum added pairwise), times `scale`, and the spread.
    fn finish(&self, scale: f64) -> (Sums, f64) {
        let s = core::array::from_fn(|k| core::array::from_fn(|j| lane_sum(&self.s[k][j]) * scale));
        (s, lane_sum(&self.spread) * scale)
    }
}

/// Adds the point `x`, `m` with weight `w` (scaled, or 1 without weights) as point `l` of
/// the current block to `acc` (see [`centred_pass`]; `R`: apply `A`). The terms are those of
/// the scalar formulas: `f[j] * mono[k]` with `f = [w, w u, w v, w q]`.
#[inline(always)]
fn lane<const R: bool>(
    k: &PassInputs,
    x: [f64; 3],
    m: [f64; 2],
    w: f64,
    l: usize,
    acc: &mut LaneSums,
) {
    let y = [
        x[0] * k.isx - k.c[0],
        x[1] * k.isx - k.c[1],
        x[2] * k.isx - k.c[2],
    ];
    let p = if R {
        let a = &k.a;
        [
            a[0][0] * y[0] + a[0][1] * y[1] + a[0][2] * y[2],
            a[1][0] * y[0] + a[1][1] * y[1] + a[1][2] * y[2],
            a[2][0] * y[0] + a[2][1] * y[1] + a[2][2] * y[2],
        ]
    } else {
        y
    };
    let (u, v) = (m[0], m[1]);
    let du = u * k.ism - k.mm[0];
    let dv = v * k.ism - k.mm[1];
    acc.spread[l] += w * (du * du + dv * dv);
    let q = u * u + v * v;
    let f = [w, w * u, w * v, w * q];
    let mono = [
        1.0,
        p[0],
        p[1],
        p[2],
        p[0] * p[0],
        p[0] * p[1],
        p[0] * p[2],
        p[1] * p[1],
        p[1] * p[2],
        p[2] * p[2],
    ];
    for (r, &mr) in mono.iter().enumerate() {
        for (j, &fj) in f.iter().enumerate() {
            // Row 0: `f[j] * 1 = f[j]` exactly.
            let term = fj * mr;
            acc.s[r][j][l] += term;
        }
    }
}

/// The centred pass over all points (`W`: weights present; `R`: apply `a` to `Y`).
///
/// Vectorised across points, in safe code built twice (baseline and AVX2,
/// [`crate::numeric::lanes::dispatched`], the same bits): the points with weight
/// `w > 0`, in order, are gathered into blocks of [`LANES`] (without weights, every point,
/// straight from the slices), and point `l` of a block goes into lane `l` of its own partial
/// sums ([`LaneSums`]), so that the compiler runs the per-point code ([`lane`]) on packed
/// registers; the lanes are added pairwise at the end. The sequence of active points, and so
/// the result to the bit, does not depend on the points of weight 0.
///
/// Every sum, `sum w` and the scatter `sum w P P^T` included, is summed in lanes: the result
/// depends on the lane count, a constant of the crate, and on nothing else (both builds give
/// the same bits), and its rounding error has the bound of a sequential sum. (The scatter and
/// `sum w` were once added in point order, to match a sequential loop to the bit: their
/// terms went through memory point by point and every block waited on seven chains of four
/// dependent additions: the algebraic solve at N = 1,000 took 12.7 us that way, 9.2 us in
/// lanes, interleaved runs.)
///
/// Without weights every scaled weight is `isw = 1 / sw`: the terms are formed with weight 1
/// (the multiplications by `w` dropped: `1 * t = t`) and the sums multiplied by `isw` at the
/// end. `isw` is a power of two, so `sum isw t = isw sum t` exactly unless a scaled term or
/// sum falls below the normal range; `frame` passes `isw = 1` without weights, where it is the
/// identity.
#[inline(always)]
fn centred_pass<const W: bool, const R: bool>(
    world: &[Point3<f64>],
    image: &[Point2<f64>],
    weights: &[f64],
    map: &CentredMap,
    a: &Matrix3<f64>,
) -> (Sums, f64) {
    let k = PassInputs {
        isx: map.inv_unit,
        c: [map.centre.x, map.centre.y, map.centre.z],
        a: [
            [a[(0, 0)], a[(0, 1)], a[(0, 2)]],
            [a[(1, 0)], a[(1, 1)], a[(1, 2)]],
            [a[(2, 0)], a[(2, 1)], a[(2, 2)]],
        ],
        ism: map.inv_image,
        mm: [map.image_mean.x, map.image_mean.y],
    };
    let isw = map.inv_weight;
    let mut acc = LaneSums {
        s: [[[0.0; LANES]; 4]; 10],
        spread: [0.0; LANES],
    };
    let mut blk = Block::new();
    let n = world.len().min(image.len());
    let (world, image) = (&world[..n], &image[..n]);
    let mut filled = 0;
    if W {
        let ControlFlow::Continue((last, n)) = weighted_blocks::<Infallible>(
            world,
            image,
            weights,
            isw,
            #[inline(always)]
            |full| {
                for l in 0..LANES {
                    let (x, m, w) = full.point(l);
                    lane::<R>(&k, x, m, w, l, &mut acc);
                }
                ControlFlow::Continue(())
            },
        );
        (blk, filled) = (last, n);
    } else {
        let mut cw = world.chunks_exact(LANES);
        let mut cm = image.chunks_exact(LANES);
        for (xs, ms) in (&mut cw).zip(&mut cm) {
            for l in 0..LANES {
                let (x, m) = (&xs[l], &ms[l]);
                lane::<R>(&k, [x.x, x.y, x.z], [m.x, m.y], 1.0, l, &mut acc);
            }
        }
        for (l, (x, m)) in cw.remainder().iter().zip(cm.remainder()).enumerate() {
            blk.set(l, x, m);
            filled = l + 1;
        }
    }
    let filled = filled.min(LANES);
    for l in 0..filled {
        let (x, m, w) = blk.point(l);
        lane::<R>(&k, x, m, w, l, &mut acc);
    }
    acc.finish(if W { 1.0 } else { isw })
}

dispatched! {
    /// [`centred_pass`] for the weights and `A` given, built for the processor
    /// ([`crate::numeric::lanes::dispatched`]).
    fn centred_sums[][](
        world: &[Point3<f64>],
        image: &[Point2<f64>],
        weights: Option<&[f64]>,
        map: &CentredMap,
        a: Option<&Matrix3<f64>>,
    ) -> (Sums, f64) = centred_sums_body;
}

#[inline(always)]
fn centred_sums_body(
    world: &[Point3<f64>],
    image: &[Point2<f64>],
    weights: Option<&[f64]>,
    map: &CentredMap,
    a: Option<&Matrix3<f64>>,
) -> (Sums, f64) {
    let id = Matrix3::identity();
    match (weights, a) {
        (None, None) => centred_pass::<false, false>(world, image, &[], map, &id),
        (None, Some(a)) => centred_pass::<false, true>(world, image, &[], map, a),
        (Some(w), None) => centred_pass::<true, false>(world, image, w, map, &id),
        (Some(w), Some(a)) => centred_pass::<true, true>(world, image, w, map, a),
    }
}

/// `frame`/`moments` fused pass: the `moments` sums of `p = A Y` (`a = Some(A)`) or of `p = Y`
/// (`a = None`), `Y = X / sx - centre`, with weights `w / sw` (points with `w = 0` are skipped, so
/// they give bit-identical sums to removing them), plus the `frame` image spread. The weights must
/// already be validated.
///
/// Cost per point: 3 (+ 15 with `A`) flops for the point, 7 for the spread, 3 for `q` and
/// `w u, w v, w q` (without weights, `q` only), 6 for the quadratic monomials and 40
/// multiply-adds for the sums, on packed registers, two points at a time with SSE2 and four
/// with AVX2 ([`centred_pass`]). Measured with callgrind (no weights, no `A`): 103
/// instructions per point at N = 1000 and 108 at N = 100 in the baseline build (158 and 159
/// for the earlier one-point-at-a-time loop), 55 at N = 1000 in the AVX2 build; most of it is
/// the 36 products and their sums (a copy, a multiply, an add and a store per block of lanes).
/// With weights (86 % active, baseline build): 127 and 135 instructions per input point.
pub(crate) fn accumulate_centred(
    world: &[Point3<f64>],
    image: &[Point2<f64>],
    weights: Option<&[f64]>,
    map: &CentredMap,
    a: Option<&Matrix3<f64>>,
) -> CentredSums {
    let (s, spread) = centred_sums(world, image, weights, map, a);
    let vec = |j: usize| Vector3::new(s[1][j], s[2][j], s[3][j]);
    let mat = |j: usize| {
        Matrix3::new(
            s[4][j], s[5][j], s[6][j], //
            s[5][j], s[7][j], s[8][j], //
            s[6][j], s[8][j], s[9][j],
        )
    };
    CentredSums {
        acc: Accumulator {
            // The spread is in image units of `sm`: back to the unit of `u`, `v` (exact).
            image_scatter: spread / (map.inv_image * map.inv_image),
            sw: s[0][0],
            su: s[0][1],
            sv: s[0][2],
            sq: s[0][3],
            a: vec(0),
            a_u: vec(1),
            a_v: vec(2),
            a_q: vec(3),
            s: mat(0),
            s_u: mat(1),
            s_v: mat(2),
            s_q: mat(3),
        },
        spread,
    }
}

/// `B S B^T` for symmetric `S`, exactly symmetric (upper triangle computed, then mirrored).
fn congruence(b: &Matrix3<f64>, s: &Matrix3<f64>) -> Matrix3<f64> {
    let bs = b * s;
    let mut out = Matrix3::zeros();
    for &(r, c) in &SYM6 {
        let x = bs.row(r).dot(&b.row(c));
        out[(r, c)] = x;
        out[(c, r)] = x;
    }
    out
}

impl Accumulator {
    /// The sums of the points `B p`, from the sums of the points `p` (same weights): scalar
    /// sums unchanged, vector sums `B a`, matrix sums `B S B^T`. An exact identity up to
    /// rounding (the sums are linear and quadratic in `p`).
    pub(crate) fn transformed(&self, b: &Matrix3<f64>) -> Accumulator {
        let v = |x: &Vector3<f64>| b * x;
        let m = |x: &Matrix3<f64>| congruence(b, x);
        Accumulator {
            sw: self.sw,
            su: self.su,
            sv: self.sv,
            sq: self.sq,
            a: v(&self.a),
            a_u: v(&self.a_u),
            a_v: v(&self.a_v),
            a_q: v(&self.a_q),
            s: m(&self.s),
            s_u: m(&self.s_u),
            s_v: m(&self.s_v),
            s_q: m(&self.s_q),
            image_scatter: self.image_scatter,
        }
    }
}

/// Zero the terms containing the working-frame z coordinate (`planar` flattening).
fn flat_vec(x: &Vector3<f64>) -> Vector3<f64> {
    Vector3::new(x.x, x.y, 0.0)
}

/// Zero row and column 2 of a symmetric matrix (terms containing z).
fn flat_mat(x: &Matrix3<f64>) -> Matrix3<f64> {
    let mut y = *x;
    for k in 0..3 {
        y[(2, k)] = 0.0;
        y[(k, 2)] = 0.0;
    }
    y
}

impl Accumulator {
    /// `M`, `G` and `trace(M)` from the sums (the Cholesky factor of `W^T W` in closed form).
    ///
    /// `flatten = true` gives the planar system of `planar` (working-frame z set to 0): every
    /// sum containing z is zeroed, which equals accumulating the flattened points.
    ///
    /// Returns `None` if `W^T W` is not positive definite (all image points coincide, which
    /// `frame` already rejects) or if a result is not finite (e.g. image coordinates so large that
    /// `u^2 + v^2` overflows).
    ///
    /// Inlined into its callers, so that `M` and `G` are built where the solve keeps them (see
    /// [`super::frame::working_frame`]: returned by value, the 840 bytes were copied two to
    /// three times).
    #[inline(always)]
    pub(crate) fn system(&self, flatten: bool) -> Option<System> {
        let (a, a_u, a_v, a_q, s, s_u, s_v, s_q) = if flatten {
            (
                flat_vec(&self.a),
                flat_vec(&self.a_u),
                flat_vec(&self.a_v),
                flat_vec(&self.a_q),
                flat_mat(&self.s),
                flat_mat(&self.s_u),
                flat_mat(&self.s_v),
                flat_mat(&self.s_q),
            )
        } else {
            (
                self.a, self.a_u, self.a_v, self.a_q, self.s, self.s_u, self.s_v, self.s_q,
            )
        };
        let sums_finite = all_finite(&[self.sw, self.su, self.sv, self.sq])
            && [a, a_u, a_v, a_q].iter().all(|x| all_finite(x.as_slice()))
            && [s, s_u, s_v, s_q].iter().all(|x| all_finite(x.as_slice()));
        if !sums_finite {
            return None;
        }
        // W^T W = L L^T in closed form: L = [[r, 0, 0], [0, r, 0], [-su / r, -sv / r, l22]]
        // with r = sqrt(sw) and l22^2 = sq - (su^2 + sv^2) / sw = `image_scatter` (positive
        // unless every image point is the same). H = L^-1 W^T V has the rows [-a, 0, a_u] / r,
        // [0, -a, a_v] / r and c = [c0, c1, c2], so M = V^T V - H^T H block by block, and
        // G = L^-T H.
        let sw = self.sw;
        if !(sw > 0.0) {
            return None;
        }
        let isw = 1.0 / sw;
        let (ku, kv) = (self.su * isw, self.sv * isw);
        let l22sq = self.image_scatter;
        if !(l22sq > 0.0 && l22sq.is_finite()) {
            return None;
        }
        let il22 = 1.0 / l22sq.sqrt();
        let c0 = (a_u - a * ku) * il22;
        let c1 = (a_v - a * kv) * il22;
        let c2 = (a_u * ku + a_v * kv - a_q) * il22;
        let outer = |x: &Vector3<f64>, y: &Vector3<f64>| x * y.transpose();
        let aw = a * isw;
        let p = s - outer(&aw, &a);
        // The blocks on and above the diagonal; each entry of the upper triangle written to
        // both of its places (M exactly symmetric).
        let mut m = SMatrix::<f64, 9, 9>::zeros();
        put_block(&mut m, 0, 0, &(p - outer(&c0, &c0)));
        put_block(&mut m, 0, 1, &-outer(&c0, &c1));
        put_block(&mut m, 0, 2, &(outer(&aw, &a_u) - s_u - outer(&c0, &c2)));
        put_block(&mut m, 1, 1, &(p - outer(&c1, &c1)));
        put_block(&mut m, 1, 2, &(outer(&aw, &a_v) - s_v - outer(&c1, &c2)));
        let m22 = s_q - (outer(&a_u, &a_u) + outer(&a_v, &a_v)) * isw - outer(&c2, &c2);
        put_block(&mut m, 2, 2, &m22);
        let g2 = [c0 * il22, c1 * il22, c2 * il22];
        let mut g = SMatrix::<f64, 3, 9>::zeros();
        for k in 0..3 {
            let rows = [
                [
                    -aw[k] + ku * g2[0][k],
                    ku * g2[1][k],
                    a_u[k] * isw + ku * g2[2][k],
                ],
                [
                    kv * g2[0][k],
                    -aw[k] + kv * g2[1][k],
                    a_v[k] * isw + kv * g2[2][k],
                ],
                [g2[0][k], g2[1][k], g2[2][k]],
            ];
            for (r, row) in rows.iter().enumerate() {
                for (b, &v) in row.iter().enumerate() {
                    g[(r, 3 * b + k)] = v;
                }
            }
        }
        let finite = all_finite(m.as_slice()) && all_finite(g.as_slice());
        if !finite {
            return None;
        }
        Some(System {
            m,
            g,
            trace: m.trace(),
        })
    }
}

/// Every entry is finite: `x * 0` is 0 for a finite `x` and NaN otherwise, summed in
/// [`LANES`] independent lanes (packed registers, no branch per entry).
#[inline(always)]
fn all_finite(x: &[f64]) -> bool {
    let mut acc = [0.0f64; LANES];
    let mut chunks = x.chunks_exact(LANES);
    for c in &mut chunks {
        for l in 0..LANES {
            acc[l] += c[l] * 0.0;
        }
    }
    for (l, &r) in chunks.remainder().iter().enumerate() {
        acc[l] += r * 0.0;
    }
    lane_sum(&acc) == 0.0
}

/// Block `(bi, bj)` (`bi <= bj`) of the symmetric 9 x 9 `m`: its entries on or above the
/// diagonal of `m`, each also at its mirrored place.
#[inline(always)]
fn put_block(m: &mut SMatrix<f64, 9, 9>, bi: usize, bj: usize, b: &Matrix3<f64>) {
    for r in 0..3 {
        for c in 0..3 {
            let (i, j) = (3 * bi + r, 3 * bj + c);
            if i <= j {
                m[(i, j)] = b[(r, c)];
                m[(j, i)] = b[(r, c)];
            }
        }
    }
}

impl System {
    /// `t = G vec(R)` (working frame).
    pub(crate) fn translation(&self, r: &Matrix3<f64>) -> Vector3<f64> {
        let rv = SMatrix::<f64, 9, 1>::from_row_slice(r.transpose().as_slice());
        self.g * rv
    }
}

/// Upper triangle of a symmetric 9 x 9 matrix, row by row: (0,0), (0,1), ..., (0,8), (1,1),
/// ..., (8,8) (the input order of the generated kernels).
pub(crate) fn m_upper(m: &SMatrix<f64, 9, 9>) -> [f64; 45] {
    let mut out = [0.0; 45];
    let mut k = 0;
    for i in 0..9 {
        for j in i..9 {
            out[k] = m[(i, j)];
            k += 1;
        }
    }
    out
}

/// The symmetric 9 x 9 matrix of an upper triangle in [`m_upper`]'s order.
#[cfg(any(test, eopnp_bench))]
pub(crate) fn m_symmetric(m45: &[f64; 45]) -> SMatrix<f64, 9, 9> {
    let mut m = SMatrix::<f64, 9, 9>::zeros();
    let mut k = 0;
    for i in 0..9 {
        for j in i..9 {
            m[(i, j)] = m45[k];
            m[(j, i)] = m45[k];
            k += 1;
        }
    }
    m
}

#[cfg(test)]
#[path = "../../tests/unit/pipeline/moments.rs"]
pub(crate) mod tests;
