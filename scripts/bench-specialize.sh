#!/usr/bin/env bash
# Specialised vs general render paths (issue "leave out what a scene does not need"), per scene, on the CPU
# host and on the Vulkan host, interleaved: for each scene and backend, ROUNDS pairs of renders
# (specialised, then --no-specialize), the median render_ms of each, their ratio and whether the images
# are byte-identical.
# Usage: scripts/bench-specialize.sh [ROUNDS] [BACKENDS]   (defaults: 3, "cpu vulkan")
# Needs a release build (cargo build --release -p fovea-cli) and python3.
set -euo pipefail
cd "$(dirname "$0")/.."
ROUNDS=${1:-3}
BACKENDS=${2:-cpu vulkan}
FOVEA=${FOVEA:-./target/release/fovea}
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT
[ -x "$FOVEA" ] || { echo "no $FOVEA: run cargo build --release -p fovea-cli" >&2; exit 1; }

CORNELL="--eye 0,1,3.9 --target 0,1,0 --fov 38"
# name|scene|options (resolutions kept small: lavapipe is slow)
CASES=(
  "cornell (bundled)|assets/cornell_box/CornellBox-Original.obj|$CORNELL --uniform --spp 16,1,1 --resolution 256x256"
  "cornell mirror|assets/cornell_box/CornellBox-Mirror.obj|$CORNELL --uniform --spp 16,1,1 --resolution 256x256"
  "cornell_stiff|assets/cornell_stiff/cornell_stiff.gltf|--uniform --spp 16,1,1 --resolution 256x256"
  "veach_mis|assets/veach_mis_pema99/VeachMIS.glb|--uniform --spp 16,1,1 --resolution 256x256"
  "roughness_scale|assets/roughness_scale_kajiya/scene.gltf|--sky 1,1,1 --uniform --spp 16,1,1 --resolution 256x256"
  "lost_empire|assets/lost_empire/lost_empire.obj|--resolution 960x540"
)

for c in "${CASES[@]}"; do
  IFS='|' read -r name scene opts <<<"$c"
  [ -f "$scene" ] || { echo "skipping $name: $scene missing" >&2; continue; }
  for backend in $BACKENDS; do
    for r in $(seq 1 "$ROUNDS"); do
      for variant in spec gen; do
        extra=""; [ "$variant" = gen ] && extra="--no-specialize"
        tag="$(echo "$name" | tr ' ()' '___')-$backend-$variant-$r"
        # shellcheck disable=SC2086
        "$FOVEA" render "$scene" $opts --backend "$backend" $extra --quiet \
          --stats "$OUT/$tag.json" -o "$OUT/$tag.png" >/dev/null 2>"$OUT/$tag.log" ||
          { echo "render failed: $name $backend $variant" >&2; cat "$OUT/$tag.log" >&2; exit 1; }
      done
    done
  done
done

python3 - "$OUT" "$ROUNDS" "$BACKENDS" <<'PY'
import glob, json, os, statistics, sys, filecmp
out, rounds, backends = sys.argv[1], int(sys.argv[2]), sys.argv[3].split()
names = sorted({os.path.basename(p).rsplit("-", 3)[0] for p in glob.glob(os.path.join(out, "*.json"))})
print("| scene | features | backend | specialised ms | general ms | speed-up | identical |")
print("|---|---|---|---|---|---|---|")
for n in names:
    for b in backends:
        spec = [json.load(open(f"{out}/{n}-{b}-spec-{r}.json")) for r in range(1, rounds + 1)
                if os.path.exists(f"{out}/{n}-{b}-spec-{r}.json")]
        gen = [json.load(open(f"{out}/{n}-{b}-gen-{r}.json")) for r in range(1, rounds + 1)
               if os.path.exists(f"{out}/{n}-{b}-gen-{r}.json")]
        if not spec or not gen:
            continue
        ms = statistics.median(d["render_ms"] for d in spec)
        mg = statistics.median(d["render_ms"] for d in gen)
        same = all(filecmp.cmp(f"{out}/{n}-{b}-spec-{r}.png", f"{out}/{n}-{b}-gen-{r}.png", shallow=False)
                   for r in range(1, rounds + 1))
        feats = ", ".join(spec[0].get("features", []))
        print(f"| {n} | {feats} | {spec[0]['device'] if b == 'vulkan' else 'cpu'} | {ms:.0f} | {mg:.0f} | {mg / ms:.3f}x | {same} |")
PY
