#!/usr/bin/env bash
# Lints api_schema/openapi.json with Spectral's own OpenAPI ruleset
# (`extends: ["spectral:oas"]`, nothing switched off) and fails on any error or
# warning. @stoplight/spectral-cli comes from the npm registry, pinned, into a
# cache outside the repository ($NURBSRT_SPECTRAL_CACHE, default
# ~/.cache/nurbsrt/spectral-<version>), installed once. Skips, saying so, where
# npm is missing (scripts/setup.sh installs it). Usage: tests/spectral.sh
# [path/to/nurbsrt] (the binary is not needed: the document is linted as written).
set -euo pipefail
HERE=$(cd "$(dirname "$0")" && pwd)
DOC="$HERE/../api_schema/openapi.json"
# Pinned: a new Spectral release may add rules, which would fail this test
# without any change to the document. 6.16.3 needs Node 16.20, 18.18 or >= 20.17.
VERSION=6.16.3
CACHE=${NURBSRT_SPECTRAL_CACHE:-$HOME/.cache/nurbsrt/spectral-$VERSION}

if ! command -v npm >/dev/null 2>&1; then
  echo "spectral.sh: SKIPPED: npm is not installed (apt-get install npm, or run scripts/setup.sh)"
  exit 0
fi
SPECTRAL="$CACHE/node_modules/.bin/spectral"
if [ ! -x "$SPECTRAL" ]; then
  echo "spectral.sh: installing @stoplight/spectral-cli@$VERSION into $CACHE"
  mkdir -p "$CACHE"
  npm install --prefix "$CACHE" --no-audit --no-fund --loglevel=error "@stoplight/spectral-cli@$VERSION" >/dev/null
fi

TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
printf 'extends: ["spectral:oas"]\n' > "$TMP/.spectral.yaml"
# --fail-severity=warn: a warning fails as an error does.
if "$SPECTRAL" lint --ruleset "$TMP/.spectral.yaml" --fail-severity=warn "$DOC"; then
  echo "spectral.sh: $DOC: no errors, no warnings under spectral:oas"
else
  echo "spectral.sh: FAILED: Spectral found problems in $DOC (above)"
  exit 1
fi
