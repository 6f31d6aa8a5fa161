//! The lens distortion of the perspective models in one uniform layout, and its inversion by
//! Newton's method with a trust region and a convergence check.

use crate::numeric::bounds::{Bound, Budget};

/// Newton stops when the step is below this (relative to `max(1, |x|)`).
const STEP_TOL: f64 = 1e-14;
/// Convergence check: the distortion equation must hold to this (relative to `max(1, |x0|)`),
/// a few ulps above the rounding of its evaluation.
const RESIDUAL_TOL: f64 = 1e-13;

/// The distortion coefficients of a model in a uniform layout:
/// `D(u, v) = (u g(r2) + 2 p1 u v + p2 (r2 + 2 u^2), v g(r2) + 2 p2 u v + p1 (r2 + 2 v^2))`
/// with `g = k1 r2 + k2 r2^2 + k3 r2^3 + k4 r2^4` (polynomial models) or
/// `g = (1 + k1 r2 + k2 r4 + k3 r6) / (1 + k4 r2 + k5 r4 + k6 r6) - 1` (FULL_OPENCV), plus
/// OpenCV's thin-prism terms `(s1 r2 + s2 r2^2, s3 r2 + s4 r2^2)` and, last, OpenCV's
/// projective tilt `(a, b) -> (X/W, Y/W)`, `(X, Y, W) = T (a, b, 1)`
/// (OPENCV_THIN_PRISM_TILTED).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Distortion {
    pub k: [f64; 4],
    pub p: [f64; 2],
    pub rational: Option<[f64; 6]>,
    /// `s1, s2, s3, s4`.
    pub prism: [f64; 4],
    /// The tilt matrix `T` (row-major); `None` for no tilt (`T = I`).
    pub tilt: Option<[[f64; 3]; 3]>,
}

/// OpenCV's `computeTiltProjectionMatrix(tau_x, tau_y)` (`calib3d/src/distortion_model.hpp`):
/// `R = Ry(tau_y) Rx(tau_x)`, `T = [[R22, 0, -R02], [0, R22, -R12], [0, 0, 1]] R`, the
/// projection onto a sensor tilted by `R`, rescaled so that the optical axis keeps its pixel.
pub(super) fn tilt_matrix(tau_x: f64, tau_y: f64) -> [[f64; 3]; 3] {
    let (sx, cx) = tau_x.sin_cos();
    let (sy, cy) = tau_y.sin_cos();
    let rx = [[1.0, 0.0, 0.0], [0.0, cx, sx], [0.0, -sx, cx]];
    let ry = [[cy, 0.0, -sy], [0.0, 1.0, 0.0], [sy, 0.0, cy]];
    let r = mul3(&ry, &rx);
    let pz = [
        [r[2][2], 0.0, -r[0][2]],
        [0.0, r[2][2], -r[1][2]],
        [0.0, 0.0, 1.0],
    ];
    mul3(&pz, &r)
}

fn mul3(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let mut c = [[0.0; 3]; 3];
    for (i, row) in c.iter_mut().enumerate() {
        for (j, cij) in row.iter_mut().enumerate() {
            *cij = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j];
        }
    }
    c
}

impl Distortion {
    /// `g(r2)` and `g'(r2)`.
    pub(super) fn radial(&self, r2: f64) -> (f64, f64) {
        if let Some([k1, k2, k3, k4, k5, k6]) = self.rational {
            let n = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
            let dn = k1 + r2 * (2.0 * k2 + 3.0 * r2 * k3);
            let d = 1.0 + r2 * (k4 + r2 * (k5 + r2 * k6));
            let dd = k4 + r2 * (2.0 * k5 + 3.0 * r2 * k6);
            (n / d - 1.0, (dn * d - n * dd) / (d * d))
        } else {
            let [k1, k2, k3, k4] = self.k;
            let g = r2 * (k1 + r2 * (k2 + r2 * (k3 + r2 * k4)));
            let dg = k1 + r2 * (2.0 * k2 + r2 * (3.0 * k3 + 4.0 * r2 * k4));
            (g, dg)
        }
    }

