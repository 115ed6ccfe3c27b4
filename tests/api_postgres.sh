#!/usr/bin/env bash
# The whole API suite (tests/api.sh) once more, with the PostgreSQL job store:
# a throwaway PostgreSQL (tests/support/pg.sh) serves the shared server, and
# every extra server a test starts gets a database of its own (one per data
# directory, so a restart on the same directory finds its jobs again). Leases
# are short so that tests of a killed service see its work resume quickly.
# Skips, saying so, where PostgreSQL is not installed. Usage: tests/api_postgres.sh path/to/nurbsrt
set -euo pipefail
BIN=$(realpath "${1:?usage: tests/api_postgres.sh path/to/nurbsrt}")
HERE=$(cd "$(dirname "$0")" && pwd)
source "$HERE/support/pg.sh"
pg_start_or_skip api_postgres.sh
NURBSRT_API_JOB_STORE="$PG_URL" NURBSRT_TEST_PG_ADMIN="$PG_ADMIN_URL" NURBSRT_LEASE_SECONDS=3 \
  bash "$HERE/api.sh" "$BIN"
