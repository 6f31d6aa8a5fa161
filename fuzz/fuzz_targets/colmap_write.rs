//! `cargo +nightly fuzz run colmap_write`: see `eopnp_fuzz::colmap_write` for the input layout and properties.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| eopnp_fuzz::colmap_write(data));
