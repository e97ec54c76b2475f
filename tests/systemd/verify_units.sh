#!/usr/bin/env bash
# Checks the unit files with systemd-analyze verify, pointed at the built
# binaries. systemd-analyze exits 0 on most findings, so any line it prints
# about our files is a failure. Also checks every daemon has a unit.
set -euo pipefail
src=$1 bin=$2
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
cp "$src"/systemd/*.service "$src"/systemd/*.target "$tmp"/
sed -i "s#/usr/bin/pex-#$bin/pex-#" "$tmp"/*.service
out=$(systemd-analyze verify "$tmp"/*.service "$tmp"/*.target 2>&1 | grep -F "$tmp" || true)
if [ -n "$out" ]; then echo "systemd-analyze verify:"; echo "$out"; exit 1; fi
for d in lidar-reader base-driver slam polygon-mapper explorer sim; do
  [ -f "$tmp/pex-$d.service" ] || { echo "no unit for pex-$d"; exit 1; }
  grep -q '^Type=notify$' "$tmp/pex-$d.service" || { echo "pex-$d: not Type=notify"; exit 1; }
  grep -q '^WatchdogSec=' "$tmp/pex-$d.service" || { echo "pex-$d: no WatchdogSec"; exit 1; }
done
echo "units OK"
