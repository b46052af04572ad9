#!/usr/bin/env bash
# Runs the benchmarks (Release build) and prints their tables; the figures
# in docs/performance.md come from this script.
# Usage: scripts/bench.sh [extra Google Benchmark flags]
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${PBA_BUILD_DIR:-$root/build/release}
export CCACHE_BASEDIR=$root

"$root/scripts/deps.sh"
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$build" -j "${PBA_JOBS:-2}" --target linear_static_bench nonlinear_static_bench element_bench
echo "machine: $(nproc) cores, $(awk '/MemTotal/ {printf "%.0f GB", $2 / 1048576}' /proc/meminfo), $(uname -m)"
"$build/bin/linear_static_bench" --benchmark_counters_tabular=true "$@"
"$build/bin/nonlinear_static_bench" --benchmark_counters_tabular=true "$@"
"$build/bin/element_bench" --benchmark_counters_tabular=true "$@"
