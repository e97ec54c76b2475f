#!/usr/bin/env bash
# build_deb.sh BUILD_DIR OUT_DIR: runs cpack on the existing build (its binaries, no
# rebuild: CMAKE_SKIP_INSTALL_ALL_DEPENDENCY) into OUT_DIR, leaving build/ alone.
set -euo pipefail
build=$1 out=$2
rm -rf "$out"; mkdir -p "$out"
cpack -G DEB --config "$build/CPackConfig.cmake" -B "$out" -D CPACK_OUTPUT_FILE_PREFIX="$out" >"$out/cpack.log" 2>&1 \
  || { cat "$out/cpack.log"; exit 1; }
ls "$out"/polyexplore_*.deb
