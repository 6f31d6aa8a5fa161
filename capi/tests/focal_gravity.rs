//! The known vertical (`EopnpProblem::gravity_*`) and the unknown focal length
//! (`EopnpProblem::unknown_focal`, `focal_min_px`, `focal_max_px`) through the exported
//! functions: the library's results bit for bit, a focal length recovered from a wrong guess,
//! `EOPNP_GRAVITY_MISMATCH` with its message, and every bad combination's status.

#[path = "support/problems.rs"]
mod problems;

use std::ffi::CStr;
use std::ptr;

use eopnp::camera::Camera;
use eopnp::ransac::Ransac;
use eopnp::{Gravity, Problem, Solver};
use eopnp_capi::*;
use nalgebra::{Point2, Rotation3, Vector3};
use problems::{flat2, flat3, synthetic, Synthetic};

/// The focal lengths the library estimated (the one place this test reads them).
fn lib_focal(s: &eopnp::Solution) -> (f64, f64) {
    s.camera.expect("an estimated camera").focal_lengths()
}

fn zeroed_solution() -> EopnpSolution {
    // SAFETY: every field of `EopnpSolution` is valid all-zero (the enum's 0 is a variant).
    unsafe { std::mem::zeroed() }
}

fn zeroed_problem() -> EopnpProblem {
    // SAFETY: all-zero is the documented default of `EopnpProblem` (NULL pointers, 0, false).
    unsafe { std::mem::zeroed() }
}

fn message() -> String {
    // SAFETY: a NUL-terminated string owned by this thread's slot.
    unsafe { CStr::from_ptr(eopnp_last_error_message()) }
        .to_string_lossy()
        .into_owned()
}

struct Handles {
    solver: *mut EopnpSolver,
    camera: *mut EopnpCamera,
}

impl Handles {
    fn new(fx: f64) -> Self {
        let (mut solver, mut camera) = (ptr::null_mut(), ptr::null_mut());
        // SAFETY: valid out-pointers.
        unsafe {
            assert_eq!(eopnp_solver_create(&mut solver), EopnpStatus::EOPNP_OK);
            assert_eq!(
                eopnp_camera_pinhole(fx, fx, 320.0, 240.0, &mut camera),
                EopnpStatus::EOPNP_OK
            );
        }
        Handles { solver, camera }
    }

    fn solve(&self, p: &EopnpProblem) -> (EopnpStatus, EopnpSolution) {
        let mut s = zeroed_solution();
        // SAFETY: live handles, a problem whose pointers outlive the call.
        let status = unsafe { eopnp_solve(self.solver, p, &mut s) };
        (status, s)
    }
}

impl Drop for Handles {
    fn drop(&mut self) {
        // SAFETY: handles made by `new`, freed once.
        unsafe {
            eopnp_camera_free(self.camera);
            eopnp_solver_free(self.solver);
        }
    }
}

/// The pixels of `syn` through a pinhole camera of focal length `f`, principal point (320, 240).
fn pixels(syn: &Synthetic, f: f64) -> Vec<Point2<f64>> {
    let cam = Camera::pinhole(f, f, 320.0, 240.0).unwrap();
    syn.normalised.iter().map(|m| cam.project(*m)).collect()
}

