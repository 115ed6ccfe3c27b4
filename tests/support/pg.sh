# Sourced by tests that need a real PostgreSQL (tests/api_postgres.sh,
# tests/scale_out.sh): pg_start starts a throwaway server from Debian's
# packages in a temporary directory on a free loopback port and sets
#   PG_ADMIN_URL  postgresql://postgres:<password>@127.0.0.1:<port>/postgres
#   PG_URL        the same for a fresh database "nurbsrt"
#   PG_PASSWORD, PG_PORT, PG_DIR, PG_BIN
# pg_stop stops it and removes everything. initdb and the server refuse to run
# as root, so as root they run as the `postgres` user the package creates.
# pg_available says whether the binaries are installed (callers skip visibly).
PG_BIN=${PG_BIN:-$(ls -d /usr/lib/postgresql/*/bin 2>/dev/null | sort -V | tail -n 1)}

pg_available() { [ -n "$PG_BIN" ] && [ -x "$PG_BIN/initdb" ] && [ -x "$PG_BIN/pg_ctl" ] && command -v psql >/dev/null; }

pg_as_owner() {
  if [ "$(id -u)" -eq 0 ]; then runuser -u postgres -- "$@"; else "$@"; fi
}

pg_free_port() { /usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])'; }

pg_start() {
  PG_DIR=$(mktemp -d /tmp/nurbsrt-pg-XXXXXX)
  PG_PASSWORD="pw-$RANDOM$RANDOM"
  PG_PORT=$(pg_free_port)
  printf '%s\n' "$PG_PASSWORD" > "$PG_DIR/pwfile"
  [ "$(id -u)" -eq 0 ] && chown -R postgres: "$PG_DIR"
  # Passwords over TCP (scram), so a test can also try a wrong one.
  pg_as_owner "$PG_BIN/initdb" -D "$PG_DIR/db" -U postgres --pwfile="$PG_DIR/pwfile" -E UTF8 \
    --auth-local=trust --auth-host=scram-sha-256 > "$PG_DIR/initdb.log" 2>&1 \
    || { cat "$PG_DIR/initdb.log"; return 1; }
  # fsync off: a test database need not survive a power loss, and it is much faster on a loaded disk.
  pg_as_owner "$PG_BIN/pg_ctl" -D "$PG_DIR/db" -l "$PG_DIR/server.log" -w -t 60 \
    -o "-p $PG_PORT -k $PG_DIR -c listen_addresses=127.0.0.1 -c fsync=off -c max_connections=200" start \
    > /dev/null || { cat "$PG_DIR/server.log"; return 1; }
  PG_ADMIN_URL="postgresql://postgres:$PG_PASSWORD@127.0.0.1:$PG_PORT/postgres"
  PG_URL="postgresql://postgres:$PG_PASSWORD@127.0.0.1:$PG_PORT/nurbsrt"
  psql -q "$PG_ADMIN_URL" -c "CREATE DATABASE nurbsrt" > /dev/null
}

pg_stop() {
  [ -n "${PG_DIR:-}" ] || return 0
  [ -d "$PG_DIR/db" ] && pg_as_owner "$PG_BIN/pg_ctl" -D "$PG_DIR/db" -m immediate -w stop > /dev/null 2>&1
  rm -rf "$PG_DIR"
  PG_DIR=""
}

# The preamble of a suite that needs PostgreSQL: where the binaries are missing,
# says "NAME: SKIPPED" and exits 0; else starts one, stopped when the script exits.
pg_start_or_skip() {
  local name=$1
  if ! pg_available; then
    echo "$name: SKIPPED: PostgreSQL binaries (initdb, pg_ctl, psql) not installed (Debian: postgresql)"
    exit 0
  fi
  trap pg_stop EXIT
  pg_start
  echo "$name: PostgreSQL on 127.0.0.1:$PG_PORT"
}
