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
//! local model of the generated kernels `so3_local_model` (the quadratic part) and
//! `so3_local_affine` (the affine part).

use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

use crate::kernels::{so3_local_affine, so3_local_model};
use crate::numeric::mat3::{ldl3, ldl3_solve, min_eigenvalue_sym3};
use crate::numeric::rotation::cgr_to_rotation;

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
    g9: [f64; 9],
}

/// The index in `[xx, xy, xz, yy, yz, zz]` of the product `x_i x_j`, `i <= j`.
const SYM3: [[usize; 3]; 3] = [[0, 1, 2], [1, 3, 4], [2, 4, 5]];

impl Cost {
    /// Accumulates the moments of the rays `(x_i, c_i, v_i, w_i)` (world point, centre, unit
    /// direction, weight; working frame) and eliminates `t`. `None` if `H` is singular (all
    /// rays parallel).
    pub(crate) fn new(
        rays: impl Iterator<Item = (Vector3<f64>, Vector3<f64>, Vector3<f64>, f64)>,
    ) -> Option<Cost> {
        // Per ray, with `Q = w (I - v v^T)` (its 6 distinct entries `qs`) and `xx` the 6
        // distinct products `x_i x_j`: `K^T Q K` is the Kronecker product `Q (x) x x^T` (block
        // `(a, b)` is `Q_ab x x^T`), so the upper triangle of `S` is the 6 x 6 products
        // `qs[ab] xx[ij]` (`SQ`); `Q K` has `(Q K)[c, 3b + j] = Q_cb x_j` (the 6 x 3 products
        // `qs[cb] x_j`, `GQ`); `K^T Q c` has entries `x_i (Q c)_a`. Straight-line sums into
        // fixed arrays: no 9 x 9 product, no index arithmetic per ray.
        let mut sq = [[0.0f64; 6]; 6];
        let mut gq = [[0.0f64; 3]; 6];
        let mut pa = [[0.0f64; 3]; 3];
        let mut hs = [0.0f64; 6];
        let mut q = Vector3::zeros();
        let mut s0 = 0.0;
        for (x, c, v, w) in rays {
            let qs = [
                w * (1.0 - v.x * v.x),
                -w * v.x * v.y,
                -w * v.x * v.z,
                w * (1.0 - v.y * v.y),
                -w * v.y * v.z,
                w * (1.0 - v.z * v.z),
            ];
            let xx = [
                x.x * x.x,
                x.x * x.y,
                x.x * x.z,
                x.y * x.y,
                x.y * x.z,
                x.z * x.z,
            ];
            let xs = [x.x, x.y, x.z];
            for a in 0..6 {
                for b in 0..6 {
                    sq[a][b] += qs[a] * xx[b];
                }
                for j in 0..3 {
                    gq[a][j] += qs[a] * xs[j];
                }
                hs[a] += qs[a];
            }
            let qc = [
                qs[0] * c.x + qs[1] * c.y + qs[2] * c.z,
                qs[1] * c.x + qs[3] * c.y + qs[4] * c.z,
                qs[2] * c.x + qs[4] * c.y + qs[5] * c.z,
            ];
            for a in 0..3 {
                for i in 0..3 {
                    pa[a][i] += xs[i] * qc[a];
                }
            }
            q += Vector3::new(qc[0], qc[1], qc[2]);
            s0 += c.x * qc[0] + c.y * qc[1] + c.z * qc[2];
        }
        let h = Matrix3::new(hs[0], hs[1], hs[2], hs[1], hs[3], hs[4], hs[2], hs[4], hs[5]);
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
        Some(Cost {
            m,
            g,
            k,
            h_inv,
            gm,
            q,
            scale,
            m45,
            g9,
        })
    }

    /// `f(R) = r^T M r + 2 g^T r + k`, clamped at 0 (its exact lower bound).
    pub(crate) fn value(&self, r: &Matrix3<f64>) -> f64 {
        let v = vec9(r);
        (v.dot(&(self.m * v)) + 2.0 * self.g.dot(&v) + self.k).max(0.0)
    }

    /// The translation minimising the cost for `R`.
    pub(crate) fn translation(&self, r: &Matrix3<f64>) -> Vector3<f64> {
        self.h_inv * (self.q - self.gm * vec9(r))
    }

    /// Value, gradient and exact Hessian of `f(R(s) R)` at `s = 0` (docs/algorithm.md,
    /// `newton`: the Hessian is `H_C - 4 f I`).
    fn local_model(&self, r: &Matrix3<f64>) -> (f64, Vector3<f64>, Matrix3<f64>) {
        let rr = row_major(r);
        let a = so3_local_model(&self.m45, &rr);
        let b = so3_local_affine(&self.g9, self.k, &rr);
        let c: [f64; 10] = std::array::from_fn(|i| a[i] + b[i]);
        let f = c[0];
        let g = Vector3::new(c[1], c[2], c[3]);
        let hc = Matrix3::new(c[4], c[5], c[6], c[5], c[7], c[8], c[6], c[8], c[9]);
        (f, g, hc - Matrix3::identity() * (4.0 * f))
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
