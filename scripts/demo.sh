#!/usr/bin/env bash
# The whole product in one command: installs the dependencies, builds
# (Release), starts pba-server on a free loopback port with a fresh data
# directory, submits examples/quickstart.yaml with the pba client, follows it,
# downloads the result, prints its summary and stops the server.
# Usage: scripts/demo.sh [SCENE.yaml]   (default examples/quickstart.yaml)
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${PBA_BUILD_DIR:-$root/build/release}
# ccache keys on paths relative to the checkout, so a fresh clone reuses
# what an earlier one compiled.
export CCACHE_BASEDIR=$root
scene=${1:-$root/examples/quickstart.yaml}
result_dir=$root/out/$(basename "${scene%.*}")

echo "== installing dependencies"
"$root/scripts/deps.sh"
echo "== building (Release) in $build"
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$build" -j "${PBA_JOBS:-2}" --target pba pba-server pba-solve

bin=$build/bin
data=$(mktemp -d "${TMPDIR:-/tmp}/pba-demo.XXXXXX")
server_pid=""
stop_server() {
  if [ -n "$server_pid" ] && kill -0 "$server_pid" 2>/dev/null; then
    kill -TERM "$server_pid"
    wait "$server_pid" || true
    echo "== server stopped"
  fi
  server_pid=""
}
trap stop_server EXIT

echo "== starting pba-server (data directory $data/server)"
"$bin/pba-server" --data "$data/server" --listen 127.0.0.1:0 >"$data/server.out" 2>"$data/server.log" &
server_pid=$!
address=""
for _ in $(seq 1 100); do
  address=$(sed -n 's/^pba-server listening on //p' "$data/server.out")
  [ -n "$address" ] && break
  if ! kill -0 "$server_pid" 2>/dev/null; then
    echo "pba-server did not start; its log:" >&2
    cat "$data/server.log" >&2
    exit 1
  fi
  sleep 0.1
done
[ -n "$address" ] || { echo "pba-server did not report its address in 10 s" >&2; exit 1; }
echo "   listening on $address"
# The first start made the user 'admin' and wrote its token there; `pba login
# --token-file` would keep it, PBA_TOKEN lends it to these commands only.
PBA_TOKEN=$(cat "$data/server/admin.token")
export PBA_TOKEN
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

stop_server
echo
echo "Result files: $result_dir (result.h5, result.xdmf, summary.json)"
echo "To look at them: paraview $result_dir/result.xdmf   (choose the XDMF reader if asked)"
echo "Server data and log of this run: $data"
