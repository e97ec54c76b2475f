#!/usr/bin/env bash
# nspawn_boot.sh SRC_DIR DEB_DIR TRUTH_MOTION [SHOT_DIR]: the package under a real
# systemd. A Debian 12 root (tests/systemd/nspawn_root.sh, kept between runs) is booted
# with `systemd-nspawn -b` in a private network (only its own loopback: LCM stays in
# it) on a throw-away overlay, and the README's "On the robot" commands are run in it
# as written:
#   1. `apt install ./build/polyexplore_*.deb`: the user, the files;
#   2. `sudoedit /etc/polyexplore/lidar_reader.toml` (the laser's address changed);
#      `systemctl enable --now polyexplore.target` with no laser and no CAN: the robot's
#      overlays win under systemd (the base driver exits 69 naming can0, the reader
#      dials the edited address, every daemon on the system clock), the multicast
#      route, health words in STATUS=, the capture records, `pex-status`,
#      `pex-mission start`, `--print-config`, `systemd-analyze security` (online);
#   3. `cp /usr/share/polyexplore/config/sim/*.toml /etc/polyexplore/`,
#      `systemctl start polyexplore-sim.target`: the units start in their After= order,
#      each after the one before is READY; every daemon OK; the robot drives;
#      `systemctl kill -s KILL pex-base-driver`: the wheels stand (SIM_TRUTH in the
#      capture, read by TRUTH_MOTION) until systemd restarts it RestartSec later, and
#      then the robot drives on;
#   4. `ssh -X robot pex-spy` from this machine (its ssh in the container's network, an
#      Xvfb screen here): lcm-spy's window opens with our types, its table (copied with
#      the keys, tests/spy/spy_table.sh) lists the set's channels decoded, no exception;
#      a screenshot in SHOT_DIR.
# Exit 0 when every check passed, 1 otherwise, 77 (skipped) when this machine cannot run
# it: not root, no systemd-nspawn, no prepared root (the message says how to make one:
# about 4 min, once), or the container does not boot.
# PEX_NSPAWN_ROOT: the prepared root (default /var/cache/polyexplore/nspawn-bookworm).
# PEX_NSPAWN_PREPARE=1: make or update that root first (needs Debian's mirror).
set -uo pipefail   # no -e: every check runs and reports
src=$1 debdir=$2 truth_motion=$3 shots=${4:-}
skip() { echo "SKIP: $*"; exit 77; }
fails=0
fail() { echo "FAIL: $*"; fails=$((fails + 1)); }

[ "$(id -u)" = 0 ] || skip "needs root (systemd-nspawn, an overlay mount)"
command -v systemd-nspawn >/dev/null || skip "no systemd-nspawn (apt-get install systemd-container)"
deb=$(ls "$debdir"/polyexplore_*.deb 2>/dev/null | head -n 1)
[ -n "$deb" ] || { echo "FAIL: no package in $debdir (package.build)"; exit 1; }
cache=${PEX_NSPAWN_ROOT:-/var/cache/polyexplore/nspawn-bookworm}
if [ -n "${PEX_NSPAWN_PREPARE:-}" ]; then "$src/tests/systemd/nspawn_root.sh" "$deb" "$cache" || exit 1; fi
[ -e "$cache/.pex-bootstrapped" ] || skip "no Debian 12 root at $cache: make it once with
  sudo $src/tests/systemd/nspawn_root.sh $deb
