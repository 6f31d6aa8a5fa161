//! The lens distortion of the perspective models, one type per model around its generated
//! kernel (`codegen/src/defs/camera.rs`, [`crate::kernels`]), and its inversion by Newton's
//! method with a trust region and a convergence check.
//!
//! The distortion of a model maps a normalised point `(u, v)` (for the fisheye models, the
//! equidistant point) to `(u, v) + D(u, v)`:
//! `D(u, v) = (u g(r2) + 2 p1 u v + p2 (r2 + 2 u^2), v g(r2) + 2 p2 u v + p1 (r2 + 2 v^2))`
//! with the radial factor `1 + g = 1 + k1 r2 + k2 r2^2 + ...` (polynomial models) or
//! `(1 + k1 r2 + k2 r4 + k3 r6) / (1 + k4 r2 + k5 r4 + k6 r6)` (FULL_OPENCV), plus
//! OpenCV's thin-prism terms `(s1 r2 + s2 r2^2, s3 r2 + s4 r2^2)` and, last, OpenCV's
//! projective tilt `(a, b) -> (X/W, Y/W)`, `(X, Y, W) = T (a, b, 1)`
//! (OPENCV_THIN_PRISM_TILTED). The polynomial maps and their Jacobians are generated; the
//! quotient of the rational models and the tilt are written here.

use crate::kernels as k;
use crate::numeric::bounds::{limit, Bound, Budget};
use crate::numeric::lanes::{dispatched, LANES};
use crate::numeric::trig::tan_quadrant;
use nalgebra::Point2;

/// Newton stops when the step is below this (relative to `max(1, |x|)`).
const STEP_TOL: f64 = 1e-14;
/// Convergence check: the distortion equation must hold to this (relative to `max(1, |x0|)`),
/// a few ulps above the rounding of its evaluation.
const RESIDUAL_TOL: f64 = 1e-13;

/// A model's distortion map.
pub(super) trait Lens: Copy {
    /// Whether the map is the identity (no Newton iteration needed to invert it).
    const IDENTITY: bool = false;
    /// Whether the map is radial, `(u, v) -> (u, v) (1 + g(u^2 + v^2))`: then it maps each ray
    /// from the centre onto itself, `apply(r, 0)` is `((r (1 + g), 0), [d/dr, 0, 0, 1 + g],
    /// 1 + g)`, and Newton's iteration from the distorted point stays on its ray
    /// ([`radial_undistortion`]).
    const RADIAL: bool = false;

    /// `(u, v) + D(u, v)` (then the tilt, if any), its Jacobian `[[a, b], [c, d]]` row-major,
    /// and the radial factor `1 + g(r2)` (positive where the point is not mirrored through the
    /// principal point).
    fn apply(&self, u: f64, v: f64) -> ([f64; 2], [f64; 4], f64);
}

/// No distortion (the pinhole models): the identity.
#[derive(Clone, Copy, Debug)]
pub(super) struct NoDistortion;

impl Lens for NoDistortion {
    const IDENTITY: bool = true;

    #[inline]
    fn apply(&self, u: f64, v: f64) -> ([f64; 2], [f64; 4], f64) {
        ([u, v], [1.0, 0.0, 0.0, 1.0], 1.0)
    }
}

