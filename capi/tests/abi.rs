//! The exported functions called from Rust: every result equals the library's bit for bit
//! (poses, costs, covariance, masks, statistics other than times), through packed and strided
//! arrays, and bad input gives its status and message.

#[path = "support/problems.rs"]
mod problems;

use std::ffi::CStr;
use std::ptr;

use eopnp::covariance::NoiseModel;
use eopnp::ransac::Ransac;
use eopnp::{Loss, Problem, Refinement, Rig, Solution, Solver};
use eopnp_capi::*;
use nalgebra::{Isometry3, Point2, Translation3, UnitQuaternion};
use problems::{flat2, flat3, opencv_camera, synthetic};

fn bits(x: &[f64]) -> Vec<u64> {
    x.iter().map(|v| v.to_bits()).collect()
}

/// Every field of `c` equals `s`'s, floats bit for bit.
fn assert_same(c: &EopnpSolution, s: &Solution) {
    let mut r = [0.0; 9];
    for i in 0..3 {
        for j in 0..3 {
            r[3 * i + j] = s.rotation[(i, j)];
        }
    }
    assert_eq!(bits(&c.rotation), bits(&r), "rotation");
    assert_eq!(
        bits(&c.translation),
        bits(s.translation.as_slice()),
        "translation"
    );
    assert_eq!(c.cost.to_bits(), s.cost.to_bits(), "cost");
    assert_eq!(c.algebraic_cost.to_bits(), s.algebraic_cost.to_bits());
    assert_eq!(c.reprojection_rmse.to_bits(), s.reprojection_rmse.to_bits());
    assert_eq!(c.used, s.used as u64);
    assert_eq!(c.skipped, s.skipped as u64);
    assert_eq!(c.newton_iterations, s.newton_iterations);
    assert_eq!(c.reprojection_iterations, s.reprojection_iterations);
    assert_eq!(
        (c.cheirality_ok, c.degenerate, c.planar, c.converged),
        (s.cheirality_ok, s.degenerate, s.planar, s.converged)
    );
    assert_eq!(c.has_covariance, s.covariance.is_some());
    // Only the focal_gravity tests estimate intrinsics: here none is.
    assert!(!c.focal_estimated && c.focal_x == 0.0 && c.focal_y == 0.0);
    assert!(s.camera.is_none());
    assert!(!c.camera_estimated && c.camera_n_params == 0);
    assert_eq!(
        bits(&c.camera_params),
        bits(&[0.0; EOPNP_MAX_CAMERA_PARAMS])
    );
    if let Some(cov) = &s.covariance {
        let mut m = [0.0; 36];
        for i in 0..6 {
            for j in 0..6 {
                m[6 * i + j] = cov.matrix[(i, j)];
            }
        }
        assert_eq!(bits(&c.covariance), bits(&m), "covariance");
        assert_eq!(c.covariance_sigma.to_bits(), cov.sigma.to_bits());
    }
}

fn zeroed_solution() -> EopnpSolution {
    // SAFETY: every field of `EopnpSolution` is valid all-zero (the enum's 0 is a variant).
    unsafe { std::mem::zeroed() }
}

fn problem(world: &[f64], image: &[f64], n: usize) -> EopnpProblem {
    EopnpProblem {
        n,
        world: world.as_ptr(),
        world_stride: 0,
        image: image.as_ptr(),
        image_stride: 0,
        weights: ptr::null(),
        camera: ptr::null(),
        rig: ptr::null(),
        rig_cameras: ptr::null(),
        focal_x: 0.0,
        focal_y: 0.0,
        gravity_camera: ptr::null(),
        gravity_world: ptr::null(),
        gravity_sigma_deg: 0.0,
        unknown_focal: false,
        focal_min_px: 0.0,
        focal_max_px: 0.0,
        refine_principal_point: false,
        refine_distortion: false,
    }
}

struct Handles {
    solver: *mut EopnpSolver,
}

impl Handles {
    fn new() -> Self {
        let mut solver = ptr::null_mut();
        assert_eq!(
            unsafe { eopnp_solver_create(&mut solver) },
            EopnpStatus::EOPNP_OK
        );
        Handles { solver }
    }
}

impl Drop for Handles {
    fn drop(&mut self) {
        unsafe { eopnp_solver_free(self.solver) };
    }
}

fn last_message() -> String {
    unsafe { CStr::from_ptr(eopnp_last_error_message()) }
        .to_str()
        .unwrap()
        .to_owned()
}

#[test]
fn normalised_solve_is_the_librarys_bit_for_bit() {
    let h = Handles::new();
    for (seed, n) in [(1, 4), (2, 6), (3, 10), (4, 100), (5, 1000)] {
        let s = synthetic(seed, n, 1e-3);
        let (w, m) = (flat3(&s.world), flat2(&s.normalised));
        let mut out = zeroed_solution();
        let st = unsafe { eopnp_solve(h.solver, &problem(&w, &m, n), &mut out) };
        assert_eq!(st, EopnpStatus::EOPNP_OK, "{}", last_message());
        let lib = Solver::default()
            .solve(&Problem::normalised(&s.world, &s.normalised))
            .unwrap();
        assert_same(&out, &lib);
    }
}

