//! `cargo +nightly fuzz run colmap_binary`: see `eopnp_fuzz::colmap_binary` for the input layout and properties.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| eopnp_fuzz::colmap_binary(data));