#[test]
fn unknown_focal_is_recovered_from_a_wrong_guess_as_the_library_does() {
    let syn = synthetic(11, 30, 0.0);
    let px = pixels(&syn, 1200.0);
    let (w, m) = (flat3(&syn.world), flat2(&px));
    let h = Handles::new(800.0);
    let mut p = zeroed_problem();
    p.n = syn.world.len();
    p.world = w.as_ptr();
    p.image = m.as_ptr();
    p.camera = h.camera;
    // Known focal length: not estimated.
    let (status, s) = h.solve(&p);
    assert_eq!(status, EopnpStatus::EOPNP_OK);
    assert!(!s.focal_estimated && s.focal_x == 0.0 && s.focal_y == 0.0);
    // Unknown: 1200 from 800.
    p.unknown_focal = true;
    let (status, s) = h.solve(&p);
    assert_eq!(status, EopnpStatus::EOPNP_OK, "{}", message());
    assert!(s.focal_estimated);
    assert!((s.focal_x - 1200.0).abs() < 1e-6, "{}", s.focal_x);
    assert!((s.focal_y - 1200.0).abs() < 1e-6, "{}", s.focal_y);
    let t = Vector3::from_row_slice(&s.translation);
    assert!((t - syn.translation).norm() < 1e-6);
    // Bit for bit the library's.
    let guess = Camera::pinhole(800.0, 800.0, 320.0, 240.0).unwrap();
    let lib = Solver::default()
        .solve(&Problem::pixels(&syn.world, &px, &guess).unknown_focal())
        .unwrap();
    let (fx, fy) = lib_focal(&lib);
    assert_eq!(s.focal_x.to_bits(), fx.to_bits());
    assert_eq!(s.focal_y.to_bits(), fy.to_bits());
    assert_eq!(s.cost.to_bits(), lib.cost.to_bits());
    // Within a range.
    p.focal_min_px = 1000.0;
    p.focal_max_px = 1500.0;
    let (status, s2) = h.solve(&p);
    assert_eq!(status, EopnpStatus::EOPNP_OK, "{}", message());
    let lib = Solver::default()
        .solve(&Problem::pixels(&syn.world, &px, &guess).unknown_focal_within(1000.0, 1500.0))
        .unwrap();
    assert_eq!(s2.focal_x.to_bits(), lib_focal(&lib).0.to_bits());
    assert!((s2.focal_x - 1200.0).abs() < 1e-6);
    // No covariance: no focal sigma; with one, the library's.
    assert_eq!(s2.focal_sigma, 0.0);
    // SAFETY: a live solver handle.
    let status = unsafe {
        eopnp_solver_set_covariance(
            h.solver,
            EopnpCovariance::EOPNP_COVARIANCE_SIGMA as i32,
            1.0,
        )
    };
    assert_eq!(status, EopnpStatus::EOPNP_OK);
    let (status, s3) = h.solve(&p);
    assert_eq!(status, EopnpStatus::EOPNP_OK, "{}", message());
    let lib = Solver::default()
        .covariance(Some(eopnp::covariance::NoiseModel::Sigma(1.0)))
        .solve(&Problem::pixels(&syn.world, &px, &guess).unknown_focal_within(1000.0, 1500.0))
        .unwrap();
    let sigma = lib.covariance.unwrap().focal_sigma.unwrap();
    assert!(s3.has_covariance && sigma > 0.0);
    assert_eq!(s3.focal_sigma.to_bits(), sigma.to_bits());
}

#[test]
fn unknown_focal_through_ransac() {
    let syn = synthetic(12, 60, 0.0);
    let mut px = pixels(&syn, 1000.0);
    // A quarter of the pixels wrong.
    for (i, q) in px.iter_mut().enumerate() {
        if i % 4 == 0 {
            *q += nalgebra::Vector2::new(37.0 + i as f64, -23.0);
        }
    }
    let (w, m) = (flat3(&syn.world), flat2(&px));
    let h = Handles::new(700.0);
    let mut p = zeroed_problem();
    p.n = syn.world.len();
    p.world = w.as_ptr();
    p.image = m.as_ptr();
    p.camera = h.camera;
    p.unknown_focal = true;
    let mut ransac = ptr::null_mut();
    let mut s = zeroed_solution();
    let mut mask = vec![0u8; p.n];
    let mut stats: EopnpRansacStats = unsafe { std::mem::zeroed() };
    // SAFETY: live handles, arrays of `n`.
    unsafe {
        assert_eq!(eopnp_ransac_create(&mut ransac), EopnpStatus::EOPNP_OK);
        let status =
            eopnp_ransac_estimate(ransac, h.solver, &p, &mut s, mask.as_mut_ptr(), &mut stats);
        eopnp_ransac_free(ransac);
        assert_eq!(status, EopnpStatus::EOPNP_OK, "{}", message());
    }
    assert!(s.focal_estimated);
    assert!((s.focal_x - 1000.0).abs() < 1e-3, "{}", s.focal_x);
    let inliers: usize = mask.iter().map(|&b| usize::from(b)).sum();
    assert_eq!(inliers, 45, "the three quarters left exact");
    let guess = Camera::pinhole(700.0, 700.0, 320.0, 240.0).unwrap();
    let lib = Ransac::default()
        .estimate(
            &Solver::default(),
            &Problem::pixels(&syn.world, &px, &guess).unknown_focal(),
        )
        .unwrap();
    assert_eq!(s.focal_x.to_bits(), lib_focal(&lib.solution).0.to_bits());
}