#[test]
fn strided_arrays_give_the_packed_result() {
    let h = Handles::new();
    let n = 30;
    let s = synthetic(7, n, 1e-3);
    let (w, m) = (flat3(&s.world), flat2(&s.normalised));
    // World points 5 doubles apart, image points 4 apart (garbage in between).
    let mut ws = vec![f64::NAN; 5 * n];
    let mut ms = vec![f64::NAN; 4 * n];
    for i in 0..n {
        ws[5 * i..5 * i + 3].copy_from_slice(&w[3 * i..3 * i + 3]);
        ms[4 * i..4 * i + 2].copy_from_slice(&m[2 * i..2 * i + 2]);
    }
    let mut p = problem(&ws, &ms, n);
    p.world_stride = 5;
    p.image_stride = 4;
    let (mut a, mut b) = (zeroed_solution(), zeroed_solution());
    assert_eq!(
        unsafe { eopnp_solve(h.solver, &p, &mut a) },
        EopnpStatus::EOPNP_OK
    );
    assert_eq!(
        unsafe { eopnp_solve(h.solver, &problem(&w, &m, n), &mut b) },
        EopnpStatus::EOPNP_OK
    );
    assert_eq!(a, b);
}

#[test]
fn options_weights_loss_covariance_and_pixels_are_the_librarys() {
    let h = Handles::new();
    let n = 40;
    let s = synthetic(11, n, 1e-3);
    let cam = opencv_camera();
    let pixels: Vec<Point2<f64>> = s.normalised.iter().map(|x| cam.project(*x)).collect();
    let weights: Vec<f64> = (0..n).map(|i| 0.5 + (i % 3) as f64).collect();
    let (w, px) = (flat3(&s.world), flat2(&pixels));
    let mut ccam = ptr::null_mut();
    let params = cam.params().to_vec();
    assert_eq!(
        unsafe {
            eopnp_camera_from_colmap(
                c"OPENCV".as_ptr(),
                640,
                480,
                params.as_ptr(),
                params.len(),
                &mut ccam,
            )
        },
        EopnpStatus::EOPNP_OK
    );
    unsafe {
        assert_eq!(
            eopnp_solver_set_loss(h.solver, 2, 2.0),
            EopnpStatus::EOPNP_OK
        );
        assert_eq!(
            eopnp_solver_set_covariance(h.solver, 2, 1.0),
            EopnpStatus::EOPNP_OK
        );
        assert_eq!(
            eopnp_solver_set_reprojection_iterations(h.solver, 100),
            EopnpStatus::EOPNP_OK
        );
    }
    let lib_solver = Solver::default()
        .loss(Loss::Cauchy(2.0))
        .covariance(Some(NoiseModel::Sigma(1.0)))
        .reprojection_iterations(100);
    let mut p = problem(&w, &px, n);
    p.camera = ccam;
    p.weights = weights.as_ptr();
    let mut out = zeroed_solution();
    assert_eq!(
        unsafe { eopnp_solve(h.solver, &p, &mut out) },
        EopnpStatus::EOPNP_OK
    );
    let lib = lib_solver
        .solve(&Problem::pixels(&s.world, &pixels, &cam).weights(&weights))
        .unwrap();
    assert!(lib.covariance.is_some());
    assert_same(&out, &lib);

    // Algebraic mode, planar detection, Newton options.
    unsafe {
        assert_eq!(
            eopnp_solver_set_refinement(h.solver, 1),
            EopnpStatus::EOPNP_OK
        );
        assert_eq!(
            eopnp_solver_set_newton_iterations(h.solver, 80),
            EopnpStatus::EOPNP_OK
        );
        assert_eq!(
            eopnp_solver_set_newton_step_tolerance(h.solver, 1e-13),
            EopnpStatus::EOPNP_OK
        );
        assert_eq!(
            eopnp_solver_set_exhaustive(h.solver, true),
            EopnpStatus::EOPNP_OK
        );
        assert_eq!(
            eopnp_solver_set_planar_detection(h.solver, 2),
            EopnpStatus::EOPNP_OK
        );
    }
    let lib_solver = lib_solver
        .refinement(Refinement::Algebraic)
        .newton_iterations(80)
        .newton_step_tolerance(1e-13)
        .exhaustive(true)
        .planar_detection(eopnp::PlanarDetection::NonPlanar);
    assert_eq!(
        unsafe { eopnp_solve(h.solver, &p, &mut out) },
        EopnpStatus::EOPNP_OK
    );
    let lib = lib_solver
        .solve(&Problem::pixels(&s.world, &pixels, &cam).weights(&weights))
        .unwrap();
    assert_same(&out, &lib);
    unsafe { eopnp_camera_free(ccam) };
}

