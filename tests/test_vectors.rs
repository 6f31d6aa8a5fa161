//! The 18 reference problems of the reference prototype (`tests/data/test_vectors.json`),
//! checked as docs/algorithm.md section 8 prescribes.
//!
//! - Algebraic mode (no `refine` stage): noise-free vectors within 1e-9 deg / 1e-9 % of the ground
//!   truth; noisy vectors within 1e-6 deg / 1e-6 % of the stored output (the same local minimum of
//!   the same cost); `cheirality_ok` and `degenerate` equal to the stored flags.
//! - Default mode (with `refine`): within 1e-6 deg of `refine` run from the stored algebraic output
//!   (the reference here is the independent LM of `common`, started at the stored pose).
//! - Intermediates (M, G, Rw, ratio): a unit test of the pipeline (`tests/unit/pipeline/driver.rs`).

// `!(err <= tol)` is deliberate throughout: a NaN error must fail the check.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use eopnp::Problem;
use eopnp_testkit as common;

use common::{lm_refine, rot_err_deg, trans_err_pct, NORMALISED};
use eopnp::{Refinement, Solver};
use nalgebra::{Matrix3, Point2, Point3, SMatrix, Vector3};
use serde_json::Value;

/// One test vector.
struct Tv {
    name: String,
    world: Vec<Point3<f64>>,
    image: Vec<Point2<f64>>,
    r_gt: Matrix3<f64>,
    t_gt: Vector3<f64>,
    r_exp: Matrix3<f64>,
    t_exp: Vector3<f64>,
    cheirality_ok: bool,
    degenerate: bool,
}

impl Tv {
    fn noise_free(&self) -> bool {
        self.name.ends_with("_sigma0")
    }
}

fn num(v: &Value) -> f64 {
    v.as_f64().expect("number")
}

fn mat<const R: usize, const C: usize>(v: &Value) -> SMatrix<f64, R, C> {
    SMatrix::from_fn(|i, j| num(&v[i][j]))
}

fn vec3(v: &Value) -> Vector3<f64> {
    Vector3::new(num(&v[0]), num(&v[1]), num(&v[2]))
}

fn load() -> Vec<Tv> {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/test_vectors.json");
    let text = std::fs::read_to_string(path).expect("tests/data/test_vectors.json");
    let all: Value = serde_json::from_str(&text).expect("valid JSON");
    let tvs: Vec<Tv> = all
        .as_array()
        .expect("array")
        .iter()
        .map(|e| {
            let ex = &e["expected"];
            Tv {
                name: e["name"].as_str().expect("name").to_owned(),
                world: e["P_world"]
                    .as_array()
                    .expect("P_world")
                    .iter()
                    .map(|p| Point3::from(vec3(p)))
                    .collect(),
                image: e["uv"]
                    .as_array()
                    .expect("uv")
                    .iter()
                    .map(|p| Point2::new(num(&p[0]), num(&p[1])))
                    .collect(),
                r_gt: mat(&e["R_gt"]),
                t_gt: vec3(&e["t_gt"]),
                r_exp: mat(&ex["R"]),
                t_exp: vec3(&ex["t"]),
                cheirality_ok: ex["cheirality_ok"].as_bool().expect("cheirality_ok"),
                degenerate: ex["degenerate"].as_bool().expect("degenerate"),
            }
        })
        .collect();
    assert_eq!(tvs.len(), 18, "test_vectors.json holds 18 problems");
    tvs
}

fn pose(s: &eopnp::Solution) -> (Matrix3<f64>, Vector3<f64>) {
    common::pose_of(s)
}

