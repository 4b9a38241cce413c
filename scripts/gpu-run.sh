#!/usr/bin/env bash
# Runs on the GPU machine (prepared here by scripts/gpu-bundle.sh, carried as gpu/): renders Lost Empire
# on the Vulkan backend at 3840x2160 and 1920x1080, foveated 32/16/8 and uniform 32 spp, with software
# and (where the driver has ray queries) hardware traversal, FRAMES frames each in one process (a gaze
# trace of FRAMES lines, so the context and scene stay warm), and writes one table:
#   $OUT/gpu-results.md and .json: device and driver, ms per frame (median of the warm frames: all but
#   the first), fps, M paths/s (primary samples per second), speed-up foveated vs uniform, upload and
#   acceleration-structure build times and sizes; $OUT/*.log: each run's stderr. Then the frame's passes
#   with temporal reuse and the denoiser (`--history --denoise`, foveated, at PASS_SIZE, default
#   1920x1080): each pass's median GPU milliseconds (the issues' budgets at 1080p: the temporal pass at
#   most 2 ms, the denoiser at most 10 ms).
# FOVEA_GPU_QUICK=1 runs a small version (320x180, 3 frames) to check the script anywhere (lavapipe).
set -uo pipefail
cd "$(dirname "$0")/.."
OUT=${OUT:-gpu-out}
mkdir -p "$OUT"
BIN=${FOVEA_BIN:-gpu/fovea}
FRAMES=${FRAMES:-8}
SIZES=${SIZES:-"3840x2160 1920x1080"}
if [ "${FOVEA_GPU_QUICK:-0}" = 1 ]; then FRAMES=3; SIZES="320x180"; fi
# The Vulkan loader, if the machine has none.
if ! ldconfig -p | grep -q libvulkan.so.1 && ls gpu/debs/*.deb >/dev/null 2>&1; then
  for f in gpu/debs/*.deb; do dpkg -x "$f" /; done
  ldconfig
fi
nvidia_icd=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
if [ -z "${VK_DRIVER_FILES:-}" ] && [ -f "$nvidia_icd" ]; then export VK_DRIVER_FILES=$nvidia_icd; fi
(nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader 2>/dev/null || echo "no nvidia-smi") \
  >"$OUT/gpu.txt"
"$BIN" devices >"$OUT/devices.txt" 2>&1
cat "$OUT/gpu.txt" "$OUT/devices.txt"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for size in $SIZES; do
  w=${size%x*}; h=${size#*x}
  trace="$work/trace-$size.csv"
  : >"$trace"
  for i in $(seq 0 $((FRAMES - 1))); do echo "$i,$((w / 2)),$((h / 2))" >>"$trace"; done
  for mode in foveated uniform; do
    for traversal in software hardware; do
      name="$size-$mode-$traversal"
      extra=(); [ "$mode" = uniform ] && extra=(--uniform)
      echo "== $name"
      timeout 240 "$BIN" render assets/lost_empire/lost_empire.obj --backend vulkan --traversal "$traversal" \
        --resolution "$size" "${extra[@]}" --gaze-trace "$trace" -o "$work/f.png" \
        --stats "$OUT/$name.json" -q 2>"$OUT/$name.log" || echo "   failed: $(tail -2 "$OUT/$name.log")"
      rm -f "$work"/f_*.png
    done
  done
done
PASS_SIZE=${PASS_SIZE:-1920x1080}
if [ "${FOVEA_GPU_QUICK:-0}" = 1 ]; then PASS_SIZE=320x180; fi
pw=${PASS_SIZE%x*}; ph=${PASS_SIZE#*x}
trace="$work/passes.csv"
: >"$trace"
# A jittering gaze, so the history is exercised as under an eye tracker.
for i in $(seq 0 $((FRAMES - 1))); do echo "$i,$((pw / 2 + (i % 3) * 3)),$((ph / 2 - (i % 2) * 2))" >>"$trace"; done
echo "== passes $PASS_SIZE (history, denoiser)"
timeout 240 "$BIN" render assets/lost_empire/lost_empire.obj --backend vulkan --resolution "$PASS_SIZE" \
  --history --denoise --gaze-trace "$trace" -o "$work/p.png" --stats "$OUT/passes.json" -q \
  2>"$OUT/passes.log" || echo "   failed: $(tail -2 "$OUT/passes.log")"
rm -f "$work"/p_*.png
python3 - "$OUT" <<'PY'
import json, os, statistics, sys
out = sys.argv[1]
rows, runs = [], {}
for f in sorted(os.listdir(out)):
    if not f.endswith(".json") or f.startswith("gpu-results") or f.startswith("passes"):
        continue
    size, mode, traversal = f[:-5].split("-")
    d = json.load(open(os.path.join(out, f)))
    frames = d.get("frames") or [d]
    warm = frames[1:] or frames
    ms = statistics.median(x["render_ms"] for x in warm)
    samples = warm[0]["primary_samples"]
    b = d.get("backend_details", {})
    accel = b.get("acceleration_structures") or {}
    runs[(size, mode, traversal)] = ms
    rows.append(dict(size=size, mode=mode, traversal=b.get("traversal", traversal), ms=ms, fps=1e3 / ms,
                     mpaths=samples / ms / 1e3, samples=samples, frames=len(frames), upload_ms=b.get("upload_ms"),
                     as_build_ms=accel.get("build_ms"), blas_mb=(accel.get("blas_bytes") or 0) / 2**20,
                     device=d.get("device"), note=b.get("traversal_note")))
for r in rows:
    u = runs.get((r["size"], "uniform", r["traversal"]))
    r["speedup"] = (u / r["ms"]) if (u and r["mode"] == "foveated") else None
gpu = open(os.path.join(out, "gpu.txt")).read().strip()
lines = [f"GPU: {gpu}", f"Vulkan device: {rows[0]['device'] if rows else '?'}", "",
         "| size | mode | traversal | ms/frame (median warm) | fps | M paths/s | speed-up fov. vs uniform | upload ms | AS build ms | BLAS MiB |",
         "|---|---|---|---|---|---|---|---|---|---|"]
for r in rows:
    sp = f"{r['speedup']:.1f}x" if r["speedup"] else ""
    ab = f"{r['as_build_ms']:.0f}" if r["as_build_ms"] else ""
    bm = f"{r['blas_mb']:.1f}" if r["blas_mb"] else ""
    up = f"{r['upload_ms']:.0f}" if r["upload_ms"] is not None else ""
    lines.append(f"| {r['size']} | {r['mode']} | {r['traversal']} | {r['ms']:.2f} | {r['fps']:.1f} | {r['mpaths']:.1f} | {sp} | {up} | {ab} | {bm} |")
passes_file = os.path.join(out, "passes.json")
if os.path.exists(passes_file):
    d = json.load(open(passes_file))
    frames = (d.get("frames") or [d])[1:] or (d.get("frames") or [d])
    # The frame's order (core's FramePass::ALL), then anything else the stats name.
    names = [n for n in ["samples", "cell_means", "fill", "gbuffer", "temporal", "resolve_history",
                         "denoise_input", "denoise_atrous", "denoise_output", "tonemap", "read_back"]
             if any(n in f.get("pass_ms", {}) for f in frames)]
    for f in frames:
        for n in f.get("pass_ms", {}):
            if n not in names:
                names.append(n)
    lines += ["", f"Passes with history and the denoiser, foveated 32/16/8, {len(frames)} warm frames, median GPU ms:", "",
              "| " + " | ".join(names) + " |", "|" + "---|" * len(names)]
    lines.append("| " + " | ".join(f"{statistics.median(f['pass_ms'][n] for f in frames if n in f.get('pass_ms', {})):.3f}" for n in names) + " |")
open(os.path.join(out, "gpu-results.md"), "w").write("\n".join(lines) + "\n")
json.dump(rows, open(os.path.join(out, "gpu-results.json"), "w"), indent=1)
print("\n".join(lines))
PY
