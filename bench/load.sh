#!/usr/bin/env bash
# Load benchmark of the HTTP service: starts `nurbsrt serve` on a free loopback
# port with a temporary data dir, drives POST /v1/renders with wrk
# (bench/load.lua), and prints a Markdown table: requests/s, latency p50/p90/p99
# and the count of 200/429/503 answers per scenario:
#   cached    the same file again and again: the scene cache hits, only the render runs
#   uncached  every body unique (still a valid file): import in a child process + render
#   overload  uncached with more connections than workers + queue: shows 503 shedding
# Usage: bench/load.sh [path/to/nurbsrt]
# Settings (environment): DURATION (s per scenario, 30), CACHED_CONNECTIONS (4),
# UNCACHED_CONNECTIONS (2), OVERLOAD_CONNECTIONS (12), WORKERS (2), MAX_QUEUE (4),
# RENDER_THREADS (1), QUERY (width=256&height=256&view=iso), MODELS (space-separated
# files; default: two real models of ../shared/models, else OCCT's sample files).
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=$(realpath "${1:-build/nurbsrt}")
DURATION=${DURATION:-30}
CACHED_CONNECTIONS=${CACHED_CONNECTIONS:-4}
UNCACHED_CONNECTIONS=${UNCACHED_CONNECTIONS:-2}
OVERLOAD_CONNECTIONS=${OVERLOAD_CONNECTIONS:-12}
WORKERS=${WORKERS:-2}
MAX_QUEUE=${MAX_QUEUE:-4}
RENDER_THREADS=${RENDER_THREADS:-1}
QUERY=${QUERY:-width=256&height=256&view=iso}

[ -x "$BIN" ] || { echo "load.sh: no executable $BIN (run scripts/setup.sh)"; exit 2; }
# wrk comes from Debian; installed here on demand (it is not a build dependency).
if ! command -v wrk >/dev/null; then
  echo "load.sh: installing wrk"
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get install -y -qq --no-install-recommends wrk >/dev/null ||
    { $SUDO apt-get update -qq && $SUDO apt-get install -y -qq --no-install-recommends wrk >/dev/null; }
fi

if [ -z "${MODELS:-}" ]; then
  shared=../shared/models
  if [ -f "$shared/step/bug27693_cornetta-step.stp" ] && [ -f "$shared/iges/bearing.iges" ]; then
    MODELS="$shared/step/bug27693_cornetta-step.stp $shared/iges/bearing.iges"
  else
    echo "load.sh: $shared is absent: using OCCT's sample files instead" >&2
    MODELS="/usr/share/opencascade/data/step/screw.step /usr/share/opencascade/data/iges/bearing.iges"
  fi
fi

source tests/support/server.sh

start_server load.sh "$BIN" \
  --workers "$WORKERS" --max-queue "$MAX_QUEUE" --queue-timeout 60 --render-threads "$RENDER_THREADS" \
  --import-timeout 300 --render-timeout 300

# Scene cache lookups so far, "hits misses" (from /metrics): proves which scenario hit.
cache_counts() {
  curl -s "$URL/metrics" | awk '/^nurbsrt_scene_cache_requests_total\{result="hit"\}/ {h=$2}
                                /^nurbsrt_scene_cache_requests_total\{result="miss"\}/ {m=$2}
                                END {printf "%d %d\n", h, m}'
}

# wrk abandons the requests still in flight when its time is up, but the service
# finishes them: wait until it is idle so that they do not load the next scenario.
wait_idle() {
  for _ in $(seq 1 600); do
    curl -s "$URL/readyz" | grep -q '"active":0,.*"queued":0' && return 0
    sleep 0.5
  done
  echo "load.sh: the service did not become idle" >&2
}

rows=()
run() {  # scenario model connections mode
  local scenario=$1 model=$2 conns=$3 mode=$4 out
  local threads=$((conns < 2 ? conns : 2))
  wait_idle
  local before after
  before=$(cache_counts)
  out=$(wrk -t"$threads" -c"$conns" -d"${DURATION}s" --timeout 300s -s bench/load.lua "$URL" \
          -- "$model" "$mode" "$QUERY")
  local line
  line=$(grep '^RESULT' <<<"$out") || { echo "load.sh: wrk gave no result:"; echo "$out"; exit 1; }
  wait_idle
  after=$(cache_counts)
  local hits=$(($(cut -d' ' -f1 <<<"$after") - $(cut -d' ' -f1 <<<"$before")))
  local misses=$(($(cut -d' ' -f2 <<<"$after") - $(cut -d' ' -f2 <<<"$before")))
  declare -A r
  for kv in ${line#RESULT }; do r[${kv%%=*}]=${kv#*=}; done
  rows+=("| $scenario | $(basename "$model") | $conns | ${r[duration_s]} | ${r[requests]} | ${r[rps]} | ${r[p50_ms]} | ${r[p90_ms]} | ${r[p99_ms]} | ${r[ok]} | ${r[s429]} | ${r[s503]} | ${r[other]} | ${r[socket_errors]} | $hits / $misses |")
  echo "load.sh: $scenario $(basename "$model"): ${line#RESULT }" >&2
}

load_before=$(cut -d' ' -f1-3 /proc/loadavg)
for model in $MODELS; do
  # Warm-up: the first render imports the file and fills the cache; it must succeed.
  code=$(curl -s -o /dev/null -w '%{http_code}' --data-binary @"$model" \
           -H 'Content-Type: application/octet-stream' "$URL/v1/renders?$QUERY")
  [ "$code" = 200 ] || { echo "load.sh: warm-up render of $model answered $code"; exit 1; }
  run cached "$model" "$CACHED_CONNECTIONS" cached
  run uncached "$model" "$UNCACHED_CONNECTIONS" unique
done
set -- $MODELS
run overload "$1" "$OVERLOAD_CONNECTIONS" unique
load_after=$(cut -d' ' -f1-3 /proc/loadavg)
kill -0 "$SERVER_PID" 2>/dev/null || { echo "load.sh: the server died"; tail -20 "$TMP/server.log"; exit 1; }

cpu=$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ *//')
echo
echo "## nurbsrt load benchmark ($(date -u '+%Y-%m-%d %H:%M UTC'))"
echo
echo "Machine: $(nproc) CPUs ($cpu), $(awk '/MemTotal/ {printf "%.1f GiB", $2/1048576}' /proc/meminfo) RAM;" \
     "load average before/after: $load_before / $load_after."
echo "Server: \`nurbsrt serve --workers $WORKERS --max-queue $MAX_QUEUE --render-threads $RENDER_THREADS\`;" \
     "requests: \`POST /v1/renders?$QUERY\` with the file as raw body; ${DURATION} s per scenario (wrk)."
echo "Latencies cover every answer, 503s included (they are fast: in the overload row they pull the percentiles down)." \
     "Cache hits / misses: scene cache lookups during the scenario, from /metrics (requests abandoned by wrk at" \
     "the end still complete and are counted there)."
echo
echo "| scenario | model | connections | seconds | requests | req/s | p50 ms | p90 ms | p99 ms | 200 | 429 | 503 | other | socket errors | cache hits / misses |"
echo "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
printf '%s\n' "${rows[@]}"