#[test]
fn solve_all_refine_ransac_and_batches_are_the_librarys() {
    let h = Handles::new();
    let n = 60;
    let s = synthetic(21, n, 5e-4);
    let mut image = s.normalised.clone();
    for m in image.iter_mut().take(12) {
        m.x += 0.2; // outliers
    }
    let (w, m) = (flat3(&s.world), flat2(&image));
    let lib_solver = Solver::default();

    // Every minimum (four points: several).
    let p4 = problem(&w, &m, 4);
    let mut all = [zeroed_solution(); EOPNP_MAX_SOLUTIONS];
    let mut count = 0usize;
    assert_eq!(
        unsafe { eopnp_solve_all(h.solver, &p4, all.as_mut_ptr(), all.len(), &mut count) },
        EopnpStatus::EOPNP_OK
    );
    let lib = lib_solver
        .solve_all(&Problem::normalised(&s.world[..4], &image[..4]))
        .unwrap();
    assert_eq!(count, lib.len());
    for (c, l) in all.iter().zip(lib.iter()) {
        assert_same(c, l);
    }
    // Too small an array: the count, the first minima, and the status.
    let mut one = [zeroed_solution(); 1];
    if lib.len() > 1 {
        assert_eq!(
            unsafe { eopnp_solve_all(h.solver, &p4, one.as_mut_ptr(), 1, &mut count) },
            EopnpStatus::EOPNP_BUFFER_TOO_SMALL
        );
        assert_eq!(count, lib.len());
        assert_same(&one[0], &lib[0]);
    }

    // Refinement from a prior pose, on the inliers.
    let (wi, mi) = (flat3(&s.world[12..]), flat2(&image[12..]));
    let prior = Isometry3::from_parts(
        Translation3::from(s.translation + nalgebra::Vector3::new(0.02, -0.01, 0.05)),
        UnitQuaternion::from_rotation_matrix(&s.rotation)
            * UnitQuaternion::from_euler_angles(0.01, -0.02, 0.01),
    );
    let r = prior.rotation.to_rotation_matrix();
    let mut rot = [0.0; 9];
    for i in 0..3 {
        for j in 0..3 {
            rot[3 * i + j] = r[(i, j)];
        }
    }
    let t = prior.translation.vector;
    let initial = EopnpPose {
        rotation: rot,
        translation: [t.x, t.y, t.z],
    };
    let mut out = zeroed_solution();
    assert_eq!(
        unsafe { eopnp_refine(h.solver, &problem(&wi, &mi, n - 12), &initial, &mut out) },
        EopnpStatus::EOPNP_OK
    );
    // The library given the same isometry the interface builds from the matrix.
    let q = UnitQuaternion::from_rotation_matrix(&nalgebra::Rotation3::from_matrix_unchecked(
        nalgebra::Matrix3::from_row_slice(&rot),
    ));
    let iso = Isometry3::from_parts(
        Translation3::new(t.x, t.y, t.z),
        UnitQuaternion::new_normalize(q.into_inner()),
    );
    let lib = lib_solver
        .refine(&Problem::normalised(&s.world[12..], &image[12..]), &iso)
        .unwrap();
    assert_same(&out, &lib);

    // RANSAC (threshold 2 px at f = 800), mask and statistics.
    let mut ransac = ptr::null_mut();
    unsafe {
        assert_eq!(eopnp_ransac_create(&mut ransac), EopnpStatus::EOPNP_OK);
        assert_eq!(
            eopnp_ransac_set_threshold_px(ransac, 2.0),
            EopnpStatus::EOPNP_OK
        );
        assert_eq!(eopnp_ransac_set_seed(ransac, 9), EopnpStatus::EOPNP_OK);
    }
    let lib_ransac = Ransac::default().threshold_px(2.0).seed(9);
    let mut p = problem(&w, &m, n);
    p.focal_x = 800.0;
    p.focal_y = 800.0;
    let mut mask = vec![7u8; n];
    let mut stats = EopnpRansacStats {
        iterations: 0,
        hypotheses: 0,
        local_fits: 0,
        final_fits: 0,
        inliers: 0,
        inlier_ratio: 0.0,
        micros: 0.0,
    };
    assert_eq!(
        unsafe {
            eopnp_ransac_estimate(
                ransac,
                h.solver,
                &p,
                &mut out,
                mask.as_mut_ptr(),
                &mut stats,
            )
        },
        EopnpStatus::EOPNP_OK,
        "{}",
        last_message()
    );
    let lib = lib_ransac
        .estimate(
            &lib_solver,
            &Problem::normalised(&s.world, &image).focal(800.0, 800.0),
        )
        .unwrap();
    assert_same(&out, &lib.solution);
    let lib_mask: Vec<u8> = lib.inliers.iter().map(|b| u8::from(*b)).collect();
    assert_eq!(mask, lib_mask);
    assert_eq!(
        (
            stats.iterations,
            stats.hypotheses,
            stats.local_fits,
            stats.final_fits,
            stats.inliers
        ),
        (
            lib.stats.iterations,
            lib.stats.hypotheses,
            lib.stats.local_fits,
            lib.stats.final_fits,
            lib.stats.inliers as u64
        )
    );
    assert!(mask[..12].iter().all(|b| *b == 0));

    // Batches on 2 threads: each problem's result is the one-problem result.
    let sets: Vec<_> = (0..8)
        .map(|k| synthetic(100 + k, 20 + k as usize, 1e-3))
        .collect();
    let flats: Vec<(Vec<f64>, Vec<f64>)> = sets
        .iter()
        .map(|s| (flat3(&s.world), flat2(&s.normalised)))
        .collect();
    let mut problems: Vec<EopnpProblem> = flats
        .iter()
        .zip(&sets)
        .map(|((w, m), s)| problem(w, m, s.world.len()))
        .collect();
    // Problem 3 is invalid (three points); the others are solved anyway.
    problems[3].n = 3;
    let mut outs = vec![zeroed_solution(); problems.len()];
    let mut statuses = vec![EopnpStatus::EOPNP_PANIC; problems.len()];
    let st = unsafe {
        eopnp_solve_batch(
            h.solver,
            problems.as_ptr(),
            problems.len(),
            2,
            outs.as_mut_ptr(),
            statuses.as_mut_ptr(),
        )
    };
    assert_eq!(st, EopnpStatus::EOPNP_TOO_FEW_POINTS);
    assert!(
        last_message().starts_with("problem 3: too few correspondences"),
        "{}",
        last_message()
    );
    for (k, s) in sets.iter().enumerate() {
        if k == 3 {
            assert_eq!(statuses[k], EopnpStatus::EOPNP_TOO_FEW_POINTS);
            continue;
        }
        assert_eq!(statuses[k], EopnpStatus::EOPNP_OK);
        let lib = lib_solver
            .solve(&Problem::normalised(&s.world, &s.normalised))
            .unwrap();
        assert_same(&outs[k], &lib);
    }
    problems[3].n = sets[3].world.len();
    for p in &mut problems {
        (p.focal_x, p.focal_y) = (800.0, 800.0);
    }
    let mut masks: Vec<Vec<u8>> = sets.iter().map(|s| vec![9u8; s.world.len()]).collect();
    let mask_ptrs: Vec<*mut u8> = masks.iter_mut().map(|m| m.as_mut_ptr()).collect();
    let st = unsafe {
        eopnp_ransac_batch(
            ransac,
            h.solver,
            problems.as_ptr(),
            problems.len(),
            2,
            outs.as_mut_ptr(),
            mask_ptrs.as_ptr(),
            ptr::null_mut(),
            statuses.as_mut_ptr(),
        )
    };
    assert_eq!(st, EopnpStatus::EOPNP_OK, "{}", last_message());
    let lib_problems: Vec<Problem<'_>> = sets
        .iter()
        .map(|s| Problem::normalised(&s.world, &s.normalised).focal(800.0, 800.0))
        .collect();
    let lib = lib_ransac.estimate_batch(&lib_solver, &lib_problems);
    for (k, l) in lib.iter().enumerate() {
        let l = l.as_ref().unwrap();
        assert_same(&outs[k], &l.solution);
        let lm: Vec<u8> = l.inliers.iter().map(|b| u8::from(*b)).collect();
        assert_eq!(masks[k], lm);
    }
    unsafe { eopnp_ransac_free(ransac) };
}

