#!/usr/bin/env bash
# Runs a one-node Slurm cluster on this machine, from Debian's slurmctld,
# slurmd, slurm-client and munge packages, for integration tests.
# Usage: scripts/slurm-local.sh start|stop [--clean]|status|restart-ctld|stop-ctld
#   start         writes the config, starts munged, slurmctld and slurmd and
#                 waits until the node is idle; a no-op when already up
#   stop          cancels the remaining jobs and stops the three daemons;
#                 --clean also removes the cluster's directory
#   status        says which daemons run, shows sinfo and squeue; exits 0
#                 only when all three run
#   restart-ctld  restarts slurmctld alone (or starts it after stop-ctld);
#                 jobs and node state survive
#   stop-ctld     stops slurmctld alone: the controller out of reach
# Everything (config, munge key and socket, spool, state, logs, pid files,
# job completion file) lives in one directory: $PBA_SLURM_DIR, default
# ${TMPDIR:-/tmp}/pba-slurm-<uid>. Nothing is written to system directories.
# Slurm commands need `export SLURM_CONF=<dir>/slurm.conf`; start prints it.
# Other settings: PBA_SLURM_CTLD_PORT (6917), PBA_SLURM_SLURMD_PORT (6918),
# PBA_SLURM_MIN_JOB_AGE (seconds a finished job stays in squeue and
# scontrol, 300), PBA_SLURM_SLURMD_TIMEOUT (seconds before a silent node is
# marked down and its jobs NODE_FAIL, 60).
set -euo pipefail

dir=${PBA_SLURM_DIR:-${TMPDIR:-/tmp}/pba-slurm-$(id -u)}
ctld_port=${PBA_SLURM_CTLD_PORT:-6917}
slurmd_port=${PBA_SLURM_SLURMD_PORT:-6918}
min_job_age=${PBA_SLURM_MIN_JOB_AGE:-300}
slurmd_timeout=${PBA_SLURM_SLURMD_TIMEOUT:-60}
partition=pba
host=$(hostname -s)

conf=$dir/slurm.conf
munge_socket=$dir/munge/munge.socket
export SLURM_CONF=$conf

usage() {
  echo "usage: $0 start|stop [--clean]|status|restart-ctld|stop-ctld" >&2
  exit 2
}

pid_file() {
  case $1 in
    munged) echo "$dir/munge/munged.pid" ;;
    *) echo "$dir/run/$1.pid" ;;
  esac
}
# pid_of NAME: the pid from NAME's pid file if that process is NAME and
# alive, else nothing (a stale pid file may name a reused pid). Builtins
# only, as it runs in polling loops.
pid_of() {
  local f pid="" comm="" stat=""
  f=$(pid_file "$1")
  [ -s "$f" ] || return 0
  read -r pid <"$f" || true
  pid=${pid//[^0-9]/}
  [ -n "$pid" ] && [ -r "/proc/$pid/comm" ] || return 0
  read -r comm <"/proc/$pid/comm" 2>/dev/null || return 0
  [ "$comm" = "$1" ] || return 0
  # A killed daemon may linger as a zombie until it is reaped.
  read -r stat <"/proc/$pid/stat" 2>/dev/null || return 0
  stat=${stat##*) }
  [ "${stat:0:1}" != Z ] || return 0
  echo "$pid"
}
running() { [ -n "$(pid_of "$1")" ]; }

log_of() {
  case $1 in
    munged) echo "$dir/munge/munged.log" ;;
    *) echo "$dir/log/$1.log" ;;
  esac
}

# started_by_us NAME: the pids of NAME processes started with this
# cluster's files on their command line (one whose pid file is missing,
# e.g. a daemon still starting when `start` gave up on it).
started_by_us() {
  local mark=$conf
  [ "$1" = munged ] && mark=$dir/munge/munge.key
  pgrep -x "$1" -a 2>/dev/null | awk -v m="$mark" 'index($0, m) { print $1 }' || true
}

# stop_daemon NAME: SIGTERM, up to 30 s for it to exit, then SIGKILL.
stop_daemon() {
  local pid stray
  pid=$(pid_of "$1")
  if [ -z "$pid" ]; then
    for stray in $(started_by_us "$1"); do
      kill -KILL "$stray" 2>/dev/null || true
    done
    rm -f "$(pid_file "$1")"
    return 0
  fi
  kill "$pid" 2>/dev/null || true
  for _ in $(seq 1 300); do
    [ -d "/proc/$pid" ] || break
    sleep 0.1
  done
  if [ -d "/proc/$pid" ]; then
    echo "slurm-local: $1 ($pid) ignored SIGTERM for 30 s, killing it" >&2
    kill -KILL "$pid" 2>/dev/null || true
    sleep 0.5
  fi
  rm -f "$(pid_file "$1")"
}

