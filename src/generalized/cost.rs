//! The generalized object-space cost and its minimisation on SO(3) (docs/algorithm.md,
//! generalized EOPnP).
//!
//! With rays `c_i + l v_i` (unit `v_i`) and `Q_i = I - v_i v_i^T`, the cost
//! `sum_i w_i |Q_i (R X_i + t - c_i)|^2` is quadratic in `(vec(R), t)`; `t` is eliminated in
//! closed form, `t*(R) = H^-1 (q - G r)`, and the cost becomes
//! `f(R) = r^T M r + 2 g^T r + k` (`r = vec(R)` row-major) with
//! `M = S - G^T H^-1 G`, `g = G^T H^-1 q - p`, `k = s0 - q^T H^-1 q`, from the O(N) moments
//! `H = sum w Q`, `G = sum w Q K_i`, `S = sum w K_i^T Q K_i`, `q = sum w Q c`,
//! `p = sum w K_i^T Q c`, `s0 = sum w c^T Q c` (`K_i r = R X_i`). Rays through one centre give
//! `g = 0`, `k = 0`: the central cost. Newton on SO(3) runs in the chart `s -> R(s) R` with the
//! local model of the generated kernels `so3_local_model` (the quadratic part, in the central
//! `newton`'s factored form) and `so3_local_affine` (the affine part).

use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

use crate::kernels::so3_local_affine;
use crate::numeric::lanes::{dispatched, lane_sum, LANES};
use crate::numeric::mat3::{ldl3, ldl3_solve, min_eigenvalue_sym3};
use crate::numeric::rotation::cgr_to_rotation;
use crate::pipeline::newton::{cost_at, local_model as newton_local_model};

pub(crate) type M9 = SMatrix<f64, 9, 9>;
pub(crate) type V9 = SVector<f64, 9>;

/// The cost's matrices in the working frame.
#[derive(Clone, Debug)]
pub(crate) struct Cost {
    pub m: M9,
    pub g: V9,
    pub k: f64,
    /// `H^-1`, `G`, `q`: the translation `t*(R) = H^-1 (q - G r)`.
    pub h_inv: Matrix3<f64>,
    pub gm: SMatrix<f64, 3, 9>,
    pub q: Vector3<f64>,
    /// `trace(M)`: the scale of the cost (damping, acceptance floor).
    pub scale: f64,
    m45: [f64; 45],
    /// `M`'s rows (the central `newton`'s local model reads them).
    rows: [[f64; 9]; 9],
    g9: [f64; 9],
}

/// The index in `[xx, xy, xz, yy, yz, zz]` of the product `x_i x_j`, `i <= j`.
const SYM3: [[usize; 3]; 3] = [[0, 1, 2], [1, 3, 4], [2, 4, 5]];

