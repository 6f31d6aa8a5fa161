//! The committed `include/eopnp.h` (what C and C++ compile against, and what the CMake package
//! installs) is byte-identical to a fresh cbindgen rendering of `src/`. A mismatch means it is
//! stale: refresh it with `cargo run -p eopnp-capi --example render_header`.

#[path = "support/header.rs"]
mod header;

#[test]
fn committed_header_is_fresh() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let fresh = header::render(dir);
    let committed =
        std::fs::read_to_string(dir.join("include/eopnp.h")).expect("read include/eopnp.h");
    if fresh != committed {
        let line = fresh
            .lines()
            .zip(committed.lines())
            .position(|(a, b)| a != b)
            .map_or_else(|| "the length".to_owned(), |i| format!("line {}", i + 1));
        panic!(
            "capi/include/eopnp.h is stale (first difference at {line}): refresh it with \
             `cargo run -p eopnp-capi --example render_header`"
        );
    }
}
