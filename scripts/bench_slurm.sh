#!/usr/bin/env bash
# What Slurm costs a job: a pba-server with the local executor and one with
# --executor slurm on the one-node cluster of scripts/slurm-local.sh, each
# given the same batch of tiny scenes (a 10 mm linear cube, a fraction of a
# second of solving) through `pba batch run`. For each executor prints the
# batch's wall time and jobs per minute, whether every member ran once and
# only once, and per job (medians over the batch): submit to start
# (created -> started, as the server records them), the solve itself
# (pba-solve's own wall time) and the rest of the run (started -> ended,
# less the solve: the process, the result collected with its digests, and
# for Slurm the polls that see the end).
#
# Usage: scripts/bench_slurm.sh [jobs]        (default 200)
#   PBA_BENCH_PARALLEL: members submitted at a time (default 50)
#   PBA_BENCH_POLL: --slurm-poll in seconds (default 2, the server's)
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${PBA_BUILD_DIR:-$root/build/release}
jobs=${1:-200}
parallel=${PBA_BENCH_PARALLEL:-50}
poll=${PBA_BENCH_POLL:-2}
for b in pba pba-server pba-solve; do
  [ -x "$build/bin/$b" ] || { echo "bench_slurm: build $b first" >&2; exit 2; }
done
py=/usr/bin/python3

work=$(mktemp -d)
chmod 755 "$work"  # munged wants every directory above its socket open to all
export PBA_SLURM_DIR=$work/slurm SLURM_CONF=$work/slurm/slurm.conf
server_pid=
cleanup() {
  [ -n "$server_pid" ] && kill "$server_pid" 2>/dev/null && wait "$server_pid" 2>/dev/null
  bash "$root/scripts/slurm-local.sh" stop --clean >/dev/null 2>&1 || true
  rm -rf "$work"
}
trap cleanup EXIT

cat >"$work/cube.yaml" <<'EOF'
name: tiny
geometry: {box: {size_mm: [10, 10, 10]}}
mesh: {element_size_mm: 2}
material: {linear_elastic: {youngs_modulus_pa: 3000, poissons_ratio: 0.45}}
boundary_conditions:
  - {set: bottom, fixed: {}}
  - {set: top, displacement: {z_mm: -0.5}}
analysis: {type: LINEAR_STATIC, linear_solver: CHOLMOD}
EOF
# Members differ by their displacement, so each is its own job.
values=$("$py" -c "print(', '.join(str(round(-0.5 - i * 1e-4, 6)) for i in range($jobs)))")

# Starts a server with `$@`, runs the batch, prints the row.
run() {
  local name=$1
  shift
  local data=$work/data-$name
  "$build/bin/pba-server" --data "$data" --listen 127.0.0.1:0 --keep-results 0 "$@" \
    >"$work/$name.out" 2>"$work/$name.log" &
  server_pid=$!
  for _ in $(seq 200); do
    grep -q "listening on" "$work/$name.out" 2>/dev/null && break
    sleep 0.1
  done
  local address
  address=$(sed -n 's/.*listening on //p' "$work/$name.out")
  [ -n "$address" ] || { cat "$work/$name.log" >&2; exit 1; }
  export PBA_SERVER=$address PBA_TOKEN
  PBA_TOKEN=$(cat "$data/admin.token")
  cat >"$work/batch-$name.yaml" <<EOF
name: bench-$name
scene: cube.yaml
parallel: $parallel
sweep:
  boundary_conditions[1].displacement.z_mm: [$values]
outputs: [performance.wall_time_s]
EOF
  local start end
  start=$(date +%s.%N)
  "$build/bin/pba" batch run "$work/batch-$name.yaml" --no-plot >"$work/batch-$name.txt" 2>&1 || {
    tail -20 "$work/batch-$name.txt" >&2
    exit 1
  }
  end=$(date +%s.%N)
  "$build/bin/pba" --json job list --all >"$work/jobs-$name.json"
  local runs=-
  [ "$name" = slurm ] && runs=$(grep -c "Name=pba-" "$work/slurm/jobcomp.txt" || true)
  "$py" - "$work/jobs-$name.json" "$name" "$start" "$end" "$jobs" "$runs" <<'EOF'
import json, statistics, sys
from datetime import datetime
path, name, start, end, n, runs = sys.argv[1:]
text = open(path).read()
jobs = [json.loads(line) for line in text.splitlines() if line.strip().startswith("{")] \
    if not text.lstrip().startswith("[") else json.loads(text)
if isinstance(jobs, dict):
    jobs = jobs.get("jobs", [])
def t(s):
    return datetime.fromisoformat(s.replace("Z", "+00:00")).timestamp()
wait, rest, solve, attempts, ok = [], [], [], [], 0
for j in jobs:
    if j.get("state") == "SUCCEEDED":
        ok += 1
    attempts.append(int(j.get("attempts", 0)))
    created, started, ended = t(j["create_time"]), t(j["start_time"]), t(j["end_time"])
    wall = j.get("summary", {}).get("performance", {}).get("wall_time_s", 0)
    wait.append(started - created)
    solve.append(wall)
    rest.append(ended - started - wall)
wall = float(end) - float(start)
once = "yes" if ok == int(n) and set(attempts) == {1} and runs in ("-", n) else "NO"
print(f"| {name} | {n} | {ok} | {once} | {wall:.1f} s | {int(n) / wall * 60:.0f} | "
      f"{statistics.median(wait):.2f} s | {statistics.median(solve):.2f} s | "
      f"{statistics.median(rest):.2f} s |")
EOF
  kill "$server_pid"
  wait "$server_pid" 2>/dev/null || true
  server_pid=
}

echo "machine: $(nproc) cores, $(awk '/MemTotal/ {printf "%.0f GB", $2 / 1048576}' /proc/meminfo); commit $(git -C "$root" rev-parse --short HEAD); $jobs jobs, $parallel submitted at a time"
echo "| executor | jobs | succeeded | each once | batch wall time | jobs per minute | submit to start (median) | solve (median) | start to recorded end, less the solve (median) |"
echo "|---|---|---|---|---|---|---|---|---|"
run local --max-running 2
bash "$root/scripts/slurm-local.sh" start >/dev/null
run slurm --executor slurm --slurm-poll "$poll"
