#!/usr/bin/env bash
# scripts/test.sh — install what is missing, build, run every test with ctest.
#   BUILD_DIR (default build), JOBS (default: number of cores), CTEST_ARGS (extra ctest arguments)
#
# scripts/test.sh --sanitize: the same sources built with AddressSanitizer and
# UndefinedBehaviorSanitizer (GCC, -O1, any finding aborts the test) in
# build-asan (SAN_BUILD_DIR), then the unit tests (every test without a label,
# which includes each fuzz target's corpus replayed: fuzz/README.md) run there.
# Integration, replay, systemd and package tests are left out: they run real
# daemons for minutes on the simulated clock (docs/reliability.md, "Sanitizers").
#   SAN_CTEST_ARGS (extra ctest arguments for that run)
set -euo pipefail
cd "$(dirname "$0")/.."
sanitize=false
for a in "$@"; do
  case "$a" in
    --sanitize) sanitize=true ;;
    *) echo "usage: scripts/test.sh [--sanitize]" >&2; exit 64 ;;
  esac
done
bash scripts/deps.sh
JOBS=${JOBS:-$(nproc)}

if $sanitize; then
  SAN_BUILD_DIR=${SAN_BUILD_DIR:-build-asan}
  san="-fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer"
  cmake -S . -B "$SAN_BUILD_DIR" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g" -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O1 -g" \
    -DCMAKE_CXX_FLAGS="$san" -DCMAKE_C_FLAGS="$san" \
    -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" -DPEX_BENCHMARKS=OFF
  cmake --build "$SAN_BUILD_DIR" -j"$JOBS" --target pex_unit_tests
  # detect_leaks: the tests' own leaks are findings too. halt_on_error: one
  # finding fails the test that met it.
  export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:halt_on_error=1:abort_on_error=1}
  export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
  # shellcheck disable=SC2086
  # Only the unit tests were built (target pex_unit_tests): the other test
  # programs' placeholders (<target>_NOT_BUILT) are left out with them.
  ctest --test-dir "$SAN_BUILD_DIR" -j"$JOBS" --output-on-failure \
    -LE 'integration|replay|systemd|package|tools|faults' -E '_NOT_BUILT$' ${SAN_CTEST_ARGS:-}
  exit 0
fi

BUILD_DIR=${BUILD_DIR:-build}
cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release
cmake --build "$BUILD_DIR" -j"$JOBS"
# shellcheck disable=SC2086
ctest --test-dir "$BUILD_DIR" -j"$JOBS" --output-on-failure ${CTEST_ARGS:-}
