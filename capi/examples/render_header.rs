//! Renders `include/eopnp.h` from this crate's sources with cbindgen (`cbindgen.toml`):
//! `cargo run -p eopnp-capi --example render_header`. `tests/header_fresh.rs` checks that the
//! committed header is what this prints.

use std::path::Path;

fn main() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let text = eopnp_capi_header::render(dir);
    let path = dir.join("include/eopnp.h");
    // Atomically: a temporary file beside the header, then a rename.
    let tmp = dir.join("include/.eopnp.h.tmp");
    std::fs::write(&tmp, &text).expect("write the temporary header");
    std::fs::rename(&tmp, &path).expect("rename the temporary header");
    println!("wrote {}", path.display());
}

#[path = "../tests/support/header.rs"]
mod eopnp_capi_header;
