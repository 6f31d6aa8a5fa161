//! Audit command for the generated kernels.
//!
//! ```text
//! cargo run -p eopnp-codegen -- emit DIR     # write every generated file into DIR (what build.rs writes)
//! cargo run -p eopnp-codegen -- check DIR    # exit 1 if DIR differs from a fresh rendering
//! cargo run -p eopnp-codegen -- list         # kernels with term and op counts
//! cargo run -p eopnp-codegen -- show NAME    # print one generated file
//! ```

use std::path::Path;
use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args
        .iter()
        .map(String::as_str)
        .collect::<Vec<_>>()
        .as_slice()
    {
        ["emit", dir] => {
            let dir = Path::new(dir);
            if let Err(e) = std::fs::create_dir_all(dir) {
                eprintln!("cannot create {}: {e}", dir.display());
                return ExitCode::FAILURE;
            }
            for (name, src) in eopnp_codegen::render_all() {
                match eopnp_codegen::write_if_changed(&dir.join(&name), &src) {
                    Ok(true) => println!("wrote {}", dir.join(&name).display()),
                    Ok(false) => println!("unchanged {}", dir.join(&name).display()),
                    Err(e) => {
                        eprintln!("cannot write {name}: {e}");
                        return ExitCode::FAILURE;
                    }
                }
            }
            ExitCode::SUCCESS
        }
        ["check", dir] => {
            let mut stale = 0;
            for (name, src) in eopnp_codegen::render_all() {
                let path = Path::new(dir).join(&name);
                if std::fs::read_to_string(&path).ok().as_deref() != Some(src.as_str()) {
                    eprintln!("stale: {}", path.display());
                    stale += 1;
                }
            }
            if stale > 0 {
                eprintln!("refresh with: cargo run -p eopnp-codegen -- emit {dir}");
                ExitCode::FAILURE
            } else {
                println!("all generated files in {dir} are fresh");
                ExitCode::SUCCESS
            }
        }
        ["list"] => {
            println!(
                "{:<26} {:>8} {:>9} {:>9} {:>11} {:>11}",
                "kernel", "terms", "cse mul", "cse add", "naive mul", "naive add"
            );
            for (_, def) in eopnp_codegen::KERNELS {
                let k = def();
                let e = eopnp_codegen::emit::emit(&k);
                println!(
                    "{:<26} {:>8} {:>9} {:>9} {:>11} {:>11}",
                    k.name, e.naive_terms, e.ops.mul, e.ops.add, e.naive.mul, e.naive.add
                );
            }
            ExitCode::SUCCESS
        }
        ["show", name] => match eopnp_codegen::KERNELS.iter().find(|(n, _)| n == name) {
            Some((_, def)) => {
                print!("{}", eopnp_codegen::emit::emit(&def()).source);
                ExitCode::SUCCESS
            }
            None => {
                eprintln!("unknown kernel {name}; see `list`");
                ExitCode::FAILURE
            }
        },
        _ => {
            eprintln!("usage: eopnp-codegen (emit DIR | check DIR | list | show NAME)");
            ExitCode::FAILURE
        }
    }
}