impl Cost {
    /// Accumulates the moments of the rays `ray(0..n)`, each `(x_i, c_i, v_i, w_i)` (world
    /// point, centre, unit direction, weight; working frame), and eliminates `t`. `None` if `H`
    /// is singular (all rays parallel).
    ///
    /// Per ray, with `Q = w (I - v v^T)` (its 6 distinct entries `qs`) and `xx` the 6 distinct
    /// products `x_i x_j`: `K^T Q K` is the Kronecker product `Q (x) x x^T` (block `(a, b)` is
    /// `Q_ab x x^T`), so the upper triangle of `S` is made of the 6 x 6 products `qs[ab] xx[ij]`;
    /// `Q K` has `(Q K)[c, 3b + j] = Q_cb x_j` (the 6 x 3 products `qs[cb] x_j`); `K^T Q c` has
    /// entries `x_i (Q c)_a` ([`ray_sums`]). No 9 x 9 product per ray.
    pub(crate) fn new(
        n: usize,
        ray: impl Fn(usize) -> (Vector3<f64>, Vector3<f64>, Vector3<f64>, f64),
    ) -> Option<Cost> {
        let sums = ray_sums(n, &ray);
        let sq: [[f64; 6]; 6] = std::array::from_fn(|a| std::array::from_fn(|b| sums[6 * a + b]));
        let gq: [[f64; 3]; 6] =
            std::array::from_fn(|a| std::array::from_fn(|j| sums[SQ_END + 3 * a + j]));
        let pa: [[f64; 3]; 3] =
            std::array::from_fn(|a| std::array::from_fn(|i| sums[GQ_END + 3 * a + i]));
        let hs: [f64; 6] = std::array::from_fn(|a| sums[PA_END + a]);
        let q = Vector3::new(sums[HS_END], sums[HS_END + 1], sums[HS_END + 2]);
        let s0 = sums[HS_END + 3];
        let h = Matrix3::new(
            hs[0], hs[1], hs[2], hs[1], hs[3], hs[4], hs[2], hs[4], hs[5],
        );
        let mut gm = SMatrix::<f64, 3, 9>::zeros();
        for cc in 0..3 {
            for b in 0..3 {
                for jj in 0..3 {
                    gm[(cc, 3 * b + jj)] = gq[SYM3[cc.min(b)][cc.max(b)]][jj];
                }
            }
        }
        let p = V9::from_fn(|i, _| pa[i / 3][i % 3]);
        let mut s = M9::zeros();
        for i in 0..9 {
            let (a, ii) = (i / 3, i % 3);
            for j in i..9 {
                let (b, jj) = (j / 3, j % 3);
                let v = sq[SYM3[a.min(b)][a.max(b)]][SYM3[ii.min(jj)][ii.max(jj)]];
                s[(i, j)] = v;
                s[(j, i)] = v;
            }
        }
        let h_inv = h.try_inverse()?;
        let hg = h_inv * gm;
        let m = s - gm.transpose() * hg;
        let m = (m + m.transpose()) * 0.5;
        let g = gm.transpose() * (h_inv * q) - p;
        let k = (s0 - q.dot(&(h_inv * q))).max(0.0);
        let scale = m.trace();
        if !(scale > 0.0 && scale.is_finite()) {
            return None;
        }
        let mut m45 = [0.0; 45];
        let mut n = 0;
        for i in 0..9 {
            for j in i..9 {
                m45[n] = m[(i, j)];
                n += 1;
            }
        }
        let g9 = std::array::from_fn(|i| g[i]);
        let rows = std::array::from_fn(|i| std::array::from_fn(|j| m[(i, j)]));
        Some(Cost {
            m,
            g,
            k,
            h_inv,
            gm,
            q,
            scale,
            m45,
            rows,
            g9,
        })
    }

    /// `f(R) = r^T M r + 2 g^T r + k`, clamped at 0 (its exact lower bound).
    pub(crate) fn value(&self, r: &Matrix3<f64>) -> f64 {
        let v = vec9(r);
        (cost_at(&self.m45, r) + 2.0 * self.g.dot(&v) + self.k).max(0.0)
    }

    /// The translation minimising the cost for `R`.
    pub(crate) fn translation(&self, r: &Matrix3<f64>) -> Vector3<f64> {
        self.h_inv * (self.q - self.gm * vec9(r))
    }

    /// Value, gradient and exact Hessian of `f(R(s) R)` at `s = 0` (docs/algorithm.md,
    /// `newton`: the Hessian is `H_C - 4 f I`, linear in the cost): the quadratic part's by the
    /// central `newton`'s factored form of the kernel `so3_local_model` (its `f` by `cost_at`,
    /// its `H_C - 4 f_q I`), plus the affine part's from the kernel `so3_local_affine`,
    /// `H_C,a - 4 f_a I`.
    fn local_model(&self, r: &Matrix3<f64>) -> (f64, Vector3<f64>, Matrix3<f64>) {
        let rr = row_major(r);
        let fq = cost_at(&self.m45, r);
        let (gq, hq) = newton_local_model(&self.rows, r);
        let b = so3_local_affine(&self.g9, self.k, &rr);
        let f = fq + b[0];
        let g = gq + Vector3::new(b[1], b[2], b[3]);
        let hca = Matrix3::new(b[4], b[5], b[6], b[5], b[7], b[8], b[6], b[8], b[9]);
        (f, g, hq + hca - Matrix3::identity() * (4.0 * b[0]))
    }

