#!/usr/bin/env bash
# The whole product in one command: installs the dependencies, builds
# (Release), starts pba-server with its web view on free loopback ports and a
# fresh data directory, submits a nonlinear scene on the brain atlas
# (examples/atlas_indentation.yaml: the synthetic atlas's 44 structures,
# Ogden tissue, the crown indented 3 mm; about a minute on two cores) with
# the pba client, follows it, downloads the result, prints its summary and
# the address of the page that shows the job, and keeps the server up until
# Enter (at once when not run from a terminal, or with PBA_DEMO_KEEP=0).
# Usage: scripts/demo.sh [SCENE.yaml]   (default examples/atlas_indentation.yaml)
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${PBA_BUILD_DIR:-$root/build/release}
# ccache keys on paths relative to the checkout, so a fresh clone reuses
# what an earlier one compiled.
export CCACHE_BASEDIR=$root
scene=${1:-$root/examples/atlas_indentation.yaml}
result_dir=$root/out/$(basename "${scene%.*}")

echo "== installing dependencies"
"$root/scripts/deps.sh"
echo "== building (Release) in $build"
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$build" -j "${PBA_JOBS:-2}" --target pba pba-server pba-solve

bin=$build/bin
data=$(mktemp -d "${TMPDIR:-/tmp}/pba-demo.XXXXXX")
# shellcheck source=scripts/local_server.sh
source "$root/scripts/local_server.sh"
stop_server() {
  if stop_local_server; then echo "== server stopped"; fi
}
trap stop_server EXIT

echo "== starting pba-server (data directory $data/server)"
start_local_server "$bin" "$data" --http 127.0.0.1:0
web=$(sed -n 's/^web view on //p' "$data/server.out")
echo "   listening on $address; web view on $web"
echo "   signed in as admin (token in $data/server/admin.token)"
pba=("$bin/pba" --server "$address")

echo "== submitting $(basename "$scene")"
submitted=$("${pba[@]}" job submit "$scene")
echo "   $submitted"
job=$(echo "$submitted" | sed -n 's/^Submitted job \([^ ]*\).*/\1/p')

echo "== following job $job"
"${pba[@]}" job watch "$job"

echo "== downloading the result"
rm -rf "$result_dir"
"${pba[@]}" job fetch "$job" -o "$result_dir"

echo
echo "Result files: $result_dir (result.h5, result.xdmf, surfaces.glb, summary.json)"
echo "To look at them: paraview $result_dir/result.xdmf   (choose the XDMF reader if asked)"
echo "Server data and log of this run: $data"
echo
echo "The job in the web view: ${web}#job=$job"
echo "   sign in with the token in $data/server/admin.token"
if [ -t 0 ] && [ "${PBA_DEMO_KEEP:-1}" != 0 ]; then
  read -r -p "Press Enter to stop the server. " _
fi
stop_server
