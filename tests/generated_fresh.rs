//! The committed copy of the generated kernels (`generated/`) is exactly what the build compiles
//! (`OUT_DIR`). Two builds of the same source produce the same bytes, so a mismatch means the
//! committed copy is stale: refresh it with `cargo run -p eopnp-codegen -- emit generated`.

use std::path::Path;

#[test]
fn committed_generated_code_is_fresh() {
    let out = Path::new(env!("OUT_DIR"));
    let committed = Path::new(env!("CARGO_MANIFEST_DIR")).join("generated");
    let mut names: Vec<_> = std::fs::read_dir(out)
        .expect("OUT_DIR")
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".rs"))
        .collect();
    names.sort();
    assert!(names.len() >= 15, "build.rs wrote {} files", names.len());
    let mut stale = Vec::new();
    for n in &names {
        let built = std::fs::read_to_string(out.join(n)).expect("built file");
        let copy = std::fs::read_to_string(committed.join(n)).unwrap_or_default();
        if built != copy {
            stale.push(n.clone());
        }
    }
    let mut extra: Vec<_> = std::fs::read_dir(&committed)
        .map(|d| {
            d.filter_map(|e| e.ok())
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .filter(|n| n.ends_with(".rs") && !names.contains(n))
                .collect()
        })
        .unwrap_or_default();
    stale.append(&mut extra);
    assert!(
        stale.is_empty(),
        "generated/ is stale ({stale:?}); run `cargo run -p eopnp-codegen -- emit generated`"
    );
}
