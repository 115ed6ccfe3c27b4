#!/usr/bin/env bash
# Sets up and builds (scripts/setup.sh), then runs the HTTP service on
# 127.0.0.1:8080 with its data in ./data. Extra arguments go to `nurbsrt serve`
# (e.g. scripts/serve.sh --port 9000 --workers 4); NURBSRT_* variables work too.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
BUILD_DIR=${NURBSRT_BUILD_DIR:-build}
exec "$BUILD_DIR/nurbsrt" serve --host "${NURBSRT_HOST:-127.0.0.1}" --port "${NURBSRT_PORT:-8080}" \
  --data-dir "${NURBSRT_DATA_DIR:-data}" "$@"
