#!/usr/bin/env bash
# Side-by-side CPU benchmark against Mitsuba 3 on the peer kit's scenes (../shared/peer, see its README):
# 512x512, 32 spp, 3 bounces, 2 threads, same camera, the kit's diffuse materials Lambertian as in
# Mitsuba; fovea and Mitsuba runs interleaved because the machine's speed drifts.
# Usage: scripts/bench-peer.sh [ROUNDS] [VARIANTS]
#   VARIANTS defaults to "scalar_rgb llvm_ad_rgb". Work files go to $PEER_WORK (default ./peer-work).
set -euo pipefail
cd "$(dirname "$0")/.."
ROUNDS="${1:-2}"
VARIANTS="${2:-scalar_rgb llvm_ad_rgb}"
source scripts/peer-env.sh
cargo build --release -q -p fovea-cli
mkdir -p out/bench
for round in $(seq 1 "$ROUNDS"); do
  for scene in small big; do
    for run in 1 2; do
      ./target/release/fovea render "$PEER_WORK/scenes/$scene/$scene.obj" "${PEER_FOVEA_VIEW[@]}" \
        "${PEER_FOVEA_MATERIALS[@]}" --spp 32,1,1 --resolution 512x512 --threads 2 --seed "$run" \
        -o "out/bench/fovea_$scene.exr" --stats "out/bench/fovea_${scene}_r${round}_${run}.json" -q
      python3 -c "import json,sys; d=json.load(open(sys.argv[1])); print(f'round $round fovea $scene: {d[\"paths_per_second\"]/1e6:.3f} M paths/s ({d[\"render_ms\"]:.0f} ms)')" \
        "out/bench/fovea_${scene}_r${round}_${run}.json"
    done
    bash "$KIT/run.sh" time --scenes "$scene" --threads 2 --runs 3 --variants "$VARIANTS" 2>&1 \
      | grep -E "^$scene " | sed "s/^/round $round mitsuba /"
  done
done