/// A polynomial model: its coefficients, the input of its generated kernel.
macro_rules! polynomial_lens {
    ($(#[$doc:meta])* $name:ident, $n:literal, $kernel:path, radial: $radial:literal) => {
        $(#[$doc])*
        #[derive(Clone, Copy, Debug)]
        pub(super) struct $name(pub [f64; $n]);

        impl Lens for $name {
            const RADIAL: bool = $radial;

            #[inline]
            fn apply(&self, u: f64, v: f64) -> ([f64; 2], [f64; 4], f64) {
                let [xd, yd, j00, j01, j10, j11, radial] = $kernel(&[u, v], &self.0);
                ([xd, yd], [j00, j01, j10, j11], radial)
            }
        }
    };
}

polynomial_lens!(
    /// `SIMPLE_RADIAL`, `SIMPLE_RADIAL_FISHEYE`: `[k]`.
    SimpleRadial,
    1,
    k::distortion_simple_radial,
    radial: true
);
polynomial_lens!(
    /// `RADIAL`, `RADIAL_FISHEYE`: `[k1, k2]`.
    Radial,
    2,
    k::distortion_radial,
    radial: true
);
polynomial_lens!(
    /// `OPENCV`: `[k1, k2, p1, p2]`.
    OpenCv,
    4,
    k::distortion_opencv,
    radial: false
);
polynomial_lens!(
    /// `OPENCV_FISHEYE` (on the equidistant point): `[k1, k2, k3, k4]`.
    Fisheye,
    4,
    k::distortion_fisheye,
    radial: true
);

/// The rational model from its generated pieces `[n, d, n_u, n_v, d_u, d_v, t, J_t]`:
/// `(u, v) n / d + t` and its Jacobian, and the radial factor `n / d`.
#[inline]
fn rational(u: f64, v: f64, p: &[f64; 12]) -> ([f64; 2], [f64; 4], f64) {
    let [n, d, n_u, n_v, d_u, d_v, tu, tv, t00, t01, t10, t11] = *p;
    let g = n / d;
    // d(n/d)/du = (n_u - g d_u) / d.
    let (g_u, g_v) = ((n_u - g * d_u) / d, (n_v - g * d_v) / d);
    (
        [u * g + tu, v * g + tv],
        [
            g + u * g_u + t00,
            u * g_v + t01,
            v * g_u + t10,
            g + v * g_v + t11,
        ],
        g,
    )
}

/// `FULL_OPENCV`: `[k1, k2, p1, p2, k3, k4, k5, k6]`.
#[derive(Clone, Copy, Debug)]
pub(super) struct FullOpenCv(pub [f64; 8]);

impl Lens for FullOpenCv {
    #[inline]
    fn apply(&self, u: f64, v: f64) -> ([f64; 2], [f64; 4], f64) {
        rational(u, v, &k::distortion_full_opencv(&[u, v], &self.0))
    }
}

/// `OPENCV_THIN_PRISM_TILTED`: `[k1, k2, p1, p2, k3, k4, k5, k6, s1, s2, s3, s4]` and the tilt
/// matrix `T` (row-major; `None` for no tilt, `T = I`).
#[derive(Clone, Copy, Debug)]
pub(super) struct ThinPrismTilted {
    pub k: [f64; 12],
    pub tilt: Option<[[f64; 3]; 3]>,
}

impl Lens for ThinPrismTilted {
    #[inline]
    fn apply(&self, u: f64, v: f64) -> ([f64; 2], [f64; 4], f64) {
        let ([a, b], j, g) = rational(u, v, &k::distortion_thin_prism(&[u, v], &self.k));
        let Some(t) = self.tilt else {
            return ([a, b], j, g);
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
        ([x, y], jj, g)
    }
}

/// The distortion of a camera, its model chosen once ([`super::Camera::projector`]).
#[derive(Clone, Copy, Debug)]
pub(super) enum Distortion {
    None(NoDistortion),
    SimpleRadial(SimpleRadial),
    Radial(Radial),
    OpenCv(OpenCv),
    Fisheye(Fisheye),
    FullOpenCv(FullOpenCv),
    ThinPrismTilted(ThinPrismTilted),
}

/// Runs `$body` with `$lens` bound to the model's [`Lens`] (monomorphised per model: one
/// dispatch, then straight-line code).
macro_rules! with_lens {
    ($d:expr, $lens:ident => $body:expr) => {
        match $d {
            Distortion::None($lens) => $body,
            Distortion::SimpleRadial($lens) => $body,
            Distortion::Radial($lens) => $body,
            Distortion::OpenCv($lens) => $body,
            Distortion::Fisheye($lens) => $body,
            Distortion::FullOpenCv($lens) => $body,
            Distortion::ThinPrismTilted($lens) => $body,
        }
    };
}
pub(super) use with_lens;

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

/// Solves `x + D(x) = x0` (with the tilt: `tilt(x + D(x)) = x0`, Newton on the whole map) for
/// `x` (COLMAP's `IterativeUndistortion`, with a tighter stopping rule and an explicit
/// convergence check), and gives `det J` of the map at the solution. `None` if it does not
/// converge, or converges to a root where the map folds (det J <= 0) or mirrors through the
/// principal point (radial factor `1 + g <= 0`).
///
/// Norms are compared squared (no `hypot`): `|a| <= c |b|` as `a.a <= c^2 b.b`. Every squared
/// norm here is of a point at which the map was evaluated finite (so `r2` did not overflow) or
/// of a step clamped to the trust region; the one that may overflow, the unclamped step, falls
/// back to `hypot`.
#[inline]
pub(super) fn iterative_undistortion<L: Lens>(d: &L, x0: (f64, f64)) -> Option<((f64, f64), f64)> {
    // COLMAP's trust region: |step| <= max(0.1 |x|, 0.1).
    const REL_RADIUS: f64 = 0.1;
    const RADIUS: f64 = 0.1;
    let (mut u, mut v) = x0;
    let scale2 = (x0.0 * x0.0 + x0.1 * x0.1).max(1.0);
    let mut steps = Budget::new(Bound::Undistort);
    loop {
        let ([xu, xv], j, radial) = d.apply(u, v);
        let (fu, fv) = (xu - x0.0, xv - x0.1);
        let det = j[0] * j[3] - j[1] * j[2];
        // Convergence check, at every iterate (the first that passes ends the iteration): the
        // equation holds, the map is locally invertible (det J > 0, as at the image centre)
        // at the solution, and the solution is not mirrored through the principal point
        // (radial factor 1 + g > 0: with an extreme coefficient both radial and tangential
        // scales can be negative, so det J > 0 alone does not exclude that root).
        if fu * fu + fv * fv <= RESIDUAL_TOL * RESIDUAL_TOL * scale2 && det > 0.0 && radial > 0.0 {
            return (u.is_finite() && v.is_finite()).then_some(((u, v), det));
        }
        if !(steps.next() && det.is_finite() && det != 0.0 && fu.is_finite() && fv.is_finite()) {
            return None;
        }
        let mut su = (j[3] * fu - j[1] * fv) / det;
        let mut sv = (j[0] * fv - j[2] * fu) / det;
        // radius = max(0.1 |x|, 0.1), squared.
        let radius2 = (REL_RADIUS * REL_RADIUS * (u * u + v * v)).max(RADIUS * RADIUS);
        let sn2 = su * su + sv * sv;
        if sn2 > radius2 {
            let sn = if sn2.is_finite() {
                sn2.sqrt()
            } else {
                su.hypot(sv)
            };
            let scale = radius2.sqrt() / sn;
            su *= scale;
            sv *= scale;
        }
        u -= su;
        v -= sv;
        // A negligible step that still leaves the check failing: no convergence.
        if su * su + sv * sv <= STEP_TOL * STEP_TOL * (u * u + v * v).max(1.0) {
            let ([xu, xv], j, radial) = d.apply(u, v);
            let (ru, rv) = (xu - x0.0, xv - x0.1);
            let det = j[0] * j[3] - j[1] * j[2];
            let ok = u.is_finite()
                && v.is_finite()
                && ru * ru + rv * rv <= RESIDUAL_TOL * RESIDUAL_TOL * scale2
                && det > 0.0
                && radial > 0.0;
            return ok.then_some(((u, v), det));
        }
    }
}

/// [`iterative_undistortion`] of a radial map (`L::RADIAL`) for up to [`GROUP`] points `x0`
/// at once (the first `n`), into `out` and `dets` (the undistorted point and `det J`; for the
/// fisheye models, the normalised point and `det J` times that of the equidistant map, as
/// [`super::Projector::undistort`]'s): Newton's iteration from `x0` stays on the ray of
/// `x0`, so with `(u, v) = r x0 / |x0|` it is Newton's iteration on the undistorted radius
/// `r`, `r -> r - (r (1 + g) - |x0|) / (d/dr)` (the generated kernel evaluated at `(r, 0)`),
/// with the same
/// trust region (`|step| <= max(0.1 |r|, 0.1)`), the same convergence check at every iterate
/// (`|r (1 + g) - |x0||` is the length of the residual `(u, v) + D(u, v) - x0`, and
/// `det J = (d/dr) (1 + g)` at the point), and at most as many steps: the same iterates in
/// exact arithmetic. With `FISHEYE`, a converged point then goes through the inverse
/// equidistant map as in [`super::Projector::undistort`]. The points run in lockstep, each frozen
/// when its check passes; a point whose iteration would stop otherwise (a failed step, a
/// negligible step without convergence, the iteration bound) is left to
/// [`iterative_undistortion`], which fails where this would: its bit is set in the returned
/// mask (bit `l`: lane `l`), as is that of a lane whose `det J` is not finite (whose weight
/// [`super::Projector::undistort_weighted`] refuses).
///
/// The map's last evaluation at every lane is kept (the loop ends after evaluating the map
/// at the final radii: when no lane needs a step, or at the iteration bound), so that the
/// final check does not evaluate it again; the points are written straight to `out`, and
/// the mask of the undecided lanes is formed only when some lane is. (Against a loop that
/// stepped before checking and a final evaluation of its own, with a record of four values
/// per lane: the undistortion of the bundled model's 6 images 0.955M -> 0.769M
/// instructions.)
#[inline(always)]
pub(super) fn radial_undistortion<L: Lens, const FISHEYE: bool>(
    d: &L,
    x0: &[[f64; 2]; GROUP],
    n: usize,
    out: &mut [[f64; 2]; GROUP],
    dets: &mut [f64; GROUP],
) -> u64 {
    const RADIUS: f64 = 0.1; // iterative_undistortion's trust region
    let mut rd = [0.0; GROUP];
    // The convergence check's bound on the squared residual.
    let mut tol2 = [0.0; GROUP];
    for l in 0..GROUP {
        let r2 = x0[l][0] * x0[l][0] + x0[l][1] * x0[l][1];
        rd[l] = r2.sqrt();
        tol2[l] = RESIDUAL_TOL * RESIDUAL_TOL * if r2 > 1.0 { r2 } else { 1.0 };
    }
    // The state of a lane is its radius alone: it stays put once the residual passes the
    // check (the rest of the check, `det J > 0` and `1 + g > 0`, is made once, below), and
    // becomes NaN where the one-pixel iteration would stop without converging (a failed or
    // negligible step): the check then fails, and `iterative_undistortion` decides. The
    // lanes past `n` start at NaN. Bitwise `&`, not `&&`, and selects instead of branches,
    // so that the lanes run as one packed iteration.
    let mut r = rd;
    for x in r.iter_mut().skip(n) {
        *x = f64::NAN;
    }
    // The map at each lane's radius, from the last evaluation (at the final radii once the
    // loop ends): the residual `f`, `d/dr` and the radial factor `1 + g`.
    let (mut f, mut dr, mut radial) = ([0.0; GROUP], [0.0; GROUP], [0.0; GROUP]);
    let steps = limit(Bound::Undistort);
    for step in 0..=steps {
        // The map at every lane's radius, and whether a lane still needs a step: its check
        // fails and its radius is a number. (Into arrays, so that the loop is packed.)
        let mut needed = false;
        for l in 0..GROUP {
            let ([xr, _], j, rad) = d.apply(r[l], 0.0);
            f[l] = xr - rd[l];
            dr[l] = j[0];
            radial[l] = rad;
            needed |= (f[l] * f[l] > tol2[l]) & !r[l].is_nan();
        }
        if !needed || step == steps {
            break;
        }
        for l in 0..GROUP {
            // On the ray, det J = (d/dr) (1 + g) ([`Lens::RADIAL`]).
            let det = dr[l] * radial[l];
            let (ff, dd) = (f[l] * f[l], det * det);
            let conv = ff <= tol2[l];
            // f and det J finite and det J non-zero, tested on their squares: this stops
            // wherever the one-pixel iteration's test would, and a little earlier (|det J|
            // below about 1e-154, |f| above about 1e154), which only leaves the lane to it.
            // (`< f64::MAX`, not `< INFINITY`: that LLVM makes integer compares.)
            let finite = (dd > 0.0) & (dd < f64::MAX) & (ff < f64::MAX);
            // The step along the ray, clamped to the trust region max(0.1 |r|, 0.1)
            // (iterative_undistortion compares squares).
            let st = f[l] / dr[l];
            let x = RADIUS * r[l].abs();
            let c = if x > RADIUS { x } else { RADIUS };
            let st = if st < c { st } else { c };
            let st = if st > -c { st } else { -c };
            let r_new = r[l] - st;
            let x = r_new * r_new;
            let negligible = st * st <= STEP_TOL * STEP_TOL * (if x > 1.0 { x } else { 1.0 });
            let go = !conv & finite & !negligible;
            let next = if go { r_new } else { f64::NAN };
            r[l] = if conv { r[l] } else { next };
        }
    }
    // The whole convergence check at each lane's last radius (after the last step allowed,
    // as the one-pixel iteration's at its last iterate), and its point: into arrays, so that
    // the loop is packed, then written out.
    let (mut u, mut v, mut det, mut ok) =
        ([0.0; GROUP], [0.0; GROUP], [0.0; GROUP], [false; GROUP]);
    for l in 0..GROUP {
        det[l] = dr[l] * radial[l];
        // (u, v) = r x0 / |x0| (x0 itself at the centre, where r = 0); the division made
        // for every lane and its result selected, so that the loop stays packed.
        let q = r[l] / if rd[l] > 0.0 { rd[l] } else { 1.0 };
        let s = if rd[l] > 0.0 { q } else { 1.0 };
        (u[l], v[l]) = (x0[l][0] * s, x0[l][1] * s);
        ok[l] = (f[l] * f[l] <= tol2[l])
            & (det[l] > 0.0)
            & (radial[l] > 0.0)
            & (u[l].abs() < f64::INFINITY)
            & (v[l].abs() < f64::INFINITY);
        if FISHEYE {
            // The equidistant map's inverse, as Projector::undistort_with: theta =
            // |(u, v)| = |r|, the normalised radius tan(theta), the determinant divided by
            // s (1 + tan^2) with s = tan(theta) / theta. Beyond the hemisphere: left to the
            // one-pixel path, which reports it.
            let theta = r[l].abs();
            ok[l] &= theta < core::f64::consts::FRAC_PI_2;
            let t = tan_quadrant(if ok[l] { theta } else { 0.0 });
            let moved = theta > f64::EPSILON;
            let s = if moved { t / theta } else { 1.0 };
            u[l] *= s;
            v[l] *= s;
            let q = det[l] / (s * (1.0 + t * t));
            det[l] = if moved { q } else { det[l] };
        }
    }
    // The points and determinants written out, and the lanes left undecided (with a
    // determinant that is not finite too: `weight_of` fails there).
    for l in 0..GROUP {
        out[l] = [u[l], v[l]];
    }
    let mut all = true;
    for l in 0..GROUP {
        ok[l] &= det[l] < f64::INFINITY;
        dets[l] = det[l];
        all &= ok[l] | (l >= n);
    }
    if all {
        return 0;
    }
    (0..n).fold(0, |m, l| m | u64::from(!ok[l]) << l)
}

/// Points iterated in lockstep by [`radial_undistortion`]: several packed registers, so that
/// the serial Newton iterations (a division each) of different points overlap. Measured on
/// the bundled model (a solve of the pixels per image, best of 3 interleaved runs): sixteen points
/// 2-5 % faster than eight, eight 1-6 % faster than four.
pub(super) const GROUP: usize = 4 * LANES;

/// Points per call of [`radial_chunk`].
pub(super) const RADIAL_CHUNK: usize = 64;

dispatched! {
    /// [`radial_undistortion`] of the pixels `px` (at most [`RADIAL_CHUNK`]) of a camera with
    /// focal lengths `focal` and principal point `centre`, [`GROUP`] at a time, into `out` (as
    /// long as `px`) and `dets` (entry `i`: pixel `i`'s undistorted point and `det J`). Returns
    /// the mask (bit `i`: pixel `i`) of the pixels left undecided, whose entries are then
    /// unspecified. Built for the processor ([`crate::numeric::lanes::dispatched`]).
    pub(super) fn radial_chunk[L: Lens, const FISHEYE: bool][L, FISHEYE](
        lens: &L,
        focal: (f64, f64),
        centre: (f64, f64),
        px: &[Point2<f64>],
        out: &mut [Point2<f64>],
        dets: &mut [f64; RADIAL_CHUNK],
    ) -> u64 = radial_chunk_body;
}

#[inline(always)]
fn radial_chunk_body<L: Lens, const FISHEYE: bool>(
    lens: &L,
    focal: (f64, f64),
    centre: (f64, f64),
    px: &[Point2<f64>],
    out: &mut [Point2<f64>],
    dets: &mut [f64; RADIAL_CHUNK],
) -> u64 {
    let n = px.len().min(out.len()).min(RADIAL_CHUNK);
    let (px, out) = (&px[..n], &mut out[..n]);
    let mut undecided = 0;
    for (g, ((block, o), d)) in px
        .chunks(GROUP)
        .zip(out.chunks_mut(GROUP))
        .zip(dets.chunks_exact_mut(GROUP))
        .enumerate()
    {
        // The points in the camera's normalised units, a whole group through fixed-size
        // arrays (so that the loops are packed), as are the results below.
        let mut x0 = [[0.0; 2]; GROUP];
        let at = |p: &Point2<f64>| [(p.x - centre.0) / focal.0, (p.y - centre.1) / focal.1];
        if let Ok(b) = <&[Point2<f64>; GROUP]>::try_from(block) {
            for l in 0..GROUP {
                x0[l] = at(&b[l]);
            }
        } else {
            for (x, p) in x0.iter_mut().zip(block) {
                *x = at(p);
            }
        }
        let d: &mut [f64; GROUP] = d.try_into().expect("chunks of GROUP");
        let mut uv = [[0.0; 2]; GROUP];
        undecided |=
            radial_undistortion::<L, FISHEYE>(lens, &x0, block.len(), &mut uv, d) << (g * GROUP);
        if let Ok(o) = <&mut [Point2<f64>; GROUP]>::try_from(&mut *o) {
            for l in 0..GROUP {
                o[l] = Point2::from(uv[l]);
            }
        } else {
            for (o, uv) in o.iter_mut().zip(&uv) {
                *o = Point2::from(*uv);
            }
        }
    }
    undecided
}
