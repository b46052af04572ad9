#!/usr/bin/env bash
# What Slurm costs a job: a pba-server with the local executor and one with
# --executor slurm on the one-node cluster of scripts/slurm-local.sh (with
# job arrays, the default, and with each job its own Slurm job), each
# given the same tiny scene (a 10 mm linear cube, a fraction of a second of
# solving). First `single` jobs one after another (`pba job submit --wait`),
# each alone: per job (medians) the turnaround (submitted -> end recorded,
# as the server stamps them), pba-solve's own wall time, and the overhead,
# the one less the other (the process started; for Slurm the submission,
# the scheduler's start and the polls; the result collected with its
# digests), split in two: submitted -> started and ended -> end recorded
# (for Slurm its own StartTime and EndTime from its job completion file,
# whole seconds: the scheduler's latency, then the poll that finds the
# end and the collection; locally the child's start, and its start plus
# its solve). Then a batch of `jobs` members through `pba batch run`: its wall
# time, jobs per minute, and whether every member succeeded and ran once
# (one attempt each; for Slurm one line per job in its job completion file),
# and for Slurm the sbatch calls the single jobs and the batch took (one
# per job, or per job array).
#
# Usage: scripts/bench_slurm.sh [jobs [single]]    (default 200 10)
#   PBA_BENCH_PARALLEL: the batch's `parallel`, members unfinished at once
#     (default all: every member handed over at once, as a batch without
#     `parallel` goes to a Slurm-backed server)
#   PBA_BENCH_POLL: --slurm-poll in seconds (default 2, the server's)
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${PBA_BUILD_DIR:-$root/build/release}
jobs=${1:-200}
single=${2:-10}
parallel=${PBA_BENCH_PARALLEL:-all}
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
  if [ -n "$server_pid" ]; then
    kill "$server_pid" 2>/dev/null || true
    wait "$server_pid" 2>/dev/null || true
  fi
  bash "$root/scripts/slurm-local.sh" stop --clean >/dev/null 2>&1 || true
  rm -rf "$work"
}
trap cleanup EXIT

cube() {  # cube DISPLACEMENT_MM
  cat <<EOF
name: tiny
geometry: {box: {size_mm: [10, 10, 10]}}
mesh: {element_size_mm: 2}
material: {linear_elastic: {youngs_modulus_pa: 3000, poissons_ratio: 0.45}}
boundary_conditions:
  - {set: bottom, fixed: {}}
  - {set: top, displacement: {z_mm: $1}}
analysis: {type: LINEAR_STATIC, linear_solver: CHOLMOD}
EOF
}
cube -0.5 >"$work/cube.yaml"
# Members differ by their displacement, so each is its own job.
values=$("$py" -c "print(', '.join(str(round(-0.5 - i * 1e-4, 6)) for i in range($jobs)))")

