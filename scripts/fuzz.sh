#!/usr/bin/env bash
# scripts/fuzz.sh [TARGET|all] [SECONDS] — runs the libFuzzer targets (fuzz/README.md).
#
# Builds them with clang (-fsanitize=fuzzer,address,undefined; every library
# they use instrumented for coverage) in build-fuzz (FUZZ_BUILD_DIR) and runs
# TARGET (default: every target, one after the other) for SECONDS each
# (default 60). A run starts from the committed seeds in fuzz/corpus/<target>
# and keeps what it learns in build-fuzz/corpus/<target> (not committed);
# a crash, sanitizer finding, leak, timeout (10 s per input) or allocation
# over 2 GB leaves its input in build-fuzz/artifacts/<target>/ and fails the
# script. Copy such an input into fuzz/corpus/<target>/ with the fix: ctest
# then replays it in every build (fuzz_corpus.<target>).
# The last line per target is a row for docs/reliability.md's table.
#   JOBS (default 2), FUZZ_ARGS (extra libFuzzer flags, e.g. -jobs=2 -workers=2)
set -euo pipefail
cd "$(dirname "$0")/.."
PEX_DEPS_FUZZ=1 bash scripts/deps.sh
FUZZ_BUILD_DIR=${FUZZ_BUILD_DIR:-build-fuzz}
JOBS=${JOBS:-2}
# Every target fuzz/CMakeLists.txt declares (a list written here once left
# keep_out out): the names pex_add_fuzz_target takes first.
mapfile -t all_targets < <(sed -n 's/^pex_add_fuzz_target(\([a-z0-9_]*\).*/\1/p' fuzz/CMakeLists.txt)
((${#all_targets[@]})) || { echo "no fuzz targets found in fuzz/CMakeLists.txt" >&2; exit 70; }
target=${1:-all}
seconds=${2:-60}
if [ "$target" = all ]; then
  targets=("${all_targets[@]}")
elif [[ " ${all_targets[*]} " == *" $target "* ]]; then
  targets=("$target")
else
  echo "usage: scripts/fuzz.sh [all|$(IFS='|'; echo "${all_targets[*]}")] [SECONDS]" >&2
  exit 64
fi
[[ "$seconds" =~ ^[0-9]+$ ]] || { echo "SECONDS must be a whole number" >&2; exit 64; }

# fuzzer-no-link: coverage for every library; the fuzz programs themselves
# link libFuzzer (fuzz/CMakeLists.txt). -O1 as libFuzzer's docs advise.
flags="-O1 -g -fno-omit-frame-pointer -fsanitize=address,undefined,fuzzer-no-link -fno-sanitize-recover=all"
cmake -S . -B "$FUZZ_BUILD_DIR" -DCMAKE_BUILD_TYPE=None \
  -DCMAKE_C_COMPILER=clang-14 -DCMAKE_CXX_COMPILER=clang++-14 \
  -DCMAKE_C_FLAGS="$flags" -DCMAKE_CXX_FLAGS="$flags" \
  -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" \
  -DPEX_FUZZ=ON -DPEX_BENCHMARKS=OFF >/dev/null
cmake --build "$FUZZ_BUILD_DIR" -j"$JOBS" --target "${targets[@]/#/fuzz_}"

failed=()
summary=()
for t in "${targets[@]}"; do
  work="$FUZZ_BUILD_DIR/corpus/$t"
  artifacts="$FUZZ_BUILD_DIR/artifacts/$t"
  log="$FUZZ_BUILD_DIR/logs/$t.log"
  mkdir -p "$work" "$artifacts" "$(dirname "$log")"
  echo "== fuzz $t for $seconds s (log: $log)"
  rc=0
  # shellcheck disable=SC2086
  "$FUZZ_BUILD_DIR/fuzz/fuzz_$t" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
    -print_final_stats=1 -artifact_prefix="$artifacts/" ${FUZZ_ARGS:-} \
    "$work" "fuzz/corpus/$t" >"$log" 2>&1 || rc=$?
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)
  ran=$seconds  # a finding ends the run early: the time it took, from libFuzzer's figures
  if [ -n "$execs" ] && [ -n "$rate" ] && [ "$rate" -gt 0 ]; then ran=$((execs / rate)); fi
  cov=$(grep -o 'cov: [0-9]*' "$log" | tail -1 | cut -d' ' -f2)

  if [ "$rc" -ne 0 ]; then
    failed+=("$t")
    grep -m1 -E 'ERROR|runtime error|fuzz check failed|SUMMARY' "$log" || true
    echo "   input: $(ls -t "$artifacts" | head -1)"
  fi
  row="| $t | $ran | ${execs:-?} | ${cov:-?} | $([ "$rc" -eq 0 ] && echo 0 || echo "1 (rc $rc)") |"
  summary+=("$row")
  echo "$row"
done
echo
echo "| target | seconds | execs | coverage (edges) | findings |"
echo "|---|---|---|---|---|"
printf '%s\n' "${summary[@]}"
if ((${#failed[@]})); then
  echo "findings in: ${failed[*]} (inputs in $FUZZ_BUILD_DIR/artifacts/)" >&2
  exit 1
fi
