#!/usr/bin/env bash
# scripts/mission-limit.sh WORLD.wkt: the demo's default mission-clock limit
# for a world, in simulated seconds: 5 s per m² of the world's extent (the
# bounding box of its walls), at least 300. The limit is a backstop (the
# mission ends DONE or DONE_WITH_UNREACHABLE by itself), so it grows with the
# building: the shipped worlds' missions took 0.2 (campus) to 2.3 (intel,
# fr079) s per m² in the benchmark (docs/exploration.md), and a fixed 300 s
# cut an office short.
set -euo pipefail
[ $# -eq 1 ] && [ -r "$1" ] || { echo "usage: $0 WORLD.wkt (a readable world file)" >&2; exit 64; }
awk '
  /^[[:space:]]*(#|START)/ { next }
  {
    gsub(/(MULTI)?(LINESTRING|POLYGON)/, " "); gsub(/[(),]/, " ")
    for (i = 1; i <= NF; ++i) {
      v = $i + 0
      if (k % 2 == 0) { if (n == 0 || v < x0) x0 = v; if (n == 0 || v > x1) x1 = v }
      else { if (n == 0 || v < y0) y0 = v; if (n == 0 || v > y1) y1 = v; ++n }
      ++k
    }
  }
  END {
    if (n == 0) { print "mission-limit.sh: no coordinates in " FILENAME > "/dev/stderr"; exit 65 }
    s = int(5 * (x1 - x0) * (y1 - y0) + 0.5)
    print (s > 300 ? s : 300)
  }' "$1"
