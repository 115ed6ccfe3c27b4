#!/usr/bin/env bash
# Throughput and queue overhead of the job stores: a fixed batch of jobs on 1, 2
# and 3 instances sharing a throwaway PostgreSQL (tests/support/pg.sh) and one
# data dir, and on one instance with SQLite, each at --workers 1 --job-runners 1
# --render-threads 1. Prints jobs/min per setup and the median queue-to-start
# latency of jobs submitted one at a time to an idle service.
# Usage: bench/scale_out.sh path/to/nurbsrt [jobs per batch, default 12]
set -euo pipefail
BIN=$(realpath "${1:?usage: bench/scale_out.sh path/to/nurbsrt [jobs]}")
HERE=$(cd "$(dirname "$0")" && pwd)
source "$HERE/../tests/support/pg.sh"
pg_available || { echo "bench/scale_out.sh: PostgreSQL binaries not installed (Debian: postgresql)"; exit 1; }
trap pg_stop EXIT
pg_start
NURBSRT_BIN="$BIN" NURBSRT_TEST_PG_ADMIN="$PG_ADMIN_URL" /usr/bin/python3 "$HERE/scale_out.py" "${2:-12}"
