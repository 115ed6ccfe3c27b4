#!/usr/bin/env bash
# The include layering and folder sizes of docs/DESIGN.md (tests/tools/check_layers.py).
# Takes (and ignores) the nurbsrt binary that scripts/test.sh passes every suite.
set -euo pipefail
exec python3 "$(dirname "$0")/tools/check_layers.py"
