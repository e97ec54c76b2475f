#!/usr/bin/env bash
# tools_exit_codes.sh BIN_DIR VERSION "TOOLS": the tools' exit codes are the README's
# (64 bad command line, 66 an input that cannot be read, 73 an output that cannot be
# written) and each answers --version with "<name> <version>". Every failure printed.
set -uo pipefail
bin=$1 version=$2 tools=$3
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
fails=0
expect() { # CODE DESCRIPTION CMD...: CMD must exit CODE
  local code=$1 what=$2; shift 2
  local out rc
  out=$("$@" 2>&1); rc=$?
  if [ "$rc" != "$code" ]; then echo "FAIL: $what: exit $rc, expected $code: $* -> $(head -c 300 <<<"$out")"; fails=$((fails + 1)); fi
}
[ -n "$tools" ] || { echo "no tools given"; exit 1; }
for t in $tools; do
  out=$("$bin/$t" --version 2>&1); rc=$?
  [ "$rc" = 0 ] && [ "$out" = "$t $version" ] || { echo "FAIL: $t --version: exit $rc, '$out'"; fails=$((fails + 1)); }
  expect 0 "$t --help" "$bin/$t" --help
  expect 64 "$t with an unknown flag" "$bin/$t" --no-such-flag
done
: >"$tmp/empty.lcm"
printf 'FLASER 3 1.0 1.0 1.0 0 0 0 0 0 0 0.0 robot 0.0\n' >"$tmp/tiny.clf"
for t in $tools; do
  case $t in
    pex-render-map)
      expect 66 "$t: no such log" "$bin/$t" --log "$tmp/none.lcm" --png "$tmp/x.png"
      expect 73 "$t: PNG into a missing folder" "$bin/$t" --log "$tmp/empty.lcm" --png /no/such/dir/x.png
      expect 73 "$t: SVG into a missing folder" "$bin/$t" --log "$tmp/empty.lcm" --svg /no/such/dir/x.svg
      expect 66 "$t: no such map file" "$bin/$t" --map "$tmp/none.geojson" --png "$tmp/x.png"
      expect 65 "$t: a map file that is not one" "$bin/$t" --map "$tmp/tiny.clf" --png "$tmp/x.png"
      expect 64 "$t: a log and a map file" "$bin/$t" --log "$tmp/empty.lcm" --map "$tmp/tiny.clf" --png "$tmp/x.png" ;;
    pex-carmen2lcm)
      expect 66 "$t: no such log" "$bin/$t" "$tmp/none.clf" "$tmp/out.lcm"
      expect 73 "$t: output into a missing folder" "$bin/$t" "$tmp/tiny.clf" /no/such/dir/x.lcm ;;
    pex-eval-slam)
      expect 66 "$t: no such poses file" "$bin/$t" --poses "$tmp/none.txt" --relations "$tmp/none.rel" ;;
    pex-make-world)
      expect 66 "$t: no such log" "$bin/$t" --log "$tmp/none.clf" --poses "$tmp/none.txt" --out "$tmp/w.wkt" ;;
    pex-plan)
      expect 66 "$t: no such log" "$bin/$t" --log "$tmp/none.lcm"
      expect 65 "$t: a log without MAP, every map" "$bin/$t" --log "$tmp/empty.lcm" --every-map
      expect 64 "$t: an unknown strategy" "$bin/$t" --log "$tmp/empty.lcm" --every-map --strategy nearest
      expect 73 "$t: a plans CSV it cannot write" "$bin/$t" --log "$tmp/empty.lcm" --every-map --plans-csv "$tmp/no/such/dir.csv" ;;
    pex-map)
      printf '%s' '{"type":"FeatureCollection","pex_map_format":1,"frame":"map","utime":0,"scan_utime":0,"particle":-1,
        "generation":0,"scans_inserted":0,"vertex_count":3,"free_area_m2":0.5,"obstacle_length_m":3.4,"frontier_length_m":0,
        "robot":{"x":0,"y":0,"theta":0},"features":[{"type":"Feature","properties":{"polygon":0,
        "edge_types":[["obstacle","obstacle","obstacle"]]},"geometry":{"type":"Polygon",
        "coordinates":[[[0,0],[1,0],[0,1],[0,0]]]}}]}' >"$tmp/map.geojson"
      expect 0 "$t: export of a map file" "$bin/$t" export --map "$tmp/map.geojson" --pgm "$tmp/m.pgm"
      expect 66 "$t: no such log" "$bin/$t" save "$tmp/x.geojson" --log "$tmp/none.lcm"
      expect 66 "$t: no such map file" "$bin/$t" export --map "$tmp/none.geojson" --pgm "$tmp/x.pgm"
      expect 65 "$t: a log without MAP" "$bin/$t" save "$tmp/x.geojson" --log "$tmp/empty.lcm"
      expect 65 "$t: a map file that is not one" "$bin/$t" export --map "$tmp/tiny.clf" --pgm "$tmp/x.pgm"
      expect 73 "$t: PGM into a missing folder" "$bin/$t" export --map "$tmp/map.geojson" --pgm /no/such/dir/x.pgm ;;
    pex-explore-report)
      expect 66 "$t: no such world" "$bin/$t" --world "$tmp/none.wkt" --log "$tmp/empty.lcm"
      printf 'START 1.5 1.5 0\nLINESTRING(0 0, 3 0, 3 3, 0 3, 0 0)\n' >"$tmp/room.wkt"
      expect 66 "$t: no such replayed SLAM log" "$bin/$t" --world "$tmp/room.wkt" --log "$tmp/empty.lcm" \
        --slam-poses-from "$tmp/none.lcm"
      expect 65 "$t: an empty run log" "$bin/$t" --world "$tmp/room.wkt" --log "$tmp/empty.lcm" ;;
  esac
done
if ((fails)); then echo "$fails failure(s)"; exit 1; fi
echo "tools OK: $tools"
