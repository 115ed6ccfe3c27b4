#!/usr/bin/env bash
# Checks that docker/runtime-packages.txt, with the dependencies apt installs
# along, owns every shared library the nurbsrt binary loads (ldd), so that the
# runtime image cannot miss one. Runs on the build machine (Debian 12 with the
# build packages installed); needs no Docker daemon.
# Usage: docker/check-runtime-deps.sh [path/to/nurbsrt]   (default: build/nurbsrt)
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${1:-build/nurbsrt}
LIST=${NURBSRT_RUNTIME_PACKAGES:-docker/runtime-packages.txt}  # overridable, to test the check itself
[ -x "$BIN" ] || { echo "check-runtime-deps: no executable $BIN (build first)"; exit 2; }

mapfile -t packages < <(sed -e 's/#.*//' -e 's/[[:space:]]//g' "$LIST" | grep -v '^$')
echo "check-runtime-deps: ${#packages[@]} packages listed in $LIST"

# Every listed package must exist for this architecture.
for p in "${packages[@]}"; do
  apt-cache show "$p" >/dev/null 2>&1 || { echo "check-runtime-deps: unknown package '$p'"; exit 1; }
done

# What apt installs for the list: the packages and their Depends/Pre-Depends, recursively
# (--no-install-recommends in the Dockerfile, so no Recommends here either).
closure=$(apt-cache depends --recurse --no-recommends --no-suggests --no-conflicts --no-breaks \
            --no-replaces --no-enhances "${packages[@]}" 2>/dev/null |
          grep -v '^ ' | sed -e 's/:.*//' -e 's/[<>]//g' | sort -u)

ldd_out=$(ldd "$BIN")
if grep -q "not found" <<<"$ldd_out"; then
  echo "check-runtime-deps: ldd cannot resolve libraries on this machine:"; grep "not found" <<<"$ldd_out"; exit 1
fi

mapfile -t entries < <(awk '$2 == "=>" && $3 ~ /^\// {print $1, $3} $1 ~ /^\// {print $1, $1}' <<<"$ldd_out")

# Owners of all library paths in one dpkg call (one call per library takes minutes).
# dpkg knows a path as packaged, which on merged-/usr systems may be the /lib or the
# /usr/lib spelling, or the symlink's target: ask for all of them.
spellings() { printf '%s\n' "$1" "$(readlink -f "$1")" "${1#/usr}" "/usr$1"; }
declare -A owner_of
while IFS= read -r line; do
  owner_of["${line#*: }"]=${line%%:*}
done < <(for e in "${entries[@]}"; do spellings "${e#* }"; done | sort -u | xargs dpkg -S 2>/dev/null | grep -v ', ')

libs=0 missing=0
for e in "${entries[@]}"; do
  lib=${e%% *} path=${e#* }
  libs=$((libs + 1))
  pkg=""
  while IFS= read -r alt; do
    [ -n "${owner_of[$alt]:-}" ] && { pkg=${owner_of[$alt]}; break; }
  done < <(spellings "$path")
  if [ -z "$pkg" ]; then
    echo "check-runtime-deps: no package owns $path ($lib)"; missing=$((missing + 1))
  elif ! grep -qx "$pkg" <<<"$closure"; then
    echo "check-runtime-deps: MISSING $lib ($path) from package $pkg, not installed by $LIST"
    missing=$((missing + 1))
  fi
done

echo "check-runtime-deps: $libs libraries from ldd, $(wc -l <<<"$closure") packages in the install closure"
if ((missing)); then
  echo "check-runtime-deps: FAIL: $missing librar(y/ies) not covered"; exit 1
fi
echo "check-runtime-deps: OK: every library is owned by a package the runtime stage installs"
