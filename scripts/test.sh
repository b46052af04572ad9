#!/usr/bin/env bash
# Installs the dependencies, builds everything (Release) and runs every test
# through ctest. Extra arguments go to ctest, e.g. `scripts/test.sh -L unit`.
# PBA_BUILD_DIR overrides the build directory (default build/release).
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${PBA_BUILD_DIR:-$root/build/release}
# ccache keys on paths relative to the checkout, so a fresh clone reuses
# what an earlier one compiled.
export CCACHE_BASEDIR=$root
jobs=${PBA_JOBS:-2}

t0=$(date +%s)
"$root/scripts/deps.sh"
t1=$(date +%s)
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DPBA_WERROR=ON >/dev/null
cmake --build "$build" -j "$jobs"
t2=$(date +%s)
status=0
ctest --test-dir "$build" --output-on-failure -j "$jobs" "$@" || status=$?
t3=$(date +%s)

echo
echo "durations: dependencies $((t1 - t0)) s, build $((t2 - t1)) s, tests $((t3 - t2)) s, total $((t3 - t0)) s"
exit "$status"
