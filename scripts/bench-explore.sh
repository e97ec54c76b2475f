#!/usr/bin/env bash
# scripts/bench.sh explore [WORLD...] — the exploration benchmark: the whole
# daemon set explores each world (default: every worlds/*.wkt) once per goal
# strategy, with the simulator at SPEED (default 10) and every daemon on the
# simulator's clock, each run in its own private network namespace. Prints one
# JSON line per run (pex-explore-report) and writes the table into
# docs/exploration.md between the "exploration-benchmark" markers.
#   STRATEGIES (default "greedy tour"), SPEED (default 10), MISSION_S (mission
#   clock limit per run, default 4000), OUT (default out/bench-explore)
set -euo pipefail
cd "$(dirname "$0")/.."
STRATEGIES=${STRATEGIES:-greedy tour}
SPEED=${SPEED:-10}
MISSION_S=${MISSION_S:-4000}
OUT=${OUT:-out/bench-explore}
BIN=${BIN:-build/bin}
worlds=("$@")
if ((${#worlds[@]} == 0)); then
  for f in worlds/*.wkt; do worlds+=("$(basename "$f" .wkt)"); done
fi
mkdir -p "$OUT"
results="$OUT/results.jsonl"
: >"$results"
for world in "${worlds[@]}"; do
  for strategy in $STRATEGIES; do
    run="$OUT/$world-$strategy"
    echo "bench explore: $world with $strategy (speed x$SPEED, mission limit ${MISSION_S} s)" >&2
    WORLD=$world STRATEGY=$strategy SPEED=$SPEED MISSION_S=$MISSION_S OUT=$run BIN=$BIN QUIET=1 \
      scripts/netns-run bash scripts/demo-run.sh >"$run.txt" 2>&1 || true
    if [ -s "$run/report.json" ]; then
      cat "$run/report.json" | tee -a "$results"
    else
      echo "bench explore: no report for $world/$strategy (see $run.txt)" >&2
    fi
  done
done
"$BIN/pex-explore-report" --table "$results" --doc docs/exploration.md
