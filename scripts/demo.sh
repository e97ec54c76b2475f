#!/usr/bin/env bash
# scripts/demo.sh — install what is missing, build, and run the main job: the
# daemon set on the simulator, in a private network namespace, recorded with
# lcm-logger to out/demo.lcm, exploring a world until no frontier is left.
#   WORLD (default two_rooms), MISSION_S (default: 5 s per m² of the world, at least 300), SPEED (default 1),
#   VIEWER_PORT (default 8080): the live view at http://127.0.0.1:VIEWER_PORT/.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$(nproc)"
# pex-viewer serves its page inside the namespace; a relay on this computer's
# loopback (only) passes it through a Unix socket in OUT, so a browser here can open it.
export OUT=${OUT:-out}
mkdir -p "$OUT"
VIEWER_PORT=${VIEWER_PORT:-8080}
socat "TCP-LISTEN:$VIEWER_PORT,bind=127.0.0.1,reuseaddr,fork" "UNIX-CONNECT:$OUT/viewer.sock" 2>"$OUT/relay.log" &
relay=$!
trap 'kill "$relay" 2>/dev/null || true' EXIT
sleep 0.3  # socat either listens by now or has exited (port taken)
if kill -0 "$relay" 2>/dev/null; then
  export VIEWER_URL="http://127.0.0.1:$VIEWER_PORT/"
else
  echo "demo: no live view on this computer: 127.0.0.1:$VIEWER_PORT is taken ($OUT/relay.log); set VIEWER_PORT" >&2
fi
scripts/netns-run bash scripts/demo-run.sh "$@"
