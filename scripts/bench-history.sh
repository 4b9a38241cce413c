#!/usr/bin/env bash
# What temporal reuse and the denoiser cost, pass by pass (a benchmark, not a test): `fovea render
# --history --denoise` over a
# simulated eye-tracker gaze and a slow pan of the bundled Lost Empire, on each backend; prints one
# Markdown row per backend with the median milliseconds of each pass per megapixel (frames after the
# first two; CPU timers on the CPU, GPU timestamps on Vulkan), read from --stats.
#
#   bash scripts/bench-history.sh [FRAMES] [WxH]      # default 24 frames at 640x360
#   FOVEA_BIN=target/debug/fovea BENCH_HISTORY_BACKENDS=cpu bash scripts/bench-history.sh
set -euo pipefail
cd "$(dirname "$0")/.."
FRAMES=${1:-24}
SIZE=${2:-640x360}
BACKENDS=${BENCH_HISTORY_BACKENDS:-"cpu vulkan"}
BIN=${FOVEA_BIN:-target/release/fovea}
[ -x "$BIN" ] || cargo build --release -q -p fovea-cli
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

# The gaze: the image centre plus 0.15 degrees RMS of noise and a 0.5 degree microsaccade every 20 frames
# (9.5 px per degree at 640 px on the default display); the camera: 0.05 units per frame sideways.
python3 - "$FRAMES" "$SIZE" "$out" <<'PY'
import random, sys
frames, (w, h), out = int(sys.argv[1]), map(int, sys.argv[2].split("x")), sys.argv[3]
ppd = 60 * (w / 70.848) * 3.14159265 / 180
random.seed(1)
with open(f"{out}/gaze.csv", "w") as g, open(f"{out}/camera.csv", "w") as c:
    g.write("frame,x,y\n")
    c.write("frame,ex,ey,ez,tx,ty,tz\n")
    for f in range(frames):
        s = 0.5 * ppd if (f // 20) % 2 else 0.0
        g.write(f"{f},{w/2 + random.gauss(0, 0.15*ppd) + s},{h/2 + random.gauss(0, 0.15*ppd)}\n")
        d = 0.05 * f
        c.write(f"{f},{-20 + d},30,60,{5 + d},15,20\n")
PY

echo "| backend | size | frames | samples | cell_means | fill | gbuffer | cell_albedo | temporal | resolve_history | denoise_input | denoise_atrous | denoise_output | tonemap |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
for backend in $BACKENDS; do
  "$BIN" render --backend "$backend" --resolution "$SIZE" --fov 60 --history --denoise -q \
    --gaze-trace "$out/gaze.csv" --camera-path "$out/camera.csv" \
    -o "$out/f_$backend.png" --stats "$out/$backend.json"
  python3 - "$out/$backend.json" "$backend" "$SIZE" <<'PY'
import json, statistics, sys
doc, backend, size = json.load(open(sys.argv[1])), sys.argv[2], sys.argv[3]
w, h = map(int, size.split("x"))
mp = w * h / 1e6
frames = doc["frames"][2:] or doc["frames"]
names = ["samples", "cell_means", "fill", "gbuffer", "cell_albedo", "temporal", "resolve_history",
         "denoise_input", "denoise_atrous", "denoise_output", "tonemap"]
cells = []
for n in names:
    values = [f["pass_ms"][n] for f in frames if n in f["pass_ms"]]
    cells.append(f"{statistics.median(values) / mp:.1f}" if values else "-")
print(f"| {backend} | {size} | {len(doc['frames'])} | " + " | ".join(cells) + " |")
PY
done
