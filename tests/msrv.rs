//! `rust-version` of eopnp is exactly the highest `rust-version` declared by its locked normal
//! and build dependencies (transitively, all features): not lower (a user's older toolchain
//! would fail in a dependency), not higher (no reason to exclude toolchains the dependencies
//! support). Dev-dependencies do not count: they are not built for users.
//!
//! The graph is `cargo metadata --locked --offline --all-features`, filtered to the host
//! platform: offline, only the host's platform-specific crates are guaranteed to be in the local
//! cache, and `cargo metadata` needs the manifest of every package it reports.

use serde_json::Value;
use std::collections::{BTreeSet, HashMap};
use std::process::Command;

/// `"1.89"`, `"1.89.0"` -> `[1, 89, 0]`.
fn parse(v: &str) -> Vec<u64> {
    let mut parts: Vec<u64> = v
        .split('.')
        .map(|p| {
            p.parse()
                .unwrap_or_else(|_| panic!("bad rust-version {v:?}"))
        })
        .collect();
    parts.resize(3, 0);
    parts
}

fn cargo() -> String {
    std::env::var("CARGO").unwrap_or_else(|_| env!("CARGO").to_owned())
}

fn host() -> String {
    let out = Command::new(cargo())
        .arg("-vV")
        .output()
        .expect("run cargo -vV");
    let text = String::from_utf8(out.stdout).expect("utf-8");
    text.lines()
        .find_map(|l| l.strip_prefix("host: "))
        .expect("`cargo -vV` prints the host")
        .trim()
        .to_owned()
}

#[test]
fn rust_version_is_the_highest_of_the_locked_dependencies() {
    let out = Command::new(cargo())
        .args(["metadata", "--format-version", "1", "--locked", "--offline"])
        .args(["--all-features", "--filter-platform", &host()])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("run cargo metadata");
    assert!(
        out.status.success(),
        "cargo metadata failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let meta: Value = serde_json::from_slice(&out.stdout).expect("metadata JSON");

    let packages: HashMap<&str, &Value> = meta["packages"]
        .as_array()
        .expect("packages")
        .iter()
        .map(|p| (p["id"].as_str().expect("id"), p))
        .collect();
    let root = meta["packages"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| {
            p["name"] == "eopnp"
                && p["manifest_path"].as_str().map(std::path::Path::new)
                    == Some(&std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("Cargo.toml"))
        })
        .expect("eopnp in cargo metadata");
    let root_id = root["id"].as_str().unwrap();
    let nodes: HashMap<&str, &Value> = meta["resolve"]["nodes"]
        .as_array()
        .expect("resolve graph (not --no-deps)")
        .iter()
        .map(|n| (n["id"].as_str().unwrap(), n))
        .collect();

    // The normal + build closure of eopnp.
    let mut seen = BTreeSet::new();
    let mut stack = vec![root_id];
    while let Some(id) = stack.pop() {
        for dep in nodes[id]["deps"].as_array().expect("deps") {
            let counts = dep["dep_kinds"]
                .as_array()
                .expect("dep_kinds")
                .iter()
                .any(|k| k["kind"].is_null() || k["kind"] == "build");
            let pkg = dep["pkg"].as_str().unwrap();
            if counts && seen.insert(pkg) {
                stack.push(pkg);
            }
        }
    }
    assert!(
        seen.iter().any(|id| packages[id]["name"] == "nalgebra"),
        "the closure misses nalgebra: {seen:?}"
    );

    let (highest, who) = seen
        .iter()
        .filter_map(|id| {
            let p = packages[id];
            let v = p["rust_version"].as_str()?;
            let name = p["name"].as_str().unwrap_or("?");
            let version = p["version"].as_str().unwrap_or("?");
            Some((parse(v), format!("{name} {version} (rust-version {v})")))
        })
        .max()
        .expect("some dependency declares a rust-version");
    let declared = root["rust_version"]
        .as_str()
        .expect("eopnp declares rust-version");
    assert_eq!(
        parse(declared),
        highest,
        "eopnp's rust-version is {declared}; the highest among its {} locked normal and build \
         dependencies is {who}: set `rust-version` in Cargo.toml to match",
        seen.len()
    );
}