/// Gravity in the camera's frame for the true pose of `syn`, world "down" = -z.
fn down(syn: &Synthetic) -> ([f64; 3], [f64; 3]) {
    let g = syn.rotation * Vector3::new(0.0, 0.0, -1.0);
    ([g.x, g.y, g.z], [0.0, 0.0, -1.0])
}

#[test]
fn gravity_solves_as_the_library_does() {
    let syn = synthetic(13, 20, 1e-3);
    let (w, m) = (flat3(&syn.world), flat2(&syn.normalised));
    let (gc, gw) = down(&syn);
    let h = Handles::new(800.0);
    let mut p = zeroed_problem();
    p.n = syn.world.len();
    p.world = w.as_ptr();
    p.image = m.as_ptr();
    p.gravity_camera = gc.as_ptr();
    p.gravity_world = gw.as_ptr();
    p.gravity_sigma_deg = 0.05;
    let (status, s) = h.solve(&p);
    assert_eq!(status, EopnpStatus::EOPNP_OK, "{}", message());
    assert!(!s.focal_estimated);
    let g = Gravity::new(Vector3::from(gc), Vector3::from(gw), 0.05).unwrap();
    let lib = Solver::default()
        .solve(&Problem::normalised(&syn.world, &syn.normalised).gravity(g))
        .unwrap();
    assert_eq!(s.cost.to_bits(), lib.cost.to_bits());
    assert_eq!(s.translation[2].to_bits(), lib.translation.z.to_bits());
    // The prior changes the pose (it is used): not the unconstrained one.
    let free = Solver::default()
        .solve(&Problem::normalised(&syn.world, &syn.normalised))
        .unwrap();
    assert_ne!(s.rotation[0].to_bits(), free.rotation[(0, 0)].to_bits());
    let r = Rotation3::from_matrix_unchecked(nalgebra::Matrix3::from_row_slice(&s.rotation));
    assert!(r.angle_to(&syn.rotation).to_degrees() < 0.5);
}

#[test]
fn a_contradicted_vertical_is_gravity_mismatch_with_angle_and_sigmas() {
    let syn = synthetic(14, 30, 1e-4);
    let (w, m) = (flat3(&syn.world), flat2(&syn.normalised));
    let (gc, gw) = down(&syn);
    // Turned 8 degrees about the camera's x axis, claimed to 0.1 degree.
    let tilt = Rotation3::from_axis_angle(&Vector3::x_axis(), 8f64.to_radians());
    let tilted = tilt * Vector3::from(gc);
    let off = tilted.angle(&Vector3::from(gc)).to_degrees();
    assert!(off > 4.0, "{off}");
    let tilted = [tilted.x, tilted.y, tilted.z];
    let h = Handles::new(800.0);
    let mut p = zeroed_problem();
    p.n = syn.world.len();
    p.world = w.as_ptr();
    p.image = m.as_ptr();
    p.gravity_camera = tilted.as_ptr();
    p.gravity_world = gw.as_ptr();
    p.gravity_sigma_deg = 0.1;
    let (status, _) = h.solve(&p);
    assert_eq!(status, EopnpStatus::EOPNP_GRAVITY_MISMATCH);
    let mut info: EopnpErrorInfo = unsafe { std::mem::zeroed() };
    // SAFETY: a writable info.
    unsafe { eopnp_last_error(&mut info) };
    assert_eq!(info.status, EopnpStatus::EOPNP_GRAVITY_MISMATCH);
    let msg = message();
    assert!(
        msg.contains("contradict") && msg.contains("standard deviations"),
        "{msg}"
    );
    let angle: f64 = msg
        .split(" degrees off")
        .next()
        .and_then(|s| s.rsplit(' ').next())
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("no angle in: {msg}"));
    assert!((angle - off).abs() < 0.2, "{angle} against {off}");
    // SAFETY: a static string.
    let name = unsafe { CStr::from_ptr(eopnp_status_name(19)) };
    assert_eq!(name.to_str().unwrap(), "EOPNP_GRAVITY_MISMATCH");
    // An honest sigma accepts it.
    p.gravity_sigma_deg = 20.0;
    assert_eq!(h.solve(&p).0, EopnpStatus::EOPNP_OK, "{}", message());
}

