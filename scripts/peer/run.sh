#!/usr/bin/env bash
# Reproduces the CalculiX peer comparison of docs/validation.md ("Peer:
# CalculiX"): builds calculix_peer_test (Release), runs every case in PBA and
# in ccx, and prints the table with one row per case.
# Usage: scripts/peer/run.sh [extra GoogleTest flags, e.g. --gtest_filter=*case14]
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
build=${PBA_BUILD_DIR:-$root/build/release}
export CCACHE_BASEDIR=$root

"$root/scripts/deps.sh"
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$build" -j "${PBA_JOBS:-2}" --target calculix_peer_test
# ccx -v exits non-zero after printing its version.
ccx_version=$(ccx -v 2>/dev/null | grep -m1 -o 'Version.*' || true)
echo "machine: $(nproc) cores, $(awk '/MemTotal/ {printf "%.0f GB", $2 / 1048576}' /proc/meminfo), $(uname -m); CalculiX ${ccx_version:-version unknown}"

log=$(mktemp)
trap 'rm -f "$log"' EXIT
status=0
"$build/bin/calculix_peer_test" "$@" >"$log" 2>&1 || status=$?
echo "| model | unknowns | reaction difference (relative to the largest reaction) | largest displacement difference (relative) | PBA wall time | CalculiX wall time | PBA's error estimate |"
echo "|---|---|---|---|---|---|---|"
grep '^| ' "$log" || true
if [ "$status" -ne 0 ]; then
  # A case that disagrees still prints its row; show what failed.
  grep -E 'Failure|Expected|actual|FAILED' "$log" >&2 || true
  echo "calculix_peer_test failed (exit $status)" >&2
fi
exit "$status"
