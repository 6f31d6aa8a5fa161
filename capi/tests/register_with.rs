//! Registration with free intrinsics (`eopnp_model_register_with`,
//! `eopnp_model_register_batch_with`, `EopnpFreeIntrinsics`) on `data/colmap-boxes`: every
//! image's registration with an unknown focal length, a focal range, a refined principal point
//! or distortion is the library's `colmap::register_image_with` bit for bit (pose, estimated
//! camera, errors, `focal_error_pct`), plain and with RANSAC; the batch is one call at a time;
//! NULL (and all-zero) intrinsics are `eopnp_model_register`; bad options have their status and
//! message.

use std::ffi::{CStr, CString};
use std::path::PathBuf;
use std::ptr;

use eopnp::colmap::{read_model, register_image_with, Model, ReadOptions, Registration};
use eopnp::ransac::Ransac;
use eopnp::{Problem, Solver};
use eopnp_capi::*;

fn bits(x: &[f64]) -> Vec<u64> {
    x.iter().map(|v| v.to_bits()).collect()
}

fn message() -> String {
    // SAFETY: a NUL-terminated string owned by this thread's slot.
    unsafe { CStr::from_ptr(eopnp_last_error_message()) }
        .to_string_lossy()
        .into_owned()
}

fn boxes() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../data/colmap-boxes")
}

/// A registration whose every field the call must overwrite: NaNs, `true`s, a count past the
/// camera array, so that a field left unwritten fails the comparisons.
fn garbage() -> EopnpRegistration {
    // SAFETY: all-zero is a valid `EopnpRegistration` (the enum's 0 is a variant).
    let mut r: EopnpRegistration = unsafe { std::mem::zeroed() };
    r.has_ransac = true;
    r.has_focal_error = true;
    r.focal_error_pct = f64::NAN;
    r.rmse_px = f64::NAN;
    r.solution.focal_estimated = true;
    r.solution.focal_x = f64::NAN;
    r.solution.focal_y = f64::NAN;
    r.solution.camera_estimated = true;
    r.solution.camera_n_params = 99;
    r.solution.camera_params = [f64::NAN; EOPNP_MAX_CAMERA_PARAMS];
    r.solution.rotation = [f64::NAN; 9];
    r
}

/// The intrinsics as the C struct.
fn intrinsics(
    unknown_focal: bool,
    range: (f64, f64),
    principal_point: bool,
    distortion: bool,
) -> EopnpFreeIntrinsics {
    EopnpFreeIntrinsics {
        unknown_focal,
        focal_min_px: range.0,
        focal_max_px: range.1,
        refine_principal_point: principal_point,
        refine_distortion: distortion,
    }
}

/// The same intrinsics as the library's problem option.
fn apply<'p>(f: &EopnpFreeIntrinsics, mut p: Problem<'p>) -> Problem<'p> {
    if f.unknown_focal {
        p = if (f.focal_min_px, f.focal_max_px) == (0.0, 0.0) {
            p.unknown_focal()
        } else {
            p.unknown_focal_within(f.focal_min_px, f.focal_max_px)
        };
    }
    if f.refine_principal_point {
        p = p.refine_principal_point();
    }
    if f.refine_distortion {
        p = p.refine_distortion();
    }
    p
}

