//! The committed copy of the generated kernels (`generated/`) is what the package ships and
//! (without feature `regenerate`) what `build.rs` compiles. Two checks, both with every file
//! compared both ways (no stale, no missing, no extra file):
//!
//! - `generated/` is byte-identical to a fresh rendering of the symbolic definitions
//!   (`eopnp_codegen::render_all()`, a dev-dependency), whatever features this build has;
//! - `OUT_DIR` (what this build compiled: rendered with `regenerate`, copied without) is
//!   byte-identical to `generated/`.
//!
//! A mismatch means the committed copy is stale: refresh it with
//! `cargo run -p eopnp-codegen -- emit generated`.

use std::collections::BTreeMap;
use std::path::Path;

const REFRESH: &str = "refresh with `cargo run -p eopnp-codegen -- emit generated`";

/// Every file of `dir` whose name passes `keep`: name -> contents.
fn read_dir(dir: &Path, keep: impl Fn(&str) -> bool) -> BTreeMap<String, String> {
    std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", dir.display()))
        .map(|e| e.expect("directory entry").path())
        .filter(|p| p.is_file())
        .filter_map(|p| {
            let name = p.file_name()?.to_str()?.to_owned();
            keep(&name).then(|| {
                let text = std::fs::read_to_string(&p)
                    .unwrap_or_else(|e| panic!("cannot read {}: {e}", p.display()));
                (name, text)
            })
        })
        .collect()
}

fn committed() -> BTreeMap<String, String> {
    // Every file: anything in `generated/` that no rendering produces is an error.
    read_dir(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("generated"),
        |_| true,
    )
}

/// The files of `expected` that `actual` lacks or holds with other bytes, and the files of
/// `actual` that `expected` lacks.
fn differences(
    expected: &BTreeMap<String, String>,
    actual: &BTreeMap<String, String>,
) -> (Vec<String>, Vec<String>, Vec<String>) {
    let mut stale = Vec::new();
    let mut missing = Vec::new();
    for (name, text) in expected {
        match actual.get(name) {
            None => missing.push(name.clone()),
            Some(t) if t != text => stale.push(name.clone()),
            Some(_) => {}
        }
    }
    let extra = actual
        .keys()
        .filter(|n| !expected.contains_key(*n))
        .cloned()
        .collect();
    (stale, missing, extra)
}

#[test]
fn committed_generated_code_matches_a_fresh_rendering() {
    let rendered: BTreeMap<String, String> = eopnp_codegen::render_all().into_iter().collect();
    assert!(
        rendered.len() >= 16,
        "render_all gave {} files",
        rendered.len()
    );
    let (stale, missing, extra) = differences(&rendered, &committed());
    assert!(
        stale.is_empty() && missing.is_empty() && extra.is_empty(),
        "generated/ differs from a fresh rendering: stale {stale:?}, missing {missing:?}, \
         extra {extra:?}; {REFRESH}"
    );
}

#[test]
fn compiled_generated_code_is_the_committed_copy() {
    let built = read_dir(Path::new(env!("OUT_DIR")), |n| n.ends_with(".rs"));
    let how = if cfg!(feature = "regenerate") {
        "rendered by build.rs (feature `regenerate`)"
    } else {
        "copied by build.rs from generated/"
    };
    assert!(
        built.len() >= 16,
        "OUT_DIR holds {} kernels {how}",
        built.len()
    );
    let (stale, missing, extra) = differences(&built, &committed());
    assert!(
        stale.is_empty() && missing.is_empty() && extra.is_empty(),
        "generated/ differs from OUT_DIR ({how}): stale {stale:?}, missing {missing:?}, \
         extra {extra:?}; {REFRESH}"
    );
}
