#!/usr/bin/env bash
# The whole test suite, as CI runs it (the README's test command), from any directory:
#
#   1. `cargo test --workspace --release --all-features`: the Rust workspace.
#   2. The Python package (python/): builds the wheel (`maturin build --release`, abi3), installs
#      it into a fresh virtual environment with numpy, pytest, mypy (for stubtest) and
#      dask[distributed] (the cluster example's test), and pycolmap when it installs (the
#      covariance comparison; skipped without it), and runs python/tests there (from outside python/, so that the installed wheel is what is
#      imported). The tests that compare with the CLI use the release binary of step 1
#      (EOPNP_CLI).
#
# Usage: scripts/test.sh [--python]   (--python: step 2 only, after building the CLI)
#
# Needs python3 (>= 3.10, with venv and pip) and PyPI for maturin, numpy, pytest, mypy and dask.
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

if ! $python_only; then
  cargo test --workspace --release --all-features
fi

start=$(date +%s)
target_dir=$(cargo metadata --format-version 1 --no-deps --offline |
  sed -E 's/.*"target_directory":"([^"]*)".*/\1/')
# The CLI the Python tests compare with: the release binary that step 1 built for the CLI's
# integration tests. (`cargo build` would build it again: without the dev-dependencies, some
# dependencies resolve to other features.)
if $python_only; then
  cargo build --release -p eopnp-cli --bin eopnp --quiet
fi
export EOPNP_CLI="$target_dir/release/eopnp"

python=${PYTHON:-python3}
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
# pycolmap: a comparison only (test_covariance.py), not a dependency; 4 s from PyPI here.
"$work/test-venv/bin/pip" install --quiet --disable-pip-version-check pycolmap ||
  echo "pycolmap did not install: the covariance comparison with it is skipped"
# From the repository root, not python/: `import eopnp` must be the installed wheel.
"$work/test-venv/bin/python" -c 'import eopnp, sys; print("eopnp", eopnp.__version__, "from", eopnp.__file__); sys.exit("eopnp imported from the source tree" if "site-packages" not in eopnp.__file__ else 0)'
"$work/test-venv/bin/pytest" -q -p no:cacheprovider python/tests
end=$(date +%s)
echo "python package: wheel built in $((built - start)) s, installed and tested in $((end - built)) s"
