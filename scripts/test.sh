#!/usr/bin/env bash
# Sets up and builds (scripts/setup.sh), then runs every test suite of the project.
# Tests that need ../shared/models skip with a visible message when it is absent.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
BUILD_DIR=${NURBSRT_BUILD_DIR:-build}

status=0
echo "== unit and integration tests (GoogleTest via ctest)"
( cd "$BUILD_DIR" && ctest --output-on-failure --timeout 900 -j "$(nproc)" ) || status=1

for suite in tests/*.sh; do
  [ -e "$suite" ] || continue
  echo "== $suite"
  bash "$suite" "$BUILD_DIR/nurbsrt" || status=1
done
exit $status
