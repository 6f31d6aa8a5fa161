#!/usr/bin/env bash
# Checks the published form of eopnp, from the repository root:
#
#   1. `cargo package` of eopnp-codegen, eopnp and eopnp-cli together, with verification (each
#      .crate is unpacked and built on its own). Needs cargo >= 1.90: it packages workspace members that
#      depend on each other by path + version before either is on crates.io, through a
#      temporary local registry. Older cargo fails with "no matching package named
#      `eopnp-codegen` found".
#   2. Unpacks target/package/eopnp-<version>.crate into a temporary directory and builds a
#      scratch binary crate outside the workspace that depends on it by path with its default
#      features (what `cargo add eopnp` gives a library user): clean debug and release builds,
#      each with a fresh target directory, run (the binary solves a synthetic problem and
#      asserts the pose), and prints their wall times. Fails if the scratch crate's dependency
#      tree holds a crate of the command line (clap, indicatif, serde, serde_json, csv-core).
#   3. Runs the library's unit tests (the one test target the package keeps; its #[path]
#      modules and data under tests/unit/, tests/data/ ship) in the unpacked package, with
#      eopnp-codegen (a dev-dependency) from its unpacked .crate until it is on crates.io.
#   4. The same scratch crate with feature `regenerate` (eopnp-codegen from its unpacked .crate
#      through [patch.crates-io]): the published feature builds and renders the same kernels.
#      Prints how long the build script runs with and without `regenerate`.
#
# Offline throughout: every registry crate is in the local cache after `cargo test --workspace`
# (run that first; `.ci/run` does). The scratch crates start from eopnp's packaged Cargo.lock,
# so they build the dependency versions that were tested.
#
# Usage: scripts/check_package.sh [--allow-dirty]   (the flag is passed to `cargo package`)
set -euo pipefail
cd "$(dirname "$0")/.."

package_flags=(--offline --locked)
if [[ "${1:-}" == "--allow-dirty" ]]; then
  package_flags+=(--allow-dirty)