(about 4 min, needs Debian's mirror; kept for later runs), or run this test with PEX_NSPAWN_PREPARE=1"
[ "$(cat "$cache/.pex-deps" 2>/dev/null)" = "$(dpkg-deb -f "$deb" Depends Recommends)" ] \
  || skip "the root at $cache lacks this package's Depends or Recommends (they changed): run
  sudo $src/tests/systemd/nspawn_root.sh $deb"

exec 9>"$cache.lock"
flock -s 9   # nspawn_root.sh does not change the root under us
tmp=$(mktemp -d /var/tmp/pex-nspawn.XXXXXX)
mkdir -p "$tmp/upper" "$tmp/work" "$tmp/root"
nspawn= leader= xvfb=
cleanup() {
  if [ -n "$leader" ] && kill -0 "$leader" 2>/dev/null; then
    nsenter -t "$leader" -a -- /usr/bin/systemctl poweroff >/dev/null 2>&1
    for _ in $(seq 200); do kill -0 "$nspawn" 2>/dev/null || break; sleep 0.1; done
  fi
  [ -n "$nspawn" ] && kill "$nspawn" 2>/dev/null && wait "$nspawn" 2>/dev/null
  [ -n "$xvfb" ] && kill "$xvfb" 2>/dev/null
  mountpoint -q "$tmp/root" && umount "$tmp/root"
  rm -rf "$tmp"
}
trap cleanup EXIT
mount -t overlay overlay -o "lowerdir=$cache,upperdir=$tmp/upper,workdir=$tmp/work" "$tmp/root" \
  || skip "cannot mount an overlay over $cache"
mkdir -p "$tmp/root/root/build"
cp "$deb" "$tmp/root/root/build/"

# --- boot ---
systemd-nspawn -q -D "$tmp/root" -M "pex-test-$$" --private-network --register=no --keep-unit -b \
  >"$tmp/console.log" 2>&1 &
nspawn=$!
# The container's PID 1: nspawn's child once it is systemd (before, a helper of nspawn's).
for _ in $(seq 300); do leader=$(pgrep -P "$nspawn" -x systemd | head -n 1); [ -n "$leader" ] && break; sleep 0.1; done
[ -n "$leader" ] || skip "systemd-nspawn -b did not start a container: $(cat "$tmp/console.log")"
# A command in the container (all its namespaces, a clean environment, as root).
c() { nsenter -t "$leader" -a -- /usr/bin/env -i PATH=/usr/sbin:/usr/bin:/sbin:/bin HOME=/root LANG=C.UTF-8 "$@"; }
for _ in $(seq 300); do c test -S /run/systemd/private && break; sleep 0.1; done  # its manager is listening
state=$(c timeout 60 systemctl is-system-running --wait 2>&1)
case $state in
  running) ;;
  degraded) echo "booted degraded: $(c systemctl --failed --no-legend --plain | tr '\n' ' ')" ;;
  *) skip "the container did not boot (systemctl is-system-running: $state): $(tail -n 20 "$tmp/console.log")" ;;
esac
echo "booted: $(c systemctl --version | head -n 1), $(c sh -c '. /etc/os-release; echo $PRETTY_NAME')"

# The README's commands, as typed: shown with their output, the exit code returned.
run() {
  echo "\$ $*"
  c sh -c "cd /root && $*" >"$tmp/out" 2>&1; local rc=$?
  sed 's/^/    /' "$tmp/out"
  return $rc
}
prop() { c systemctl show -P "$2" "$1"; }
# Polls `condition` (a shell command here) until true or `seconds` pass.
wait_for() {
  local seconds=$1; shift
  local end=$((SECONDS + seconds))
  until eval "$@"; do ((SECONDS < end)) || return 1; sleep 0.2; done
}
now_us() { date +%s%6N; }
daemons="pex-lidar-reader pex-base-driver pex-slam pex-polygon-mapper pex-explorer pex-viewer"
words='^(STARTING|OK|DEGRADED|ERROR|STOPPING)\b'

# --- 1. install ---
echo "== 1. install"
run "sudo apt install -y ./build/polyexplore_*.deb" || fail "apt install of the package failed"
c id polyexplore >/dev/null 2>&1 || fail "no user polyexplore after the install"
c test -f /usr/share/polyexplore/config/slam.toml || fail "no /usr/share/polyexplore/config/slam.toml"

# --- 2. the robot's set, with no laser and no CAN ---
echo "== 2. the robot's set (no laser, no CAN here)"
printf '#!/bin/sh\nsed -i "s/^host = .*/host = \\"192.168.0.9\\"/" "$1"\n' >"$tmp/root/root/set-host"
chmod +x "$tmp/root/root/set-host"
run "SUDO_EDITOR=/root/set-host sudoedit /etc/polyexplore/lidar_reader.toml" || fail "sudoedit failed"
run "sudo systemctl enable --now polyexplore.target" || fail "systemctl enable --now polyexplore.target failed"
for u in pex-lidar-reader pex-slam pex-polygon-mapper pex-explorer pex-viewer pex-capture; do
  wait_for 30 '[ "$(prop $u ActiveState)" = active ]' || fail "$u not active: $(c systemctl status $u --no-pager -n 5)"
