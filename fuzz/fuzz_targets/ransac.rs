//! `cargo +nightly fuzz run ransac`: see `eopnp_fuzz::ransac` for the input layout and properties.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| eopnp_fuzz::ransac(data));