#[test]
fn algebraic_mode_matches_reference() {
    let solver = Solver::default().refinement(Refinement::Algebraic);
    let mut report = Vec::new();
    let mut failures = Vec::new();
    for tv in load() {
        let sol = match solver.solve(&Problem::normalised(&tv.world, &tv.image)) {
            Ok(s) => s,
            Err(e) => {
                failures.push(format!("{}: error {e:?}", tv.name));
                continue;
            }
        };
        let (r, t) = pose(&sol);
        let (er, et, what) = if tv.noise_free() {
            (
                rot_err_deg(&r, &tv.r_gt),
                trans_err_pct(&t, &tv.t_gt),
                "truth",
            )
        } else {
            (
                rot_err_deg(&r, &tv.r_exp),
                trans_err_pct(&t, &tv.t_exp),
                "stored",
            )
        };
        // Noise-free: the reference reaches the truth to <= 5.5e-10 deg (docs/algorithm.md section 7,
        // planar N = 4; typically 1e-13), so 1e-9 deg / 1e-9 % is the section-8 tolerance.
        // Noisy: the same local minimum of the same cost, located to ~1e-8 deg by `newton`'s
        // stopping rules; section 8 prescribes 1e-6 deg / 1e-6 %.
        let (tol_r, tol_t) = if tv.noise_free() {
            (1e-9, 1e-9)
        } else {
            (1e-6, 1e-6)
        };
        report.push(format!(
            "{:22} vs {what:6}: {er:9.2e} deg {et:9.2e} %  cheirality {} degenerate {}",
            tv.name, sol.cheirality_ok, sol.degenerate
        ));
        if !(er <= tol_r && et <= tol_t) {
            failures.push(format!(
                "{}: rotation {er:e} deg (tol {tol_r:e}), translation {et:e} % (tol {tol_t:e}) vs {what}",
                tv.name
            ));
        }
        if sol.cheirality_ok != tv.cheirality_ok || sol.degenerate != tv.degenerate {
            failures.push(format!(
                "{}: flags cheirality_ok {} degenerate {}, expected {} {}",
                tv.name, sol.cheirality_ok, sol.degenerate, tv.cheirality_ok, tv.degenerate
            ));
        }
    }
    eprintln!("algebraic mode:\n{}", report.join("\n"));
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn default_mode_matches_refine_from_expected() {
    let solver = Solver::default();
    let mut report = Vec::new();
    let mut failures = Vec::new();
    for tv in load() {
        let sol = match solver.solve(&Problem::normalised(&tv.world, &tv.image)) {
            Ok(s) => s,
            Err(e) => {
                failures.push(format!("{}: error {e:?}", tv.name));
                continue;
            }
        };
        let (r, t) = pose(&sol);
        // Reference: minimise the same reprojection error (normalised coordinates, isotropic)
        // from the stored algebraic-mode output.
        let lm = lm_refine(&tv.world, &tv.image, &tv.r_exp, &tv.t_exp, NORMALISED);
        let er = rot_err_deg(&r, &lm.r);
        let et = trans_err_pct(&t, &lm.t);
        report.push(format!(
            "{:22} vs `refine`-from-expected: {er:9.2e} deg {et:9.2e} %  (LM {} it)",
            tv.name, lm.iterations
        ));
        // Two correct minimisers of E agree to ~1e-7 deg (E is flat to rounding there;
        // docs/algorithm.md, `refine`), hence section 8's 1e-6 deg. Measured on these 18 vectors:
        // this reference vs reproj_refine.py's `refine` from the same start, <= 1.6e-8 deg and <=
        // 4.2e-9 % (so the 1e-6 % translation tolerance has a 200x margin).
        if !(er <= 1e-6 && et <= 1e-6) {
            failures.push(format!(
                "{}: {er:e} deg, {et:e} % from `refine`-from-expected",
                tv.name
            ));
        }
        if tv.noise_free() {
            let er = rot_err_deg(&r, &tv.r_gt);
            let et = trans_err_pct(&t, &tv.t_gt);
            // `refine` does not move a noise-free exact pose (docs/algorithm.md, `refine`: <=
            // 1.6e-13 deg).
            if !(er <= 1e-9 && et <= 1e-9) {
                failures.push(format!("{}: {er:e} deg, {et:e} % from the truth", tv.name));
            }
        }
        if sol.cheirality_ok != tv.cheirality_ok {
            failures.push(format!("{}: cheirality_ok {}", tv.name, sol.cheirality_ok));
        }
        if !(sol.cost.is_finite() && sol.reprojection_rmse.is_finite()) {
            failures.push(format!("{}: non-finite cost", tv.name));
        }
    }
    eprintln!("default mode:\n{}", report.join("\n"));
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