#[test]
fn rig_solve_is_the_librarys() {
    let h = Handles::new();
    let cam = opencv_camera();
    let left = Isometry3::from_parts(
        Translation3::new(0.25, 0.0, 0.0),
        UnitQuaternion::from_euler_angles(0.0, 0.3, 0.0),
    );
    let right = Isometry3::from_parts(
        Translation3::new(-0.25, 0.0, 0.0),
        UnitQuaternion::from_euler_angles(0.0, -0.3, 0.0),
    );
    let pose_of = |iso: &Isometry3<f64>| {
        let r = iso.rotation.to_rotation_matrix();
        let mut rot = [0.0; 9];
        for i in 0..3 {
            for j in 0..3 {
                rot[3 * i + j] = r[(i, j)];
            }
        }
        let t = iso.translation.vector;
        EopnpPose {
            rotation: rot,
            translation: [t.x, t.y, t.z],
        }
    };
    let params = cam.params().to_vec();
    let mut ccam = ptr::null_mut();
    let mut crig = ptr::null_mut();
    unsafe {
        assert_eq!(
            eopnp_camera_from_colmap(
                c"OPENCV".as_ptr(),
                640,
                480,
                params.as_ptr(),
                params.len(),
                &mut ccam
            ),
            EopnpStatus::EOPNP_OK
        );
        let cams = [ccam as *const EopnpCamera, ccam];
        let poses = [pose_of(&left), pose_of(&right)];
        assert_eq!(
            eopnp_rig_create(cams.as_ptr(), poses.as_ptr(), 2, &mut crig),
            EopnpStatus::EOPNP_OK
        );
        eopnp_camera_free(ccam); // the rig keeps its own copies
    }
    // The library's rig built from the same poses as the interface reads them.
    let iso_of = |p: &EopnpPose| {
        let q = UnitQuaternion::from_rotation_matrix(&nalgebra::Rotation3::from_matrix_unchecked(
            nalgebra::Matrix3::from_row_slice(&p.rotation),
        ));
        Isometry3::from_parts(
            Translation3::new(p.translation[0], p.translation[1], p.translation[2]),
            UnitQuaternion::new_normalize(q.into_inner()),
        )
    };
    let rig = Rig::new(vec![
        (cam, iso_of(&pose_of(&left))),
        (cam, iso_of(&pose_of(&right))),
    ])
    .unwrap();
    let s = synthetic(31, 24, 0.0);
    let rig_from_world = Isometry3::from_parts(
        Translation3::from(s.translation),
        UnitQuaternion::from_rotation_matrix(&s.rotation),
    );
    let mut pixels = Vec::new();
    let mut which = Vec::new();
    for (i, x) in s.world.iter().enumerate() {
        let k = i % 2;
        let pc = rig.cam_from_rig()[k] * (rig_from_world * x);
        pixels.push(rig.cameras()[k].project(Point2::new(pc.x / pc.z, pc.y / pc.z)));
        which.push(k as u32);
    }
    let (w, px) = (flat3(&s.world), flat2(&pixels));
    let mut p = problem(&w, &px, s.world.len());
    p.rig = crig;
    p.rig_cameras = which.as_ptr();
    let mut out = zeroed_solution();
    assert_eq!(
        unsafe { eopnp_solve(h.solver, &p, &mut out) },
        EopnpStatus::EOPNP_OK,
        "{}",
        last_message()
    );
    let lib = Solver::default()
        .solve(&Problem::rig(&s.world, &pixels, &which, &rig))
        .unwrap();
    assert_same(&out, &lib);
    // An unknown camera index.
    which[5] = 7;
    assert_eq!(
        unsafe { eopnp_solve(h.solver, &p, &mut out) },
        EopnpStatus::EOPNP_UNKNOWN_CAMERA
    );
    let mut info = EopnpErrorInfo {
        status: EopnpStatus::EOPNP_OK,
        input: EopnpInput::EOPNP_INPUT_NONE,
        degenerate: EopnpDegenerate::EOPNP_DEGENERATE_NONE,
        index: 0,
        got: 0,
        need: 0,
    };
    assert_eq!(
        unsafe { eopnp_last_error(&mut info) },
        EopnpStatus::EOPNP_OK
    );
    assert_eq!(
        (info.status, info.index, info.got),
        (EopnpStatus::EOPNP_UNKNOWN_CAMERA, 5, 7)
    );
    unsafe { eopnp_rig_free(crig) };
}