    /// `(u, v) + D(u, v)` (then the tilt, if any) and its Jacobian `[[a, b], [c, d]]`.
    pub(super) fn apply(&self, u: f64, v: f64) -> ((f64, f64), [f64; 4]) {
        let (u2, v2, uv) = (u * u, v * v, u * v);
        let r2 = u2 + v2;
        let (g, dg) = self.radial(r2);
        let [p1, p2] = self.p;
        let [s1, s2, s3, s4] = self.prism;
        // Thin prism: (s1 r2 + s2 r2^2, s3 r2 + s4 r2^2), d/du = 2u (s1 + 2 s2 r2), ...
        let (ta, tb) = (r2 * (s1 + s2 * r2), r2 * (s3 + s4 * r2));
        let (dta, dtb) = (2.0 * (s1 + 2.0 * s2 * r2), 2.0 * (s3 + 2.0 * s4 * r2));
        let du = u * g + 2.0 * p1 * uv + p2 * (r2 + 2.0 * u2) + ta;
        let dv = v * g + 2.0 * p2 * uv + p1 * (r2 + 2.0 * v2) + tb;
        let j = [
            1.0 + g + 2.0 * u2 * dg + 2.0 * p1 * v + 6.0 * p2 * u + u * dta,
            2.0 * uv * dg + 2.0 * p1 * u + 2.0 * p2 * v + v * dta,
            2.0 * uv * dg + 2.0 * p2 * v + 2.0 * p1 * u + u * dtb,
            1.0 + g + 2.0 * v2 * dg + 2.0 * p2 * u + 6.0 * p1 * v + v * dtb,
        ];
        let (a, b) = (u + du, v + dv);
        let Some(t) = self.tilt else {
            return ((a, b), j);
        };
        // Projective tilt (X/W, Y/W): d(X/W)/da = (T00 - (X/W) T20) / W, etc.
        let w = t[2][0] * a + t[2][1] * b + t[2][2];
        let x = (t[0][0] * a + t[0][1] * b + t[0][2]) / w;
        let y = (t[1][0] * a + t[1][1] * b + t[1][2]) / w;
        let jt = [
            (t[0][0] - x * t[2][0]) / w,
            (t[0][1] - x * t[2][1]) / w,
            (t[1][0] - y * t[2][0]) / w,
            (t[1][1] - y * t[2][1]) / w,
        ];
        let jj = [
            jt[0] * j[0] + jt[1] * j[2],
            jt[0] * j[1] + jt[1] * j[3],
            jt[2] * j[0] + jt[3] * j[2],
            jt[2] * j[1] + jt[3] * j[3],
        ];
        ((x, y), jj)
    }
}

/// Solves `x + D(x) = x0` (with the tilt: `tilt(x + D(x)) = x0`, Newton on the whole map) for
/// `x` (COLMAP's `IterativeUndistortion`, with a tighter stopping
/// rule and an explicit convergence check). `None` if it does not converge, or converges to a
/// root where the map folds (det J <= 0) or mirrors through the principal point (1 + g <= 0).
pub(super) fn iterative_undistortion(d: &Distortion, x0: (f64, f64)) -> Option<(f64, f64)> {
    // COLMAP's trust region: |step| <= max(0.1 |x|, 0.1).
    const REL_RADIUS: f64 = 0.1;
    const RADIUS: f64 = 0.1;
    let scale0 = 1f64.max(x0.0.hypot(x0.1));
    let (mut u, mut v) = x0;
    let mut steps = Budget::new(Bound::Undistort);
    while steps.next() {
        let ((xu, xv), j) = d.apply(u, v);
        let (fu, fv) = (xu - x0.0, xv - x0.1);
        let det = j[0] * j[3] - j[1] * j[2];
        if !(det.is_finite() && det != 0.0 && fu.is_finite() && fv.is_finite()) {
            return None;
        }
        let mut su = (j[3] * fu - j[1] * fv) / det;
        let mut sv = (j[0] * fv - j[2] * fu) / det;
        let radius = (REL_RADIUS * u.hypot(v)).max(RADIUS);
        let sn = su.hypot(sv);
        if sn > radius {
            su *= radius / sn;
            sv *= radius / sn;
        }
        u -= su;
        v -= sv;
        if su.hypot(sv) <= STEP_TOL * 1f64.max(u.hypot(v)) {
            break;
        }
    }
    // Convergence check: the equation holds, the map is locally invertible (det J > 0, as at
    // the image centre) at the solution, and the solution is not mirrored through the
    // principal point (radial scale 1 + g > 0: with an extreme coefficient both radial and
    // tangential scales can be negative, so det J > 0 alone does not exclude that root).
    let ((xu, xv), j) = d.apply(u, v);
    let res = (xu - x0.0).hypot(xv - x0.1);
    let det = j[0] * j[3] - j[1] * j[2];
    let (g, _) = d.radial(u * u + v * v);
    // (Running out of iterations is accepted only if this residual test passes anyway.)
    let ok = u.is_finite()
        && v.is_finite()
        && res <= RESIDUAL_TOL * scale0
        && det > 0.0
        && 1.0 + g > 0.0;
    ok.then_some((u, v))
}
