#!/usr/bin/env bash
# Several instances on one PostgreSQL job queue and one shared data directory
# (tests/pg/): a throwaway PostgreSQL from Debian's packages (tests/support/pg.sh),
# three `nurbsrt serve` instances, ~30 jobs, one instance SIGKILLed while it runs
# outputs; plus the start-up errors of a bad configuration. Prints the counts
# (jobs, outputs re-run, time until the dead instance's lease expired and its
# work resumed). Skips, saying so, where PostgreSQL is not installed.
# Usage: tests/scale_out.sh path/to/nurbsrt
set -euo pipefail
BIN=$(realpath "${1:?usage: tests/scale_out.sh path/to/nurbsrt}")
HERE=$(cd "$(dirname "$0")" && pwd)
source "$HERE/support/pg.sh"
pg_start_or_skip scale_out.sh
status=0
# The store's own unit tests (leases, fencing, takeover), in a database of their own.
UNIT_TESTS="$(dirname "$BIN")/nurbsrt_tests"
if [ -x "$UNIT_TESTS" ]; then
  psql -q "$PG_ADMIN_URL" -c "CREATE DATABASE unit" > /dev/null
  NURBSRT_TEST_PG_URL="${PG_ADMIN_URL%/*}/unit" "$UNIT_TESTS" --gtest_filter='PgJobStoreTest.*' --gtest_brief=1 \
    || status=1
else
  echo "scale_out.sh: $UNIT_TESTS not built: PgJobStoreTest not run"
fi
NURBSRT_BIN="$BIN" NURBSRT_TEST_PG_URL="$PG_URL" NURBSRT_TEST_PG_ADMIN="$PG_ADMIN_URL" NURBSRT_TEST_PG_PORT="$PG_PORT" \
  /usr/bin/python3 -m pytest -q -s -rs -p no:cacheprovider "$HERE/pg" || status=1
exit $status
