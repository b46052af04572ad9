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
cmake --build "$build" -j "${PBA_JOBS:-2}" --target linear_static_bench nonlinear_static_bench element_bench \
  peer_bench scaling_bench server_bench tled_bench
echo "machine: $(nproc) cores, $(awk '/MemTotal/ {printf "%.0f GB", $2 / 1048576}' /proc/meminfo), $(uname -m)"
"$build/bin/linear_static_bench" --benchmark_counters_tabular=true "$@"
"$build/bin/nonlinear_static_bench" --benchmark_counters_tabular=true "$@"
"$build/bin/element_bench" --benchmark_counters_tabular=true "$@"
# The explicit engine's internal force on 1 and 2 threads, beside a STREAM
# triad measured in the same run.
"$build/bin/tled_bench" --benchmark_counters_tabular=true "$@"
# Against CalculiX (ccx from scripts/deps.sh), which it runs with OMP_NUM_THREADS=2.
"$build/bin/peer_bench" --benchmark_counters_tabular=true "$@"
# Each row alone, so that its peak memory is its own.
for row in cells:10/tet10:0 cells:20/tet10:0 cells:30/tet10:0 cells:5/tet10:1 cells:10/tet10:1 \
  cells:15/tet10:1; do
  "$build/bin/scaling_bench" --benchmark_counters_tabular=true --benchmark_filter="$row/" "$@"
done
# pba-server in-process on loopback (its jobs run the real pba-solve); its
# data directories go under the system temp dir, so that disk's fsync shows.
"$build/bin/server_bench" --benchmark_counters_tabular=true "$@"
