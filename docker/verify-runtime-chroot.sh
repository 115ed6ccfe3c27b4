#!/usr/bin/env bash
# Tests the runtime stage of docker/Dockerfile without Docker: debootstraps a
# minimal Debian 12 (bookworm) into a directory, runs docker/install-runtime.sh
# in it (the same packages and user as the image), copies the binary in, starts
# `nurbsrt serve` there as the unprivileged user with the image's environment,
# runs the image's HEALTHCHECK command, and renders and converts a sample file
# through HTTP. Proves that the package list suffices for a working service.
# Needs root, debootstrap (installed from Debian if missing) and Debian's archive.
# Usage: docker/verify-runtime-chroot.sh [path/to/nurbsrt] [rootfs dir]
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=$(realpath "${1:-build/nurbsrt}")
ROOT=${2:-$(mktemp -d /tmp/nurbsrt-rootfs.XXXXXX)}
MIRROR=${DEBIAN_MIRROR:-http://deb.debian.org/debian}
PORT=${PORT:-18080}
[ "$(id -u)" -eq 0 ] || { echo "verify-runtime-chroot: needs root (debootstrap, chroot)"; exit 2; }
[ -x "$BIN" ] || { echo "verify-runtime-chroot: no executable $BIN"; exit 2; }
command -v debootstrap >/dev/null ||
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends debootstrap >/dev/null

SERVER_PID=""
cleanup() {
  [ -n "$SERVER_PID" ] && kill "$SERVER_PID" 2>/dev/null && wait "$SERVER_PID" 2>/dev/null || true
  mountpoint -q "$ROOT/proc" && umount "$ROOT/proc"
  [ -n "${KEEP_ROOTFS:-}" ] || rm -rf "$ROOT"
}
trap cleanup EXIT

if [ ! -x "$ROOT/bin/sh" ]; then
  echo "verify-runtime-chroot: debootstrap bookworm (minbase) into $ROOT"
  debootstrap --variant=minbase bookworm "$ROOT" "$MIRROR" >"$ROOT.debootstrap.log" 2>&1 ||
    { tail -20 "$ROOT.debootstrap.log"; exit 1; }
  rm -f "$ROOT.debootstrap.log"
fi
chmod 0755 "$ROOT"   # mktemp -d makes it 0700: the unprivileged user must reach /
cp /etc/resolv.conf "$ROOT/etc/resolv.conf"
cp docker/install-runtime.sh docker/runtime-packages.txt "$ROOT/tmp/"
echo "verify-runtime-chroot: docker/install-runtime.sh (the Dockerfile's runtime stage)"
chroot "$ROOT" /tmp/install-runtime.sh /tmp/runtime-packages.txt >/dev/null
install -m 0755 "$BIN" "$ROOT/usr/local/bin/nurbsrt"
# The image writer module, beside the binary as in the image.
install -m 0644 "$(dirname "$BIN")/libnurbsrt_image.so" "$ROOT/usr/local/bin/libnurbsrt_image.so"
mount -t proc proc "$ROOT/proc"   # the service finds its own binary through /proc/self/exe

for f in nurbsrt libnurbsrt_image.so; do
  missing=$(chroot "$ROOT" ldd "/usr/local/bin/$f" | grep -c "not found" || true)
  [ "$missing" -eq 0 ] || { chroot "$ROOT" ldd "/usr/local/bin/$f" | grep "not found"; exit 1; }
done

# The image's ENV, USER and CMD (nothing else of the host leaks in: env -i).
chroot --userspec=10001:10001 "$ROOT" env -i HOME=/home/nurbsrt PATH=/usr/local/bin:/usr/bin:/bin \
  NURBSRT_HOST=0.0.0.0 NURBSRT_PORT="$PORT" NURBSRT_DATA_DIR=/data /usr/local/bin/nurbsrt serve \
  2>"$ROOT/tmp/serve.log" &
SERVER_PID=$!
for _ in $(seq 1 50); do curl -fs "http://127.0.0.1:$PORT/healthz" >/dev/null && break; sleep 0.2; done

fail=0
check() {  # name command...
  if "${@:2}"; then echo "verify-runtime-chroot: ok   $1"; else echo "verify-runtime-chroot: FAIL $1"; fail=1; fi
}
# The HEALTHCHECK command of the Dockerfile, run inside the runtime system.
check "HEALTHCHECK (curl in the image)" chroot --userspec=10001:10001 "$ROOT" env NURBSRT_PORT="$PORT" \
  sh -c 'curl -fsS "http://127.0.0.1:${NURBSRT_PORT}/healthz" >/dev/null'
post() {  # path expected-content-type
  local got
  got=$(curl -s -o /dev/null -w '%{http_code} %{content_type}' --data-binary @/usr/share/opencascade/data/step/screw.step \
          -H 'Content-Type: application/octet-stream' "http://127.0.0.1:$PORT$1")
  [ "$got" = "200 $2" ] || { echo "  $1 answered: $got"; return 1; }
}
check "render (OSMesa, isolated import)" post "/v1/renders?width=128&height=128" image/png
for f in step:model/step iges:model/iges stl:model/stl glb:model/gltf-binary json:application/json; do
  check "conversion to ${f%%:*}" post "/v1/conversions?format=${f%%:*}" "${f#*:}"
done
check "runs as uid 10001" test "$(stat -c %u /proc/$SERVER_PID 2>/dev/null || echo none)" = 10001
check "data directory on /data" test -d "$ROOT/data/tmp"
if ((fail)); then echo "verify-runtime-chroot: server log:"; tail -20 "$ROOT/tmp/serve.log"; exit 1; fi
echo "verify-runtime-chroot: OK ($(chroot "$ROOT" dpkg -l | grep -c '^ii') packages in the runtime system)"
