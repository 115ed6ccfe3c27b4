#!/usr/bin/env bash
# API integration tests: starts the real `nurbsrt serve` on a free loopback port
# with a temporary data dir, runs tests/api/ with Debian's python3 (pytest,
# requests, jsonschema), then stops the server. Usage: tests/api.sh path/to/nurbsrt
# With NURBSRT_API_JOB_STORE set (tests/api_postgres.sh) the server keeps its
# jobs there instead of SQLite in the data dir.
set -euo pipefail
BIN=$(realpath "${1:?usage: tests/api.sh path/to/nurbsrt}")
HERE=$(cd "$(dirname "$0")" && pwd)
PY=/usr/bin/python3   # python3 on PATH may be another build without Debian's python3-* modules

source "$HERE/support/server.sh"

# Small limits so that the limit tests are cheap; 2 workers + 2 queued so that
# the concurrency test sees the queue fill up.
start_server api.sh "$BIN" \
  --workers 2 --max-queue 2 --queue-timeout 60 --max-upload-mb 4 --max-dimension 4096 \
  --max-pixels 4000000 --import-timeout 60 --render-timeout 60 --render-threads 2 \
  ${NURBSRT_API_JOB_STORE:+--job-store "$NURBSRT_API_JOB_STORE"}

# NURBSRT_API_TESTS: the test files to run (names in tests/api/, space-separated;
# scripts/test.sh --fast); default: all of them.
targets=("$HERE/api")
if [ -n "${NURBSRT_API_TESTS:-}" ]; then
  targets=()
  for f in $NURBSRT_API_TESTS; do targets+=("$HERE/api/$f"); done
fi

status=0
NURBSRT_URL="$URL" NURBSRT_BIN="$BIN" NURBSRT_DATA_DIR="$TMP/data" \
  "$PY" -m pytest -q -rs -p no:cacheprovider "${targets[@]}" || status=$?

if ! kill -0 "$SERVER_PID" 2>/dev/null; then
  echo "api.sh: the server died during the tests"; status=1
fi
if [ $status -ne 0 ]; then echo "api.sh: server log (last 40 lines):"; tail -n 40 "$TMP/server.log"; fi
exit $status
