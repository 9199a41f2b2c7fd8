#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# One set-up for both README commands, so they cannot drift apart:
#   bash cmake/bootstrap.sh bench [impact-collide-bench arguments...]
#   bash cmake/bootstrap.sh test  [extra ctest arguments...]
# It installs the Debian packages it needs (apt-get, as root or through sudo), configures a Release
# build with warnings as errors in build/release (bench) or build/test (test; IMPACT_BUILD_DIR
# overrides either), then builds and runs
# the collision benchmark, or builds everything and runs the whole ctest suite. Set IMPACT_DATA_DIR to a folder that
# holds meshes/ and ccd-queries/ to run the data-driven tests (they report SKIPPED without it, and FAIL when CI=true).
set -euo pipefail

mode="${1:-test}"
[ $# -gt 0 ] && shift
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

# libqhull-dev: qhull, the peer of impact-convex-bench --hulls (its smoke test runs in the test mode)
packages=(cmake ninja-build g++ libeigen3-dev libassimp-dev libccd-dev libfcl-dev libbullet-dev libgtest-dev libbenchmark-dev libboost-dev libqhull-dev)
# the test suite also reads Debian's sample models (about 150 files in many formats) as loader input
[ "$mode" = test ] && packages+=(assimp-testmodels)
# the bench mode also installs matplotlib for benches/plot.py (charts from the benches' --json)
# and Intel Embree 3, the peer of impact-ray-bench (built without its Embree rows when absent)
[ "$mode" = bench ] && packages+=(python3-matplotlib libembree-dev)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  sudo=""
  [ "$(id -u)" -ne 0 ] && sudo="sudo"
  echo "bootstrap: installing ${missing[*]}"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

# Two build folders, so that neither mode recompiles the other's: the bench mode's build/release
# compiles the benches at -O3; the test mode's build/test compiles the benches and examples at -Og
# (IMPACT_BENCH_OPTIMIZATION, as the tests), since there they only run as smoke tests.
if [ "$mode" = test ]; then
  build="${IMPACT_BUILD_DIR:-$root/build/test}"
  bench_optimization=-Og
else
  build="${IMPACT_BUILD_DIR:-$root/build/release}"
  bench_optimization=
fi
jobs="$(nproc 2>/dev/null || echo 2)"
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DIMPACT_WARNINGS_AS_ERRORS=ON -DIMPACT_DATA_DIR="${IMPACT_DATA_DIR:-}" \
  -DIMPACT_BENCH_OPTIMIZATION="$bench_optimization" ${IMPACT_CMAKE_ARGS:-}
case "$mode" in
  bench)
    cmake --build "$build" -j "$jobs" --target impact-collide-bench
    exec "$build/benches/impact-collide-bench" "$@" ;;
  test)
    cmake --build "$build" -j "$jobs"
    exec ctest --test-dir "$build" --output-on-failure -j "$jobs" "$@" ;;
  *) echo "usage: bash cmake/bootstrap.sh bench|test [args...]" >&2; exit 2 ;;
esac