done
[ "$(prop pex-lcm-route ActiveState)" = active ] || fail "pex-lcm-route not active"
route=$(c ip route show 224.0.0.0/4)
[[ "$route" == *"dev lo"* ]] || fail "no multicast route on lo: $route"
# The robot's overlay wins: SocketCAN on can0, which a container has not: exit 69, retried.
wait_for 30 '[ "$(prop pex-base-driver ExecMainStatus)" = 69 ]' \
  || fail "pex-base-driver did not exit 69: $(c systemctl status pex-base-driver --no-pager -n 5)"
c journalctl -u pex-base-driver --no-pager | grep -q can0 || fail "pex-base-driver's journal does not name can0"
[ "$(prop pex-base-driver Restart)" = on-failure ] || fail "pex-base-driver Restart=$(prop pex-base-driver Restart)"
echo "pex-base-driver: exit $(prop pex-base-driver ExecMainStatus), $(prop pex-base-driver ActiveState)/$(prop pex-base-driver SubState): $(c journalctl -u pex-base-driver -o cat --no-pager | grep -m 1 can0)"
# The edited laser address is the one dialled.
wait_for 20 'c journalctl -u pex-lidar-reader --no-pager | grep -q 192.168.0.9' \
  || fail "pex-lidar-reader's journal never names the edited host 192.168.0.9: $(c journalctl -u pex-lidar-reader -o cat --no-pager | tail -n 3)"
for u in pex-lidar-reader pex-slam pex-polygon-mapper pex-explorer pex-viewer; do
  wait_for 20 '[[ "$(prop $u StatusText)" =~ $words ]]' || fail "$u: STATUS= has no state word: '$(prop $u StatusText)'"
  echo "$u: $(prop $u StatusText)"
done
wait_for 20 'c test -s /var/log/polyexplore/pex.lcm.0' || fail "the capture wrote nothing to /var/log/polyexplore/pex.lcm.0"
run "systemctl list-units 'pex-*'" || fail "systemctl list-units failed"
run "timeout 3 journalctl -u pex-slam -f"; [ $? = 124 ] || fail "journalctl -u pex-slam -f ended by itself"
grep -q . "$tmp/out" || fail "journalctl -u pex-slam showed nothing"
run "pex-status --seconds 2" || true
for d in lidar_reader slam polygon_mapper explorer viewer; do
  grep -Eq "\b$d\b.*\b(OK|DEGRADED|ERROR|STARTING)\b" "$tmp/out" || fail "pex-status does not show $d with a state word"
done
run "pex-mission start" || fail "pex-mission start failed"
run "pex-slam --print-config --config /usr/share/polyexplore/config/slam.toml --config /etc/polyexplore/slam.toml" \
  || fail "pex-slam --print-config failed"
grep -q '^clock = "system" .*# /etc/polyexplore/slam.toml:' "$tmp/out" || fail "the robot's clock does not come from /etc/polyexplore/slam.toml"
for d in lidar_reader slam polygon_mapper explorer; do  # the running daemons: clock from /etc
  out=$(c sh -c "pex-${d//_/-} --print-config \$(systemctl show -P ExecStart pex-${d//_/-} | sed 's/.*argv\[\]=[^ ]* \([^;]*\);.*/\1/')")
  grep -q '^clock = "system" .*# /etc/polyexplore/' <<<"$out" || fail "pex-${d//_/-}, as its unit runs it: clock not the robot's: $(grep '^clock' <<<"$out")"
done
echo "systemd-analyze security under this systemd (online):"
for u in $daemons pex-sim pex-capture pex-lcm-route; do
  score=$(c systemd-analyze security "$u.service" 2>/dev/null | sed -n 's/.*Overall exposure level for [^:]*: \([0-9.]*\).*/\1/p')
  echo "  $u: ${score:-?}"
  [ -n "$score" ] && awk -v s="$score" 'BEGIN { exit !(s <= 4.0) }' || fail "$u: exposure ${score:-unknown} > 4.0"
