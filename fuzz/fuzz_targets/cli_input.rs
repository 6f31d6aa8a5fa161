//! `cargo +nightly fuzz run cli_input`: see `eopnp_fuzz::cli_input` for the input layout and properties.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| eopnp_fuzz::cli_input(data));
