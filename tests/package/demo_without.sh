#!/usr/bin/env bash
# demo_without.sh SOURCE_DIR BIN_DIR simulator|explorer: the demo with a
# daemon that cannot start (the simulator: its world file missing; the
# explorer: an unknown key in its config) must end soon, non-zero, and say
# so on its last line, not follow a mission clock or a state that never moves.
set -uo pipefail
src=$1 bin=$2 which=$3
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cp -r "$src/config" "$tmp/config"
cp -r "$src/worlds" "$tmp/worlds"  # sim.toml names its world relative to its folder
case "$which" in
  simulator)
    sed -i 's|^world_file *=.*|world_file = "/nonexistent/world.wkt"|' "$tmp/config/sim.toml"
    want_last="demo: mission not done: no simulator (see $tmp/out/sim.log)"
    want_reason="cannot read '/nonexistent/world.wkt'" ;;
  explorer)
    echo 'no_such_key_m = 1.0' >>"$tmp/config/explorer.toml"
    want_last="demo: mission not done: the explorer's EXPLORE_STATE stopped (see $tmp/out/explorer.log)"
    want_reason="no EXPLORE_STATE for 3 s (wall clock) since the start: is the explorer running?" ;;
  *) echo "usage: $0 SOURCE_DIR BIN_DIR simulator|explorer" >&2; exit 64 ;;
esac
out=$(CONFIG="$tmp/config" BIN="$bin" OUT="$tmp/out" WORLD=two_rooms SPEED=10 MISSION_S=60 STATE_TIMEOUT_S=3 \
  "$src/scripts/netns-run" bash "$src/scripts/demo-run.sh" 2>&1)
rc=$?
echo "$out"
[ "$rc" -ne 0 ] || { echo "FAIL: the demo exited 0 without its $which"; exit 1; }
last=$(tail -n 1 <<<"$out")
[ "${last%%;*}" = "$want_last" ] || { echo "FAIL: last line '$last'"; exit 1; }
grep -qF -- "$want_reason" <<<"$out" || { echo "FAIL: '$want_reason' not shown"; exit 1; }
echo "ok: the demo ended without its $which (exit $rc)"
