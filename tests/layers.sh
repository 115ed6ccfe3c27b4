#!/usr/bin/env bash
# The include layering and folder sizes of docs/DESIGN.md (tests/tools/check_layers.py),
# and the house style (.clang-format: scripts/format.sh --check lists files that differ).
# Takes (and ignores) the nurbsrt binary that scripts/test.sh passes every suite.
set -euo pipefail
cd "$(dirname "$0")/.."
status=0
python3 tests/tools/check_layers.py || status=1
if ! scripts/format.sh --check; then
    echo "tests/layers.sh: the files above differ from .clang-format (run scripts/format.sh)" >&2
    status=1
fi
exit $status