#[test]
fn bad_input_gives_a_status_and_a_message() {
    let h = Handles::new();
    let s = synthetic(41, 10, 0.0);
    let (mut w, m) = (flat3(&s.world), flat2(&s.normalised));
    let mut out = zeroed_solution();
    let solve =
        |p: &EopnpProblem, out: &mut EopnpSolution| unsafe { eopnp_solve(h.solver, p, out) };
    // NULL handle, problem, output, points.
    assert_eq!(
        unsafe { eopnp_solve(ptr::null(), &problem(&w, &m, 10), &mut out) },
        EopnpStatus::EOPNP_NULL_POINTER
    );
    assert_eq!(last_message(), "`solver` is NULL");
    assert_eq!(
        unsafe { eopnp_solve(h.solver, ptr::null(), &mut out) },
        EopnpStatus::EOPNP_NULL_POINTER
    );
    assert_eq!(
        unsafe { eopnp_solve(h.solver, &problem(&w, &m, 10), ptr::null_mut()) },
        EopnpStatus::EOPNP_NULL_POINTER
    );
    let mut p = problem(&w, &m, 10);
    p.world = ptr::null();
    assert_eq!(solve(&p, &mut out), EopnpStatus::EOPNP_NULL_POINTER);
    assert_eq!(last_message(), "`world` is NULL");
    // Zero points.
    assert_eq!(
        solve(&problem(&w, &m, 0), &mut out),
        EopnpStatus::EOPNP_TOO_FEW_POINTS
    );
    // A stride too small, a misaligned pointer.
    let mut p = problem(&w, &m, 10);
    p.image_stride = 1;
    assert_eq!(solve(&p, &mut out), EopnpStatus::EOPNP_INVALID_ARGUMENT);
    assert!(
        last_message().contains("image_stride"),
        "{}",
        last_message()
    );
    let mut p = problem(&w, &m, 9);
    p.world = unsafe { w.as_ptr().cast::<u8>().add(1).cast() };
    assert_eq!(solve(&p, &mut out), EopnpStatus::EOPNP_INVALID_ARGUMENT);
    // A huge count whose size overflows.
    let mut p = problem(&w, &m, usize::MAX / 2);
    p.world_stride = 3;
    assert_eq!(solve(&p, &mut out), EopnpStatus::EOPNP_INVALID_ARGUMENT);
    // A NaN.
    w[3 * 4 + 1] = f64::NAN;
    assert_eq!(
        solve(&problem(&w, &m, 10), &mut out),
        EopnpStatus::EOPNP_NON_FINITE
    );
    let mut info = EopnpErrorInfo {
        status: EopnpStatus::EOPNP_OK,
        input: EopnpInput::EOPNP_INPUT_NONE,
        degenerate: EopnpDegenerate::EOPNP_DEGENERATE_NONE,
        index: 0,
        got: 0,
        need: 0,
    };
    unsafe { eopnp_last_error(&mut info) };
    assert_eq!((info.input, info.index), (EopnpInput::EOPNP_INPUT_WORLD, 4));
    // Unknown enumeration values, bad option values.
    unsafe {
        assert_eq!(
            eopnp_solver_set_refinement(h.solver, 2),
            EopnpStatus::EOPNP_INVALID_ARGUMENT
        );
        assert_eq!(
            eopnp_solver_set_loss(h.solver, 1, f64::NAN),
            EopnpStatus::EOPNP_INVALID_OPTION
        );
        assert_eq!(
            eopnp_solver_set_loss(h.solver, -1, 1.0),
            EopnpStatus::EOPNP_INVALID_ARGUMENT
        );
        assert_eq!(
            eopnp_solver_set_covariance(h.solver, 2, 0.0),
            EopnpStatus::EOPNP_INVALID_OPTION
        );
        assert_eq!(
            CStr::from_ptr(eopnp_status_name(EopnpStatus::EOPNP_DEGENERATE as i32))
                .to_str()
                .unwrap(),
            "EOPNP_DEGENERATE"
        );
        assert_eq!(
            CStr::from_ptr(eopnp_status_name(99)).to_str().unwrap(),
            "EOPNP_UNKNOWN_STATUS"
        );
    }
}

