#!/usr/bin/env bash
# The CPU's specialised render path (only the features a scene uses compiled in) against the general
# one (--no-specialize), per scene: `fovea bench paths` renders the frame with each path in turn in one
# process, ROUNDS times each (the order alternating), and prints their medians, the ratio and whether
# every image was identical. A change to the integrator or the CPU host's sample loop quotes this table
# in its commit message (docs/performance.md keeps its history).
# Usage: scripts/bench-specialize.sh [ROUNDS]   (default 5)
# Needs a release build (cargo build --release -p fovea-cli) and python3.
set -euo pipefail
cd "$(dirname "$0")/.."
ROUNDS=${1:-5}
FOVEA=${FOVEA:-./target/release/fovea}
[ -x "$FOVEA" ] || { echo "no $FOVEA: run cargo build --release -p fovea-cli" >&2; exit 1; }
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT

CORNELL="--eye 0,1,3.9 --target 0,1,0 --fov 38"
# name|scene|options ("-": the bundled Lost Empire with its view and sky, what `fovea render` renders)
CASES=(
  "cornell 960x540 uniform 32|assets/cornell_box/CornellBox-Original.obj|$CORNELL --uniform --spp 32,32,32 --resolution 960x540"
  "cornell mirror 256x256|assets/cornell_box/CornellBox-Mirror.obj|$CORNELL --uniform --spp 16,16,16 --resolution 256x256"
  "cornell_stiff 256x256|assets/cornell_stiff/cornell_stiff.gltf|--uniform --spp 16,16,16 --resolution 256x256"
  "veach_mis 256x256|assets/veach_mis_pema99/VeachMIS.glb|--uniform --spp 16,16,16 --resolution 256x256"
  "roughness_scale 256x256|assets/roughness_scale_kajiya/scene.gltf|--sky 1,1,1 --uniform --spp 16,16,16 --resolution 256x256"
  "lost_empire 1920x1080 32/16/8 (the default render)|-|--resolution 1920x1080"
)

i=0
for c in "${CASES[@]}"; do
  IFS='|' read -r name scene opts <<<"$c"
  args=()
  [ "$scene" = - ] || args=("$scene")
  # shellcheck disable=SC2086
  "$FOVEA" bench paths ${args[@]+"${args[@]}"} $opts --rounds "$ROUNDS" --json "$OUT/$i.json" >/dev/null
  echo "$name" >"$OUT/$i.name"
  i=$((i + 1))
done

python3 - "$OUT" "$i" <<'PY'
import json, sys
out, n = sys.argv[1], int(sys.argv[2])
print("| frame | specialised path | specialised ms | general ms | speed-up | identical |")
print("|---|---|---:|---:|---:|---|")
for k in range(n):
    d = json.load(open(f"{out}/{k}.json"))
    name = open(f"{out}/{k}.name").read().strip()
    feats = ", ".join(d["specialised_features"])
    print(f"| {name} | {feats} | {d['specialised_ms']:.0f} | {d['general_ms']:.0f} | "
          f"{d['speedup']:.3f}x | {d['identical']} |")
PY
