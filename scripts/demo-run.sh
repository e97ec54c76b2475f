#!/usr/bin/env bash
# Runs inside scripts/netns-run (loopback only): the whole set on the simulator
# explores a world by itself, recorded with lcm-logger; then the map is drawn.
#   WORLD (default two_rooms; any worlds/<name>.wkt), MISSION_S (default 300),
#   SPEED (simulator speed factor, default 1), OUT (default out)
set -euo pipefail
cd "$(dirname "$0")/.."
[ "${PEX_IN_NETNS:-}" = "1" ] || { echo "demo-run.sh: run me through scripts/netns-run" >&2; exit 64; }
export LCM_DEFAULT_URL="udpm://239.255.76.67:7667?ttl=0"
WORLD=${WORLD:-two_rooms}
MISSION_S=${MISSION_S:-300}
SPEED=${SPEED:-1}
OUT=${OUT:-out}
BIN=${BIN:-build/bin}
[ -f "worlds/$WORLD.wkt" ] || { echo "demo: no world worlds/$WORLD.wkt" >&2; exit 64; }
mkdir -p "$OUT"

pids=()
cleanup() {
  for p in "${pids[@]}"; do kill -TERM "$p" 2>/dev/null || true; done
  for p in "${pids[@]}"; do wait "$p" 2>/dev/null || true; done
}
trap cleanup EXIT

lcm-logger -f -q "$OUT/demo.lcm" & pids+=($!)
sleep 0.3
"$BIN/pex-sim" --config config/sim.toml --world "worlds/$WORLD.wkt" --speed "$SPEED" 2>"$OUT/sim.log" & pids+=($!)
sleep 0.5
for d in lidar_reader base_driver slam polygon_mapper explorer; do
  "$BIN/pex-${d//_/-}" --config "config/$d.toml" 2>"$OUT/$d.log" & pids+=($!)
done
echo "demo: exploring worlds/$WORLD.wkt with the whole set (sim, lidar_reader, base_driver, slam,"
echo "      polygon_mapper, explorer) for at most ${MISSION_S} s; logs in $OUT/, record in $OUT/demo.lcm"
result=0
"$BIN/pex-status" --follow-mission "$MISSION_S" || result=$?
echo "demo: health of the set:"
"$BIN/pex-status" --seconds 1.5 --counters || true
cleanup; pids=()
trap - EXIT

"$BIN/pex-render-map" --log "$OUT/demo.lcm" --svg "$OUT/map.svg" --png "$OUT/map.png" \
  && echo "demo: map written to $OUT/map.svg and $OUT/map.png"
if [ "$result" -eq 0 ]; then
  echo "demo: mission DONE: no reachable frontier left."
else
  echo "demo: mission not DONE within ${MISSION_S} s (see the last line above; MISSION_S sets the limit)."
fi
