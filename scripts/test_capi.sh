#!/usr/bin/env bash
# The C and C++ interface (capi/, docs/c-cpp.md), as CI runs it, from any directory:
#
#   1. Installs cmake, g++, pkg-config and OpenCV's development package from Debian's packages
#      when one is missing (apt-get; sudo only when not root).
#   2. The CMake project: configure with the tests and the examples, build (cargo builds
#      eopnp-capi into the workspace's target/), ctest (the C tests against the static and the
#      shared library, the C++ tests in C++17 and C++20 and with OpenCV), and install into a
#      temporary prefix.
#   3. The outside consumer (capi/tests/consumer/): find_package(eopnp) against that prefix, its
#      C and C++ programs built and run; and a C program built with `pkg-config --cflags --libs
#      eopnp` alone, run.
#   4. The C and C++ tests again, built with AddressSanitizer and UndefinedBehaviorSanitizer
#      (-fsanitize=address,undefined -fno-sanitize-recover=all; LeakSanitizer on).
#   5. The example (examples/cpp/compare_opencv) once, with few repetitions: it must run; its
#      timings are docs/c-cpp.md's business, not a test's.
#
# Scratch directory: target/capi-test/ (removed at the start of each run).
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)

need=()
command -v cmake >/dev/null 2>&1 || need+=(cmake)
command -v g++ >/dev/null 2>&1 || need+=(g++)
command -v pkg-config >/dev/null 2>&1 || need+=(pkg-config)
[ -f /usr/include/opencv4/opencv2/calib3d.hpp ] || need+=(libopencv-dev)
if [ ${#need[@]} -gt 0 ]; then
  echo "== installing ${need[*]} (apt-get)"
  sudo=""
  [ "$(id -u)" -eq 0 ] || sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${need[@]}" >/dev/null
fi
cmake --version | head -1
g++ --version | head -1

target_dir=$(cargo metadata --format-version 1 --no-deps --offline |
  sed -E 's/.*"target_directory":"([^"]*)".*/\1/')
work="$target_dir/capi-test"
rm -rf "$work"
mkdir -p "$work"
jobs=$(nproc 2>/dev/null || echo 2)

step() { echo "== capi: $*"; }
t0=$(date +%s)

step "configure, build, ctest, install"
cmake -S . -B "$work/build" -DEOPNP_BUILD_TESTS=ON -DEOPNP_BUILD_EXAMPLES=ON \
  -DEOPNP_CARGO_TARGET_DIR="$target_dir" >"$work/configure.log"
grep -q "OpenCV not found" "$work/configure.log" && { echo "OpenCV not found" >&2; exit 1; }
cmake --build "$work/build" -j "$jobs"
ctest --test-dir "$work/build" --output-on-failure
cmake --install "$work/build" --prefix "$work/prefix" >/dev/null
t1=$(date +%s)

step "outside consumer: find_package(eopnp) against the installed prefix"
cmake -S capi/tests/consumer -B "$work/consumer" -DCMAKE_PREFIX_PATH="$work/prefix" >/dev/null
cmake --build "$work/consumer" -j "$jobs" >/dev/null
"$work/consumer/consumer_c"
"$work/consumer/consumer_cpp"
step "outside consumer: pkg-config"
export PKG_CONFIG_PATH="$work/prefix/lib/pkgconfig"
pkg-config --modversion eopnp
# shellcheck disable=SC2046
gcc -std=c11 -Wall -Werror capi/tests/consumer/main.c -o "$work/consumer_pkgconfig" \
  $(pkg-config --cflags --libs eopnp) -lm -Wl,-rpath,"$work/prefix/lib"
"$work/consumer_pkgconfig"
t2=$(date +%s)

step "the C and C++ tests under AddressSanitizer and UndefinedBehaviorSanitizer"
cmake -S . -B "$work/sanitize" -DEOPNP_BUILD_TESTS=ON -DEOPNP_SANITIZE=ON \
  -DEOPNP_CARGO_TARGET_DIR="$target_dir" >/dev/null
cmake --build "$work/sanitize" -j "$jobs"
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  ctest --test-dir "$work/sanitize" --output-on-failure
t3=$(date +%s)

step "example: examples/cpp/compare_opencv (a short run)"
"$work/build/examples/cpp/compare_opencv" --repetitions 3
t4=$(date +%s)

echo "capi: build + ctest + install $((t1 - t0)) s, consumer $((t2 - t1)) s," \
  "sanitizers $((t3 - t2)) s, example $((t4 - t3)) s"
