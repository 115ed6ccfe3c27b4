#!/usr/bin/env bash
# The glb that `nurbsrt convert` writes, validated by the Khronos glTF
# validator (npm gltf-validator, pinned, called as a library by
# tests/tools/gltf_validate.js): 0 errors and 0 warnings, or the test fails.
# Models: OCCT's sample files (always installed), the generated coloured
# assembly (nurbsrt_fixture beside the binary), and, when ../shared/models is
# there, real assemblies and free-form parts (skipped, saying so, when absent).
# The validator comes from the npm registry into a cache outside the repository
# ($NURBSRT_GLTF_VALIDATOR_CACHE, default ~/.cache/nurbsrt/gltf-validator-<version>),
# installed once; the test skips, saying so, where npm is missing.
# Usage: tests/gltf_validator.sh [path/to/nurbsrt]
set -euo pipefail
HERE=$(cd "$(dirname "$0")" && pwd)
NURBSRT=${1:-$HERE/../build/nurbsrt}
# Pinned: a new release may add checks, which would fail this test without any change of ours.
VERSION=2.0.0-dev.3.10
CACHE=${NURBSRT_GLTF_VALIDATOR_CACHE:-$HOME/.cache/nurbsrt/gltf-validator-$VERSION}
MODELS=${NURBSRT_MODELS:-$HERE/../../shared/models}
OCCT_DATA=/usr/share/opencascade/data

if ! command -v npm >/dev/null 2>&1 || ! command -v node >/dev/null 2>&1; then
  echo "gltf_validator.sh: SKIPPED: npm/node is not installed (apt-get install npm, or run scripts/setup.sh)"
  exit 0
fi
if [ ! -d "$CACHE/node_modules/gltf-validator" ]; then
  echo "gltf_validator.sh: installing gltf-validator@$VERSION into $CACHE"
  mkdir -p "$CACHE"
  npm install --prefix "$CACHE" --no-audit --no-fund --loglevel=error "gltf-validator@$VERSION" >/dev/null
fi

TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
inputs=("$OCCT_DATA/step/screw.step" "$OCCT_DATA/iges/bearing.iges")
FIXTURE="$(dirname "$NURBSRT")/nurbsrt_fixture"
if [ -x "$FIXTURE" ]; then
  "$FIXTURE" assembly "$TMP/assembly.step"
  inputs+=("$TMP/assembly.step")
else
  echo "gltf_validator.sh: no $FIXTURE: the generated assembly is not checked"
fi
if [ -d "$MODELS" ]; then
  for m in step/as1-oc-214.stp step/box_sides.STEP step/bug27693_cornetta-step.stp step/bug31670_russian.stp \
           iges/as1_pe_203.igs iges/ship_kcs.igs; do
    inputs+=("$MODELS/$m")
  done
else
  echo "gltf_validator.sh: SKIPPED the real models: $MODELS is absent"
fi

glbs=()
for f in "${inputs[@]}"; do
  out="$TMP/$(basename "${f%.*}").glb"
  "$NURBSRT" convert -q "$f" "$out"
  glbs+=("$out")
done
if node "$HERE/tools/gltf_validate.js" "$CACHE" "${glbs[@]}"; then
  echo "gltf_validator.sh: ${#glbs[@]} glb file(s): no errors, no warnings"
else
  echo "gltf_validator.sh: FAILED: the Khronos glTF validator found problems (above)"
  exit 1
fi