done

# --- 3. the simulator's set: order, READY, health, a killed driver ---
echo "== 3. the simulator's set"
run "sudo systemctl disable --now polyexplore.target" || fail "systemctl disable --now polyexplore.target failed"
run "sudo cp /usr/share/polyexplore/config/sim/*.toml /etc/polyexplore/ && sudo systemctl start polyexplore-sim.target" \
  || fail "starting polyexplore-sim.target failed"
for u in pex-sim $daemons pex-capture; do
  wait_for 30 '[ "$(prop $u ActiveState)" = active ]' || fail "$u not active: $(c systemctl status $u --no-pager -n 5)"
done
# In order: a unit's process started after each pex unit it is After= was READY (Type=notify: active).
t0=$(prop pex-sim ExecMainStartTimestampMonotonic)
for u in pex-sim $daemons; do
  start=$(prop $u ExecMainStartTimestampMonotonic) ready=$(prop $u ActiveEnterTimestampMonotonic)
  echo "$u: started +$(( (start - t0) / 1000 )) ms, READY +$(( (ready - t0) / 1000 )) ms"
  for v in $(prop $u After); do
    case $v in pex-sim.service|pex-lidar-reader.service|pex-base-driver.service|pex-slam.service|pex-polygon-mapper.service) ;; *) continue ;; esac
    v_ready=$(prop "$v" ActiveEnterTimestampMonotonic)
    ((start >= v_ready)) || fail "$u started before $v was READY ($start < $v_ready)"
  done
done
for u in pex-sim $daemons; do
  wait_for 60 '[[ "$(prop $u StatusText)" == OK* ]]' || fail "$u never OK: '$(prop $u StatusText)'"
done
run "systemctl status pex-slam"
grep -q 'Status: "OK' "$tmp/out" || fail "systemctl status pex-slam shows no health word"
log=$tmp/root/var/log/polyexplore/pex.lcm.0
speed_now() {  # SIM_TRUTH's largest speed in the last second of the capture
  local t; t=$(now_us); "$truth_motion" "$log" $((t - 1000000)) "$t" | sed -n 's/.*max_speed_mps \([0-9.]*\).*/\1/p'
}
moving() { awk -v v="$(speed_now)" 'BEGIN { exit !(v > 0.2) }'; }
# The wheels turned in the half second before `t`: the robot moved or turned.
turning_before() {
  "$truth_motion" "$log" $(($1 - 500000)) "$1" \
    | awk '{ for (i = 1; i < NF; i++) v[$i] = $(i + 1) } END { exit !(v["max_speed_mps"] > 0.1 || v["max_omega_radps"] > 0.2) }'
}
wait_for 120 moving || fail "the robot never drove faster than 0.2 m/s (explorer: $(prop pex-explorer StatusText))"
pid=$(prop pex-base-driver MainPID)
c systemctl kill -s KILL pex-base-driver   # returns once the signal is sent
t_kill=$(now_us)
wait_for 10 '[ "$(prop pex-base-driver SubState)" = auto-restart ]' \
  || fail "pex-base-driver killed: not waiting for its restart ($(prop pex-base-driver ActiveState)/$(prop pex-base-driver SubState))"
wait_for 30 '[ "$(prop pex-base-driver NRestarts)" -ge 1 ] && [ "$(prop pex-base-driver ActiveState)" = active ]' \
  || fail "pex-base-driver not restarted: $(c systemctl status pex-base-driver --no-pager -n 5)"
