#!/usr/bin/env bash
# End-to-end test of the web page in a real browser: starts `nurbsrt serve` on
# a free loopback port and drives Debian's headless Chromium over the DevTools
# protocol (tests/web/webpage_e2e.py, with Debian's python3-websocket). Skips,
# saying so, where Chromium or python3-websocket is missing (scripts/setup.sh
# installs both). The service requires an API key, which the test types into
# the page. On failure, screenshots and the console go to
# <build dir>/webpage-artifacts. Usage: tests/webpage.sh path/to/nurbsrt
set -euo pipefail
BIN=$(realpath "${1:?usage: tests/webpage.sh path/to/nurbsrt}")
HERE=$(cd "$(dirname "$0")" && pwd)
PY=/usr/bin/python3   # python3 on PATH may be another build, without Debian's modules

if ! command -v chromium >/dev/null 2>&1 && ! command -v chromium-browser >/dev/null 2>&1; then
  echo "webpage.sh: SKIPPED: no chromium on PATH (apt-get install chromium, or run scripts/setup.sh)"
  exit 0
fi
if ! "$PY" -c 'import websocket' 2>/dev/null; then
  echo "webpage.sh: SKIPPED: Debian's python3-websocket is not installed (run scripts/setup.sh)"
  exit 0
fi
STEP=/usr/share/opencascade/data/step/screw.step
OTHER=/usr/share/opencascade/data/step/linkrods.step
for f in "$STEP" "$OTHER"; do
  [ -f "$f" ] || { echo "webpage.sh: $f is missing (Debian's occt-misc installs it)"; exit 1; }
done

# A part of about 300 faces (310) for the interaction latency, when ../shared/models is there.
BIG="$HERE/../../shared/models/step/box_sides.STEP"

source "$HERE/support/server.sh"

# With an API key required, as a service open to a network would run: the page
# must send it with every API request (the test types it into the page).
KEY="web-test-$(od -An -N12 -tx1 /dev/urandom | tr -d ' \n')"
NURBSRT_API_KEYS="$KEY" start_server webpage.sh "$BIN" \
  --max-upload-mb 16 --import-timeout 120 --render-timeout 120

ARTIFACTS="$(dirname "$BIN")/webpage-artifacts"
rm -rf "$ARTIFACTS"
# An assembly of two brackets under a node (the CAD views' parts panel), made with OCCT.
ASSEMBLY="$TMP/assembly.step"
"$(dirname "$BIN")/nurbsrt_fixture" assembly "$ASSEMBLY"
# The 10 mm cube the measuring step measures (its corner off the origin), made with OCCT.
CUBE="$TMP/cube10.step"
"$(dirname "$BIN")/nurbsrt_fixture" cube10 "$CUBE"
# A cylinder (r 10, h 30): a point snapped to its top rim, a curved edge.
CYLINDER="$TMP/cylinder.step"
"$(dirname "$BIN")/nurbsrt_fixture" cylinder "$CYLINDER"
status=0
NURBSRT_URL="$URL" NURBSRT_WEB_ARTIFACTS="$ARTIFACTS" NURBSRT_WEB_KEY="$KEY" \
  timeout 600 "$PY" "$HERE/web/webpage_e2e.py" "$STEP" "$OTHER" "$BIG" "$ASSEMBLY" "$CUBE" "$CYLINDER" || status=$?
if [ $status -ne 0 ]; then
  echo "webpage.sh: FAILED; artifacts in $ARTIFACTS; server log (last 30 lines):"; tail -n 30 "$TMP/server.log"
fi
exit $status
