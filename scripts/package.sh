#!/usr/bin/env bash
# scripts/package.sh — the Debian package: build/polyexplore_<version>_<arch>.deb
# (what is in it: docs/deployment.md). Builds only what the package holds (daemons,
# tools, the types jar) in the existing build dir, then runs cpack there.
#   BUILD_DIR (default build), JOBS (default: number of cores, at most 2 here)
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/deps.sh
BUILD_DIR=${BUILD_DIR:-build}
JOBS=${JOBS:-$(nproc)}
[ -f "$BUILD_DIR/CMakeCache.txt" ] || cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release
cmake --build "$BUILD_DIR" -j"$JOBS" --target pex-package-inputs
(cd "$BUILD_DIR" && cpack -G DEB --config CPackConfig.cmake)
ls "$BUILD_DIR"/polyexplore_*.deb
