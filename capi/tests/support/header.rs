//! The rendering of `include/eopnp.h` (shared by `tests/header_fresh.rs` and
//! `examples/render_header.rs`).

use std::path::Path;

/// The header cbindgen renders from the crate at `dir` with its `cbindgen.toml`.
pub fn render(dir: &Path) -> String {
    let config =
        cbindgen::Config::from_file(dir.join("cbindgen.toml")).expect("read cbindgen.toml");
    let bindings = cbindgen::Builder::new()
        .with_crate(dir)
        .with_config(config)
        .generate()
        .expect("cbindgen renders the header");
    let mut out = Vec::new();
    bindings.write(&mut out);
    String::from_utf8(out).expect("UTF-8 header")
}