# The figures of one run, from the single jobs' status and the batch's list.
report() {
  "$py" - "$@" <<'PY'
import json, statistics, sys
from datetime import datetime
work, name, start, end, n, runs, single, submissions = sys.argv[1:]
def t(s):
    return datetime.fromisoformat(s.replace("Z", "+00:00")).timestamp()
def get(j, snake, camel):
    return j.get(snake, j.get(camel))
# Slurm's own start and end of each job (its job completion file, whole
# seconds of the machine's local time), by PBA job id.
slurm_times = {}
try:
    for line in open(f"{work}/slurm/jobcomp.txt"):
        fields = dict(f.split("=", 1) for f in line.split() if "=" in f)
        if fields.get("Name", "").startswith("pba-j"):
            slurm_times[fields["Name"][4:]] = (datetime.fromisoformat(fields["StartTime"]).timestamp(),
                                              datetime.fromisoformat(fields["EndTime"]).timestamp())
except FileNotFoundError:
    pass
turn, solve, to_start, to_collected = [], [], [], []
for line in open(f"{work}/single-{name}.json"):
    if not line.strip():
        continue
    j = json.loads(line)
    perf = j.get("summary", {}).get("performance", {})
    created = t(get(j, "create_time", "createTime"))
    ended = t(get(j, "end_time", "endTime"))
    wall = float(get(perf, "wall_time_s", "wallTimeS") or 0)
    turn.append(ended - created)
    solve.append(wall)
    if name.startswith("slurm"):
        # Slurm's start and end: the scheduler's latency, then the poll
        # that sees the end and the collection.
        started, finished = slurm_times[j["id"]]
        to_start.append(started - created)
        to_collected.append(ended - finished)
    else:
        # The child process started, and its end: start plus its solve.
        started = t(get(j, "start_time", "startTime"))
        to_start.append(started - created)
        to_collected.append(ended - started - wall)
over = [a - b for a, b in zip(turn, solve)]
med = statistics.median
listed = json.load(open(f"{work}/jobs-{name}.json")).get("jobs", [])
batch = [j for j in listed if j.get("name") != "one"]
ok = sum(j.get("state") == "SUCCEEDED" for j in batch)
attempts = {int(j.get("attempts", 0)) for j in batch}
each_once = ok == int(n) and attempts == {1} and (runs == "-" or int(runs) == int(n) + int(single))
wall = float(end) - float(start)
print(f"| {name} | {med(turn):.2f} s | {med(solve):.2f} s | "
      f"{med(over):.2f} s ({min(over):.2f} .. {max(over):.2f}) | {med(to_start):.2f} s | "
      f"{med(to_collected):.2f} s | {n} | {ok} | "
      f"{'yes' if each_once else 'NO'} | {wall:.1f} s | {int(n) / wall * 60:.0f} | {submissions} |")
PY
}

# run NAME SERVER_ARGS...: a server, the single jobs, the batch, the row.
run() {
  local name=$1
  shift
  local data=$work/data-$name
  # Slurm's job completion file so far: this run's lines are the ones after.
  local before=0
  [ -f "$work/slurm/jobcomp.txt" ] && before=$(wc -l <"$work/slurm/jobcomp.txt")
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

  : >"$work/single-$name.json"
  for i in $(seq "$single"); do
    cube "-0.4$i" | sed 's/^name: tiny/name: one/' >"$work/one.yaml"
    local id
    id=$("$build/bin/pba" job submit "$work/one.yaml" --wait 2>&1 |
      sed -n 's/.*Submitted job \([^ ]*\).*/\1/p' | head -n 1)
    [ -n "$id" ] || { echo "bench_slurm: a single job failed" >&2; exit 1; }
    "$build/bin/pba" --json job status "$id" | tr -d '\n' >>"$work/single-$name.json"
    echo >>"$work/single-$name.json"
  done

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
  local runs=- submissions=-
  case $name in
    slurm*)
      local lines
      lines=$(tail -n +"$((before + 1))" "$work/slurm/jobcomp.txt")
      runs=$(grep -c "Name=pba-" <<<"$lines" || true)
      # One Slurm job name per sbatch: a job's, or a whole array's.
      submissions=$(grep -o "Name=pba-[^ ]*" <<<"$lines" | sort -u | wc -l)
      ;;
  esac
  report "$work" "$name" "$start" "$end" "$jobs" "$runs" "$single" "$submissions"
  kill "$server_pid"
  wait "$server_pid" 2>/dev/null || true
  server_pid=
}

echo "machine: $(nproc) cores, $(awk '/MemTotal/ {printf "%.0f GB", $2 / 1048576}' /proc/meminfo); commit $(git -C "$root" rev-parse --short HEAD); --slurm-poll $poll s; batch submitted $parallel at a time"
echo "| executor | turnaround of one job (median of $single) | its solve | overhead (range) | submitted to started | ended to result collected | batch jobs | succeeded | each ran once | batch wall time | jobs per minute | sbatch calls |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|"
run local --max-running 2
bash "$root/scripts/slurm-local.sh" start >/dev/null
run slurm-arrays --executor slurm --slurm-poll "$poll"
run slurm-single --executor slurm --slurm-poll "$poll" --slurm-array-min 0
