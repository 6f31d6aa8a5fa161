//! Unit tests of the pipeline's driver (`src/pipeline/mod.rs`): the `frame`/`moments` intermediates
//! against the reference prototype's, and the solver in the user's axes (no principal-axes
//! rotation in `frame`), where the working-frame rotation sits at the CGR singularity.

use super::*;
use nalgebra::{Matrix3, Rotation3, SMatrix, Unit, Vector3};

/// `(M, G, Rw, ratio)` of `frame` and `moments` in the working frame, or `None` on invalid input
/// (for the tests against the reference prototype).
#[allow(clippy::type_complexity)]
pub(crate) fn intermediates(
    world: &[Point3<f64>],
    image: &[Point2<f64>],
) -> Option<(
    nalgebra::SMatrix<f64, 9, 9>,
    nalgebra::SMatrix<f64, 3, 9>,
    Matrix3<f64>,
    f64,
)> {
    let fr = frame::working_frame(world, image, None, true).ok()?;
    let sys = fr.sums.system(false)?;
    Some((sys.m, sys.g, fr.rw, fr.ratio))
}

/// M, G, Rw and the planarity ratio of `frame`/`moments` against the stored intermediates, after
/// aligning the working frames (docs/algorithm.md section 8): D = Rw_port Rw_ref^T must be diagonal
/// +-1 with det +1; compare M_port with Bd M_ref Bd^T and G_port with G_ref Bd^T, Bd = blockdiag(D,
/// D, D).
#[test]
fn intermediates_match_reference() {
    let mut failures = Vec::new();
    for name in crate::test_data::vector_names() {
        let tv = crate::test_data::vector(&name);
        let Some((m, g, rw, ratio)) = intermediates(&tv.world, &tv.image) else {
            failures.push(format!("{}: intermediates returned None", name));
            continue;
        };
        let d = rw * tv.rw.transpose();
        // The singular values of these scenes are distinct, so Rw is unique up to the sign of
        // each row: D must be diagonal +-1 to rounding (1e-9 leaves room for the SVD's
        // ~1e-15 / gap error).
        let dd = Matrix3::from_diagonal(&Vector3::new(
            d[(0, 0)].signum(),
            d[(1, 1)].signum(),
            d[(2, 2)].signum(),
        ));
        if (d - dd).amax() > 1e-9 || (dd.determinant() - 1.0).abs() > 0.5 {
            failures.push(format!(
                "{}: Rw not aligned with the reference: D = {d}",
                name
            ));
            continue;
        }
        let mut bd = SMatrix::<f64, 9, 9>::zeros();
        for k in 0..3 {
            bd.fixed_view_mut::<3, 3>(3 * k, 3 * k).copy_from(&dd);
        }
        let m_ref = bd * tv.m * bd.transpose();
        let g_ref = tv.g * bd.transpose();
        let em = (m - m_ref).amax() / m_ref.amax();
        let eg = (g - g_ref).amax() / g_ref.amax();
        // Section 8: M, G within 1e-12 relative (`moments` is checked against explicit K^T K to
        // 9e-16).
        if !(em <= 1e-12 && eg <= 1e-12) {
            failures.push(format!("{}: M rel {em:e}, G rel {eg:e}", name));
        }
        // ratio = sv2 / sv0 in [0, 1]: rounding-level absolute agreement.
        if !((ratio - tv.ratio).abs() <= 1e-12) {
            failures.push(format!("{}: ratio {ratio:e} vs {:e}", name, tv.ratio));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Noise-free problems whose rotation is within 1e-3 degrees of 180 degrees (exactly 180 in
/// one trial in twenty): with `align_world_axes = false` the working-frame rotation is the
/// world one, so `newton` starts and ends at the singularity of the global CGR chart. The moving
/// chart of `newton` and `refine` must not care: rotation error < 1e-6 degrees, translation < 1e-8
/// relative, in every one of 10,000 trials for each N = 4, 5, 6, 10, 100, 1000 (release builds;
/// 200 in debug builds).
#[test]
fn near_180_degrees_in_the_users_axes() {
    let opts = Options {
        align_world_axes: false,
        ..Options::default()
    };
    let mut s = 0x9E37_79B9_7F4A_7C15u64;
    let mut u = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    let mut worst = (0.0f64, 0.0f64);
    let trials = if cfg!(debug_assertions) { 200 } else { 10_000 };
    for trial in 0..6 * trials {
        let n = [4, 5, 6, 10, 100, 1000][trial % 6];
        let axis = Unit::new_normalize(Vector3::new(u(), u(), u()));
        let dev = if trial % 20 == 0 {
            0.0
        } else {
            1e-3 * u().abs()
        };
        let r = Rotation3::from_axis_angle(&axis, (180.0 - dev).to_radians()).into_inner();
        let t = Vector3::new(u(), u(), 6.0 + u());
        let world: Vec<Point3<f64>> = (0..n)
            .map(|_| Point3::new(2.0 * u(), 2.0 * u(), 2.0 * u()))
            .collect();
        let image: Vec<Point2<f64>> = world
            .iter()
            .map(|x| {
                let p = r * x.coords + t;
                Point2::new(p.x / p.z, p.y / p.z)
            })
            .collect();
        let sol = run(&opts, &world, &image, None, &opts.reproj, None, None).unwrap();
        let er = crate::numeric::rotation::rotation_error_deg(&sol.rotation, &r);
        let et = (sol.translation - t).norm() / t.norm();
        worst = (worst.0.max(er), worst.1.max(et));
        assert!(er < 1e-6 && et < 1e-8, "trial {trial}: {er:e} deg, {et:e}");
    }
    eprintln!("worst: {:e} deg, {:e} relative", worst.0, worst.1);
}
