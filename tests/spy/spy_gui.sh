#!/usr/bin/env bash
# spy_gui.sh SRC_DIR BIN_DIR OUT_DIR: pex-spy and pex-logplayer-gui as a person uses
# them, on a real X server (Xvfb), inside a private network namespace while the set
# (pex-sim, lidar_reader, base_driver, slam, polygon_mapper, explorer) runs:
#  1. pex-spy opens its window and lists the set's channels, each with its registry
#     type (platform/runtime/channels.hpp) and 0 undecodable messages; the table is read
#     through the clipboard (click, Ctrl+A, Ctrl+C, xclip), as a person copies it;
#  2. a double click on MAP opens its message view (pex.polygon_map_t, jchart2d's
#     plots), which stays open while more MAP messages arrive, with no exception on
#     stderr: OUT_DIR/pex-spy.png is the screenshot of both windows;
#  3. the set stopped, pex-logplayer-gui plays a log recorded in step 1: its window
#     opens and the spy counts new LIDAR_SCAN messages again (OUT_DIR/pex-logplayer-gui.png).
# Every wait is for a state (a window, a count), bounded in time.
set -uo pipefail
src=$1 bin=$2 out=$3
if [ "${PEX_IN_NETNS:-}" != 1 ]; then exec "$src/scripts/netns-run" "$0" "$@"; fi
export LCM_DEFAULT_URL="udpm://239.255.76.67:7667?ttl=0"
mkdir -p "$out"
tmp=$(mktemp -d)
pids=() set_pids=()
cleanup() {
  for p in "${set_pids[@]}" "${pids[@]}"; do kill -TERM "$p" 2>/dev/null; done
  wait 2>/dev/null; rm -rf "$tmp"
}
trap cleanup EXIT
fail() {
  echo "FAIL: $*"
  for f in "$tmp"/*.err; do [ -s "$f" ] && { echo "--- $(basename "$f"):"; tail -n 15 "$f"; }; done
  exit 1
}
for t in Xvfb xdotool xclip import; do command -v $t >/dev/null || fail "$t not installed (scripts/deps.sh)"; done

# An X server of our own: -displayfd picks a free display number.
Xvfb -displayfd 3 -screen 0 1600x900x24 -nolisten tcp 3>"$tmp/display" 2>"$tmp/xvfb.err" & pids+=($!)
for _ in $(seq 100); do [ -s "$tmp/display" ] && break; sleep 0.1; done
[ -s "$tmp/display" ] || fail "Xvfb did not start"
export DISPLAY=:$(cat "$tmp/display")

# channel -> type from the registry (kLidarScan = "LIDAR_SCAN"; {kLidarScan, "pex.laser_scan_t", ...})
declare -A type_of
while read -r const name; do
  t=$(sed -n "s/^ *{$const, \"pex\.\([a-z0-9_]*\)\".*/\1/p" "$src/platform/runtime/channels.hpp")
  [ -n "$t" ] && type_of[$name]=$t
done < <(sed -n 's/^inline constexpr std::string_view \(k[A-Za-z]*\) = "\([A-Z_]*\)";/\1 \2/p' "$src/platform/runtime/channels.hpp")
((${#type_of[@]} >= 10)) || fail "could not read the channel registry"
expected=(LIDAR_SCAN ODOMETRY SLAM_UPDATE SLAM_POSE MAP EXPLORE_STATE DAEMON_STATUS SIM_TRUTH SIM_CLOCK)

"$bin/pex-sim" --config "$src/config/sim.toml" --world "$src/worlds/two_rooms.wkt" 2>"$tmp/sim.err" & set_pids+=($!)
for _ in $(seq 30); do "$bin/pex-status" --seconds 0.5 --expect sim >/dev/null 2>&1 && break; done
for d in lidar_reader base_driver slam polygon_mapper explorer; do
  "$bin/pex-${d//_/-}" --config "$src/config/$d.toml" 2>"$tmp/$d.err" & set_pids+=($!)
done
lcm-logger -q "$tmp/set.lcm" & set_pids+=($!)

"$bin/pex-spy" >"$tmp/spy.out" 2>"$tmp/spy.err" & pids+=($!)
spy=$(timeout 30 xdotool search --sync --name '^LCM Spy$' | head -n 1)
[ -n "$spy" ] || fail "no 'LCM Spy' window within 30 s"
grep -q "Found $(ls "$src"/lcmtypes/*.lcm | wc -l) LCM types" "$tmp/spy.out" || fail "pex-spy did not load our types: $(head -n 3 "$tmp/spy.out")"

. "$src/tests/spy/spy_table.sh"
table() { spy_table "$spy"; }
col() { awk -F'\t' -v c="$1" -v f="$2" '$1 == c { gsub(/^ +| +$/, "", $f); print $f }'; }
# 1. every expected channel listed, with its type, nothing undecodable
ok=0
for _ in $(seq 60); do
  tab=$(table)
  missing=()
  for c in "${expected[@]}"; do grep -q "^$c	" <<<"$tab" || missing+=("$c"); done
  ((${#missing[@]} == 0)) && { ok=1; break; }
  sleep 1
done
echo "lcm-spy's table:"; echo "$tab"
((ok)) || fail "channels not listed within 60 s: ${missing[*]}"
while IFS=$'\t' read -r channel type _ _ _ _ _ undecodable; do
  [ -n "$channel" ] || continue
  [ "$channel" = LCM_SELF_TEST ] && continue  # LCM's own (each C client's start-up self test), not ours
  want=${type_of[$channel]:-}
  [ -n "$want" ] || fail "channel $channel is not in the registry"
  [ "$type" = "$want" ] || fail "$channel decoded as '$type', expected $want"
  [ "${undecodable// /}" = 0 ] || fail "$channel: $undecodable undecodable messages"
done <<<"$tab"
echo "1. every channel decoded with its registry type, 0 undecodable"

# 2. the MAP message view: double click on its row (rows 16 px from y=27, in table order)
row=$(awk -F'\t' '$1 == "MAP" { print NR - 1 }' <<<"$tab")
xdotool mousemove --window "$spy" 60 $((27 + 16 * row + 8)) click --repeat 2 --delay 80 1
view=$(timeout 15 xdotool search --sync --name '^MAP$' | head -n 1)
[ -n "$view" ] || fail "no message view 'MAP' within 15 s after a double click on row $row"
# beside the spy's window (800 px wide), so the table stays clickable and both are in the picture
# Without a window manager the move lands when the X server and Java have both
# handled it, which under load can be after xdotool's --sync gave up: ask again
# until the geometry says so (a state, bounded in time), never a single look.
moved=0
for _ in $(seq 50); do
  timeout 5 xdotool windowmove "$view" 810 0 windowsize "$view" 780 880 2>/dev/null
  xdotool getwindowgeometry "$view" 2>/dev/null | grep -q 'Position: 810,0' && { moved=1; break; }
  sleep 0.2
done
((moved)) || fail "could not move the MAP view in 10 s: $(xdotool getwindowgeometry "$view")"
# MAPs published while the view is open, as polygon_mapper counts them (MAP and MAP_FREE:
# 2 a map). Read from DAEMON_STATUS: with no window manager the spy's table cannot take
# the keyboard back from the view for another copy.
published() { "$bin/pex-status" --seconds 1.2 2>/dev/null | awk '$1 == "polygon_mapper" { print $5 }'; }
maps0=$(published)
[ -n "$maps0" ] || fail "no polygon_mapper in pex-status"
for _ in $(seq 30); do
  maps=$(published)
  ((maps >= maps0 + 6)) && break
done
((maps >= maps0 + 6)) || fail "polygon_mapper published $maps0 -> $maps with the view open"
maps=$(((maps - maps0) / 2))
import -window root "$out/pex-spy.png" || fail "no screenshot"
xdotool search --name '^MAP$' >/dev/null || fail "the MAP view closed"
grep -E "Exception|Error" "$tmp/spy.err" && fail "pex-spy wrote an exception"
echo "2. the MAP view open while $maps MAPs arrived, no exception; screenshot $out/pex-spy.png"

# 3. the set stopped, the recorded log played with pex-logplayer-gui
for p in "${set_pids[@]}"; do kill -TERM "$p" 2>/dev/null; done
for p in "${set_pids[@]}"; do wait "$p" 2>/dev/null; done
set_pids=()
[ -s "$tmp/set.lcm" ] || fail "lcm-logger recorded nothing"
# with the set stopped only the player publishes: what a logger hears is its playing
lcm-logger -q "$tmp/played.lcm" & pids+=($!)
"$bin/pex-logplayer-gui" "$tmp/set.lcm" >"$tmp/player.out" 2>"$tmp/player.err" & pids+=($!)
player=$(timeout 30 xdotool search --sync --name '^LogPlayer$' | head -n 1)
[ -n "$player" ] || fail "no LogPlayer window within 30 s"
timeout 10 xdotool windowmove --sync "$player" 0 610
recorded=$(stat -c %s "$tmp/set.lcm")
for _ in $(seq 60); do
  played=$(stat -c %s "$tmp/played.lcm" 2>/dev/null || echo 0)
  ((played >= recorded / 4)) && break
  sleep 0.5
done
((played >= recorded / 4)) || fail "the player played $played bytes of a $recorded-byte log in 30 s"
import -window root "$out/pex-logplayer-gui.png" || fail "no screenshot"
grep -E "Exception|Error" "$tmp/spy.err" "$tmp/player.err" && fail "an exception"
echo "3. pex-logplayer-gui plays the log ($played of $recorded bytes heard); screenshot $out/pex-logplayer-gui.png"
echo "spy_gui: every check passed"
