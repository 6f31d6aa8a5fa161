//! `cargo run -p eopnp-verify --release`: runs every check of `eopnp_verify::checks` and
//! `eopnp_verify::camera` and prints
//! a Markdown table (kernel | check | samples | worst error (norm) | bound | worst/bound | ops
//! after CSE | naive ops (terms)). Exits with status 1 if any check fails.

fn main() {
    let mut ms = eopnp_verify::checks::all();
    ms.extend(eopnp_verify::camera::all(eopnp_verify::camera::N_CAMERA));
    print!("{}", eopnp_verify::report::table(&ms));
    let failed: Vec<_> = ms.iter().filter(|m| !m.passed()).collect();
    if !failed.is_empty() {
        eprintln!();
        for m in &failed {
            eprintln!(
                "FAILED {} ({}): worst error/bound {:.3e} at {}",
                m.kernel, m.check, m.worst_ratio, m.worst_input
            );
        }
        std::process::exit(1);
    }
}
