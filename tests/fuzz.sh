#!/usr/bin/env bash
# The fuzz suite of scripts/test.sh: every libFuzzer harness of fuzz/ runs for
# NURBSRT_FUZZ_SECONDS seconds (default 30, at most 60) through scripts/fuzz.sh,
# which builds them in build-fuzz with clang first. Any crash, sanitizer error,
# unexpected exception, leak, hang or out-of-memory fails the suite and names
# the reproducer. $1 (the nurbsrt binary) is not used: the harnesses link only
# the parsers they test.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${NURBSRT_FUZZ_SECONDS:-30}
if ! [[ $seconds =~ ^[0-9]+$ ]] || [ "$seconds" -lt 1 ] || [ "$seconds" -gt 60 ]; then
  echo "tests/fuzz.sh: NURBSRT_FUZZ_SECONDS must be 1..60 (scripts/fuzz.sh runs longer)" >&2
  exit 2
fi
exec scripts/fuzz.sh "$seconds"
