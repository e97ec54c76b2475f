#!/usr/bin/env bash
# mission_limit.sh SOURCE_DIR: the demo's default mission-clock limit
# (scripts/mission-limit.sh) is 5 s per m² of the world's wall extent, at
# least 300, whatever the geometry kinds and line breaks; a world without
# coordinates is refused.
set -uo pipefail
src=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
expect() {  # FILE WANT
  local got
  got=$("$src/scripts/mission-limit.sh" "$1" 2>&1)
  [ "$got" = "$2" ] || { echo "FAIL: $1: got '$got', want '$2'"; fail=1; }
}
# two_rooms: walls from (0, 0) to (12, 7): 84 m², 420 s.
expect "$src/worlds/two_rooms.wkt" 420
# 60 x 40 m, its coordinates spread over several lines and kinds, a START
# beyond nothing and comments with numbers that are not walls: 2400 m², 12000 s.
cat >"$tmp/spread.wkt" <<'W'
# 999 999 a comment with numbers
START 1.0 1.0 0.0
MULTILINESTRING((-10 -5, 50 -5),
  (50 -5, 50 35))
POLYGON((0 0, 2 0, 2 2, 0 2, 0 0))
LINESTRING(-10 35, 50.0 35.0)
W
expect "$tmp/spread.wkt" 12000
# A 5 x 5 m box: 125 s, raised to the 300 s floor.
echo 'LINESTRING(0 0, 5 0, 5 5, 0 5, 0 0)' >"$tmp/small.wkt"
expect "$tmp/small.wkt" 300
# No coordinates: refused (exit 65), not a limit of 0.
echo '# nothing here' >"$tmp/empty.wkt"
"$src/scripts/mission-limit.sh" "$tmp/empty.wkt" >/dev/null 2>&1
rc=$?
[ "$rc" -eq 65 ] || { echo "FAIL: a world without coordinates gave exit $rc, want 65"; fail=1; }
[ "$fail" -eq 0 ] && echo "ok: mission limits"
exit "$fail"
