#!/usr/bin/env bash
# Runs inside scripts/netns-run (loopback only): the whole set on the simulator
# explores a world by itself, recorded with lcm-logger; then the map is drawn
# and the run is measured against the world (OUT/report.json).
#   WORLD (default two_rooms; any worlds/<name>.wkt), MISSION_S (mission-clock
#   limit: simulated seconds, so the same at any SPEED; default 5 s per m² of
#   the world's extent, at least 300: a backstop, the mission ends by itself),
#   SPEED (simulator speed factor, default 1), STRATEGY (goal strategy,
#   default: the explorer config's), OUT (default out), QUIET=1 (no progress
#   lines), CONFIG (the daemons' config directory, default config),
#   STATE_TIMEOUT_S (no EXPLORE_STATE this many wall seconds: the explorer is
#   not running, the demo ends; default 30)
set -euo pipefail
cd "$(dirname "$0")/.."
[ "${PEX_IN_NETNS:-}" = "1" ] || { echo "demo-run.sh: run me through scripts/netns-run" >&2; exit 64; }
export LCM_DEFAULT_URL="udpm://239.255.76.67:7667?ttl=0"
WORLD=${WORLD:-two_rooms}
SPEED=${SPEED:-1}
OUT=${OUT:-out}
BIN=${BIN:-build/bin}
CONFIG=${CONFIG:-config}
[ -f "worlds/$WORLD.wkt" ] || { echo "demo: no world worlds/$WORLD.wkt" >&2; exit 64; }
# The mission-clock limit is a backstop: by default it grows with the world.
[ -n "${MISSION_S:-}" ] || MISSION_S=$(scripts/mission-limit.sh "worlds/$WORLD.wkt")
mkdir -p "$OUT"
rm -f "$OUT/report.json"

explorer_config=$CONFIG/explorer.toml
if [ -n "${STRATEGY:-}" ]; then
  explorer_config="$OUT/explorer.toml"
  sed "s/^goal_strategy *=.*/goal_strategy = \"$STRATEGY\"/" "$CONFIG/explorer.toml" >"$explorer_config"
fi

pids=()
cleanup() {
  for p in "${pids[@]}"; do kill -TERM "$p" 2>/dev/null || true; done
  for p in "${pids[@]}"; do wait "$p" 2>/dev/null || true; done
}
trap cleanup EXIT

lcm-logger -f -q "$OUT/demo.lcm" & pids+=($!)
"$BIN/pex-sim" --config "$CONFIG/sim.toml" --world "worlds/$WORLD.wkt" --speed "$SPEED" 2>"$OUT/sim.log" & pids+=($!)
# The base driver needs the simulated CAN bus up: wait for the sim's OK. A
# simulator that never comes up (its config refused, say) ends the demo here:
# without its clock the mission would stand still until pex-status's wall limit.
sim_up=0
for _ in $(seq 30); do "$BIN/pex-status" --seconds 0.5 --expect sim >/dev/null && { sim_up=1; break; }; done
if [ "$sim_up" = 0 ]; then
  cleanup; pids=()
  echo "demo: the simulator did not come up: $(tail -n 1 "$OUT/sim.log" 2>/dev/null)" >&2
  echo "demo: mission not done: no simulator (see $OUT/sim.log)"
  exit 1
fi
for d in lidar_reader base_driver slam polygon_mapper; do
  "$BIN/pex-${d//_/-}" --config "$CONFIG/$d.toml" 2>"$OUT/$d.log" & pids+=($!)
done
"$BIN/pex-explorer" --config "$explorer_config" 2>"$OUT/explorer.log" & pids+=($!)
# The live view: pex-viewer on this namespace's loopback, and its page handed
# to demo.sh's relay on this computer's loopback through a Unix socket in $OUT
# (a file, so it crosses the namespace; no network does).
"$BIN/pex-viewer" --config "$CONFIG/viewer.toml" 2>"$OUT/viewer.log" & pids+=($!)
viewer_port=$(sed -n 's/^port *= *\([0-9]*\).*/\1/p' "$CONFIG/viewer.toml")
if command -v socat >/dev/null; then
  socat "UNIX-LISTEN:$OUT/viewer.sock,fork,unlink-early" "TCP:127.0.0.1:${viewer_port:-8080}" 2>/dev/null & pids+=($!)
fi
url=${VIEWER_URL:-"http://127.0.0.1:${viewer_port:-8080}/ (in this network namespace)"}
echo "demo: live view at $url"
echo "demo: exploring worlds/$WORLD.wkt with the whole set (sim x$SPEED, lidar_reader, base_driver, slam,"
echo "      polygon_mapper, explorer) for at most ${MISSION_S} s of mission time; logs in $OUT/, record in $OUT/demo.lcm"
result=0
if [ "${QUIET:-0}" = 1 ]; then
  "$BIN/pex-status" --follow-mission "$MISSION_S" --state-timeout "${STATE_TIMEOUT_S:-30}" >"$OUT/progress.txt" || result=$?
  tail -n 1 "$OUT/progress.txt"
else
  "$BIN/pex-status" --follow-mission "$MISSION_S" --state-timeout "${STATE_TIMEOUT_S:-30}" || result=$?
fi
echo "demo: health of the set:"
"$BIN/pex-status" --seconds 1.5 --counters >"$OUT/health.txt" || true
[ "${QUIET:-0}" = 1 ] || cat "$OUT/health.txt"
cleanup; pids=()
trap - EXIT

"$BIN/pex-render-map" --log "$OUT/demo.lcm" --svg "$OUT/map.svg" --png "$OUT/map.png" \
  && echo "demo: map written to $OUT/map.svg and $OUT/map.png"
"$BIN/pex-explore-report" --world "worlds/$WORLD.wkt" --log "$OUT/demo.lcm" --json-out "$OUT/report.json" >/dev/null \
  || echo "demo: no report (pex-explore-report failed)"
# The last line says what happened, from the report: the phase the mission
# ended in, how much of the reachable floor the map covers, collisions.
field() { sed -n "s/.*\"$1\": *\"\{0,1\}\([^\",}]*\).*/\1/p" "$OUT/report.json" 2>/dev/null | head -n 1; }
phase=$(field phase); coverage=$(field coverage); collisions=$(field collisions)
facts="coverage ${coverage:-?} of the reachable floor, ${collisions:-?} collisions; report in $OUT/report.json"
case "$result" in
  0) echo "demo: mission DONE: no frontier left; $facts" ;;
  3) echo "demo: mission not done: the explorer's EXPLORE_STATE stopped (see $OUT/explorer.log); $facts" ;;
  2) echo "demo: mission DONE_WITH_UNREACHABLE: frontier goals are left that the robot cannot reach (the explorer's last status above says how many and why); $facts" ;;
  *) echo "demo: mission not done: ended ${phase:-without a state} within ${MISSION_S} s of mission time (MISSION_S sets the limit); $facts" ;;
esac
[ "$result" -eq 0 ]
