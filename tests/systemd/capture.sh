#!/usr/bin/env bash
# capture.sh SRC_DIR BIN_DIR: runs pex-capture.service's ExecStart — read from the
# unit, ${VARS} as systemd sets them (Environment=, then lcm.env and capture.env),
# the LogsDirectory /var/log/polyexplore swapped for a scratch folder — inside a
# private network namespace while pex-sim and pex-lidar-reader publish, and checks:
#  1. with the shipped settings, a few seconds give a non-empty LCM log (pex.lcm.0);
#  2. a second start keeps the first recording (lcm-logger appends to pex.lcm.0);
#     SIGHUP (`systemctl kill -s HUP pex-capture`) starts a new file;
#  3. with PEX_CAPTURE_SPLIT_MB=0.02 and PEX_CAPTURE_FILES=3 the same command line
#     splits and rotates: exactly 3 files, each about the split size, none beyond.
set -uo pipefail
src=$1 bin=$2
if [ "${PEX_IN_NETNS:-}" != 1 ]; then exec "$src/scripts/netns-run" "$0" "$@"; fi
tmp=$(mktemp -d)
pids=()
cleanup() { for p in "${pids[@]}"; do kill -TERM "$p" 2>/dev/null; done; wait 2>/dev/null; rm -rf "$tmp"; }
trap cleanup EXIT
fail() { echo "FAIL: $*"; exit 1; }
unit=$src/systemd/pex-capture.service
line=$(sed -n 's/^ExecStart=//p' "$unit")
[ -n "$line" ] || fail "no ExecStart in $unit"
grep -q '^LogsDirectory=polyexplore$' "$unit" || fail "the unit does not write /var/log/polyexplore (LogsDirectory=polyexplore)"
# systemd's environment for the unit: Environment= first, EnvironmentFile= over it
for assignment in $(sed -n 's/^Environment=//p' "$unit"); do export "${assignment?}"; done
set -a; . "$src/systemd/lcm.env"; . "$src/systemd/capture.env"; set +a
[ "$LCM_DEFAULT_URL" = "udpm://239.255.76.67:7667?ttl=0" ] || fail "lcm.env: LCM_DEFAULT_URL=$LCM_DEFAULT_URL"
expand() { # the ExecStart line as systemd runs it: ${VAR} replaced, %% -> %, the LogsDirectory moved
  local l=${line//\/var\/log\/polyexplore/$tmp/logs}
  l=${l//%%/%}
  eval "printf '%s' \"$l\""
}
mkdir -p "$tmp/logs"

"$bin/pex-sim" --config "$src/config/sim.toml" --world "$src/worlds/two_rooms.wkt" 2>"$tmp/sim.log" & pids+=($!)
for _ in $(seq 30); do "$bin/pex-status" --seconds 0.5 --expect sim >/dev/null 2>&1 && break; done
"$bin/pex-lidar-reader" --config "$src/config/lidar_reader.toml" 2>"$tmp/reader.log" & pids+=($!)
"$bin/pex-status" --seconds 2 --expect lidar_reader >/dev/null 2>&1 || fail "the publishers did not come up: $(tail -n 3 "$tmp"/*.log)"

run_logger() { # seconds [hup_after_s]: runs the expanded command line, then SIGTERM as systemd stops it
  local cmd
  cmd=$(expand)
  echo "running: $cmd"
  # shellcheck disable=SC2086
  $cmd & local p=$!
  if [ -n "${2:-}" ]; then sleep "$2"; kill -HUP "$p"; fi
  sleep "$1"
  kill -0 "$p" 2>/dev/null || { wait "$p"; fail "lcm-logger exited (status $?) before being stopped"; }
  kill -TERM "$p"; wait "$p"
}
lcm_log_ok() { [ -s "$1" ] && [ "$(od -An -tx1 -N4 "$1" | tr -d ' ')" = eda1da01 ]; }  # LCM's event sync word

# 1. shipped settings
run_logger 3
ls -l "$tmp/logs"
lcm_log_ok "$tmp/logs/pex.lcm.0" || fail "no LCM log in pex.lcm.0 with the shipped settings"
size0=$(stat -c %s "$tmp/logs/pex.lcm.0")
echo "1. shipped settings: pex.lcm.0, $size0 bytes"
# 2. a restart keeps the first recording: appended to, not overwritten
cp "$tmp/logs/pex.lcm.0" "$tmp/first.lcm"
run_logger 1
size1=$(stat -c %s "$tmp/logs/pex.lcm.0")
((size1 > size0)) && cmp -s -n "$size0" "$tmp/first.lcm" "$tmp/logs/pex.lcm.0" \
  || fail "after a restart pex.lcm.0 ($size1 bytes) does not begin with the first recording ($size0 bytes)"
echo "2. restart: pex.lcm.0 $size0 -> $size1 bytes, the first recording kept"
run_logger 1 1
[ "$(stat -c %s "$tmp/logs/pex.lcm.1" 2>/dev/null)" -ge "$size1" ] 2>/dev/null && lcm_log_ok "$tmp/logs/pex.lcm.0" \
  || fail "SIGHUP did not start a new file: $(ls -l "$tmp/logs")"
echo "2. SIGHUP: new pex.lcm.0, the earlier one now pex.lcm.1"
# 3. split and rotation, with small settings
rm -f "$tmp"/logs/*
export PEX_CAPTURE_SPLIT_MB=0.02 PEX_CAPTURE_FILES=3
run_logger 6   # ~120 KB/s published: several splits of 0.02 MB
ls -l "$tmp/logs"
n=$(find "$tmp/logs" -type f | wc -l)
[ "$n" = 3 ] || fail "$n files with PEX_CAPTURE_FILES=3 (expected 3: did it split and rotate?)"
[ -f "$tmp/logs/pex.lcm.0" ] || fail "no pex.lcm.0"   # the newest: may be just begun (empty)
for i in 1 2; do lcm_log_ok "$tmp/logs/pex.lcm.$i" || fail "pex.lcm.$i is not an LCM log"; done
split_bytes=$((20 * 1048576 / 1000))
for i in 1 2; do
  s=$(stat -c %s "$tmp/logs/pex.lcm.$i")
  ((s >= split_bytes && s <= split_bytes + 65536)) || fail "pex.lcm.$i is $s bytes, not about the split ($split_bytes)"
done
echo "capture OK"