elif [[ $# -gt 0 ]]; then
  echo "usage: $0 [--allow-dirty]" >&2
  exit 2
fi

cargo_minor=$(cargo --version | sed -E 's/^cargo 1\.([0-9]+).*/\1/')
if [[ "$cargo_minor" =~ ^[0-9]+$ ]] && ((cargo_minor < 90)); then
  echo "$(cargo --version): packaging eopnp with the unpublished eopnp-codegen needs cargo >= 1.90" >&2
  exit 1
fi

now_ms() {
  if [[ -n "${EPOCHREALTIME:-}" ]]; then # bash >= 5: seconds.microseconds
    local t=${EPOCHREALTIME/[.,]/}
    echo $((10#$t / 1000))
  else
    date +%s%3N
  fi
}
seconds() { awk -v ms="$1" 'BEGIN { printf "%.2f s", ms / 1000 }'; }

target_dir=$(cargo metadata --format-version 1 --no-deps --offline |
  sed -E 's/.*"target_directory":"([^"]*)".*/\1/')
pkgid=$(cargo pkgid --offline -p eopnp)
version=${pkgid##*[#@]}
codegen_pkgid=$(cargo pkgid --offline -p eopnp-codegen)
codegen_version=${codegen_pkgid##*[#@]}

cli_pkgid=$(cargo pkgid --offline -p eopnp-cli)
cli_version=${cli_pkgid##*[#@]}

# Cargo unpacks the temporary registry's crates into $CARGO_HOME/registry/src/-<hash>/ (the
# hash of the registry's path) and reuses an unpacked copy it finds there: a second check from
# a checkout at the same path would verify eopnp-cli against the eopnp of the first. Those
# copies of this workspace's own crates are removed first (only the temporary registries'
# directories, whose names start with "-"; crates.io's are left alone).
cargo_home=${CARGO_HOME:-$HOME/.cargo}
for crate in "eopnp-codegen-$codegen_version" "eopnp-$version" "eopnp-cli-$cli_version"; do
  rm -rf "$cargo_home"/registry/src/-*/"$crate"
done

echo "== cargo package -p eopnp-codegen -p eopnp -p eopnp-cli (verified)"
cargo package "${package_flags[@]}" -p eopnp-codegen -p eopnp -p eopnp-cli
for crate in "eopnp-codegen-$codegen_version" "eopnp-$version" "eopnp-cli-$cli_version"; do
  file="$target_dir/package/$crate.crate"
  echo "$crate.crate: $(wc -c <"$file") bytes, $(tar -tzf "$file" | wc -l) files"
done

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
tar -xzf "$target_dir/package/eopnp-$version.crate" -C "$tmp"
tar -xzf "$target_dir/package/eopnp-codegen-$codegen_version.crate" -C "$tmp"

# scratch_crate DIR EXTRA_DEPENDENCY_KEYS EXTRA_MANIFEST
scratch_crate() {
  mkdir -p "$1/src"
  cat >"$1/Cargo.toml" <<EOF
[package]
name = "eopnp-scratch"
version = "0.0.0"
edition = "2021"
publish = false

[dependencies]
eopnp = { path = "$tmp/eopnp-$version"$2 }
nalgebra = "0.35"

$3
# Not part of any enclosing workspace.
[workspace]
EOF
  cp "$tmp/eopnp-$version/Cargo.lock" "$1/Cargo.lock"
  cat >"$1/src/main.rs" <<'EOF'
use nalgebra::{Point2, Point3, Rotation3, Vector3};

fn main() {
    let rotation = Rotation3::from_euler_angles(0.3, -0.2, 0.5);
    let translation = Vector3::new(0.1, -0.2, 6.0);
    let (mut world, mut image) = (Vec::new(), Vec::new());
    for i in 0..12 {
        let a = f64::from(i);
        let x = Point3::new(2.0 * (1.7 * a).sin(), 1.5 * (0.9 * a).cos(), (2.3 * a).sin());
        let c = rotation * x.coords + translation;
        world.push(x);
        image.push(Point2::new(c.x / c.z, c.y / c.z));
    }
    let sol = eopnp::solve(&world, &image).expect("eopnp::solve");
    let r_err = (sol.rotation - rotation.matrix()).norm();
    let t_err = (sol.translation - translation).norm();
    assert!(r_err < 1e-8 && t_err < 1e-8, "pose error: rotation {r_err:e}, translation {t_err:e}");
    println!("eopnp::solve recovered the pose (rotation error {r_err:.1e}, translation error {t_err:.1e})");
}
EOF
}

# build_and_run DIR PROFILE: a clean build in a fresh target directory, timed, then the binary.
build_and_run() {
  local dir=$1 profile=$2 flags=()
  [[ $profile == release ]] && flags=(--release)
  local start
  start=$(now_ms)
  (cd "$dir" && CARGO_TARGET_DIR="$dir/target-$profile" cargo build --offline --quiet ${flags[@]+"${flags[@]}"})
  built_ms=$(($(now_ms) - start))
  "$dir/target-$profile/$profile/eopnp-scratch"
}

# build_script_ms DIR PROFILE: one more run of eopnp's compiled build script, timed.
build_script_ms() {
  local script out start
  script=$(find "$1/target-$2/$2/build" -path '*/eopnp-*/build-script-build' -type f | head -n 1)
  out="$1/build-script-out"
  mkdir -p "$out"
  start=$(now_ms)
  OUT_DIR="$out" CARGO_MANIFEST_DIR="$tmp/eopnp-$version" "$script" >/dev/null
  echo $(($(now_ms) - start))
}

echo "== unit tests of the unpacked package (cargo test --lib --release)"
# The repository's target directory: the dependencies are already built there.
unit_log="$tmp/unit-tests.log"
if ! (cd "$tmp/eopnp-$version" && CARGO_TARGET_DIR="$target_dir" cargo test --offline --release \
  --lib --config "patch.crates-io.eopnp-codegen.path='$tmp/eopnp-codegen-$codegen_version'" \
  >"$unit_log" 2>&1); then
  cat "$unit_log" >&2
  echo "the unit tests of the unpacked package failed" >&2
  exit 1
fi
grep -E '^test result' "$unit_log"

echo "== scratch crate: eopnp $version by path, default features"
user="$tmp/scratch"
scratch_crate "$user" "" ""
# The library's default features pull in none of the command line's dependencies.
cli_deps=$(cd "$user" && cargo tree --offline -e normal --prefix none | sed -E 's/ .*//' |
  grep -xE 'clap|indicatif|serde|serde_json|csv-core' | sort -u || true)
if [[ -n "$cli_deps" ]]; then
  echo "eopnp with its default features depends on the command line's crates: $cli_deps" >&2
  exit 1
fi
echo "dependencies of eopnp with its default features: $(cd "$user" && cargo tree --offline -e normal --prefix none | sed -E 's/ .*//' | sort -u | grep -vx eopnp-scratch | tr '\n' ' ')"
build_and_run "$user" debug
debug_ms=$built_ms
build_and_run "$user" release
release_ms=$built_ms
copy_ms=$(build_script_ms "$user" debug)

echo "== scratch crate with feature regenerate (eopnp-codegen $codegen_version from its .crate)"
regen="$tmp/scratch-regenerate"
scratch_crate "$regen" ', features = ["regenerate"]' \
  "[patch.crates-io]
eopnp-codegen = { path = \"$tmp/eopnp-codegen-$codegen_version\" }"
build_and_run "$regen" debug
regen_debug_ms=$built_ms
render_ms=$(build_script_ms "$regen" debug)
# The regenerating build script wrote exactly the shipped generated/ files.
diff -r "$tmp/eopnp-$version/generated" "$regen/build-script-out"

echo "== timings (wall clock, $(nproc) cores)"
echo "clean debug build of the scratch crate:   $(seconds "$debug_ms")"
echo "clean release build of the scratch crate: $(seconds "$release_ms")"
echo "clean debug build with regenerate:        $(seconds "$regen_debug_ms")"
echo "eopnp build script (debug), copy:         $(seconds "$copy_ms")"
echo "eopnp build script (debug), regenerate:   $(seconds "$render_ms")"