/// The interface's registration is the library's, bit for bit (times apart); `focal_free`: the
/// focal length was unknown.
fn assert_librarys(c: &EopnpRegistration, lib: &Registration, focal_free: bool) {
    let s = &lib.solution;
    let r: Vec<f64> = (0..9).map(|k| s.rotation[(k / 3, k % 3)]).collect();
    let id = lib.image_id;
    assert_eq!(c.image_id, id);
    assert_eq!(bits(&c.solution.rotation), bits(&r), "{id}: rotation");
    assert_eq!(
        bits(&c.solution.translation),
        bits(s.translation.as_slice()),
        "{id}: translation"
    );
    assert_eq!(c.solution.cost.to_bits(), s.cost.to_bits(), "{id}: cost");
    assert_eq!(
        c.solution.reprojection_rmse.to_bits(),
        s.reprojection_rmse.to_bits()
    );
    assert_eq!(
        (c.n, c.inliers, c.skipped, c.has_ransac),
        (
            lib.n as u64,
            lib.inliers as u64,
            lib.skipped as u64,
            lib.ransac.is_some()
        ),
        "{id}"
    );
    if let Some(stats) = &lib.ransac {
        assert_eq!(
            (c.ransac.iterations, c.ransac.hypotheses, c.ransac.inliers),
            (stats.iterations, stats.hypotheses, stats.inliers as u64),
            "{id}"
        );
    }
    let errors = [
        c.rotation_error_deg,
        c.translation_error_pct,
        c.rmse_px,
        c.model_rmse_px,
    ];
    let want = [
        lib.rotation_error_deg,
        lib.translation_error_pct,
        lib.rmse_px,
        lib.model_rmse_px,
    ];
    assert_eq!(bits(&errors), bits(&want), "{id}: errors");
    assert_eq!(c.has_focal_error, lib.focal_error_pct.is_some(), "{id}");
    assert_eq!(
        c.focal_error_pct.to_bits(),
        lib.focal_error_pct.unwrap_or(0.0).to_bits(),
        "{id}: focal_error_pct"
    );
    // The estimated camera, and the focal length when it was unknown.
    let mut params = [0.0; EOPNP_MAX_CAMERA_PARAMS];
    let n = s.camera.map_or(0, |cam| cam.params().len());
    if let Some(cam) = &s.camera {
        params[..n].copy_from_slice(cam.params());
    }
    assert_eq!(c.solution.camera_estimated, s.camera.is_some(), "{id}");
    assert_eq!(c.solution.camera_n_params as usize, n, "{id}");
    assert_eq!(bits(&c.solution.camera_params), bits(&params), "{id}");
    assert_eq!(c.solution.focal_estimated, focal_free, "{id}");
    let (fx, fy) = match (&s.camera, focal_free) {
        (Some(cam), true) => cam.focal_lengths(),
        _ => (0.0, 0.0),
    };
    assert_eq!(
        (c.solution.focal_x.to_bits(), c.solution.focal_y.to_bits()),
        (fx.to_bits(), fy.to_bits()),
        "{id}: focal"
    );
}

/// Every field but the times equal, floats bit for bit.
fn assert_same(a: &EopnpRegistration, b: &EopnpRegistration) {
    let (mut a, mut b) = (*a, *b);
    a.micros = 0.0;
    b.micros = 0.0;
    a.ransac.micros = 0.0;
    b.ransac.micros = 0.0;
    // The floats that matter bit for bit (`PartialEq` takes -0 for 0), then every field.
    let fields = |r: &EopnpRegistration| {
        let mut v = vec![
            r.rotation_error_deg,
            r.translation_error_pct,
            r.rmse_px,
            r.model_rmse_px,
            r.focal_error_pct,
            r.solution.cost,
            r.solution.reprojection_rmse,
            r.solution.focal_x,
            r.solution.focal_y,
            r.ransac.inlier_ratio,
        ];
        v.extend(r.solution.rotation);
        v.extend(r.solution.translation);
        v.extend(r.solution.camera_params);
        bits(&v)
    };
    assert_eq!(fields(&a), fields(&b), "image {}", a.image_id);
    assert_eq!(a, b, "image {}", a.image_id);
}

struct Handles {
    model: *mut EopnpModel,
    solver: *mut EopnpSolver,
    ransac: *mut EopnpRansac,
    lib: Model,
    ids: Vec<u32>,
}

impl Handles {
    fn new() -> Self {
        let dir = boxes();
        let lib = read_model(&dir, &ReadOptions::default()).unwrap();
        let ids: Vec<u32> = lib.images.keys().copied().collect();
        let path = CString::new(dir.to_str().unwrap()).unwrap();
        let (mut model, mut solver, mut ransac) =
            (ptr::null_mut(), ptr::null_mut(), ptr::null_mut());
        // SAFETY: a NUL-terminated path, valid out-pointers.
        unsafe {
            assert_eq!(
                eopnp_model_read(path.as_ptr(), &mut model),
                EopnpStatus::EOPNP_OK
            );
            assert_eq!(eopnp_solver_create(&mut solver), EopnpStatus::EOPNP_OK);
            assert_eq!(eopnp_ransac_create(&mut ransac), EopnpStatus::EOPNP_OK);
        }
        assert_eq!(ids.len(), 6);
        Handles {
            model,
            solver,
            ransac,
            lib,
            ids,
        }
    }

    fn ransac(&self, with: bool) -> *const EopnpRansac {
        if with {
            self.ransac
        } else {
            ptr::null()
        }
    }