#[test]
fn bad_verticals_and_focal_options_have_their_status() {
    let syn = synthetic(15, 12, 0.0);
    let px = pixels(&syn, 900.0);
    let (w, m) = (flat3(&syn.world), flat2(&px));
    let (gc, gw) = down(&syn);
    let zero = [0.0; 3];
    let h = Handles::new(900.0);
    let base = {
        let mut p = zeroed_problem();
        p.n = syn.world.len();
        p.world = w.as_ptr();
        p.image = m.as_ptr();
        p.camera = h.camera;
        p
    };
    let check = |p: &EopnpProblem, want: EopnpStatus, needle: &str| {
        let (status, _) = h.solve(p);
        assert_eq!(status, want, "{}", message());
        assert!(
            message().contains(needle),
            "`{needle}` not in {}",
            message()
        );
    };
    let with_gravity = |c: *const f64, w: *const f64, sigma: f64| {
        let mut p = base;
        p.gravity_camera = c;
        p.gravity_world = w;
        p.gravity_sigma_deg = sigma;
        p
    };
    for sigma in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let p = with_gravity(gc.as_ptr(), gw.as_ptr(), sigma);
        check(&p, EopnpStatus::EOPNP_INVALID_OPTION, "sigma_deg");
    }
    check(
        &with_gravity(zero.as_ptr(), gw.as_ptr(), 1.0),
        EopnpStatus::EOPNP_INVALID_OPTION,
        "non-zero",
    );
    check(
        &with_gravity(gc.as_ptr(), ptr::null(), 1.0),
        EopnpStatus::EOPNP_INVALID_ARGUMENT,
        "gravity_world",
    );
    check(
        &with_gravity(ptr::null(), ptr::null(), 1.0),
        EopnpStatus::EOPNP_INVALID_ARGUMENT,
        "gravity_sigma_deg",
    );
    // A misaligned direction.
    let bytes = [0u8; 40];
    let odd = bytes[1..].as_ptr().cast::<f64>();
    check(
        &with_gravity(odd, gw.as_ptr(), 1.0),
        EopnpStatus::EOPNP_INVALID_ARGUMENT,
        "gravity_camera",
    );
    // The vertical and the unknown focal length do not combine.
    let mut p = with_gravity(gc.as_ptr(), gw.as_ptr(), 1.0);
    p.unknown_focal = true;
    check(
        &p,
        EopnpStatus::EOPNP_INVALID_OPTION,
        "unknown focal length",
    );
    // A bad range, a range without the option, the option on normalised input.
    for (lo, hi) in [
        (900.0, 800.0),
        (0.0, 800.0),
        (-1.0, 800.0),
        (800.0, f64::INFINITY),
    ] {
        let mut p = base;
        p.unknown_focal = true;
        p.focal_min_px = lo;
        p.focal_max_px = hi;
        check(
            &p,
            EopnpStatus::EOPNP_INVALID_OPTION,
            "unknown focal length",
        );
    }
    let mut p = base;
    p.focal_min_px = 100.0;
    p.focal_max_px = 1000.0;
    check(&p, EopnpStatus::EOPNP_INVALID_ARGUMENT, "unknown_focal");
    let mut p = base;
    p.camera = ptr::null();
    p.unknown_focal = true;
    check(
        &p,
        EopnpStatus::EOPNP_INVALID_OPTION,
        "unknown focal length",
    );
}
