#!/usr/bin/env bash
# Frames per second and gaze-to-present latency of `fovea view` (a benchmark, not a test): for each scene,
# backend, size and mode, a headless window under Xvfb renders N frames while a simulated eye tracker sends
# gaze samples over UDP at 120 Hz (the gaze drifts slowly, so every frame starts a new mean, as with a
# moving eye). Prints one Markdown row per run from the view's --stats JSON.
#
#   bash scripts/bench-view.sh [FRAMES]            # default 20 frames per run
#   BENCH_VIEW_BUDGET=0 bash scripts/bench-view.sh  # whole configuration every frame (no frame budget)
#   BENCH_VIEW_BACKENDS="vulkan" BENCH_VIEW_SIZES="1920x1080" BENCH_VIEW_SCENES="assets/lost_empire/lost_empire.obj" ...
set -euo pipefail
cd "$(dirname "$0")/.."
FRAMES=${1:-20}
BUDGET=${BENCH_VIEW_BUDGET:-33}
BACKENDS=${BENCH_VIEW_BACKENDS:-"cpu vulkan"}
SIZES=${BENCH_VIEW_SIZES:-"1280x720 1920x1080"}
MODES=${BENCH_VIEW_MODES:-"foveated uniform"}
SCENES=${BENCH_VIEW_SCENES:-"assets/lost_empire/lost_empire.obj assets/cornell_box/CornellBox-Original.obj"}
BIN=${FOVEA_BIN:-target/release/fovea}
[ -x "$BIN" ] || cargo build --release -q -p fovea-cli
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

# The eye tracker: `t,x,y` datagrams (normalised, origin top-left) at 120 Hz, drifting around the centre.
cat >"$out/tracker.py" <<'EOF'
import math, socket, sys, time
port, seconds = int(sys.argv[1]), float(sys.argv[2])
s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
start = time.time()
while time.time() - start < seconds:
    t = time.time() - start
    x, y = 0.5 + 0.2 * math.cos(0.5 * t), 0.5 + 0.15 * math.sin(0.7 * t)
    s.sendto(f"{t:.4f},{x:.5f},{y:.5f}\n".encode(), ("127.0.0.1", port))
    time.sleep(1 / 120)
EOF

echo "| scene | backend | size | mode | budget ms | median frame ms | fps | median render ms | median latency ms | samples/frame | per-frame spp |"
echo "|---|---|---|---|---|---|---|---|---|---|---|"
for scene in $SCENES; do
  camera=()
  case "$scene" in *Cornell*) camera=(--eye 0,1,3.9 --target 0,1,0 --fov 38) ;; esac
  for backend in $BACKENDS; do
    for size in $SIZES; do
      for mode in $MODES; do
        port=$(python3 -c 'import socket; s=socket.socket(socket.AF_INET, socket.SOCK_DGRAM); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])')
        uniform=(); [ "$mode" = uniform ] && uniform=(--uniform)
        python3 "$out/tracker.py" "$port" 600 &
        tracker=$!
        xvfb-run -a -s "-screen 0 2048x1200x24" "$BIN" view "$scene" "${camera[@]}" --backend "$backend" \
          --size "$size" "${uniform[@]}" --budget-ms "$BUDGET" --gaze-source "udp:$port" \
          --exit-after-frames "$FRAMES" --stats "$out/s.json" -q || echo "(run failed)"
        kill "$tracker" 2>/dev/null || true
        python3 - "$out/s.json" "$scene" "$backend" "$size" "$mode" "$BUDGET" <<'EOF'
import json, statistics, sys, os
d = json.load(open(sys.argv[1]))
frames = d["frames"][2:] or d["frames"]  # the first frames compile pipelines and settle the budget
med = lambda xs: statistics.median(xs) if xs else float("nan")
fm = med([f["frame_ms"] for f in frames])
lat = med([f["latency_ms"] for f in frames if f["latency_ms"] is not None])
print(f"| {os.path.basename(sys.argv[2])} | {sys.argv[3]} | {sys.argv[4]} | {sys.argv[5]} | {sys.argv[6]} | {fm:.1f} | {1e3/fm:.1f} | "
      f"{med([f['render_ms'] for f in frames]):.1f} | {lat:.1f} | {med([f['primary_samples'] for f in frames])/1e6:.3f} M | "
      f"{'/'.join(map(str, frames[-1]['frame_spp']))} |")
EOF
        rm -f "$out/s.json"
      done
    done
  done
done