[ "$(prop pex-base-driver MainPID)" != "$pid" ] || fail "pex-base-driver has the same process after the kill"
restart_us=$(date -d "$(c systemctl show -P ExecMainStartTimestamp --timestamp=us+utc pex-base-driver | cut -d' ' -f2-)" +%s%6N)
dead_s=$(awk -v a="$t_kill" -v b="$restart_us" 'BEGIN { printf "%.1f", (b - a) / 1e6 }')
awk -v d="$dead_s" 'BEGIN { exit !(d >= 9.5) }' || fail "restarted $dead_s s after the kill (RestartSec=10s)"
# The drives stop the wheels by themselves: drive_heartbeat_consumer_ms after the
# driver's last heartbeat (at most master_heartbeat_period_ms before the kill), then a
# quick stop ramp of quick_stop_decel_mps2 at the wheel from the fastest wheel's speed
# (v + omega * wheel_base / 2) before the kill (docs/can.md; ctest -L faults measures
# it driving straight). Those times are pex-sim's clock, which it holds while SLAM_POSE
# lags (pacing: with no odometry SLAM stops, until pace_silence_s of wall time): so the
# stop is read on SIM_TRUTH's clock, and the robot must stand from then until the new
# driver starts. The values are the installed configuration's.
cfg() { c sh -c "$1 --print-config --config /usr/share/polyexplore/config/$2.toml --config /etc/polyexplore/$2.toml" \
          | sed -n "s/^$3 = \([0-9.]*\) .*/\1/p"; }
consumer_ms=$(cfg pex-base-driver base_driver drive_heartbeat_consumer_ms)
period_ms=$(cfg pex-base-driver base_driver master_heartbeat_period_ms)
decel=$(cfg pex-base-driver base_driver quick_stop_decel_mps2)
wheel_base=$(cfg pex-sim sim base.wheel_base_m)
read -r _ _ _ _ _ v_kill _ w_kill _ < <("$truth_motion" "$log" $((t_kill - 500000)) "$t_kill")
limit_ms=$(awk -v c="$consumer_ms" -v p="$period_ms" -v d="$decel" -v b="$wheel_base" -v v="$v_kill" -v w="$w_kill" \
  'BEGIN { printf "%d", c + p + 1000 * (v + w * b / 2) / d }')
read -r _ n _ moved _ vmax _ _ _ stood_wall _ stood_sim < <("$truth_motion" "$log" "$t_kill" "$restart_us")
echo "pex-base-driver killed at $v_kill m/s, $w_kill rad/s; restarted by systemd $dead_s s later; the robot stood ${stood_sim} ms of simulated time after the kill (limit $limit_ms ms: $consumer_ms + $period_ms + the ramp; ${stood_wall} ms of wall time; $n SIM_TRUTH poses) until then"
((n > 100)) || fail "only $n SIM_TRUTH poses captured while the driver was dead"
[ -n "$consumer_ms" ] && [ -n "$period_ms" ] && [ -n "$decel" ] && [ -n "$wheel_base" ] || fail "could not read the drive watchdog's settings"
((stood_sim >= 0 && stood_sim <= limit_ms)) \
  || fail "the wheels did not stand within $limit_ms ms (simulated) of the kill until the restart: from +$stood_sim ms (moved $moved m, max $vmax m/s)"
wait_for 60 moving || fail "the robot did not drive again after the driver's restart"
c journalctl -u pex-base-driver -o cat --no-pager | grep -m 1 'restart counter' || fail "the journal does not show the scheduled restart"
run "ls -l /var/log/polyexplore"
grep -Eq -- '-rw-r----- +1 polyexplore polyexplore .* pex\.lcm\.0' "$tmp/out" || fail "the capture is not 0640 polyexplore:polyexplore"

