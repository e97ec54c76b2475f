#!/usr/bin/env bash
# scripts/test.sh — install what is missing, build, run every test with ctest.
#   BUILD_DIR (default build), JOBS (default: number of cores), CTEST_ARGS (extra ctest arguments)
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/deps.sh
BUILD_DIR=${BUILD_DIR:-build}
JOBS=${JOBS:-$(nproc)}
cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release
cmake --build "$BUILD_DIR" -j"$JOBS"
# shellcheck disable=SC2086
ctest --test-dir "$BUILD_DIR" -j"$JOBS" --output-on-failure ${CTEST_ARGS:-}
