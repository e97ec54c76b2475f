#!/usr/bin/env bash
# nspawn_root.sh DEB [ROOT]: makes, or brings up to date, the Debian 12 root that
# tests/systemd/nspawn_boot.sh boots with systemd-nspawn (docs/deployment.md, "The units
# under systemd"). Run as root, with Debian's mirror reachable; it is kept, not rebuilt
# by each test run (CI's budget):
#   - debootstrap bookworm (minbase, with systemd, dbus, sudo, openssh-server, xauth):
#     about 2 min, once;
#   - the package's Depends and Recommends, installed as the README's
#     `apt install ./polyexplore_*.deb` installs them, then the package purged and its
#     user deleted again (each test run installs the package it tests, on a root that
#     never had it): again whenever DEB's Depends or Recommends change.
# ROOT: default $PEX_NSPAWN_ROOT, else /var/cache/polyexplore/nspawn-bookworm.
# PEX_DEBIAN_MIRROR: default http://deb.debian.org/debian.
set -euo pipefail
[ $# -ge 1 ] && [ -f "$1" ] || { echo "usage: nspawn_root.sh POLYEXPLORE.deb [ROOT]" >&2; exit 64; }
deb=$(readlink -f "$1")
root=${2:-${PEX_NSPAWN_ROOT:-/var/cache/polyexplore/nspawn-bookworm}}
mirror=${PEX_DEBIAN_MIRROR:-http://deb.debian.org/debian}
[ "$(id -u)" = 0 ] || { echo "nspawn_root.sh: needs root (debootstrap, systemd-nspawn)" >&2; exit 69; }
for p in debootstrap systemd-nspawn; do
  command -v $p >/dev/null || { echo "nspawn_root.sh: no $p (apt-get install debootstrap systemd-container)" >&2; exit 69; }
done
mkdir -p "$(dirname "$root")"
exec 9>"$root.lock"
flock 9   # one writer; nspawn_boot.sh takes the lock shared

if [ ! -e "$root/.pex-bootstrapped" ]; then
  rm -rf "$root.new"
  echo "debootstrap bookworm into $root (about 2 min)"
  debootstrap --variant=minbase --include=systemd,systemd-sysv,dbus,sudo,openssh-server,xauth,procps \
    bookworm "$root.new" "$mirror" >"$root.debootstrap.log" 2>&1 \
    || { tail -n 20 "$root.debootstrap.log"; exit 1; }
  touch "$root.new/.pex-bootstrapped"
  rm -rf "$root"
  mv "$root.new" "$root"
fi

# What Debian's installer writes and debootstrap does not: the host name (robot) and
# /etc/hosts (without it neither "localhost" nor the host name resolves: sudo warns, and
# an X client cannot reach ssh -X's localhost:10). sshd as Debian ships it, plus root's
# key login for the test (X11Forwarding is Debian's default).
if [ "$(cat "$root/etc/hostname")" != robot ]; then
  echo robot >"$root/etc/hostname"
  printf '127.0.0.1\tlocalhost\n127.0.1.1\trobot\n::1\tlocalhost ip6-localhost ip6-loopback\n' >"$root/etc/hosts"
  printf 'PermitRootLogin prohibit-password\n' >"$root/etc/ssh/sshd_config.d/pex-test.conf"
fi

in_root() {
  systemd-nspawn -q -D "$root" --register=no --keep-unit --pipe -E DEBIAN_FRONTEND=noninteractive -- "$@"
}
want=$(dpkg-deb -f "$deb" Depends Recommends)
if [ "$(cat "$root/.pex-deps" 2>/dev/null)" != "$want" ]; then
  echo "installing the package's dependencies into $root"
  cp "$deb" "$root/var/tmp/polyexplore.deb"
  in_root apt-get update -q
  in_root apt-get install -y -q /var/tmp/polyexplore.deb
  in_root apt-get purge -y -q polyexplore
  in_root sh -c 'deluser --system --quiet polyexplore; delgroup --system --quiet polyexplore 2>/dev/null || true'
  in_root apt-get clean
  rm -f "$root/var/tmp/polyexplore.deb"
  echo "$want" >"$root/.pex-deps"
fi
echo "nspawn root ready: $root ($(du -sh "$root" | cut -f1))"
