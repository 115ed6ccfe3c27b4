#!/usr/bin/env bash
# Installs every Debian 12 package nurbsrt needs, then configures and builds it
# (Release, Ninja) in ./build. Idempotent: a second run installs nothing and
# only rebuilds what changed. Used by scripts/test.sh, scripts/serve.sh and the Dockerfile.
set -euo pipefail
cd "$(dirname "$0")/.."

# libfontconfig-dev: OCCT's CMake target TKService (pulled in through TKXCAF/TKRWMesh)
# links "-lfontconfig" by name, but no OCCT package depends on the -dev package, so a
# fresh Debian 12 (the Docker build stage) fails to link without it.
# iproute2: the API tests read the service's listen backlog with `ss`.
# libembree-dev: `nurbsrt bench` traces the same camera's rays through a BRepMesh
# mesh with Embree, the mesh ray tracer our frame is measured against (CMake
# builds the bench without that peer where it is missing).
# clang, libclang-rt-14-dev: the libFuzzer harnesses (scripts/fuzz.sh, the fuzz suite
# of scripts/test.sh) build with clang; libclang_rt.fuzzer and the sanitizer runtimes
# are in libclang-rt-14-dev, which clang's packages only recommend (not installed
# with --no-install-recommends). libfuzzer-14-dev is not needed: it holds a libFuzzer
# for linking by hand, not the runtime that clang's -fsanitize=fuzzer links.
# clang-format: the house style (.clang-format), checked by tests/layers.sh
# (scripts/format.sh --check).
# chromium, python3-websocket: the web page's end-to-end test (tests/webpage.sh) drives
# Debian's headless Chromium over the DevTools protocol from Python; nothing downloads
# a browser of its own.
# libpq-dev: the PostgreSQL job store (nurbsrt serve --job-store postgresql://...);
# postgresql: the server the multi-instance tests start themselves (tests/scale_out.sh,
# tests/api_postgres.sh: initdb and pg_ctl from /usr/lib/postgresql/15/bin).
PACKAGES=(
  cmake ninja-build pkg-config g++ git ca-certificates
  libgtest-dev libgmock-dev libbenchmark-dev libcli11-dev
  libocct-foundation-dev libocct-modeling-data-dev libocct-modeling-algorithms-dev
  libocct-data-exchange-dev libocct-ocaf-dev occt-misc libtbb-dev
  libfontconfig-dev
  libosmesa6-dev libopenimageio-dev libcpp-httplib-dev nlohmann-json3-dev fonts-dejavu-core
  libsqlite3-dev sqlite3 libembree-dev
  libpq-dev postgresql libzip-dev
  iproute2
  clang libclang-rt-14-dev clang-format
  python3 python3-pytest python3-requests python3-jsonschema python3-numpy python3-venv python3-setuptools
  chromium python3-websocket
  occt-draw libocct-draw-dev xvfb
)
# occt-draw, libocct-draw-dev, xvfb: bench/occt_viewer.py times OCCT's own viewer (DRAW,
# scripted for a thumbnail) against `nurbsrt render`; DRAW's plugin loader opens the
# unversioned libTKTopTest.so, which only the -dev package holds; its OpenGL view needs
# an X display (one Xvfb for the whole benchmark).
# fonts-dejavu-core: the labels of contact sheets (OpenImageIO draws DejaVu Sans).
# python3-venv, python3-setuptools: the Python client package (clients/python) is
# installed into a venv by its tests, built offline with Debian's setuptools.
# libzip-dev: ZIP answers of requests that make several files (a render's separate views,
# a conversion to OBJ and its .mtl).
# npm: tests/spectral.sh lints the OpenAPI document with Spectral, and
# tests/gltf_validator.sh checks our glb with the Khronos glTF validator, from the npm
# registry. Only where no npm is on PATH: a Node.js from elsewhere (NodeSource's
# nodejs package bundles npm) conflicts with Debian's npm package.
command -v npm >/dev/null 2>&1 || PACKAGES+=(npm)

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "setup: installing ${#missing[@]} package(s): ${missing[*]}"
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  export DEBIAN_FRONTEND=noninteractive
  # A machine where 'apt-get update' never ran has no package lists: update first.
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

BUILD_DIR=${NURBSRT_BUILD_DIR:-build}
BUILD_TYPE=${NURBSRT_BUILD_TYPE:-Release}
if [ ! -f "$BUILD_DIR/build.ninja" ]; then
  cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE="$BUILD_TYPE" ${NURBSRT_CMAKE_ARGS:-}
fi
cmake --build "$BUILD_DIR" --parallel "$(nproc)"
echo "setup: built $BUILD_DIR/nurbsrt"
