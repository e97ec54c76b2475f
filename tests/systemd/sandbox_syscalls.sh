#!/usr/bin/env bash
# sandbox_syscalls.sh SRC_DIR BIN_DIR: the units' SystemCallFilter= and
# RestrictAddressFamilies= against what the programs really do. Runs the simulated
# set (pex-sim, -lidar-reader, -base-driver, -slam, -polygon-mapper, -explorer with
# checkpoints on, -viewer with its page, state, events and a button fetched) and lcm-logger, each under strace -f, in a private network
# namespace: start, pex-mission start, a few seconds of mission, SIGTERM (checkpoints
# written on stop); and pex-lcm-route's ip command. Every system call each made must
# be allowed by its unit's SystemCallFilter= lines (groups expanded with
# systemd-analyze syscall-filter) and every socket family it opened must be in its
# RestrictAddressFamilies=. (No systemd needed: this is what seccomp would refuse.)
set -uo pipefail
src=$1 bin=$2
if [ "${PEX_IN_NETNS:-}" != 1 ]; then exec "$src/scripts/netns-run" "$0" "$@"; fi
command -v strace >/dev/null || { echo "strace is not installed (scripts/deps.sh)"; exit 1; }
export LCM_DEFAULT_URL="udpm://239.255.76.67:7667?ttl=0"
tmp=$(mktemp -d)
declare -A tracer=()   # unit -> strace pid
cleanup() {
  for s in "${tracer[@]}"; do pkill -TERM -P "$s" 2>/dev/null; done
  wait 2>/dev/null; [ -n "${PEX_KEEP_TRACE:-}" ] && echo "traces kept in $tmp" || rm -rf "$tmp"
}
trap cleanup EXIT
traced() { # UNIT CMD...: runs CMD under strace, its trace in $tmp/UNIT.st
  local unit=$1; shift
  strace -f -qq -o "$tmp/$unit.st" "$@" 2>"$tmp/$unit.log" &
  tracer[$unit]=$!
}
for d in slam polygon_mapper explorer; do
  sed "s#^checkpoint_file = .*#checkpoint_file = \"$tmp/$d.checkpoint\"#" "$src/config/$d.toml" >"$tmp/$d.toml"
done
traced pex-capture lcm-logger --quiet --rotate=3 --split-mb=0.05 "$tmp/capture.lcm"
traced pex-sim "$bin/pex-sim" --config "$src/config/sim.toml" --world "$src/worlds/two_rooms.wkt"
for _ in $(seq 60); do "$bin/pex-status" --seconds 0.5 --expect sim >/dev/null 2>&1 && break; done
traced pex-lidar-reader "$bin/pex-lidar-reader" --config "$src/config/lidar_reader.toml"
traced pex-base-driver "$bin/pex-base-driver" --config "$src/config/base_driver.toml"
traced pex-slam "$bin/pex-slam" --config "$tmp/slam.toml"
traced pex-polygon-mapper "$bin/pex-polygon-mapper" --config "$tmp/polygon_mapper.toml"
traced pex-explorer "$bin/pex-explorer" --config "$tmp/explorer.toml"
traced pex-viewer "$bin/pex-viewer" --config "$src/config/viewer.toml"
"$bin/pex-mission" start --timeout 60 || { echo "FAIL: the mission did not start"; tail -n 3 "$tmp"/*.log; exit 1; }
# The viewer's page, its state, a stream of events and a button, as a browser would.
for path in / /api/state; do curl -sf --max-time 5 "http://127.0.0.1:8080$path" >/dev/null \
  || { echo "FAIL: pex-viewer did not serve $path"; tail -n 3 "$tmp/pex-viewer.log"; exit 1; }; done
curl -s --max-time 2 "http://127.0.0.1:8080/events" >/dev/null
curl -sf --max-time 5 -X POST "http://127.0.0.1:8080/api/mission/resume" >/dev/null
"$bin/pex-status" --seconds 8 >/dev/null 2>&1   # the robot explores meanwhile
# stop as systemd does: SIGTERM to the program (strace then ends with it)
for u in "${!tracer[@]}"; do pkill -TERM -P "${tracer[$u]}"; done
for u in "${!tracer[@]}"; do wait "${tracer[$u]}"; done
tracer=()
ip route del 224.0.0.0/4
strace -f -qq -o "$tmp/pex-lcm-route.st" ip route replace 224.0.0.0/4 dev lo
for f in slam polygon_mapper explorer; do
  [ -s "$tmp/$f.checkpoint" ] || { echo "FAIL: no $f checkpoint: the run did not get far enough"; exit 1; }
done

expand() { # syscall names of the groups and names given
  local x
  for x in "$@"; do
    if [[ $x == @* ]]; then
      expand $(systemd-analyze syscall-filter "$x" | sed -e 's/#.*//' -e 's/^ *//' | grep -v -e '^$' -e "^$x\$")
    else echo "$x"; fi
  done
}
fails=0
for unit in pex-capture pex-sim pex-lidar-reader pex-base-driver pex-slam pex-polygon-mapper pex-explorer pex-viewer pex-lcm-route; do
  u=$src/systemd/$unit.service
  allow=$(sed -n 's/^SystemCallFilter=\([^~].*\)/\1/p' "$u")
  deny=$(sed -n 's/^SystemCallFilter=~\(.*\)/\1/p' "$u")
  [ -n "$allow" ] || { echo "FAIL: $unit: no SystemCallFilter allow-list"; fails=$((fails + 1)); continue; }
  expand $allow | sort -u >"$tmp/allow"
  expand $deny | sort -u >"$tmp/deny"
  comm -23 "$tmp/allow" "$tmp/deny" >"$tmp/allowed"
  grep -oE '^[0-9]+ +[a-z0-9_]+\(' "$tmp/$unit.st" | awk '{print $2}' | tr -d '(' | sort -u >"$tmp/used"
  n=$(wc -l <"$tmp/used")
  ((n > 20)) || { echo "FAIL: $unit: only $n system calls traced"; fails=$((fails + 1)); continue; }
  refused=$(comm -23 "$tmp/used" "$tmp/allowed" | tr '\n' ' ')
  [ -z "$refused" ] || { echo "FAIL: $unit: its SystemCallFilter refuses $refused"; fails=$((fails + 1)); }
  families=$(grep -ohE 'socket(pair)?\(AF_[A-Z0-9]+' "$tmp/$unit.st" | sed 's/.*(//' | sort -u | tr '\n' ' ')
  restrict=" $(sed -n 's/^RestrictAddressFamilies=//p' "$u") "
  for fam in $families; do
    [[ "$restrict" == *" $fam "* ]] || { echo "FAIL: $unit opens $fam, not in RestrictAddressFamilies=$restrict"; fails=$((fails + 1)); }
  done
  echo "$unit: $n system calls, sockets: ${families:-none}: allowed"
done
((fails == 0)) || exit 1
echo "sandbox OK"
