#!/usr/bin/env bash
# status_without_explorer.sh BIN_DIR: `pex-status --follow-mission` on a bus
# where no explorer publishes EXPLORE_STATE ends after --state-timeout with
# exit 3 and says why, instead of waiting for its wall limit (hours for a
# long mission). Runs in a private network namespace like every LCM test.
set -uo pipefail
bin=$1
here=$(cd "$(dirname "$0")/../.." && pwd)
out=$(LCM_DEFAULT_URL='udpm://239.255.76.67:7667?ttl=0' \
  "$here/scripts/netns-run" "$bin/pex-status" --follow-mission 8000 --state-timeout 2 2>&1)
rc=$?
echo "$out"
[ "$rc" -eq 3 ] || { echo "FAIL: exit $rc, expected 3"; exit 1; }
grep -qF "no EXPLORE_STATE for 2 s (wall clock) since the start: is the explorer running?" <<<"$out" \
  || { echo "FAIL: the reason not printed"; exit 1; }
echo "ok: pex-status gave up without an explorer (exit 3)"
