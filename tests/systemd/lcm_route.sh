#!/usr/bin/env bash
# lcm_route.sh SRC_DIR: runs pex-lcm-route.service's ExecStart (read from the unit,
# ${VARS} from systemd/lcm.env) inside a private network namespace (scripts/netns-run):
# with no multicast route, again with its own route there (idempotent), and with
# 224.0.0.0/4 on another interface (taken over). Each time: exit 0 and exactly
# one 224.0.0.0/4 route, on the interface lcm.env names.
set -euo pipefail
src=$1
if [ "${PEX_IN_NETNS:-}" != 1 ]; then exec "$src/scripts/netns-run" "$0" "$@"; fi
unit=$src/systemd/pex-lcm-route.service
cmd=$(sed -n 's/^ExecStart=//p' "$unit")
[ -n "$cmd" ] || { echo "no ExecStart in $unit"; exit 1; }
# the unit's Environment= default, then the env file over it, as systemd does
eval "$(sed -n 's/^Environment=//p' "$unit")"
set -a; . "$src/systemd/lcm.env"; set +a
dev=$PEX_LCM_ROUTE_DEV
cmd=$(eval echo "\"$cmd\"")   # ${PEX_LCM_ROUTE_DEV} as systemd expands it
echo "ExecStart: $cmd"
check() {
  local routes
  routes=$(ip route show table all 224.0.0.0/4)
  [ "$(grep -c . <<<"$routes")" = 1 ] || { echo "FAIL ($1): routes: $routes"; exit 1; }
  grep -q "dev $dev " <<<"$routes" || { echo "FAIL ($1): route not on $dev: $routes"; exit 1; }
  echo "$1: $routes"
}
ip route del 224.0.0.0/4 2>/dev/null || true
$cmd || { echo "FAIL: exit $? with no route"; exit 1; }
check "from none"
$cmd || { echo "FAIL: exit $? run again"; exit 1; }
check "again"
ip link add pexbr0 type bridge && ip link set pexbr0 up   # any other interface will do
ip route replace 224.0.0.0/4 dev pexbr0
$cmd || { echo "FAIL: exit $? with the route on pexbr0"; exit 1; }
check "over another interface's route"
echo "route OK"
