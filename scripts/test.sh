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

for suite in tests/*.sh; do
  [ -e "$suite" ] || continue
  echo "== $suite"
  bash "$suite" "$BUILD_DIR/nurbsrt" || status=1
done
exit $status