# --- 4. ssh -X robot pex-spy ---
echo "== 4. ssh -X robot pex-spy"
if command -v Xvfb >/dev/null && command -v xdotool >/dev/null && command -v xclip >/dev/null && command -v ssh >/dev/null; then
  Xvfb -displayfd 3 -screen 0 1280x800x24 -nolisten tcp 3>"$tmp/display" 2>"$tmp/xvfb.log" &  # a free display
  xvfb=$!
  wait_for 10 '[ -s "$tmp/display" ]' || fail "Xvfb did not start: $(cat "$tmp/xvfb.log")"
  export DISPLAY=:$(cat "$tmp/display")
  ssh-keygen -q -t ed25519 -N '' -f "$tmp/key"
  mkdir -p -m 700 "$tmp/root/root/.ssh"
  cp "$tmp/key.pub" "$tmp/root/root/.ssh/authorized_keys"
  wait_for 20 '[ "$(prop ssh ActiveState)" = active ]' || fail "sshd not running in the container"
  # This machine's ssh, in the container's network (its loopback is the robot's).
  nsenter -t "$leader" -n -- ssh -v -X -i "$tmp/key" -o StrictHostKeyChecking=no \
    -o UserKnownHostsFile=/dev/null -o BatchMode=yes -o HostName=127.0.0.1 -l root robot pex-spy >"$tmp/spy.log" 2>&1 &
  ssh_pid=$!
  spy=$(timeout 60 xdotool search --sync --name '^LCM Spy$' 2>/dev/null | head -n 1)
  if [ -n "$spy" ]; then
    echo "lcm-spy's window is open on this machine's screen $DISPLAY"
    types=$(ls "$src"/lcmtypes/*.lcm | wc -l)
    wait_for 10 'grep -q "Found $types LCM types" "$tmp/spy.log"' || fail "pex-spy on the robot did not load our $types types"
    # Its table, copied as a person would: the simulator's set, every row decoded.
    . "$src/tests/spy/spy_table.sh"
    expected="LIDAR_SCAN ODOMETRY SLAM_UPDATE SLAM_POSE MAP EXPLORE_STATE DAEMON_STATUS SIM_TRUTH SIM_CLOCK BASE_CMD"
    listed() { tab=$(spy_table "$spy") || return 1; for ch in $expected; do grep -q "^$ch	" <<<"$tab" || return 1; done; }
    # One copy a second: two clicks on the table closer than AWT's double-click interval
    # (500 ms) would open a message view, which then takes the keys.
    ok=0
    for _ in $(seq 60); do listed && { ok=1; break; }; sleep 1; done
    ((ok)) || fail "lcm-spy over ssh -X does not list every channel of the set: $(tr '\t\n' ' |' <<<"${tab:-}")"
    echo "lcm-spy's table over ssh -X:"; sed 's/^/    /' <<<"${tab:-}"
    while IFS=$'\t' read -r channel type _ _ _ _ _ undecodable; do
      [ -n "$channel" ] && [ "$channel" != LCM_SELF_TEST ] || continue  # LCM's own start-up test, not ours
      [[ "$type" =~ ^[a-z0-9_]+_t$ ]] || fail "$channel not decoded over ssh -X: type '$type'"
      [ "${undecodable// /}" = 0 ] || fail "$channel: $undecodable undecodable messages"
    done <<<"${tab:-}"
    if [ -n "$shots" ] && command -v import >/dev/null; then
      mkdir -p "$shots"
      import -window root "$shots/pex-spy-over-ssh.png" && echo "screenshot: $shots/pex-spy-over-ssh.png"
    fi
  else
    fail "no LCM Spy window over ssh -X (ssh -v and pex-spy, then sshd's journal):
$(grep -v '^debug1: \(Reading\|Applying\|kex\|Will attempt\|Offering\|Server accepts\|SSH2_MSG\|expecting\|rekey\|Local version\|Remote protocol\|compat\|Authenticating\|Connecting\|Connection established\|identity file\|load_hostkeys\|Host\|channel 0\|pledge\|Sending env\|Next authentication\|Authentications\|get_agent\|Skipping\|Found key\|hostkeys\|ssh_packet\|send_pubkey\|sign_and\|Requesting no-more\|Entering\|client_input_global\|Remote: \)' "$tmp/spy.log")
$(c journalctl -u ssh --no-pager -n 20)"
  fi
  kill "$ssh_pid" 2>/dev/null; wait "$ssh_pid" 2>/dev/null
  grep -E 'Exception|Error' "$tmp/spy.log" | grep -v '^\(Warning\|debug\)' | head -n 5 | while read -r l; do fail "pex-spy: $l"; done
else
  echo "not run: Xvfb, xdotool, xclip or ssh missing here"
fi

if ((fails)); then
  echo "$fails failure(s); the container's journal, last lines:"
  c journalctl --no-pager -n 40
  exit 1
fi
echo "nspawn_boot: every check passed"
