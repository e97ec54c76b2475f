#!/usr/bin/env bash
# scripts/bench.sh explore [WORLD...] — the exploration benchmark: the whole
# daemon set explores each world (default: every worlds/*.wkt) once per goal
# strategy, with the simulator at SPEED (default 10) and every daemon on the
# simulator's clock, each run in its own private network namespace. Prints one
# JSON line per run (pex-explore-report) and writes the table into
# docs/exploration.md between the "exploration-benchmark" markers, for the
# whole benchmark only (every world, the default strategies; DOCS=1 forces
# it, DOCS=0 keeps it out): a partial run's table stays in OUT/table.md.
#   STRATEGIES (default "greedy tour"), SPEED (default 10), MISSION_S (mission
#   clock limit per run, default 8000: campus's greedy mission took 5907 s to
#   its end on 2026-11-26, docs/exploration.md), OUT (default out/bench-explore),
#   JOBS (runs side by side, default 1), TABLE_ONLY=1 (tabulate the runs in OUT),
#   CONFIG (the daemons' config directory, default config: copied to
#   OUT/snapshot/config once at the start, so that every run has the same,
#   whatever changes in the work tree while the benchmark runs)
set -euo pipefail
cd "$(dirname "$0")/.."
STRATEGIES=${STRATEGIES:-greedy tour}
SPEED=${SPEED:-10}
MISSION_S=${MISSION_S:-8000}
OUT=${OUT:-out/bench-explore}
BIN=${BIN:-build/bin}
worlds=("$@")
whole=0
if (($# == 0)) && [ "$STRATEGIES" = "greedy tour" ]; then whole=1; fi
if ((${#worlds[@]} == 0)); then
  for f in worlds/*.wkt; do worlds+=("$(basename "$f" .wkt)"); done
fi
mkdir -p "$OUT"
results="$OUT/results.jsonl"
if [ "${TABLE_ONLY:-0}" != 1 ]; then
  # With the worlds beside it: sim.toml names its world relative to its folder.
  rm -rf "$OUT/snapshot"
  mkdir -p "$OUT/snapshot"
  cp -r "${CONFIG:-config}" "$OUT/snapshot/config"
  cp -r worlds "$OUT/snapshot/worlds"
fi
# One run (its own namespace, its own directory); the report is collected below.
run_one() {
  local world=$1 strategy=$2 run="$OUT/$1-$2"
  echo "bench explore: $world with $strategy (speed x$SPEED, mission limit ${MISSION_S} s)" >&2
  rm -f "$run/report.json"
  WORLD=$world STRATEGY=$strategy SPEED=$SPEED MISSION_S=$MISSION_S CONFIG=$OUT/snapshot/config OUT=$run BIN=$BIN QUIET=1 \
    scripts/netns-run bash scripts/demo-run.sh >"$run.txt" 2>&1 || true
}
# JOBS runs side by side (default 1): each has its own namespace and bus, and
# the simulator paces its clock to the daemons, so a loaded machine changes
# only the wall time. TABLE_ONLY=1 tabulates the runs already in OUT.
if [ "${TABLE_ONLY:-0}" != 1 ]; then
  running=0
  for world in "${worlds[@]}"; do
    for strategy in $STRATEGIES; do
      run_one "$world" "$strategy" &
      running=$((running + 1))
      if ((running >= ${JOBS:-1})); then wait -n || true; running=$((running - 1)); fi
    done
  done
  wait || true
fi
: >"$results"
for world in "${worlds[@]}"; do
  for strategy in $STRATEGIES; do
    run="$OUT/$world-$strategy"
    if [ -s "$run/report.json" ]; then
      cat "$run/report.json" | tee -a "$results"
    else
      echo "bench explore: no report for $world/$strategy (see $run.txt)" >&2
    fi
  done
done

# The table: one row per run, then the path summed per strategy over the
# worlds every strategy finished, and the tour/greedy ratio.
table="$OUT/table.md"
awk -v speed="$SPEED" '
  function field(name,   v) {  # flat JSON of pex-explore-report: no commas inside values
    v = $0
    if (!sub(".*\"" name "\": *", "", v)) return "?"
    sub(/[,}].*/, "", v); gsub(/"/, "", v)
    return v
  }
  BEGIN {
    print "| world | strategy | phase | sim time (s) | path (m) | explored (m²) | reachable (m²) | coverage | IoU | obstacle on wall | collisions | goals | plans | plan p50 (ms) | plan p99 (ms) | plan CPU p99 (ms) | control p99 (ms) | map beyond walls (m²) | SLAM error mean / max (aligned) (m) | map scored |"
    print "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
  }
  {
    w = field("world"); s = field("strategy")
    printf "| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s / %s (%s) | %s |\n", w, s, field("phase"),
      field("sim_time_s"), field("path_m"), field("explored_m2"), field("reachable_m2"), field("coverage"), field("iou"),
      field("obstacle_on_wall"), field("collisions"), field("goals"), field("plans"), field("plan_ms_p50"),
      field("plan_ms_p99"), field("plan_cpu_ms_p99"), field("control_ms_p99"), field("map_outside_free_m2"),
      field("slam_error_mean_m"), field("slam_error_max_m"), field("slam_error_aligned_mean_m"), field("scored_map")
    if (field("phase") == "done" || field("phase") == "done_with_unreachable") { path[w, s] = field("path_m"); worlds[w] = 1; strategies[s] = 1 }
  }
  END {
    printf "\nSimulator at x%s, every daemon on SIM_CLOCK. Path summed over the worlds every strategy finished:", speed
    n = 0
    for (w in worlds) { ok = 1; for (s in strategies) if (!((w, s) in path)) ok = 0; if (ok) { for (s in strategies) sum[s] += path[w, s]; n++ } }
    for (s in strategies) printf " %s %.1f m;", s, sum[s]
    if (sum["greedy"] > 0 && ("tour" in strategies)) printf " tour / greedy = %.3f", sum["tour"] / sum["greedy"]
    printf " (%d worlds).\n", n
  }' "$results" >"$table"
cat "$table"
if [ "${DOCS:-$whole}" != 1 ]; then
  echo "bench explore: a partial run: the table is in $table (DOCS=1 writes it into docs/exploration.md)" >&2
  exit 0
fi
# Into docs/exploration.md, between its markers.
awk -v table="$table" '
  /<!-- exploration-benchmark:begin -->/ { print; while ((getline line < table) > 0) print line; skip = 1; next }
  /<!-- exploration-benchmark:end -->/ { skip = 0 }
  !skip { print }' docs/exploration.md >"$OUT/exploration.md" && mv "$OUT/exploration.md" docs/exploration.md
echo "bench explore: table written to docs/exploration.md" >&2