# wait_for NAME SECONDS: waits for NAME's pid file to name a live process.
wait_for() {
  for _ in $(seq 1 $(($2 * 5))); do
    running "$1" && return 0
    sleep 0.2
  done
  echo "slurm-local: $1 did not start; read $(log_of "$1")" >&2
  echo "slurm-local: '$0 stop' stops what did start" >&2
  exit 1
}

# port_free PORT: nothing listens on 127.0.0.1:PORT.
port_free() {
  ! (exec 3<>"/dev/tcp/127.0.0.1/$1") 2>/dev/null
}

write_conf() {
  # Node size as slurmd sees it; memory a little under the total so the
  # node is not drained for "Low RealMemory".
  local hw cpus boards sockets cores threads mem real_mem user
  hw=$(slurmd -C 2>/dev/null | head -n 1 || true)
  field() { sed -n "s/.* $1=\([0-9]*\).*/\1/p" <<<"$hw"; }
  cpus=$(field CPUs)
  boards=$(field Boards)
  sockets=$(field SocketsPerBoard)
  cores=$(field CoresPerSocket)
  threads=$(field ThreadsPerCore)
  mem=$(free -m | awk '/^Mem:/ {print $2}')
  real_mem=$((mem * 95 / 100))
  local node="NodeName=$host NodeAddr=127.0.0.1 RealMemory=$real_mem State=UNKNOWN"
  if [ -n "$cpus" ] && [ -n "$cores" ]; then
    node+=" CPUs=$cpus Boards=$boards SocketsPerBoard=$sockets CoresPerSocket=$cores ThreadsPerCore=$threads"
  else
    cpus=$(nproc)
    node+=" CPUs=$cpus"
  fi
  user=$(id -un)

  mkdir -p "$dir/state" "$dir/spool" "$dir/log" "$dir/run"
  : >"$dir/plugstack.conf"
  cat >"$conf" <<EOF
# Written by slurm-local.sh: a one-node cluster for integration tests.
ClusterName=pba
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=$user
SlurmdUser=$user
AuthType=auth/munge
CredType=cred/munge
# cred_expire also holds a requeued job back that long (120 s by default).
AuthInfo=socket=$munge_socket,cred_expire=30

StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/run/slurmctld.pid
SlurmdPidFile=$dir/run/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
PlugStackConfig=$dir/plugstack.conf
MailProg=/bin/true

# No cgroups: processes tracked through /proc, memory limits enforced by
# the accounting sampler (every 2 s) killing a step over its --mem.
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/linux
JobAcctGatherFrequency=task=2
JobAcctGatherParams=OverMemoryKill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
DefMemPerCPU=$((real_mem / cpus))
# Refuse at submission a job the node can never run (more CPUs than it
# has) rather than leave it pending for ever.
EnforcePartLimits=ALL

# No slurmdbd: finished jobs go to a text file that \`sacct -c\` reads.
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/filetxt
JobCompLoc=$dir/jobcomp.txt

# Backfill every 5 s (not 30) so a small job does not wait long behind a
# big one that does not fit yet.
SchedulerType=sched/backfill
SchedulerParameters=bf_interval=5

ReturnToService=2
MinJobAge=$min_job_age
KillWait=5
InactiveLimit=0
SlurmdTimeout=$slurmd_timeout

$node
PartitionName=$partition Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
}

start_munged() {
  running munged && return 0
  # munged wants its socket's directory searchable by all and its key
  # readable by its owner alone.
  mkdir -p "$dir/munge"
  chmod 755 "$dir" "$dir/munge"
  if [ ! -s "$dir/munge/munge.key" ]; then
    mungekey --create --keyfile="$dir/munge/munge.key"
  fi
  chmod 600 "$dir/munge/munge.key"
  munged --key-file="$dir/munge/munge.key" --socket="$munge_socket" \
    --pid-file="$dir/munge/munged.pid" --log-file="$dir/munge/munged.log" \
    --seed-file="$dir/munge/munged.seed"
  wait_for munged 10
}

start_slurmctld() {
  running slurmctld && return 0
  if ! port_free "$ctld_port"; then
    echo "slurm-local: port $ctld_port is taken (another Slurm?); set PBA_SLURM_CTLD_PORT" >&2
    exit 1
  fi
  slurmctld -f "$conf"
  wait_for slurmctld 30
}