    /// One image through `eopnp_model_register_with`.
    fn register(
        &self,
        id: u32,
        ransac: bool,
        free: *const EopnpFreeIntrinsics,
    ) -> (EopnpStatus, EopnpRegistration) {
        let mut out = garbage();
        // SAFETY: live handles, `free` NULL or a live struct, a writable out.
        let status = unsafe {
            eopnp_model_register_with(
                self.model,
                id,
                self.solver,
                self.ransac(ransac),
                free,
                &mut out,
            )
        };
        (status, out)
    }

    /// The images `ids` through `eopnp_model_register_batch_with` on 3 threads.
    fn batch(
        &self,
        ids: &[u32],
        ransac: bool,
        free: *const EopnpFreeIntrinsics,
    ) -> (EopnpStatus, Vec<EopnpRegistration>, Vec<EopnpStatus>) {
        let mut out = vec![garbage(); ids.len()];
        let mut statuses = vec![EopnpStatus::EOPNP_PANIC; ids.len()];
        // SAFETY: live handles; `ids.len()` ids, registrations and statuses.
        let status = unsafe {
            eopnp_model_register_batch_with(
                self.model,
                ids.as_ptr(),
                ids.len(),
                self.solver,
                self.ransac(ransac),
                free,
                3,
                out.as_mut_ptr(),
                statuses.as_mut_ptr(),
            )
        };
        (status, out, statuses)
    }

    /// The library's registration of `id` with the intrinsics `f`.
    fn librarys(&self, id: u32, ransac: bool, f: &EopnpFreeIntrinsics) -> Registration {
        let r = Ransac::default();
        register_image_with(
            &self.lib,
            id,
            &Solver::default(),
            ransac.then_some(&r),
            |p| apply(f, p),
        )
        .unwrap()
    }
}

impl Drop for Handles {
    fn drop(&mut self) {
        // SAFETY: handles made by `new`, freed once.
        unsafe {
            eopnp_ransac_free(self.ransac);
            eopnp_solver_free(self.solver);
            eopnp_model_free(self.model);
        }
    }
}

#[test]
fn unknown_focal_registration_is_the_librarys_for_every_image() {
    let h = Handles::new();
    let f = intrinsics(true, (0.0, 0.0), false, false);
    for &id in &h.ids {
        for ransac in [false, true] {
            let (status, c) = h.register(id, ransac, &f);
            assert_eq!(status, EopnpStatus::EOPNP_OK, "{id}: {}", message());
            let lib = h.librarys(id, ransac, &f);
            assert_librarys(&c, &lib, true);
            // The bundled model's focal lengths, found again from the model's own.
            assert!(
                c.has_focal_error && c.focal_error_pct < 0.01,
                "{id}: {}",
                c.focal_error_pct
            );
            assert!(
                c.rotation_error_deg < 0.01,
                "{id}: {}",
                c.rotation_error_deg
            );
            // focal_x is the camera's first parameter (SIMPLE_RADIAL: f, cx, cy, k).
            assert_eq!(c.solution.camera_n_params, 4);
            assert_eq!(
                c.solution.focal_x.to_bits(),
                c.solution.camera_params[0].to_bits()
            );
            let model_f = h.lib.cameras[&h.lib.images[&id].camera_id]
                .focal_lengths()
                .0;
            let pct = 100.0 * (c.solution.focal_x - model_f).abs() / model_f;
            assert_eq!(pct.to_bits(), c.focal_error_pct.to_bits(), "{id}");
        }
    }
}

#[test]
fn a_focal_range_and_refined_intrinsics_are_the_librarys() {
    let h = Handles::new();
    let cases = [
        intrinsics(true, (900.0, 2500.0), false, false),
        intrinsics(false, (0.0, 0.0), false, true),
        intrinsics(false, (0.0, 0.0), true, false),
        intrinsics(true, (0.0, 0.0), true, true),
    ];
    for f in &cases {
        for &id in &h.ids {
            let (status, c) = h.register(id, false, f);
            assert_eq!(status, EopnpStatus::EOPNP_OK, "{f:?} {id}: {}", message());
            let lib = h.librarys(id, false, f);
            assert_librarys(&c, &lib, f.unknown_focal);
            assert!(
                c.solution.camera_estimated && c.has_focal_error,
                "{f:?} {id}"
            );
            if !f.unknown_focal {
                // The focal length known: the model camera's, bit for bit, its error 0.
                let cam = h.lib.cameras[&h.lib.images[&id].camera_id];
                assert_eq!(
                    c.solution.camera_params[0].to_bits(),
                    cam.params()[0].to_bits()
                );
                assert_eq!(c.focal_error_pct, 0.0, "{f:?} {id}");
                assert!(!c.solution.focal_estimated && c.solution.focal_x == 0.0);
            }
        }
    }
}

