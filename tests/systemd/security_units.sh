#!/usr/bin/env bash
# security_units.sh SRC_DIR [THRESHOLD]: every unit in systemd/ must score at most
# THRESHOLD (default 4.0, "OK") with `systemd-analyze security --offline=yes` (the
# unit file alone, nothing loaded). Prints each score. First makes sure the
# check can fail: a bare unit (User= only, 9.x) must be refused.
set -uo pipefail
src=$1 limit=${2:-4.0}
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
# --threshold= takes tenths (4.0 -> 40); an exposure above it exits non-zero.
threshold=$(awk -v t="$limit" 'BEGIN { printf "%d", t * 10 + 0.5 }')
score() { systemd-analyze security --offline=yes --threshold="$threshold" "$1" 2>&1 | sed -n 's/^→ Overall exposure level for .*: //p'; }
printf '[Service]\nExecStart=/bin/true\nUser=nobody\n' >"$tmp/pex-bare.service"
if systemd-analyze security --offline=yes --threshold="$threshold" "$tmp/pex-bare.service" >/dev/null 2>&1; then
  echo "a bare unit ($(score "$tmp/pex-bare.service")) passes --threshold=$threshold (tenths): the check cannot fail"; exit 1
fi
fails=0 n=0
for u in "$src"/systemd/*.service; do
  n=$((n + 1))
  s=$(score "$u")
  if systemd-analyze security --offline=yes --threshold="$threshold" "$u" >/dev/null 2>&1; then
    echo "$(basename "$u"): $s"
  else
    echo "FAIL $(basename "$u"): $s (above $limit)"; fails=$((fails + 1))
  fi
done
((n)) || { echo "no units in $src/systemd"; exit 1; }
((fails == 0)) || exit 1
echo "$n units at most $limit"
