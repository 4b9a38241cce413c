#!/usr/bin/env bash
# Interleaved A/B of two fovea binaries on one thread: the peer kit's small and big scenes (256x256, SPP
# samples per pixel, 3 bounces, uniform) and the bundled Lost Empire (640x360, foveated), alternating A and
# B for ROUNDS rounds and printing the minimum and median render_ms of each and their ratios. One thread
# and interleaving because this VM's speed drifts by +-15 % within minutes; minima are the least disturbed
# runs. Usage: scripts/bench-ab.sh BIN_A BIN_B [ROUNDS] [SPP]   (e.g. a copy of an older build as BIN_A)
set -euo pipefail
cd "$(dirname "$0")/.."
if [ $# -lt 2 ]; then
  echo "usage: scripts/bench-ab.sh BIN_A BIN_B [ROUNDS] [SPP]" >&2
  exit 2
fi
BIN_A="$1"; BIN_B="$2"; ROUNDS="${3:-8}"; SPP="${4:-8}"
source scripts/peer-env.sh
# Both binaries render this checkout's bundled Lost Empire, wherever they were built.
export FOVEA_ASSETS="$PWD/assets"
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for scene in small big lost_empire; do
  a=(); b=()
  for _ in $(seq 1 "$ROUNDS"); do
    for side in A B; do
      bin=$BIN_A; [ "$side" = B ] && bin=$BIN_B
      if [ "$scene" = lost_empire ]; then
        args=(--resolution 640x360 --depth 3)
      else
        args=("$PEER_WORK/scenes/$scene/$scene.obj" "${PEER_FOVEA_VIEW[@]}" --spp "$SPP,1,1"
          --resolution 256x256)
      fi
      "$bin" render "${args[@]}" --threads 1 -o "$out/img.exr" --stats "$out/stats.json" -q
      ms=$(python3 -c "import json,sys; print(round(json.load(open(sys.argv[1]))['render_ms']))" "$out/stats.json")
      if [ "$side" = A ]; then a+=("$ms"); else b+=("$ms"); fi
    done
  done
  python3 - "$scene" "${a[*]}" "${b[*]}" <<'PY'
import statistics, sys
scene, a, b = sys.argv[1], [int(x) for x in sys.argv[2].split()], [int(x) for x in sys.argv[3].split()]
ma, mb = statistics.median(a), statistics.median(b)
print(f"{scene}: A min {min(a)} median {ma:.0f} ms | B min {min(b)} median {mb:.0f} ms | "
      f"B/A min {min(b) / min(a):.3f} median {mb / ma:.3f}")
PY
done