    /// Damped Newton on SO(3) from `r0` (the central `newton` stage's iteration, without its
    /// early exits): at most `max_iterations` iterations, each with at most 30 trial steps;
    /// stops when a step is at most `step_tolerance`. Returns the minimum, its cost and the
    /// iterations.
    pub(crate) fn newton(
        &self,
        r0: &Matrix3<f64>,
        max_iterations: u32,
        step_tolerance: f64,
    ) -> (Matrix3<f64>, f64, u32) {
        let mut r = *r0;
        let (mut f, mut g, mut h) = self.local_model(&r);
        let mut mu = 1e-6;
        let mut iterations = 0;
        let floor = 1e-13 * self.scale;
        while iterations < max_iterations {
            iterations += 1;
            // shift = max(0, -lambda_min(H)); a successful factorisation of H proves
            // lambda_min > 0 (shift 0): the eigenvalue only for an indefinite H (as `newton`).
            let shift = if ldl3(&h).is_some() {
                0.0
            } else {
                (-min_eigenvalue_sym3(&h)).max(0.0)
            };
            let mut accepted = false;
            for _ in 0..30 {
                let lambda = mu * self.scale + shift;
                let Some(fac) = ldl3(&(h + Matrix3::identity() * lambda)) else {
                    mu *= 10.0;
                    continue;
                };
                let d = -ldl3_solve(&fac, &g);
                if !d.iter().all(|x| x.is_finite()) {
                    mu *= 10.0;
                    continue;
                }
                let rn = cgr_to_rotation(&d) * r;
                let fn_ = self.value(&rn);
                if fn_ < f
                    || (fn_ <= f + floor && {
                        let (_, g2, _) = self.local_model(&rn);
                        g2.norm() < g.norm()
                    })
                {
                    r = rn;
                    let step = d.norm();
                    (f, g, h) = self.local_model(&r);
                    mu = (mu / 10.0).max(1e-15);
                    accepted = true;
                    if step <= step_tolerance {
                        return (r, f.max(0.0), iterations);
                    }
                    break;
                }
                mu *= 10.0;
                if mu > 1e8 {
                    break;
                }
            }
            if !accepted {
                break;
            }
        }
        (r, f.max(0.0), iterations)
    }
}

/// The layout of [`ray_sums`]' output: `sq` (36, `qs[a] xx[b]`), `gq` (18, `qs[a] x_j`), `pa`
/// (9, `x_i (Q c)_a`), `hs` (6, `qs[a]`), `q` (3, `Q c`), `s0` (1, `c^T Q c`).
const SQ_END: usize = 36;
const GQ_END: usize = SQ_END + 18;
const PA_END: usize = GQ_END + 9;
const HS_END: usize = PA_END + 6;
const NSUMS: usize = HS_END + 4;

dispatched! {
/// The per-ray sums of [`Cost::new`] over the rays `ray(0..n)`, vectorised across rays: blocks of
/// [`LANES`] rays, lane `l` of every sum accumulating rays `l, l + LANES, ...` (a last partial
/// block padded with weight 0, which adds nothing), the lanes added at the end. Built for the
/// processor ([`crate::numeric::lanes::dispatched`]).
fn ray_sums[F: Fn(usize) -> (Vector3<f64>, Vector3<f64>, Vector3<f64>, f64)][F](
        n: usize,
        ray: &F,
    ) -> [f64; NSUMS] = ray_sums_body;
}

