#!/usr/bin/env bash
# scripts/make-log-world.sh NAME — remakes worlds/NAME.wkt, a simulator world
# of a real building, from its real laser log in ../shared/data/:
#
#   NAME.clf --pex-carmen2lcm--> NAME.lcm
#       --pex-slam (offline, config/slam.toml + config/datasets/slam.toml)--> poses.txt (best trajectory, `t x y theta` per scan)
#       --pex-make-world--> worlds/NAME.wkt
#
# NAME is one of the logs below:
#   intel   the Intel Research Lab, Seattle (loop corridor, rooms, glass gaps)
#   fr079   building 079 of the University of Freiburg (a long corridor, offices on both sides)
#
# pex-make-world ray-traces every scan at its pose into a 5 cm log-odds grid
# and writes the boundary of the observed free space connected to the robot's
# path as walls (tools/make_world/make_world.hpp says how). pex-slam is
# deterministic (seeded), so the same inputs give the same world.
#
# Environment (all optional):
#   BUILD   build directory (default build; configured and the programs built if needed)
#   SHARED  the shared/ folder (default ../shared)
#   OUT     the world file (default worlds/NAME.wkt)
#   POSES   an existing poses file: skips pex-carmen2lcm and pex-slam
#   PNG     also draw the grid, free space, walls and path to this PNG
#   SVG     also draw the walls to this SVG
set -euo pipefail
cd "$(dirname "$0")/.."
NAME=${1:-}
case "$NAME" in
  intel)
    TITLE="polyexplore world: intel (the Intel Research Lab, Seattle, from its real laser log; ragged walls, clutter, glass gaps)" ;;
  fr079)
    TITLE="polyexplore world: fr079 (building 079, University of Freiburg, from its real laser log; a long corridor, offices with clutter)" ;;
  *)
    echo "usage: scripts/make-log-world.sh intel|fr079" >&2
    exit 64 ;;
esac
BUILD=${BUILD:-build}
SHARED=${SHARED:-../shared}
OUT=${OUT:-worlds/$NAME.wkt}
LOG="$SHARED/data/$NAME.clf"
[ -f "$LOG" ] || { echo "make-log-world: no $LOG" >&2; exit 1; }

if [ ! -f "$BUILD/CMakeCache.txt" ]; then cmake -S . -B "$BUILD" -DCMAKE_BUILD_TYPE=Release; fi
cmake --build "$BUILD" -j2 --target pex-carmen2lcm pex-slam pex-eval-slam pex-make-world

WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
if [ -z "${POSES:-}" ]; then
  "$BUILD/bin/pex-carmen2lcm" "$LOG" "$WORK/$NAME.lcm"
  # pex-slam opens an LCM instance even offline: keep it off any real network.
  scripts/netns-run "$BUILD/bin/pex-slam" --config config/slam.toml --config config/datasets/slam.toml --log "$WORK/$NAME.lcm" \
    --poses "$WORK/poses.txt" --log-level warn
  POSES="$WORK/poses.txt"
fi
ACCURACY=$("$BUILD/bin/pex-eval-slam" --poses "$POSES" --relations "$SHARED/data/$NAME.relations")
echo "make-log-world: trajectory $ACCURACY" >&2

# Every parameter explicit (these are pex-make-world's defaults); the world's
# header repeats them.
ARGS=(
  --cell-m 0.05 --max-range-m 12 --hit-log-odds 0.9 --miss-log-odds -0.15 --free-on-no-return 0
  --occupied-log-odds 0.5 --free-log-odds -0.5 --min-obstacle-cells 3 --max-unseen-pocket-m2 0.5
  --min-clutter-m2 0.0075 --spike-width-cells 1 --simplify-m 0.03
  --robot-radius-m 0.25 --start-clearance-m 0.6 --shift-margin-m 0.5
)
[ -n "${PNG:-}" ] && ARGS+=(--png "$PNG")
[ -n "${SVG:-}" ] && ARGS+=(--svg "$SVG")
"$BUILD/bin/pex-make-world" --log "$LOG" --poses "$POSES" --out "$OUT" "${ARGS[@]}" \
  --title "$TITLE" \
  --note "Made by scripts/make-log-world.sh $NAME: pex-carmen2lcm ../shared/data/$NAME.clf -> pex-slam --config config/slam.toml --config config/datasets/slam.toml" \
  --note "(offline, its best trajectory) -> pex-make-world (the parameters below). Do not edit by hand: rerun the script." \
  --note "Trajectory vs $NAME.relations (pex-eval-slam): $ACCURACY" \
  --note "Walls are the boundary of the free space the laser observed, connected to the robot's path: where the data" \
  --note "ends (doors to nowhere, views out of the building) the boundary closes the opening; inner doors stay open."
echo "make-log-world: wrote $OUT" >&2
