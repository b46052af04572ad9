# Sourced by scripts that drive a pba-server of their own (demo.sh,
# study_scenes.sh): start_local_server BIN DATA [pba-server options...]
# starts BIN/pba-server on a free loopback port with the data directory
# DATA/server, its output in DATA/server.out and DATA/server.log, waits up
# to 10 s for its address, and sets server_pid and address, with the first
# start's admin token exported as PBA_TOKEN (it lends the token to the
# script's commands; `pba login --token-file` would keep it).
# stop_local_server stops it (SIGTERM, then waits); it returns 0 whether or
# not a server ran, and server_pid is empty after it.

server_pid=""
address=""

start_local_server() {
  local bin=$1 data=$2
  shift 2
  "$bin/pba-server" --data "$data/server" --listen 127.0.0.1:0 "$@" \
    >"$data/server.out" 2>"$data/server.log" &
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
  PBA_TOKEN=$(cat "$data/server/admin.token")
  export PBA_TOKEN
}

stop_local_server() {
  local stopped=1
  if [ -n "$server_pid" ] && kill -0 "$server_pid" 2>/dev/null; then
    kill -TERM "$server_pid"
    wait "$server_pid" || true
    stopped=0
  fi
  server_pid=""
  return $stopped
}