#[test]
fn last_error_is_per_thread() {
    let threads: Vec<_> = (0..4)
        .map(|k| {
            std::thread::spawn(move || {
                let h = Handles::new();
                let s = synthetic(50 + k, 12, 1e-3);
                let (w, m) = (flat3(&s.world), flat2(&s.normalised));
                let lib = Solver::default()
                    .solve(&Problem::normalised(&s.world, &s.normalised))
                    .unwrap();
                for i in 0..200 {
                    if (i + k) % 2 == 0 {
                        let mut out = zeroed_solution();
                        assert_eq!(
                            unsafe { eopnp_solve(h.solver, &problem(&w, &m, 12), &mut out) },
                            EopnpStatus::EOPNP_OK
                        );
                        assert_same(&out, &lib);
                    } else {
                        // Thread k fails with its own count of points.
                        let n = (k % 4) as usize;
                        let mut out = zeroed_solution();
                        assert_eq!(
                            unsafe { eopnp_solve(h.solver, &problem(&w, &m, n), &mut out) },
                            EopnpStatus::EOPNP_TOO_FEW_POINTS
                        );
                    }
                    if i > 0 {
                        let msg = last_message();
                        let want = format!("got {}, need", k % 4);
                        assert!(msg.contains(&want), "thread {k}: {msg}");
                    }
                }
            })
        })
        .collect();
    for t in threads {
        t.join().unwrap();
    }
}