#[test]
fn the_batch_is_one_image_at_a_time() {
    let h = Handles::new();
    let cases = [
        intrinsics(true, (0.0, 0.0), false, false),
        intrinsics(false, (0.0, 0.0), false, true),
    ];
    for f in &cases {
        for ransac in [false, true] {
            let (status, out, statuses) = h.batch(&h.ids, ransac, f);
            assert_eq!(status, EopnpStatus::EOPNP_OK, "{}", message());
            for (i, &id) in h.ids.iter().enumerate() {
                assert_eq!(statuses[i], EopnpStatus::EOPNP_OK);
                let (status, one) = h.register(id, ransac, f);
                assert_eq!(status, EopnpStatus::EOPNP_OK, "{}", message());
                assert_same(&out[i], &one);
                assert_librarys(&out[i], &h.librarys(id, ransac, f), f.unknown_focal);
            }
        }
    }
    // An unknown image among them: its own status, the others registered.
    let with_bad = [h.ids[0], 4242, h.ids[1]];
    let f = intrinsics(true, (0.0, 0.0), false, false);
    let (status, out, statuses) = h.batch(&with_bad, false, &f);
    assert_eq!(status, EopnpStatus::EOPNP_REGISTER_ERROR);
    assert!(message().starts_with("problem 1: "), "{}", message());
    assert_eq!(
        statuses,
        [
            EopnpStatus::EOPNP_OK,
            EopnpStatus::EOPNP_REGISTER_ERROR,
            EopnpStatus::EOPNP_OK
        ]
    );
    assert_same(&out[2], &h.register(h.ids[1], false, &f).1);
}

#[test]
fn no_free_intrinsics_is_plain_registration() {
    let h = Handles::new();
    let zero = EopnpFreeIntrinsics::default();
    assert_eq!(zero, intrinsics(false, (0.0, 0.0), false, false));
    for ransac in [false, true] {
        for &id in &h.ids {
            let mut plain = garbage();
            // SAFETY: live handles, a writable out.
            let status = unsafe {
                eopnp_model_register(h.model, id, h.solver, h.ransac(ransac), &mut plain)
            };
            assert_eq!(status, EopnpStatus::EOPNP_OK, "{}", message());
            assert!(!plain.has_focal_error && plain.focal_error_pct == 0.0);
            assert!(!plain.solution.camera_estimated && !plain.solution.focal_estimated);
            for free in [ptr::null(), &zero as *const EopnpFreeIntrinsics] {
                let (status, with) = h.register(id, ransac, free);
                assert_eq!(status, EopnpStatus::EOPNP_OK, "{}", message());
                assert_same(&with, &plain);
            }
            let lib = h.librarys(id, ransac, &zero);
            assert_librarys(&plain, &lib, false);
        }
        // The batches: NULL and all-zero intrinsics, and the batch without them.
        let mut out = vec![garbage(); h.ids.len()];
        let mut statuses = vec![EopnpStatus::EOPNP_PANIC; h.ids.len()];
        // SAFETY: live handles; 6 ids, registrations and statuses.
        let status = unsafe {
            eopnp_model_register_batch(
                h.model,
                h.ids.as_ptr(),
                h.ids.len(),
                h.solver,
                h.ransac(ransac),
                2,
                out.as_mut_ptr(),
                statuses.as_mut_ptr(),
            )
        };
        assert_eq!(status, EopnpStatus::EOPNP_OK, "{}", message());
        for free in [ptr::null(), &zero as *const EopnpFreeIntrinsics] {
            let (status, with, _) = h.batch(&h.ids, ransac, free);
            assert_eq!(status, EopnpStatus::EOPNP_OK, "{}", message());
            for (a, b) in with.iter().zip(&out) {
                assert_same(a, b);
            }
        }
    }
}