// Index loops over the lanes are what the compiler vectorises.
#[allow(clippy::needless_range_loop)]
#[inline(always)]
fn ray_sums_body<F: Fn(usize) -> (Vector3<f64>, Vector3<f64>, Vector3<f64>, f64)>(
    n: usize,
    ray: &F,
) -> [f64; NSUMS] {
    let mut acc = [[0.0f64; LANES]; NSUMS];
    let mut i = 0;
    while i < n {
        let (mut x, mut c, mut v, mut w) = (
            [[0.0f64; LANES]; 3],
            [[0.0f64; LANES]; 3],
            [[0.0f64; LANES]; 3],
            [0.0f64; LANES],
        );
        for l in 0..LANES.min(n - i) {
            let (xi, ci, vi, wi) = ray(i + l);
            for k in 0..3 {
                x[k][l] = xi[k];
                c[k][l] = ci[k];
                v[k][l] = vi[k];
            }
            w[l] = wi;
        }
        let mut qs = [[0.0f64; LANES]; 6];
        let mut xx = [[0.0f64; LANES]; 6];
        for l in 0..LANES {
            qs[0][l] = w[l] * (1.0 - v[0][l] * v[0][l]);
            qs[1][l] = -w[l] * v[0][l] * v[1][l];
            qs[2][l] = -w[l] * v[0][l] * v[2][l];
            qs[3][l] = w[l] * (1.0 - v[1][l] * v[1][l]);
            qs[4][l] = -w[l] * v[1][l] * v[2][l];
            qs[5][l] = w[l] * (1.0 - v[2][l] * v[2][l]);
            xx[0][l] = x[0][l] * x[0][l];
            xx[1][l] = x[0][l] * x[1][l];
            xx[2][l] = x[0][l] * x[2][l];
            xx[3][l] = x[1][l] * x[1][l];
            xx[4][l] = x[1][l] * x[2][l];
            xx[5][l] = x[2][l] * x[2][l];
        }
        for a in 0..6 {
            for b in 0..6 {
                for l in 0..LANES {
                    acc[6 * a + b][l] += qs[a][l] * xx[b][l];
                }
            }
            for j in 0..3 {
                for l in 0..LANES {
                    acc[SQ_END + 3 * a + j][l] += qs[a][l] * x[j][l];
                }
            }
            for l in 0..LANES {
                acc[PA_END + a][l] += qs[a][l];
            }
        }
        let mut qc = [[0.0f64; LANES]; 3];
        for l in 0..LANES {
            qc[0][l] = qs[0][l] * c[0][l] + qs[1][l] * c[1][l] + qs[2][l] * c[2][l];
            qc[1][l] = qs[1][l] * c[0][l] + qs[3][l] * c[1][l] + qs[4][l] * c[2][l];
            qc[2][l] = qs[2][l] * c[0][l] + qs[4][l] * c[1][l] + qs[5][l] * c[2][l];
        }
        for a in 0..3 {
            for k in 0..3 {
                for l in 0..LANES {
                    acc[GQ_END + 3 * a + k][l] += x[k][l] * qc[a][l];
                }
            }
            for l in 0..LANES {
                acc[HS_END + a][l] += qc[a][l];
            }
        }
        for l in 0..LANES {
            acc[HS_END + 3][l] += c[0][l] * qc[0][l] + c[1][l] * qc[1][l] + c[2][l] * qc[2][l];
        }
        i += LANES;
    }
    std::array::from_fn(|k| lane_sum(&acc[k]))
}

/// `vec(R)`, row-major.
pub(crate) fn vec9(r: &Matrix3<f64>) -> V9 {
    V9::from_fn(|i, _| r[(i / 3, i % 3)])
}

fn row_major(r: &Matrix3<f64>) -> [f64; 9] {
    std::array::from_fn(|i| r[(i / 3, i % 3)])
}

#[cfg(test)]
#[path = "../../tests/unit/generalized/cost.rs"]
mod tests;
