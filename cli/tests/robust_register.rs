//! The outlier experiment of the README, run as the README runs it:
//! `eopnp register data/colmap-boxes --ransac --threshold 4 --outliers F --seed 42 --json`
//! for F = 0, 0.5 and 0.8. A fraction F of each image's correspondences is replaced by wrong 3D
//! points (random cloud points plus 0.5-unit Gaussian noise). Every image must be registered,
//! and the worst and the median rotation and translation errors must stay within 1.25x of the
//! floor (EOPnP on the true correspondences alone, reported by the same command).

use std::path::PathBuf;
use std::process::Command;

/// (rotation, translation) errors of every image, and of the floor of every image.
type Errors = (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>);

fn run(fraction: f64) -> Errors {
    let model = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../data/colmap-boxes");
    let out = Command::new(env!("CARGO_BIN_EXE_eopnp"))
        .arg("register")
        .arg(&model)
        .args(["--ransac", "--threshold", "4", "--seed", "42", "--json"])
        .args(["--outliers", &fraction.to_string()])
        .output()
        .expect("run eopnp");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON output");
    let images = v["images"].as_array().expect("images");
    assert_eq!(images.len(), 6, "every image of the bundled model");
    let (mut r, mut t, mut fr, mut ft) = (vec![], vec![], vec![], vec![]);
    for img in images {
        assert!(img.get("error").is_none(), "{fraction}: {img}");
        let f = |k: &str| img[k].as_f64().unwrap_or_else(|| panic!("{k} in {img}"));
        let floor = &img["robust"]["floor"];
        let g = |k: &str| {
            floor[k]
                .as_f64()
                .unwrap_or_else(|| panic!("floor {k} in {img}"))
        };
        eprintln!(
            "  {fraction:.2} image {}: n {} inliers {} (true {}) rot {:.5} (floor {:.5}) trans \
             {:.5} (floor {:.5})",
            img["image_id"],
            img["n"],
            img["inliers"],
            img["robust"]["true_inliers"],
            f("rotation_error_deg"),
            g("rotation_error_deg"),
            f("translation_error_pct"),
            g("translation_error_pct"),
        );
        r.push(f("rotation_error_deg"));
        t.push(f("translation_error_pct"));
        fr.push(g("rotation_error_deg"));
        ft.push(g("translation_error_pct"));
    }
    (r, t, fr, ft)
}

fn worst(v: &[f64]) -> f64 {
    v.iter().copied().fold(0.0, f64::max)
}

fn median(v: &[f64]) -> f64 {
    let mut v = v.to_vec();
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

#[test]
fn robust_registration_reaches_the_floor() {
    for fraction in [0.0, 0.5, 0.8] {
        let (r, t, fr, ft) = run(fraction);
        eprintln!(
            "outliers {:>3.0} %: rot worst {:.5} median {:.5} (floor {:.5} / {:.5}); trans % \
             worst {:.5} median {:.5} (floor {:.5} / {:.5})",
            fraction * 100.0,
            worst(&r),
            median(&r),
            worst(&fr),
            median(&fr),
            worst(&t),
            median(&t),
            worst(&ft),
            median(&ft),
        );
        // Within 1.25x of the floor (maximum likelihood on the true correspondences), per
        // level, for the worst and the median image.
        let bound = 1.25;
        assert!(
            worst(&r) <= bound * worst(&fr),
            "{fraction}: worst rotation"
        );
        assert!(
            median(&r) <= bound * median(&fr),
            "{fraction}: median rotation"
        );
        assert!(
            worst(&t) <= bound * worst(&ft),
            "{fraction}: worst translation"
        );
        assert!(
            median(&t) <= bound * median(&ft),
            "{fraction}: median translation"
        );
    }
}

#[test]
fn the_same_seed_gives_the_same_output() {
    let a = run(0.8);
    let b = run(0.8);
    assert_eq!(a, b);
}