#[test]
fn bad_intrinsics_have_their_status_and_message() {
    let h = Handles::new();
    let id = h.ids[0];
    let check = |f: &EopnpFreeIntrinsics, want: EopnpStatus, needle: &str| {
        let (status, _) = h.register(id, false, f);
        assert_eq!(status, want, "{f:?}: {}", message());
        let msg = message();
        assert!(msg.contains(needle), "{f:?}: `{needle}` not in {msg}");
        let mut info: EopnpErrorInfo = unsafe { std::mem::zeroed() };
        // SAFETY: a writable info.
        unsafe { eopnp_last_error(&mut info) };
        assert_eq!(info.status, want);
    };
    // A bad range: the library's InvalidOption("unknown_focal"), as for a problem.
    for (lo, hi) in [
        (2000.0, 1000.0),
        (1000.0, 1000.0),
        (0.0, 1000.0),
        (-5.0, 1000.0),
        (1000.0, f64::INFINITY),
        (f64::NAN, 1000.0),
    ] {
        check(
            &intrinsics(true, (lo, hi), false, false),
            EopnpStatus::EOPNP_INVALID_OPTION,
            "within a range 0 < min < max",
        );
    }
    // A range without the unknown focal length: EopnpProblem's argument error.
    check(
        &intrinsics(false, (500.0, 2000.0), false, true),
        EopnpStatus::EOPNP_INVALID_ARGUMENT,
        "`focal_min_px`/`focal_max_px` are set without `unknown_focal`",
    );
    // The same through a problem: the one check, the same message.
    let mut p: EopnpProblem = unsafe { std::mem::zeroed() };
    let (w, m) = ([0.0; 12], [0.0; 8]);
    p.n = 4;
    p.world = w.as_ptr();
    p.image = m.as_ptr();
    p.focal_min_px = 500.0;
    p.focal_max_px = 2000.0;
    let mut s: EopnpSolution = unsafe { std::mem::zeroed() };
    // SAFETY: a live solver, 4 points.
    let status = unsafe { eopnp_solve(h.solver, &p, &mut s) };
    assert_eq!(status, EopnpStatus::EOPNP_INVALID_ARGUMENT);
    assert_eq!(
        message(),
        "`focal_min_px`/`focal_max_px` are set without `unknown_focal`"
    );
    // A misaligned struct.
    let bytes = [0u8; std::mem::size_of::<EopnpFreeIntrinsics>() + 8];
    let odd = bytes[1..].as_ptr().cast::<EopnpFreeIntrinsics>();
    let (status, _) = h.register(id, false, odd);
    assert_eq!(status, EopnpStatus::EOPNP_INVALID_ARGUMENT, "{}", message());
    assert!(message().contains("`intrinsics`"), "{}", message());
    // An unknown image, NULL handles.
    let f = intrinsics(true, (0.0, 0.0), false, false);
    assert_eq!(
        h.register(4242, false, &f).0,
        EopnpStatus::EOPNP_REGISTER_ERROR
    );
    let mut out = garbage();
    // SAFETY: NULL handles are reported, not read.
    unsafe {
        assert_eq!(
            eopnp_model_register_with(ptr::null(), id, h.solver, ptr::null(), &f, &mut out),
            EopnpStatus::EOPNP_NULL_POINTER
        );
        assert_eq!(
            eopnp_model_register_with(h.model, id, ptr::null(), ptr::null(), &f, &mut out),
            EopnpStatus::EOPNP_NULL_POINTER
        );
        assert_eq!(
            eopnp_model_register_with(h.model, id, h.solver, ptr::null(), &f, ptr::null_mut()),
            EopnpStatus::EOPNP_NULL_POINTER
        );
    }
    // The batch: a bad range is each image's status; a range without the option fails the
    // call before any image (no status written).
    let bad = intrinsics(true, (2000.0, 1000.0), false, false);
    let (status, _, statuses) = h.batch(&h.ids, false, &bad);
    assert_eq!(status, EopnpStatus::EOPNP_INVALID_OPTION);
    assert!(message().starts_with("problem 0: "), "{}", message());
    assert!(statuses
        .iter()
        .all(|s| *s == EopnpStatus::EOPNP_INVALID_OPTION));
    let stray = intrinsics(false, (500.0, 2000.0), false, false);
    let (status, _, statuses) = h.batch(&h.ids, true, &stray);
    assert_eq!(status, EopnpStatus::EOPNP_INVALID_ARGUMENT);
    assert!(
        message().contains("without `unknown_focal`"),
        "{}",
        message()
    );
    assert!(statuses.iter().all(|s| *s == EopnpStatus::EOPNP_PANIC));
    // SAFETY: NULL arrays are reported, not read.
    let status = unsafe {
        eopnp_model_register_batch_with(
            h.model,
            ptr::null(),
            6,
            h.solver,
            ptr::null(),
            &f,
            1,
            ptr::null_mut(),
            ptr::null_mut(),
        )
    };
    assert_eq!(status, EopnpStatus::EOPNP_NULL_POINTER);
}
