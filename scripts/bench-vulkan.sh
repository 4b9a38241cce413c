#!/usr/bin/env bash
# CPU host vs the Vulkan host (lavapipe or a GPU), paths per second, on two workloads:
#   (a) the bundled Lost Empire, 1920x1080 foveated (32/16/8 spp, blocks 1/2/4);
#   (b) a big scene, uniform 32 spp at 512x512 (the peer benchmark's view).
# Usage: scripts/bench-vulkan.sh [BIG_SCENE.obj]   (default: /work/peer-work/scenes/big/big.obj)
# Needs a release build with the Vulkan backend (cargo build --release -p fovea-cli) and python3.
# JIT cost: pipeline_create_ms (vkCreateComputePipelines) and warmup_ms (first empty dispatch of each
# pipeline) are reported apart from render_ms, which is the frame alone.
set -euo pipefail
cd "$(dirname "$0")/.."
BIG=${1:-/work/peer-work/scenes/big/big.obj}
FOVEA=${FOVEA:-./target/release/fovea}
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT
[ -x "$FOVEA" ] || { echo "no $FOVEA: run cargo build --release -p fovea-cli" >&2; exit 1; }

run() { # NAME BACKEND ARGS...
    local name=$1 backend=$2
    shift 2
    "$FOVEA" render --backend "$backend" --quiet --stats "$OUT/$name-$backend.json" \
        -o "$OUT/$name-$backend.png" "$@" >/dev/null 2>"$OUT/$name-$backend.log" ||
        { echo "fovea render $name $backend failed:" >&2; cat "$OUT/$name-$backend.log" >&2; exit 1; }
}

for backend in cpu vulkan; do
    run lost_empire "$backend" --resolution 1920x1080
    if [ -f "$BIG" ]; then
        run big "$backend" "$BIG" --uniform --spp 32,1,1 --resolution 512x512 \
            --eye 0,0,2.8 --target 0,0,-1 --fov 45
    fi
done
[ -f "$BIG" ] || echo "note: $BIG not found; only Lost Empire measured" >&2

python3 - "$OUT" <<'PY'
import json, os, sys
out = sys.argv[1]
print("| workload | backend | device | samples | render s | M paths/s | vs CPU | pipeline create ms | warm-up ms |")
print("|---|---|---|---|---|---|---|---|---|")
for name, label in (("lost_empire", "Lost Empire 1920x1080 foveated"), ("big", "big.obj 512x512 uniform 32 spp")):
    cpu = None
    for backend in ("cpu", "vulkan"):
        path = os.path.join(out, f"{name}-{backend}.json")
        if not os.path.exists(path):
            continue
        d = json.load(open(path))
        pps = d["paths_per_second"]
        if backend == "cpu":
            cpu = pps
        b = d.get("backend_details") or {}
        pc = b.get("pipeline_create_ms")
        wu = b.get("warmup_ms")
        print(f"| {label} | {backend} | {d['device']} | {d['primary_samples']} | {d['render_ms'] / 1e3:.2f} "
              f"| {pps / 1e6:.3f} | {pps / cpu:.2f}x | {'-' if pc is None else f'{pc:.0f}'} "
              f"| {'-' if wu is None else f'{wu:.0f}'} |")
PY
