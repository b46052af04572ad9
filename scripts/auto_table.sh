#!/usr/bin/env bash
# The table of docs/scenes.md "What AUTO chooses for each example": every
# example scene solved as written and with formulation: AUTO (Release
# build). Takes about as long as solving every example twice.
# Usage: scripts/auto_table.sh [examples/NAME.yaml ...]
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${PBA_BUILD_DIR:-$root/build/release}
export CCACHE_BASEDIR=$root

"$root/scripts/deps.sh" >/dev/null
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$build" -j "${PBA_JOBS:-2}" --target auto_formulation_table
cd "$root"
"$build/bin/auto_formulation_table" examples "$@"
