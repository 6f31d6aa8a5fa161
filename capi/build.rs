//! Gives the shared library an ELF SONAME (`libeopnp_capi.so`), so that programs linked against
//! the installed library find it by name (the CMake package's imported target records it).

fn main() {
    let os = std::env::var("CARGO_CFG_TARGET_OS").unwrap_or_default();
    if os == "linux" || os == "android" || os.ends_with("bsd") {
        println!("cargo:rustc-cdylib-link-arg=-Wl,-soname,libeopnp_capi.so");
    }
    println!("cargo:rerun-if-changed=build.rs");
}
