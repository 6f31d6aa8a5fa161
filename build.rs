//! Puts the generated kernels into `OUT_DIR`, where `src/kernels.rs` includes them.
//!
//! - Default: copies the committed, reviewed copy in `generated/` (no symbolic algebra, no
//!   codegen dependencies: what a user of the published crate builds).
//! - Feature `regenerate`: renders every kernel of `eopnp_codegen::KERNELS` from the symbolic
//!   definitions instead (the workspace's test suite turns it on through `eopnp-verify`).
//!
//! Either way `tests/generated_fresh.rs` proves `generated/` byte-identical to a fresh
//! rendering; refresh it with `cargo run -p eopnp-codegen -- emit generated`.

use std::path::{Path, PathBuf};

fn main() {
    let out = PathBuf::from(std::env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    println!("cargo:rerun-if-changed=build.rs");
    let kernels = kernels();
    for (name, source) in &kernels {
        write_if_changed(&out.join(name), source)
            .unwrap_or_else(|e| panic!("cannot write {name} to OUT_DIR: {e}"));
    }
    // A kernel removed since the last run leaves no stale copy behind.
    for entry in std::fs::read_dir(&out).expect("OUT_DIR").flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        if name.ends_with(".rs") && !kernels.iter().any(|(n, _)| *n == name) {
            std::fs::remove_file(entry.path())
                .unwrap_or_else(|e| panic!("cannot remove {name} from OUT_DIR: {e}"));
        }
    }
}

/// Renders every kernel from the symbolic definitions. Edits to the codegen crate rebuild it
/// and rerun this script; nothing else is read.
#[cfg(feature = "regenerate")]
fn kernels() -> Vec<(String, String)> {
    eopnp_codegen::render_all()
}

/// The committed copy: every `generated/*.rs`.
#[cfg(not(feature = "regenerate"))]
fn kernels() -> Vec<(String, String)> {
    let root = std::env::var_os("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR");
    let dir = Path::new(&root).join("generated");
    // A directory: cargo reruns this script when any file under it changes.
    println!("cargo:rerun-if-changed=generated");
    let entries =
        std::fs::read_dir(&dir).unwrap_or_else(|e| panic!("cannot read {}: {e}", dir.display()));
    let mut files = Vec::new();
    for entry in entries {
        let path = entry.expect("generated/ entry").path();
        let Some(name) = path.file_name().and_then(|n| n.to_str()) else {
            continue;
        };
        if name.ends_with(".rs") {
            let source = std::fs::read_to_string(&path)
                .unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
            files.push((name.to_owned(), source));
        }
    }
    files.sort();
    assert!(!files.is_empty(), "no kernels in {}", dir.display());
    files
}

/// Writes `contents` to `path` unless it already holds exactly those bytes (no spurious
/// rebuilds of the crate).
fn write_if_changed(path: &Path, contents: &str) -> std::io::Result<()> {
    if std::fs::read_to_string(path).ok().as_deref() == Some(contents) {
        return Ok(());
    }
    std::fs::write(path, contents)
}
