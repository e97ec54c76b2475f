#!/usr/bin/env bash
# demo_without_simulator.sh SOURCE_DIR BIN_DIR: the demo with a simulator that
# cannot start (its world file missing) must end at once, non-zero, and say so
# on its last line, not follow a mission clock that never moves.
set -uo pipefail
src=$1 bin=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cp -r "$src/config" "$tmp/config"
sed -i 's|^world_file *=.*|world_file = "/nonexistent/world.wkt"|' "$tmp/config/sim.toml"
out=$(CONFIG="$tmp/config" BIN="$bin" OUT="$tmp/out" WORLD=two_rooms SPEED=10 MISSION_S=60 QUIET=1 \
  "$src/scripts/netns-run" bash "$src/scripts/demo-run.sh" 2>&1)
rc=$?
echo "$out"
[ "$rc" -ne 0 ] || { echo "FAIL: the demo exited 0 without a simulator"; exit 1; }
last=$(tail -n 1 <<<"$out")
[ "$last" = "demo: mission not done: no simulator (see $tmp/out/sim.log)" ] \
  || { echo "FAIL: last line '$last'"; exit 1; }
grep -qF "cannot read '/nonexistent/world.wkt'" <<<"$out" || { echo "FAIL: the simulator's reason not shown"; exit 1; }
echo "ok: the demo ended without a simulator (exit $rc)"
