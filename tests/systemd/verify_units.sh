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
# After= a target without Wants= it orders against something nobody pulls in.
for u in "$tmp"/*.service "$tmp"/*.target; do
  if grep -q '^After=.*network-online.target' "$u" && ! grep -q '^Wants=.*network-online.target' "$u"; then
    echo "$(basename "$u"): After=network-online.target without Wants="; exit 1
  fi
  if grep -q '^EnvironmentFile=-/etc/polyexplore/lcm.env' "$u" && [ "$(basename "$u")" != pex-lcm-route.service ] \
     && ! grep -q '^Wants=.*pex-lcm-route.service' "$u"; then
    echo "$(basename "$u"): on the LCM bus without Wants=pex-lcm-route.service (the multicast route)"; exit 1
  fi
done
# Exit 69 (no CAN interface) is retried slowly and within a start limit.
grep -q '^StartLimitBurst=' "$tmp/pex-base-driver.service" && grep -q '^StartLimitIntervalSec=' "$tmp/pex-base-driver.service" \
  || { echo "pex-base-driver: no start limit for exit 69"; exit 1; }
echo "units OK"
