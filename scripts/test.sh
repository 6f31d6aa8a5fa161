#!/usr/bin/env bash
# The whole test suite, as CI runs it (the README's test command), from any directory:
#
#   1. `cargo test --workspace --release --all-features`: the Rust workspace.
#   2. The Python package (python/): builds the wheel (`maturin build --release`, abi3), installs
#      it into a fresh virtual environment with numpy, pytest, mypy (for stubtest),
#      dask[distributed] (the cluster example's test) and pycolmap (the covariance comparison),
#      and runs python/tests there (from outside python/, so that the installed wheel is what is
#      imported). The tests that compare with the CLI use the release binary of step 1
#      (EOPNP_CLI). EOPNP_REQUIRE_PEERS=1: a comparison package that does not import is a test
#      error, not a skip.
#   3. The skips: scripts/check_skips.py prints the number of ignored Rust tests and skipped
#      Python tests and fails on any that scripts/expected_skips.txt does not list (by name,
#      with the reason), and on a listed one that did not skip.
#
# Usage: scripts/test.sh [--python]   (--python: step 2 only, after building the CLI)
#
# Needs python3 (>= 3.10, with venv and pip) and PyPI for maturin, numpy, pytest, mypy, dask and
# pycolmap.
# Scratch directories: target/python-test/ (the wheel and the virtual environments; the
# cargo target of python/ is python/target unless CARGO_TARGET_DIR is set).
set -euo pipefail
cd "$(dirname "$0")/.."

python_only=false
if [[ "${1:-}" == "--python" ]]; then
  python_only=true
elif [[ $# -gt 0 ]]; then
  echo "usage: $0 [--python]" >&2
  exit 2
fi

target_dir=$(cargo metadata --format-version 1 --no-deps --offline |
  sed -E 's/.*"target_directory":"([^"]*)".*/\1/')
skips="$target_dir/test-skips"
mkdir -p "$skips"
python=${PYTHON:-python3}

if ! $python_only; then
  # The log (stdout and stderr: cargo names each test binary on stderr) for the skip check, and
  # the test executables' source files (nothing is built again).
  cargo test --workspace --release --all-features 2>&1 | tee "$skips/cargo-test.log"
  cargo test --workspace --release --all-features --no-run --message-format=json \
    >"$skips/cargo-artifacts.json"
  "$python" scripts/check_skips.py rust "$skips/cargo-test.log" "$skips/cargo-artifacts.json"
fi

start=$(date +%s)
# The CLI the Python tests compare with: the release binary that step 1 built for the CLI's
# integration tests. (`cargo build` would build it again: without the dev-dependencies, some
# dependencies resolve to other features.)
if $python_only; then
  cargo build --release -p eopnp-cli --bin eopnp --quiet
fi
export EOPNP_CLI="$target_dir/release/eopnp"

work="$target_dir/python-test"
rm -rf "$work"
mkdir -p "$work"
echo "== python package: maturin build --release ($("$python" --version))"
"$python" -m venv "$work/build-venv"
"$work/build-venv/bin/pip" install --quiet --disable-pip-version-check "maturin>=1.9,<2"
"$work/build-venv/bin/maturin" build --release --manifest-path python/Cargo.toml \
  --interpreter "$work/build-venv/bin/python" --out "$work/wheels"
wheel=$(ls "$work"/wheels/eopnp-*.whl)
built=$(date +%s)

echo "== python package: install $(basename "$wheel") into a fresh venv, run pytest"
"$python" -m venv "$work/test-venv"
"$work/test-venv/bin/pip" install --quiet --disable-pip-version-check "$wheel" numpy pytest mypy \
  "dask[distributed]"
# pycolmap: a comparison only (test_covariance.py), not a dependency; 4 s from PyPI here. Not
# optional: a failed install fails the run (the comparison would otherwise silently not run).
"$work/test-venv/bin/pip" install --quiet --disable-pip-version-check pycolmap
# From the repository root, not python/: `import eopnp` must be the installed wheel.
"$work/test-venv/bin/python" -c 'import eopnp, sys; print("eopnp", eopnp.__version__, "from", eopnp.__file__); sys.exit("eopnp imported from the source tree" if "site-packages" not in eopnp.__file__ else 0)'
# -rs: the reason of any skip in the summary; the JUnit report (xunit1: with each test's file)
# is what check_skips.py reads.
EOPNP_REQUIRE_PEERS=1 "$work/test-venv/bin/pytest" -q -rs -p no:cacheprovider \
  -o junit_family=xunit1 --junitxml="$skips/pytest.xml" python/tests
"$python" scripts/check_skips.py python "$skips/pytest.xml"
end=$(date +%s)
echo "python package: wheel built in $((built - start)) s, installed and tested in $((end - built)) s"
