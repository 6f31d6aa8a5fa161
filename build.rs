//! Renders every kernel of `eopnp_codegen::KERNELS` into `OUT_DIR` (see `src/kernels.rs`).
//! The committed copy in `generated/` must be byte-identical (`tests/generated_fresh.rs`);
//! refresh it with `cargo run -p eopnp-codegen -- emit generated`.

use std::path::PathBuf;

fn main() {
    let out = PathBuf::from(std::env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    for (name, source) in eopnp_codegen::render_all() {
        eopnp_codegen::write_if_changed(&out.join(&name), &source)
            .unwrap_or_else(|e| panic!("cannot write {name}: {e}"));
    }
    // Edits to the codegen crate rebuild it and rerun this script; nothing else is read.
    println!("cargo:rerun-if-changed=build.rs");
}