#[test]
fn colmap_registration_is_the_librarys() {
    use eopnp::colmap::{read_model, register_frame, register_image, ReadOptions};
    let h = Handles::new();
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    for (dir, frames) in [("data/colmap-boxes", false), ("data/colmap-rig", true)] {
        let path = root.join(dir);
        let lib_model = read_model(&path, &ReadOptions::default()).unwrap();
        let cpath = std::ffi::CString::new(path.to_str().unwrap()).unwrap();
        let mut model = ptr::null_mut();
        assert_eq!(
            unsafe { eopnp_model_read(cpath.as_ptr(), &mut model) },
            EopnpStatus::EOPNP_OK
        );
        let id = *lib_model.images.keys().next().unwrap();
        // SAFETY: all-zero is a valid `EopnpRegistration`.
        let mut reg: EopnpRegistration = unsafe { std::mem::zeroed() };
        assert_eq!(
            unsafe { eopnp_model_register(model, id, h.solver, ptr::null(), &mut reg) },
            EopnpStatus::EOPNP_OK,
            "{}",
            last_message()
        );
        let lib = register_image(&lib_model, id, &Solver::default(), None).unwrap();
        assert_same(&reg.solution, &lib.solution);
        assert_eq!(
            (
                reg.n,
                reg.inliers,
                reg.rotation_error_deg.to_bits(),
                reg.rmse_px.to_bits()
            ),
            (
                lib.n as u64,
                lib.inliers as u64,
                lib.rotation_error_deg.to_bits(),
                lib.rmse_px.to_bits()
            )
        );
        if frames {
            let fid = *lib_model.frames.keys().next().unwrap();
            // SAFETY: all-zero is a valid `EopnpFrameRegistration`.
            let mut f: EopnpFrameRegistration = unsafe { std::mem::zeroed() };
            assert_eq!(
                unsafe { eopnp_model_register_frame(model, fid, h.solver, ptr::null(), &mut f) },
                EopnpStatus::EOPNP_OK,
                "{}",
                last_message()
            );
            let lib = register_frame(&lib_model, fid, &Solver::default(), None).unwrap();
            assert_same(&f.solution, &lib.solution);
            assert_eq!((f.images, f.n), (lib.image_ids.len() as u64, lib.n as u64));
        }
        unsafe { eopnp_model_free(model) };
    }
}

