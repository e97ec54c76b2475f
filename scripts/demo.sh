#!/usr/bin/env bash
# scripts/demo.sh — install what is missing, build, and run the main job: the
# daemon set on the simulator, in a private network namespace, recorded with
# lcm-logger to out/demo.lcm, exploring a world until no frontier is left.
#   WORLD (default two_rooms), MISSION_S (default 300), SPEED (default 1).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$(nproc)"
exec scripts/netns-run bash scripts/demo-run.sh "$@"
