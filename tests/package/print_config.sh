#!/usr/bin/env bash
# print_config.sh SRC_DIR BIN_DIR: `pex-<daemon> --print-config` for every daemon, with
# the layering rule of runtime/config.hpp (defaults < each --config file in order):
#  1. no file: every key with "# default", exit 0;
#  2. config/X.toml, then config/robot/X.toml where there is one: every key a file
#     sets names that file and the line that sets it (checked against the file), keys
#     the overlay sets come from the overlay, the rest from config/X.toml or default;
#  3. the printed configuration is itself a config: read back, it prints the same values;
#  4. a bad value in the overlay: exit 78, the message names the overlay.
set -uo pipefail
src=$1 bin=$2
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
fails=0
fail() { echo "FAIL: $*"; fails=$((fails + 1)); }
values() { grep -v '^#' "$1" | sed 's/  *# [^#]*$//; s/ *$//'; }  # key = value, the source comments cut
for d in lidar_reader base_driver slam polygon_mapper explorer sim viewer; do
  prog=pex-${d//_/-}
  # 1. the defaults
  (cd "$src" && "$bin/$prog" --print-config) >"$tmp/$d.defaults" 2>"$tmp/err"; rc=$?  # from the source tree: pex-sim's default world_file is relative
  [ "$rc" = 0 ] || { fail "$prog --print-config: exit $rc: $(cat "$tmp/err")"; continue; }
  n=$(grep -vc '^#' "$tmp/$d.defaults")
  ((n >= 2)) || fail "$prog --print-config printed $n keys"
  grep -v '^#' "$tmp/$d.defaults" | grep -v '  # default$' | head -n 3 | while read -r l; do fail "$prog, no file: not a default: $l"; done
  # 2. the layers
  layers=(--config "$src/config/$d.toml")
  robot=$src/config/robot/$d.toml
  [ -f "$robot" ] && layers+=(--config "$robot")
  "$bin/$prog" --print-config "${layers[@]}" >"$tmp/$d.toml" 2>"$tmp/err"; rc=$?
  [ "$rc" = 0 ] || { fail "$prog --print-config ${layers[*]}: exit $rc: $(cat "$tmp/err")"; continue; }
  from_files=0
  while IFS= read -r line; do
    key=${line%% = *}
    source=${line##*# }
    [ "$source" = default ] && continue
    file=${source%:*} n=${source##*:}
    from_files=$((from_files + 1))
    leaf=${key##*.}
    sed -n "${n}p" "$file" | grep -Eq "^[[:space:]]*\"?$leaf\"?[[:space:]]*=" \
      || fail "$prog: $key says $source, but that line is: $(sed -n "${n}p" "$file")"
    if [ -f "$robot" ] && [ "$file" != "$robot" ]; then
      # a key the overlay sets must come from the overlay
      section=${key%.*}; [ "$section" = "$key" ] && section=
      awk -v s="$section" -v k="$leaf" '
        /^\[/ { gsub(/[\[\] ]/, ""); cur = $0; next }
        cur == s && $0 ~ "^[ \t]*" k "[ \t]*=" { found = 1 } END { exit !found }' "$robot" \
        && fail "$prog: $key is set in $robot but printed from $source"
    fi
  done < <(grep -v '^#' "$tmp/$d.toml")
  ((from_files > 0)) || fail "$prog: no key printed from a file"
  if [ -f "$robot" ]; then
    grep -q "^clock = .*# $robot:" "$tmp/$d.toml" || fail "$prog: clock not from the robot overlay: $(grep '^clock' "$tmp/$d.toml")"
  fi
  # 3. read back
  "$bin/$prog" --print-config --config "$tmp/$d.toml" >"$tmp/$d.again" 2>"$tmp/err" || fail "$prog: its printed config does not load: $(cat "$tmp/err")"
  diff <(values "$tmp/$d.toml") <(values "$tmp/$d.again") >"$tmp/diff" || fail "$prog: read back differs: $(head -n 5 "$tmp/diff")"
  echo "$prog: $(grep -vc '^#' "$tmp/$d.toml") keys, $from_files from files"
done
# 4. a bad value in an overlay names the overlay
printf 'heartbeat_period_ms = 5\n' >"$tmp/overlay.toml"
out=$("$bin/pex-slam" --print-config --config "$src/config/slam.toml" --config "$tmp/overlay.toml" 2>&1); rc=$?
[ "$rc" = 78 ] || fail "a bad overlay value: exit $rc, expected 78"
grep -q "$tmp/overlay.toml: key 'heartbeat_period_ms'" <<<"$out" || fail "the error does not name the overlay: $out"
if ((fails)); then echo "$fails failure(s)"; exit 1; fi
echo "print_config: every check passed"
