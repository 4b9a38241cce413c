#!/usr/bin/env bash
# Ray traversal alone, fovea against Mitsuba 3's Embree (llvm_ad_rgb), on the very same rays: for each
# peer scene, scripts/bench-rays.py writes a ray file and times Mitsuba on it, then `fovea bench rays`
# traces the file; rounds interleaved because the machine's speed drifts. 2 threads.
# Usage: scripts/bench-rays.sh [ROUNDS] [RAYS_PER_KIND]. Work files go to $PEER_WORK (default ./peer-work).
set -euo pipefail
cd "$(dirname "$0")/.."
ROUNDS="${1:-2}"
COUNT="${2:-2097152}"
KIT="$(cd ../shared/peer && pwd)"
export PEER_WORK="${PEER_WORK:-$PWD/peer-work}"
[ -x "$PEER_WORK/venv/bin/python" ] || bash "$KIT/run.sh" setup
[ -f "$PEER_WORK/scenes/big/big.obj" ] || bash "$KIT/run.sh" scenes
export DRJIT_CACHE_DIR="$PEER_WORK/drjit_cache"
if [ -z "${DRJIT_LIBLLVM_PATH:-}" ]; then
  for f in /usr/lib/*/libLLVM.so.19* /usr/lib/*/libLLVM-19.so* /usr/lib/llvm-19/lib/libLLVM*.so*; do
    if [ -f "$f" ]; then export DRJIT_LIBLLVM_PATH="$f"; break; fi
  done
fi
cargo build --release -q -p fovea-cli
mkdir -p out/bench
for round in $(seq 1 "$ROUNDS"); do
  for scene in small big; do
    rays="out/bench/rays_$scene.bin"
    PEER_KIT="$KIT" "$PEER_WORK/venv/bin/python" scripts/bench-rays.py "$scene" "$rays" "$COUNT" 2 \
      | grep '^mitsuba' | sed "s/^/round $round /"
    ./target/release/fovea bench --threads 2 --json "out/bench/rays_${scene}_r$round.json" rays \
      "$PEER_WORK/scenes/$scene/$scene.obj" --rays "$rays" --runs 3 >/dev/null 2>"out/bench/rays.log"
    python3 -c "
import json, sys
d = json.load(open(sys.argv[1]))
for kind, hits in (('closest', 'closest_hits'), ('occlusion', 'occluded')):
    print(f'round $round fovea $scene {kind}: {d[hits]} of {d[kind + \"_rays\"]} hit, '
          f'{d[kind + \"_rays_per_second\"] / 1e6:.2f} M rays/s')
" "out/bench/rays_${scene}_r$round.json"
  done
done
