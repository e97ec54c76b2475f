#!/usr/bin/env bash
# scripts/bench.sh NAME [ARGS...] — install what is missing, build, and run the
# benchmark bench/NAME (pex-bench-NAME). Figures are reported, never asserted;
# the tables live in docs/. Each benchmark ends with one JSON line of its figures.
#   scripts/bench.sh mapping
#   scripts/bench.sh slam            (see docs/slam.md for its arguments)
#   scripts/bench.sh explore [WORLD...]  (whole missions on the simulator; docs/exploration.md)
set -euo pipefail
cd "$(dirname "$0")/.."
name=${1:?usage: scripts/bench.sh NAME [ARGS...]   (NAME: explore $(ls bench | grep -v CMakeLists | tr '\n' ' '))}
shift
if [ "$name" = explore ]; then
  bash scripts/deps.sh
  cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
  cmake --build build -j"$(nproc)"
  exec bash scripts/bench-explore.sh "$@"
fi
[ -d "bench/$name" ] || { echo "bench.sh: no benchmark bench/$name" >&2; exit 64; }
bash scripts/deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j"$(nproc)" --target "pex-bench-$name"
exec "build/bin/pex-bench-$name" "$@"
