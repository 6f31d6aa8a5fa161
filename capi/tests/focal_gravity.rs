//! The known vertical (`EopnpProblem::gravity_*`), the unknown focal length
//! (`EopnpProblem::unknown_focal`, `focal_min_px`, `focal_max_px`) and the refined principal
//! point and distortion (`refine_principal_point`, `refine_distortion`; the solution's
//! `camera_*`) through the exported functions: the library's results bit for bit, a focal
//! length and a camera recovered from a wrong guess, `EOPNP_GRAVITY_MISMATCH` with its message,
//! and every bad combination's status.

#[path = "support/problems.rs"]
mod problems;

use std::ffi::CStr;
use std::ptr;

use eopnp::camera::{Camera, CameraModel, SUPPORTED_MODELS};
use eopnp::ransac::Ransac;
use eopnp::{Gravity, Problem, Solver};
use eopnp_capi::*;
use nalgebra::{Point2, Point3, Rotation3, Vector3};
use problems::{flat2, flat3, synthetic, Lcg, Synthetic};

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

/// The problem of the packed points `w` (x, y, z) and `m` (x, y), through `camera` (NULL:
/// normalised points); every other field zero.
fn problem(w: &[f64], m: &[f64], camera: *const EopnpCamera) -> EopnpProblem {
    let mut p = zeroed_problem();
    p.n = w.len() / 3;
    p.world = w.as_ptr();
    p.image = m.as_ptr();
    p.camera = camera;
    p
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
    let mut p = problem(&w, &m, h.camera);
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
    let mut p = problem(&w, &m, h.camera);
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
    let mut p = problem(&w, &m, ptr::null());
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
    let mut p = problem(&w, &m, ptr::null());
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
    let base = problem(&w, &m, h.camera);
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

// ---------------------------------------------------------------------------------------------
// The refined principal point and distortion.

fn bits(x: &[f64]) -> Vec<u64> {
    x.iter().map(|v| v.to_bits()).collect()
}

/// A solution whose every field the solve must overwrite: NaNs, `true`s and a count past the
/// array, so that a field left unwritten fails the comparisons.
fn garbage_solution() -> EopnpSolution {
    let mut s = zeroed_solution();
    s.focal_estimated = true;
    s.focal_x = f64::NAN;
    s.focal_y = f64::NAN;
    s.camera_estimated = true;
    s.camera_n_params = 99;
    s.camera_params = [f64::NAN; EOPNP_MAX_CAMERA_PARAMS];
    s
}

/// The interface's solution has the library's pose, cost and estimated camera, bit for bit;
/// `focal_free`: the focal length was unknown.
fn assert_librarys(c: &EopnpSolution, lib: &eopnp::Solution, focal_free: bool) {
    let r: Vec<f64> = (0..9).map(|k| lib.rotation[(k / 3, k % 3)]).collect();
    assert_eq!(bits(&c.rotation), bits(&r), "rotation");
    assert_eq!(bits(&c.translation), bits(lib.translation.as_slice()));
    assert_eq!(c.cost.to_bits(), lib.cost.to_bits(), "cost");
    assert_eq!(
        c.reprojection_rmse.to_bits(),
        lib.reprojection_rmse.to_bits()
    );
    let cam = lib.camera.expect("an estimated camera");
    assert!(c.camera_estimated);
    assert_eq!(c.camera_n_params as usize, cam.params().len());
    let mut want = [0.0; EOPNP_MAX_CAMERA_PARAMS];
    want[..cam.params().len()].copy_from_slice(cam.params());
    assert_eq!(bits(&c.camera_params), bits(&want), "camera_params");
    assert_eq!(c.focal_estimated, focal_free);
    let (fx, fy) = if focal_free {
        cam.focal_lengths()
    } else {
        (0.0, 0.0)
    };
    assert_eq!(
        (c.focal_x.to_bits(), c.focal_y.to_bits()),
        (fx.to_bits(), fy.to_bits())
    );
}

/// A noise-free problem of `n` points over the whole 640 x 480 image of `truth`, 2 to 10 units
/// away, at a random pose: world points and pixels.
fn wide_problem(seed: u64, truth: &Camera, n: usize) -> (Vec<Point3<f64>>, Vec<Point2<f64>>) {
    let mut g = Lcg(seed);
    let r =
        Rotation3::from_euler_angles(g.range(-3.0, 3.0), g.range(-1.5, 1.5), g.range(-3.0, 3.0));
    let t = Vector3::new(g.range(-1.0, 1.0), g.range(-1.0, 1.0), g.range(-1.0, 1.0));
    let (mut world, mut pixels) = (Vec::new(), Vec::new());
    for _ in 0..n {
        let px = Point2::new(g.range(0.0, 640.0), g.range(0.0, 480.0));
        let z = g.range(2.0, 10.0);
        let m = truth
            .undistort(px)
            .expect("a mild distortion undistorts everywhere");
        world.push(Point3::from(
            r.inverse() * (Vector3::new(m.x * z, m.y * z, z) - t),
        ));
        // The pixel of the point as the camera projects it (not `px`, which undistortion only
        // reaches to its tolerance): the problem is exact.
        pixels.push(truth.project(m));
    }
    (world, pixels)
}

/// `truth` with its principal point moved by (7, -5) px, no distortion and its focal lengths
/// scaled by `scale`: the starting guess.
fn perturbed(truth: &Camera, scale: f64) -> Camera {
    let mut p = truth.params().to_vec();
    let pp = if truth.model() == CameraModel::SimpleRadial {
        1
    } else {
        2
    };
    p[pp] += 7.0;
    p[pp + 1] -= 5.0;
    p[pp + 2..].iter_mut().for_each(|k| *k = 0.0);
    p[..pp].iter_mut().for_each(|f| *f *= scale);
    Camera::from_colmap(truth.model().name(), 640, 480, p).unwrap()
}

/// A camera handle of the interface with `camera`'s model and parameters.
fn c_camera(camera: &Camera) -> *mut EopnpCamera {
    let name = std::ffi::CString::new(camera.model().name()).unwrap();
    let params = camera.params();
    let mut out = ptr::null_mut();
    // SAFETY: a NUL-terminated name, `params.len()` doubles, a valid out-pointer.
    let status = unsafe {
        eopnp_camera_from_colmap(
            name.as_ptr(),
            640,
            480,
            params.as_ptr(),
            params.len(),
            &mut out,
        )
    };
    assert_eq!(status, EopnpStatus::EOPNP_OK, "{}", message());
    out
}

#[test]
fn max_camera_params_is_the_largest_model() {
    // Every model of the library: COLMAP's and its own full OpenCV model.
    let counts: Vec<usize> = SUPPORTED_MODELS
        .iter()
        .chain([&CameraModel::OpenCvThinPrismTilted])
        .map(|m| m.num_params())
        .collect();
    assert_eq!(counts.iter().max(), Some(&EOPNP_MAX_CAMERA_PARAMS));
    assert_eq!(
        std::mem::size_of_val(&zeroed_solution().camera_params),
        EOPNP_MAX_CAMERA_PARAMS * 8
    );
}

#[test]
fn refined_principal_point_and_distortion_are_the_librarys_and_the_truth() {
    let cameras = [
        problems::opencv_camera(),
        Camera::from_colmap("SIMPLE_RADIAL", 640, 480, vec![500.0, 318.0, 243.0, -0.08]).unwrap(),
    ];
    for (k, truth) in cameras.iter().enumerate() {
        for focal_free in [false, true] {
            let (world, pixels) = wide_problem(40 + k as u64, truth, 50);
            let guess = perturbed(truth, if focal_free { 1.3 } else { 1.0 });
            let (w, m) = (flat3(&world), flat2(&pixels));
            let h = Handles::new(800.0);
            let cam = c_camera(&guess);
            let mut p = problem(&w, &m, cam);
            p.unknown_focal = focal_free;
            let case = format!("{} focal_free {focal_free}", truth.model().name());
            // Nothing refined but maybe the focal length: the camera fields say so.
            if !focal_free {
                let mut s = garbage_solution();
                // SAFETY: live handles, arrays of `n`.
                let status = unsafe { eopnp_solve(h.solver, &p, &mut s) };
                assert_eq!(status, EopnpStatus::EOPNP_OK, "{case}: {}", message());
                assert!(!s.camera_estimated && s.camera_n_params == 0, "{case}");
                assert_eq!(
                    bits(&s.camera_params),
                    bits(&[0.0; EOPNP_MAX_CAMERA_PARAMS])
                );
                assert!(!s.focal_estimated && s.focal_x == 0.0 && s.focal_y == 0.0);
                // The guess does not fit: a refinement has something to do.
                assert!(s.cost > 1.0, "{case}: {}", s.cost);
            }
            p.refine_principal_point = true;
            p.refine_distortion = true;
            let mut s = garbage_solution();
            // SAFETY: as above.
            let status = unsafe { eopnp_solve(h.solver, &p, &mut s) };
            assert_eq!(status, EopnpStatus::EOPNP_OK, "{case}: {}", message());
            let mut problem = Problem::pixels(&world, &pixels, &guess)
                .refine_principal_point()
                .refine_distortion();
            if focal_free {
                problem = problem.unknown_focal();
            }
            let lib = Solver::default().solve(&problem).unwrap();
            assert_librarys(&s, &lib, focal_free);
            // The truth, from the perturbed guess.
            let n = truth.params().len();
            assert_eq!(s.camera_n_params as usize, n, "{case}");
            for (j, (a, b)) in s.camera_params[..n].iter().zip(truth.params()).enumerate() {
                assert!(
                    (a - b).abs() <= 1e-6 * b.abs().max(1.0),
                    "{case}: parameter {j}: {a} against {b}"
                );
            }
            assert!(s.cost < 1e-12, "{case}: {}", s.cost);
            // RANSAC and the batch write the same fields.
            let mut ransac = ptr::null_mut();
            let mut r = garbage_solution();
            // SAFETY: live handles; NULL mask and statistics.
            unsafe {
                assert_eq!(eopnp_ransac_create(&mut ransac), EopnpStatus::EOPNP_OK);
                let status = eopnp_ransac_estimate(
                    ransac,
                    h.solver,
                    &p,
                    &mut r,
                    ptr::null_mut(),
                    ptr::null_mut(),
                );
                eopnp_ransac_free(ransac);
                assert_eq!(status, EopnpStatus::EOPNP_OK, "{case}: {}", message());
            }
            let lib = Ransac::default()
                .estimate(&Solver::default(), &problem)
                .unwrap();
            assert_librarys(&r, &lib.solution, focal_free);
            let mut plain = p;
            plain.refine_principal_point = false;
            plain.refine_distortion = false;
            plain.unknown_focal = false;
            let batch = [p, plain];
            let mut out = [garbage_solution(), garbage_solution()];
            let mut statuses = [EopnpStatus::EOPNP_PANIC; 2];
            // SAFETY: 2 problems, 2 solutions, 2 statuses.
            let status = unsafe {
                eopnp_solve_batch(
                    h.solver,
                    batch.as_ptr(),
                    2,
                    1,
                    out.as_mut_ptr(),
                    statuses.as_mut_ptr(),
                )
            };
            assert_eq!(status, EopnpStatus::EOPNP_OK, "{case}: {}", message());
            assert_eq!(bits(&out[0].camera_params), bits(&s.camera_params));
            assert_eq!(out[0].focal_estimated, focal_free);
            assert!(out[0].camera_estimated && !out[1].camera_estimated);
            assert!(!out[1].focal_estimated && out[1].camera_n_params == 0);
            let mut out = [garbage_solution(), garbage_solution()];
            // SAFETY: live handles; 2 problems, 2 solutions, 2 statuses; no masks or statistics.
            unsafe {
                assert_eq!(eopnp_ransac_create(&mut ransac), EopnpStatus::EOPNP_OK);
                let status = eopnp_ransac_batch(
                    ransac,
                    h.solver,
                    batch.as_ptr(),
                    2,
                    1,
                    out.as_mut_ptr(),
                    ptr::null(),
                    ptr::null_mut(),
                    statuses.as_mut_ptr(),
                );
                eopnp_ransac_free(ransac);
                assert_eq!(status, EopnpStatus::EOPNP_OK, "{case}: {}", message());
            }
            assert_eq!(out[0].focal_estimated, focal_free);
            assert!(out[0].camera_estimated && !out[1].camera_estimated);
            assert!(!out[1].focal_estimated && out[1].camera_n_params == 0);
            assert!((out[0].camera_params[2] - truth.params()[2]).abs() < 1e-6);
            // SAFETY: a handle made by `c_camera`, freed once.
            unsafe { eopnp_camera_free(cam) };
        }
    }
}

#[test]
fn principal_point_alone_keeps_the_focal_length_and_the_distortion() {
    let truth = problems::opencv_camera();
    let (world, pixels) = wide_problem(47, &truth, 40);
    // The truth's distortion, its principal point off: only the principal point to find.
    let mut params = truth.params().to_vec();
    params[2] -= 9.0;
    params[3] += 4.0;
    let guess = Camera::from_colmap("OPENCV", 640, 480, params).unwrap();
    let (w, m) = (flat3(&world), flat2(&pixels));
    let h = Handles::new(800.0);
    let cam = c_camera(&guess);
    let mut p = problem(&w, &m, cam);
    p.refine_principal_point = true;
    let (status, s) = {
        let mut s = garbage_solution();
        // SAFETY: live handles, arrays of `n`.
        let status = unsafe { eopnp_solve(h.solver, &p, &mut s) };
        (status, s)
    };
    // SAFETY: a handle made by `c_camera`, freed once.
    unsafe { eopnp_camera_free(cam) };
    assert_eq!(status, EopnpStatus::EOPNP_OK, "{}", message());
    let lib = Solver::default()
        .solve(&Problem::pixels(&world, &pixels, &guess).refine_principal_point())
        .unwrap();
    assert_librarys(&s, &lib, false);
    // The focal lengths and the distortion are the guess's, bit for bit; the principal point
    // the truth's.
    for j in [0, 1, 4, 5, 6, 7] {
        assert_eq!(
            s.camera_params[j].to_bits(),
            guess.params()[j].to_bits(),
            "{j}"
        );
    }
    for j in [2, 3] {
        assert!((s.camera_params[j] - truth.params()[j]).abs() < 1e-6, "{j}");
    }
}

#[test]
fn refinement_needs_pixels_through_one_camera_without_a_vertical() {
    let truth = problems::opencv_camera();
    let (world, pixels) = wide_problem(48, &truth, 12);
    let normalised: Vec<Point2<f64>> = pixels
        .iter()
        .map(|q| truth.undistort(*q).unwrap())
        .collect();
    let (w, m, mn) = (flat3(&world), flat2(&pixels), flat2(&normalised));
    let h = Handles::new(800.0);
    let cam = c_camera(&truth);
    let base = problem(&w, &m, cam);
    let check = |p: &EopnpProblem, want: EopnpStatus, needles: &[&str]| {
        let mut s = garbage_solution();
        // SAFETY: live handles; the problem's pointers outlive the call.
        let status = unsafe { eopnp_solve(h.solver, p, &mut s) };
        assert_eq!(status, want, "{}", message());
        let mut info: EopnpErrorInfo = unsafe { std::mem::zeroed() };
        // SAFETY: a writable info.
        unsafe { eopnp_last_error(&mut info) };
        assert_eq!(info.status, want);
        for needle in needles {
            assert!(
                message().contains(needle),
                "`{needle}` not in {}",
                message()
            );
        }
    };
    // Each of the two options alone on `p` is refused, the message naming it and `why`.
    let refused = |p: &EopnpProblem, why: &str| {
        type Set = fn(&mut EopnpProblem);
        let options: [(&str, Set); 2] = [
            ("`refine_distortion`", |q| q.refine_distortion = true),
            ("`refine_principal_point`", |q| {
                q.refine_principal_point = true
            }),
        ];
        for (name, set) in options {
            let mut q = *p;
            set(&mut q);
            check(&q, EopnpStatus::EOPNP_INVALID_OPTION, &[name, why]);
        }
    };
    // Normalised input.
    let mut p = base;
    p.camera = ptr::null();
    p.image = mn.as_ptr();
    refused(&p, "pixels through one camera");
    // A rig (of the one camera, at the rig's origin).
    let identity = EopnpPose {
        rotation: [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
        translation: [0.0; 3],
    };
    let mut rig = ptr::null_mut();
    let cams = [cam as *const EopnpCamera];
    // SAFETY: one live camera, one pose, a valid out-pointer.
    let status = unsafe { eopnp_rig_create(cams.as_ptr(), &identity, 1, &mut rig) };
    assert_eq!(status, EopnpStatus::EOPNP_OK, "{}", message());
    let which = vec![0u32; world.len()];
    let mut p = base;
    p.camera = ptr::null();
    p.rig = rig;
    p.rig_cameras = which.as_ptr();
    // The rig problem itself is fine.
    assert_eq!(h.solve(&p).0, EopnpStatus::EOPNP_OK, "{}", message());
    refused(&p, "pixels through one camera");
    // SAFETY: a rig made above, freed once.
    unsafe { eopnp_rig_free(rig) };
    // A known vertical.
    let (gc, gw) = ([0.0, 1.0, 0.0], [0.0, 0.0, -1.0]);
    let mut p = base;
    p.gravity_camera = gc.as_ptr();
    p.gravity_world = gw.as_ptr();
    p.gravity_sigma_deg = 1.0;
    refused(&p, "without a known vertical");
    // Too few points for the free parameters: OPENCV with everything free has 6 + 1 + 2 + 4 =
    // 13, 7 points at least.
    let mut p = base;
    p.unknown_focal = true;
    p.refine_principal_point = true;
    p.refine_distortion = true;
    p.n = 6;
    check(
        &p,
        EopnpStatus::EOPNP_TOO_FEW_POINTS,
        &["got 6, need at least 7"],
    );
    p.n = 7;
    assert_eq!(h.solve(&p).0, EopnpStatus::EOPNP_OK, "{}", message());
    // SAFETY: a handle made by `c_camera`, freed once.
    unsafe { eopnp_camera_free(cam) };
}
