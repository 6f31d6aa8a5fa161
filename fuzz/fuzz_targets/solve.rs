//! `cargo +nightly fuzz run solve`: see `eopnp_fuzz::solve` for the input layout and properties.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| eopnp_fuzz::solve(data));