/// Random problems with random bad values (NaN, infinities, negative and zero weights, huge and
/// tiny coordinates, duplicated points, strides, counts, camera indices): every call returns a
/// status (never `EOPNP_PANIC`), and an `EOPNP_OK` pose is finite.
#[test]
fn random_bad_input_never_panics() {
    let h = Handles::new();
    let mut g = problems::Lcg(77);
    let cam = opencv_camera();
    let params = cam.params().to_vec();
    let (mut ccam, mut crig) = (ptr::null_mut(), ptr::null_mut());
    let identity = EopnpPose {
        rotation: [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
        translation: [0.0; 3],
    };
    let mut ransac = ptr::null_mut();
    unsafe {
        assert_eq!(
            eopnp_camera_from_colmap(
                c"OPENCV".as_ptr(),
                640,
                480,
                params.as_ptr(),
                params.len(),
                &mut ccam
            ),
            EopnpStatus::EOPNP_OK
        );
        let cams = [ccam as *const EopnpCamera, ccam];
        let poses = [identity, identity];
        assert_eq!(
            eopnp_rig_create(cams.as_ptr(), poses.as_ptr(), 2, &mut crig),
            EopnpStatus::EOPNP_OK
        );
        assert_eq!(eopnp_ransac_create(&mut ransac), EopnpStatus::EOPNP_OK);
        assert_eq!(
            eopnp_ransac_set_max_iterations(ransac, 50),
            EopnpStatus::EOPNP_OK
        );
    }
    let specials = [
        f64::NAN,
        f64::INFINITY,
        -f64::INFINITY,
        0.0,
        -0.0,
        1e300,
        -1e300,
        1e-300,
        5e-324,
    ];
    let mut outcomes = std::collections::BTreeMap::new();
    for round in 0..1500 {
        let n = (g.uniform() * 14.0) as usize;
        let s = synthetic(5000 + round, n.max(1), 1e-3);
        let (ws, is) = ((g.uniform() * 3.0) as usize, (g.uniform() * 3.0) as usize);
        let world_stride = if ws == 0 { 0 } else { 2 + ws };
        let image_stride = if is == 0 { 0 } else { 1 + is };
        let (wstep, istep) = (world_stride.max(3), image_stride.max(2));
        let mut w = vec![0.0; wstep * n.max(1)];
        let mut m = vec![0.0; istep * n.max(1)];
        for i in 0..n {
            let x = s.world[i.min(s.world.len() - 1)];
            w[wstep * i..wstep * i + 3].copy_from_slice(&[x.x, x.y, x.z]);
            let y = s.normalised[i.min(s.normalised.len() - 1)];
            m[istep * i..istep * i + 2].copy_from_slice(&[y.x, y.y]);
        }
        let mut weights: Vec<f64> = (0..n.max(1)).map(|_| g.range(-0.2, 2.0).max(0.0)).collect();
        // A few bad values.
        for _ in 0..(g.uniform() * 3.0) as usize {
            let v = specials[(g.uniform() * specials.len() as f64) as usize];
            match (g.uniform() * 4.0) as usize {
                0 if !w.is_empty() => {
                    let k = (g.uniform() * w.len() as f64) as usize;
                    w[k] = v;
                }
                1 if !m.is_empty() => {
                    let k = (g.uniform() * m.len() as f64) as usize;
                    m[k] = v;
                }
                2 => {
                    let k = (g.uniform() * weights.len() as f64) as usize;
                    weights[k] = if g.uniform() < 0.5 { v } else { -1.0 };
                }
                _ => {
                    // All points the same.
                    for i in 1..n {
                        w.copy_within(0..3, wstep * i);
                    }
                }
            }
        }
        let which: Vec<u32> = (0..n.max(1)).map(|_| (g.uniform() * 2.3) as u32).collect();
        let mut p = problem(&w, &m, n);
        p.world_stride = world_stride;
        p.image_stride = image_stride;
        if g.uniform() < 0.5 {
            p.weights = weights.as_ptr();
        }
        match (g.uniform() * 3.0) as usize {
            0 => {}
            1 => p.camera = ccam,
            _ => {
                p.rig = crig;
                p.rig_cameras = which.as_ptr();
            }
        }
        if g.uniform() < 0.3 {
            p.focal_x = specials[(g.uniform() * specials.len() as f64) as usize];
            p.focal_y = 800.0;
        }
        let mut out = zeroed_solution();
        let st = match round % 4 {
            0 => unsafe { eopnp_solve(h.solver, &p, &mut out) },
            1 => {
                let mut all = [zeroed_solution(); EOPNP_MAX_SOLUTIONS];
                let mut count = 0;
                let st = unsafe {
                    eopnp_solve_all(h.solver, &p, all.as_mut_ptr(), all.len(), &mut count)
                };
                out = all[0];
                st
            }
            2 => {
                let prior = EopnpPose {
                    rotation: identity.rotation,
                    translation: [
                        0.0,
                        0.0,
                        specials[(g.uniform() * specials.len() as f64) as usize],
                    ],
                };
                unsafe { eopnp_refine(h.solver, &p, &prior, &mut out) }
            }
            _ => {
                let mut mask = vec![0u8; n.max(1)];
                unsafe {
                    eopnp_ransac_estimate(
                        ransac,
                        h.solver,
                        &p,
                        &mut out,
                        mask.as_mut_ptr(),
                        ptr::null_mut(),
                    )
                }
            }
        };
        assert_ne!(
            st,
            EopnpStatus::EOPNP_PANIC,
            "round {round}: {}",
            last_message()
        );
        if st == EopnpStatus::EOPNP_OK {
            assert!(
                out.rotation
                    .iter()
                    .chain(&out.translation)
                    .all(|x| x.is_finite()),
                "round {round}: a non-finite pose"
            );
        } else {
            assert!(!last_message().is_empty());
        }
        *outcomes.entry(format!("{st:?}")).or_insert(0) += 1;
    }
    println!("{outcomes:?}");
    // Both outcomes occur: the generator reaches the solver and the checks.
    assert!(
        outcomes.get("EOPNP_OK").copied().unwrap_or(0) > 100,
        "{outcomes:?}"
    );
    assert!(outcomes.len() >= 5, "{outcomes:?}");
    unsafe {
        eopnp_ransac_free(ransac);
        eopnp_rig_free(crig);
        eopnp_camera_free(ccam);
    }
}

#[test]
fn camera_info_and_params_are_the_cameras() {
    use eopnp::camera::Camera;
    let params = [500.0, 505.0, 320.0, 240.0, -0.08, 0.01, 0.001, -0.0005];
    let lib = Camera::from_colmap("OPENCV", 640, 480, params.to_vec()).unwrap();
    let mut cam = ptr::null_mut();
    let name = c"OPENCV";
    let st =
        unsafe { eopnp_camera_from_colmap(name.as_ptr(), 640, 480, params.as_ptr(), 8, &mut cam) };
    assert_eq!(st, EopnpStatus::EOPNP_OK, "{}", last_message());
    let mut info = std::mem::MaybeUninit::<EopnpCameraInfo>::zeroed();
    assert_eq!(
        unsafe { eopnp_camera_info(cam, info.as_mut_ptr()) },
        EopnpStatus::EOPNP_OK
    );
    let info = unsafe { info.assume_init() };
    let model = unsafe { CStr::from_ptr(info.model.as_ptr()) };
    assert_eq!(model.to_str().unwrap(), lib.model().name());
    assert_eq!((info.width, info.height, info.n_params), (640, 480, 8));
    assert_eq!((info.fx, info.fy), lib.focal_lengths());
    let (mut out, mut count) = ([0.0; 8], 0usize);
    let st = unsafe { eopnp_camera_params(cam, out.as_mut_ptr(), 8, &mut count) };
    assert_eq!(st, EopnpStatus::EOPNP_OK);
    assert_eq!((count, bits(&out)), (8, bits(lib.params())));
    // Too small: the count, the first values, a status.
    let (mut three, mut count) = ([0.0; 3], 0usize);
    let st = unsafe { eopnp_camera_params(cam, three.as_mut_ptr(), 3, &mut count) };
    assert_eq!(st, EopnpStatus::EOPNP_BUFFER_TOO_SMALL);
    assert_eq!((count, three), (8, [500.0, 505.0, 320.0]));
    assert!(
        last_message().contains("8 parameters, room for 3"),
        "{}",
        last_message()
    );
    unsafe { eopnp_camera_free(cam) };
}
