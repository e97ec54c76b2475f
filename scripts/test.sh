#!/usr/bin/env bash
# scripts/test.sh — install what is missing, build, run every test with ctest.
#   BUILD_DIR (default build), JOBS (default: number of cores), CTEST_ARGS (extra ctest arguments)
#
# After every test, the sanitizer job (what CI runs of it): the parsers of
# outside bytes — CoLa telegrams, CAN frames, LCM messages, LCM log files,
# CARMEN lines — built with AddressSanitizer and UndefinedBehaviorSanitizer
# (GCC, -O1, any finding aborts) in build-asan (SAN_BUILD_DIR), and their fuzz
# corpora (every seed and every input that once crashed: fuzz/README.md)
# replayed there. About a minute on two cores; SANITIZER_JOB=0 skips it.
#
# scripts/test.sh --sanitize: every program built so, and every test run on
# it — unit tests, each fuzz target's corpus replay, and the integration,
# fault, replay and tools tests, whose daemons then run sanitized as
# processes — except systemd, package and spy (an installed system, a .deb,
# the Java lcm-spy: not our code under test). About an hour of CPU to build
# and half an hour of tests on two cores (docs/reliability.md, "Sanitizers").
#   SAN_CTEST_ARGS (extra ctest arguments for that run, e.g. -LE integration)
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

SAN_BUILD_DIR=${SAN_BUILD_DIR:-build-asan}
# configure_sanitized: the sanitizer build's configuration (GCC, -O1 -g).
configure_sanitized() {
  local san="-fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer"
  cmake -S . -B "$SAN_BUILD_DIR" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g" -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O1 -g" \
    -DCMAKE_CXX_FLAGS="$san" -DCMAKE_C_FLAGS="$san" \
    -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" -DPEX_BENCHMARKS=OFF
}
# detect_leaks: the tests' own leaks are findings too. halt_on_error: one
# finding fails the test that met it. verify_asan_link_order=0: the
# wall-clock fault test preloads libfaketime (LD_PRELOAD) into
# pex-base-driver ahead of the ASan runtime; it wraps the clock functions,
# which ASan does not intercept.
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:halt_on_error=1:abort_on_error=1:verify_asan_link_order=0}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
# Third-party leaks only, each with its reason (the file).
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$PWD/scripts/lsan-suppressions.txt}

if $sanitize; then
  configure_sanitized
  cmake --build "$SAN_BUILD_DIR" -j"$JOBS"
  # shellcheck disable=SC2086
  ctest --test-dir "$SAN_BUILD_DIR" -j"$JOBS" --output-on-failure \
    -LE '^(systemd|package|spy)$' ${SAN_CTEST_ARGS:-}
  exit 0
fi

BUILD_DIR=${BUILD_DIR:-build}
cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release
cmake --build "$BUILD_DIR" -j"$JOBS"
# shellcheck disable=SC2086
ctest --test-dir "$BUILD_DIR" -j"$JOBS" --output-on-failure ${CTEST_ARGS:-}

if [ "${SANITIZER_JOB:-1}" != 0 ]; then
  parsers=(cola canopen lcm_message lcm_log carmen)
  echo "== sanitizer job: ${parsers[*]} under ASan + UBSan ($SAN_BUILD_DIR)"
  configure_sanitized >/dev/null
  targets=() tests=()
  for p in "${parsers[@]}"; do targets+=("fuzz_${p}_replay"); tests+=("fuzz_corpus[.]$p"); done
  cmake --build "$SAN_BUILD_DIR" -j"$JOBS" --target "${targets[@]}"
  regex="^($(IFS='|'; echo "${tests[*]}"))\$"
  ctest --test-dir "$SAN_BUILD_DIR" -j"$JOBS" --output-on-failure -R "$regex" --no-tests=error
  [ "$(ctest --test-dir "$SAN_BUILD_DIR" -N -R "$regex" | sed -n 's/^Total Tests: //p')" = "${#parsers[@]}" ] ||
    { echo "sanitizer job: expected ${#parsers[@]} corpus replays" >&2; exit 1; }
fi
