#!/usr/bin/env bash
# Ray traversal alone, fovea against Mitsuba 3's Embree (llvm_ad_rgb), on the very same rays: for each
# peer scene, scripts/bench-rays.py writes a ray file and times Mitsuba on it, then `fovea bench rays`
# traces the file; rounds interleaved because the machine's speed drifts. 2 threads.
# Usage: scripts/bench-rays.sh [ROUNDS] [RAYS_PER_KIND]. Work files go to $PEER_WORK (default ./peer-work).
set -euo pipefail
cd "$(dirname "$0")/.."
ROUNDS="${1:-2}"
COUNT="${2:-2097152}"
source scripts/peer-env.sh
cargo build --release -q -p fovea-cli
mkdir -p out/bench
for round in $(seq 1 "$ROUNDS"); do
  for scene in small big; do
    rays="out/bench/rays_$scene.bin"
    PEER_KIT="$KIT" "$PEER_WORK/venv/bin/python" scripts/bench-rays.py "$scene" "$rays" "$COUNT" 2 \
      | grep '^mitsuba' | sed "s/^/round $round /"
    ./target/release/fovea bench --threads 2 --json "out/bench/rays_${scene}_r$round.json" rays \
      "$PEER_WORK/scenes/$scene/$scene.obj" --rays "$rays" --runs 3 2>&1 >/dev/null \
      | sed "s/^/round $round fovea $scene /"
  done
done
