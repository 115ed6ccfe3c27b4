# Sourced by the shell suites that drive a `nurbsrt serve` of their own
# (tests/api.sh, tests/webpage.sh, bench/load.sh): a temporary directory $TMP,
# removed when the script exits, with the server stopped first (TERM; KILL
# after 5 s).
#   start_server NAME BIN [serve options...]
# starts BIN serve on a free loopback port, its data in $TMP/data and its log
# in $TMP/server.log; sets SERVER_PID and URL. When it does not start within
# 10 s, prints its log and exits, naming NAME. The caller's environment
# (NURBSRT_API_KEYS=... start_server ...) is the server's.
TMP=$(mktemp -d)
SERVER_PID=""
server_cleanup() {
  if [ -n "$SERVER_PID" ] && kill -0 "$SERVER_PID" 2>/dev/null; then
    kill -TERM "$SERVER_PID" 2>/dev/null || true
    for _ in $(seq 1 50); do kill -0 "$SERVER_PID" 2>/dev/null || break; sleep 0.1; done
    kill -KILL "$SERVER_PID" 2>/dev/null || true
  fi
  rm -rf "$TMP"
}
trap server_cleanup EXIT

start_server() {
  local name=$1 bin=$2
  shift 2
  "$bin" serve --host 127.0.0.1 --port 0 --port-file "$TMP/port" --data-dir "$TMP/data" "$@" \
    2> "$TMP/server.log" &
  SERVER_PID=$!
  for _ in $(seq 1 100); do [ -s "$TMP/port" ] && break; sleep 0.1; done
  if [ ! -s "$TMP/port" ]; then
    echo "$name: the server did not start; its log:"
    cat "$TMP/server.log"
    exit 1
  fi
  URL="http://127.0.0.1:$(cat "$TMP/port")"
}
