#!/bin/sh
# The runtime stage of docker/Dockerfile, as a script so that
# docker/verify-runtime-chroot.sh can run exactly the same steps without Docker:
# installs the packages of runtime-packages.txt (no recommends) and creates the
# unprivileged user `nurbsrt` (uid/gid 10001) and its data directory /data.
# Usage (as root, inside the target system): install-runtime.sh PACKAGE_LIST
set -eu
LIST=${1:?usage: install-runtime.sh runtime-packages.txt}
export DEBIAN_FRONTEND=noninteractive
apt-get update -qq
sed -e 's/#.*//' -e 's/[[:space:]]//g' "$LIST" | grep -v '^$' |
  xargs apt-get install -y -qq --no-install-recommends
rm -rf /var/lib/apt/lists/*
# A fixed uid, so that a bind-mounted data directory can be chowned to it.
groupadd --gid 10001 nurbsrt
useradd --uid 10001 --gid nurbsrt --create-home --home-dir /home/nurbsrt --shell /usr/sbin/nologin nurbsrt
mkdir -p /data
chown nurbsrt:nurbsrt /data