start_slurmd() {
  running slurmd && return 0
  if ! port_free "$slurmd_port"; then
    echo "slurm-local: port $slurmd_port is taken (another Slurm?); set PBA_SLURM_SLURMD_PORT" >&2
    exit 1
  fi
  slurmd -f "$conf"
  wait_for slurmd 30
}

# wait_node_up SECONDS: waits until slurmctld answers and hears from the
# node (sinfo marks a node it has not heard from with "*"). A drained node
# counts as up: draining is the caller's business.
wait_node_up() {
  local state=""
  for _ in $(seq 1 "$1"); do
    state=$(sinfo -h -n "$host" -o %T 2>/dev/null | head -n 1 || true)
    case $state in
      *'*') ;;
      idle | mixed | allocated | completing | draining | drained)
        if [ "$state" = drained ] || [ "$state" = draining ]; then
          echo "slurm-local: note: node $host is $state ($(sinfo -h -n "$host" -o %E))"
        fi
        return 0
        ;;
    esac
    sleep 1
  done
  echo "slurm-local: node $host not up after $1 s (state: ${state:-no answer});" \
    "read $dir/log/slurmctld.log and $dir/log/slurmd.log" >&2
  echo "slurm-local: '$0 stop' stops what did start" >&2
  exit 1
}

cmd_start() {
  if running munged && running slurmctld && running slurmd; then
    echo "slurm-local: already running in $dir"
    echo "export SLURM_CONF=$conf"
    return 0
  fi
  # The munge socket path must fit a Unix socket address.
  if [ ${#munge_socket} -ge 100 ]; then
    echo "slurm-local: $dir is too long a path for the munge socket; set a shorter PBA_SLURM_DIR" >&2
    exit 1
  fi
  mkdir -p "$dir"
  # The config is rewritten only while slurmctld is down, so a partial
  # restart does not change it under a running daemon.
  if ! running slurmctld && ! running slurmd; then
    write_conf
  else
    ctld_port=$(sed -n 's/^SlurmctldPort=//p' "$conf")
    slurmd_port=$(sed -n 's/^SlurmdPort=//p' "$conf")
  fi
  start_munged
  start_slurmctld
  start_slurmd
  wait_node_up 60
  echo "slurm-local: running in $dir (partition $partition, node $host)"
  echo "export SLURM_CONF=$conf"
}

cmd_stop() {
  local clean=${1:-}
  if [ -n "$clean" ] && [ "$clean" != --clean ]; then usage; fi
  if running slurmctld; then
    local jobs
    jobs=$(squeue -h -o %A 2>/dev/null || true)
    if [ -n "$jobs" ]; then
      # shellcheck disable=SC2086  # one argument per job id
      scancel $jobs 2>/dev/null || true
      # Give slurmd a moment to kill them so none is left behind.
      for _ in $(seq 1 20); do
        [ -z "$(squeue -h -t running,completing -o %A 2>/dev/null || true)" ] && break
        sleep 0.5
      done
    fi
  fi
  stop_daemon slurmd
  stop_daemon slurmctld
  stop_daemon munged
  if [ "$clean" = --clean ]; then
    rm -rf "$dir"
    echo "slurm-local: stopped, $dir removed"
  elif [ -d "$dir" ]; then
    echo "slurm-local: stopped; state kept in $dir"
  else
    echo "slurm-local: stopped"
  fi
}

cmd_status() {
  local all=0 pid d
  for d in munged slurmctld slurmd; do
    pid=$(pid_of "$d")
    if [ -n "$pid" ]; then
      echo "$d: running (pid $pid)"
    else
      echo "$d: not running"
      all=1
    fi
  done
  if running slurmctld; then
    sinfo || true
    squeue || true
  fi
  return "$all"
}

cmd_restart_ctld() {
  if ! running munged || ! running slurmd; then
    echo "slurm-local: cluster not running; use start" >&2
    exit 1
  fi
  stop_daemon slurmctld
  # Without -c slurmctld recovers its jobs and node states from
  # StateSaveLocation.
  start_slurmctld
  wait_node_up 60
  echo "slurm-local: slurmctld restarted"
}

case ${1:-} in
  start) [ $# -eq 1 ] || usage; cmd_start ;;
  stop) [ $# -le 2 ] || usage; cmd_stop "${2:-}" ;;
  status) [ $# -eq 1 ] || usage; cmd_status ;;
  restart-ctld) [ $# -eq 1 ] || usage; cmd_restart_ctld ;;
  stop-ctld) [ $# -eq 1 ] || usage; stop_daemon slurmctld; echo "slurm-local: slurmctld stopped" ;;
  *) usage ;;
esac
