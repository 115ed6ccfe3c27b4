#!/usr/bin/env bash
# Sets up and builds (scripts/setup.sh), then runs every test suite of the project.
# Tests that need ../shared/models skip with a visible message when it is absent.
#
#   scripts/test.sh          the whole suite (what CI runs)
#   scripts/test.sh --fast   the edit loop: the `unit` ctest label and the API smoke
#                            files (tests/api.sh with NURBSRT_API_TESTS), no model,
#                            accuracy or full-frame checks, no fuzzing, no browser;
#                            the include layering (tests/layers.sh)
set -euo pipefail
cd "$(dirname "$0")/.."
fast=0
case "${1:-}" in
  "") ;;
  --fast) fast=1 ;;
  *) echo "usage: scripts/test.sh [--fast]" >&2; exit 2 ;;
esac
scripts/setup.sh
BUILD_DIR=${NURBSRT_BUILD_DIR:-build}

# The API files the fast run takes: the service's routes, errors and HTTP
# conventions, and renders (about a minute on the 2-core machine).
API_SMOKE="test_service.py test_errors.py test_http_conventions.py test_renders.py"

status=0
if [ $fast -eq 1 ]; then
  echo "== unit tests (ctest -L unit)"
  ( cd "$BUILD_DIR" && ctest --output-on-failure --timeout 900 -j "$(nproc)" -L unit ) || status=1
  echo "== tests/layers.sh"
  bash tests/layers.sh || status=1
  echo "== tests/api.sh (smoke: $API_SMOKE)"
  NURBSRT_API_TESTS="$API_SMOKE" bash tests/api.sh "$BUILD_DIR/nurbsrt" || status=1
  exit $status
fi

echo "== unit and integration tests (GoogleTest via ctest)"
( cd "$BUILD_DIR" && ctest --output-on-failure --timeout 900 -j "$(nproc)" ) || status=1

# The two API suites run side by side: each drives its own server (free port,
# data dir, job store) and leaves a core mostly idle while it waits on it. Their
# output is shown whole, one after the other.
SIDE_BY_SIDE="tests/api.sh tests/api_postgres.sh"
logs=$(mktemp -d)
trap 'rm -rf "$logs"' EXIT
pids=()
for suite in $SIDE_BY_SIDE; do
  bash "$suite" "$BUILD_DIR/nurbsrt" > "$logs/$(basename "$suite").log" 2>&1 &
  pids+=($!)
done
i=0
for suite in $SIDE_BY_SIDE; do
  rc=0
  wait "${pids[$i]}" || rc=$?
  echo "== $suite (side by side with the other API suite)"
  cat "$logs/$(basename "$suite").log"
  [ $rc -eq 0 ] || { echo "== $suite: FAILED (exit $rc)"; status=1; }
  i=$((i + 1))
done

for suite in tests/*.sh; do
  [ -e "$suite" ] || continue
  case " $SIDE_BY_SIDE " in *" $suite "*) continue ;; esac
  echo "== $suite"
  bash "$suite" "$BUILD_DIR/nurbsrt" || status=1
done
exit $status
