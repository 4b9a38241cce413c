#!/usr/bin/env bash
# Ray traversal alone, fovea against Mitsuba 3's Embree (llvm_ad_rgb), on the very same rays: for each
# peer scene and ray set (`random`: uniform rays in the room; `paths`: the rays of three-bounce paths from
# the kit's camera, see scripts/bench-rays.py), bench-rays.py writes a ray file and times Mitsuba on it,
# then `fovea bench rays` traces the file; rounds interleaved because the machine's speed drifts.
# Usage: scripts/bench-rays.sh [ROUNDS] [THREADS] [SETS]   (defaults: 2, 2, "random paths").
# Work files go to $PEER_WORK (default ./peer-work).
set -euo pipefail
cd "$(dirname "$0")/.."
ROUNDS="${1:-2}"
THREADS="${2:-2}"
SETS="${3:-random paths}"
source scripts/peer-env.sh
cargo build --release -q -p fovea-cli
mkdir -p out/bench
for round in $(seq 1 "$ROUNDS"); do
  for scene in small big; do
    for set in $SETS; do
      rays="out/bench/rays_${scene}_$set.bin"
      PEER_KIT="$KIT" "$PEER_WORK/venv/bin/python" scripts/bench-rays.py "$scene" "$rays" "" "$THREADS" "$set" \
        | grep '^mitsuba' | sed "s/^/round $round /"
      ./target/release/fovea bench --threads "$THREADS" --json "out/bench/rays_${scene}_${set}_r$round.json" \
        rays "$PEER_WORK/scenes/$scene/$scene.obj" --rays "$rays" --runs 3 2>&1 >/dev/null \
        | sed "s/^/round $round fovea $scene $set /"
    done
  done
done
