#!/usr/bin/env bash
# Runs on the GPU machine (prepared here by scripts/gpu-bundle.sh, carried as gpu/): renders the bundled
# Lost Empire view on the Vulkan backend at 3840x2160 and 1920x1080, foveated 32/16/8 and uniform 32 spp, with software
# and (where the driver has ray queries) hardware traversal, FRAMES frames each in one process (a gaze
# trace of FRAMES lines, so the context and scene stay warm), and writes one table:
#   $OUT/gpu-results.md and .json: device and driver, ms per frame (median of the warm frames: all but
#   the first), the sampling pass's GPU ms, fps, M paths/s (primary samples per second), speed-up foveated
#   vs uniform, upload and acceleration-structure build times and sizes. First (the part that matters
#   most if the time runs out) the frame's passes with temporal reuse and the denoiser (`--history
#   --denoise`, foveated, at each of PASS_SIZES, default 1920x1080 and 3840x2160): each pass's median GPU
#   milliseconds (the issues' budgets at 1080p: the temporal pass at most 2 ms, the denoiser at most
#   10 ms). Then the GPU's frame against the CPU's (`fovea compare`, AGREE_SIZE, default 640x360).
#   Each run's --stats JSON and stderr go to RAW (default $OUT/raw); after every run they are packed into
#   $OUT/gpu-raw.tgz, so a run cut short by its time limit still brings back what it finished (the device
#   tool returns at most 8 files: there, set RAW outside $OUT).
# FOVEA_GPU_QUICK=1 runs a small version (320x180, 3 frames) to check the script anywhere (lavapipe).
set -uo pipefail
cd "$(dirname "$0")/.."
OUT=${OUT:-gpu-out}
mkdir -p "$OUT"
BIN=${FOVEA_BIN:-gpu/fovea}
# The scene: by default the bundled Lost Empire with its own camera and sky, the view of the README's
# figures (naming the OBJ's path instead frames the whole map from outside, with no sky: another
# workload). SCENE=path renders another scene.
scene=(); [ -n "${SCENE:-}" ] && scene=("$SCENE")
FRAMES=${FRAMES:-8}
SIZES=${SIZES:-"3840x2160 1920x1080"}
if [ "${FOVEA_GPU_QUICK:-0}" = 1 ]; then FRAMES=3; SIZES="320x180"; fi
# The Vulkan loader and the GL vendor-neutral libraries the NVIDIA driver's ICD links against, if the
# machine lacks them (a bare container with the driver mounted under /usr/local/nvidia has neither).
nvidia_icd=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
if { ! ldconfig -p | grep -q libvulkan.so.1 || { [ -f "$nvidia_icd" ] && ! ldconfig -p | grep -q libGLX.so.0; }; } \
  && ls gpu/debs/*.deb >/dev/null 2>&1; then
  for f in gpu/debs/*.deb; do dpkg -x "$f" /; done
  ldconfig
fi
if [ -z "${VK_DRIVER_FILES:-}" ] && [ -f "$nvidia_icd" ]; then export VK_DRIVER_FILES=$nvidia_icd; fi
RAW=${RAW:-$OUT/raw}
mkdir -p "$RAW"
pack() { tar czf "$OUT/gpu-raw.tgz" -C "$RAW" . ; }
(nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader 2>/dev/null || echo "no nvidia-smi") \
  >"$RAW/gpu.txt"
"$BIN" devices >"$RAW/devices.txt" 2>&1
# No Vulkan device: the loader's own account of why, for the log.
grep -q "^vulkan" "$RAW/devices.txt" || VK_LOADER_DEBUG=error,warn "$BIN" devices >"$RAW/loader.txt" 2>&1
cat "$RAW/gpu.txt" "$RAW/devices.txt"
pack
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# Untimed warm-up: the first process on a fresh machine compiles the kernel's pipelines (about 40 s on
# the H200, which meanwhile idles at 345 MHz); the driver's disk cache serves the later ones in about
# 10 ms. Without it the first measured run's frames came while the clocks ramped up (130 ms falling to
# 30 ms per frame over its eight frames).
warm="$work/warm.csv"
: >"$warm"
for i in 0 1 2 3 4 5; do echo "$i,960,540" >>"$warm"; done
echo "== warm-up (untimed)"
timeout 150 "$BIN" render "${scene[@]}" --backend vulkan --resolution 1920x1080 --history --denoise \
  --gaze-trace "$warm" -o "$work/w.png" -q 2>"$RAW/warm-up.log" || echo "   failed: $(tail -2 "$RAW/warm-up.log")"
rm -f "$work"/w_*.png
# The GPU's frame against the CPU's, the same view and samples (the CPU renders there too): the share of
# pixels within 1e-3, the largest difference, relMSE and FLIP (`fovea compare`).
AGREE_SIZE=${AGREE_SIZE:-640x360}
if [ "${FOVEA_GPU_QUICK:-0}" = 1 ]; then AGREE_SIZE=160x90; fi
echo "== the GPU's frame against the CPU's ($AGREE_SIZE, uniform 8 spp)"
for b in vulkan cpu; do
  timeout 150 "$BIN" render "${scene[@]}" --backend "$b" --resolution "$AGREE_SIZE" --uniform --spp 8,8,8 \
    -o "$RAW/agree-$b.exr" -q 2>"$RAW/agree-$b.log" || echo "   failed: $(tail -2 "$RAW/agree-$b.log")"
done
"$BIN" compare "$RAW/agree-vulkan.exr" "$RAW/agree-cpu.exr" --json "$RAW/agree.json" 2>&1 | tee "$RAW/agree.txt"
pack
PASS_SIZES=${PASS_SIZES:-"1920x1080 3840x2160"}
if [ "${FOVEA_GPU_QUICK:-0}" = 1 ]; then PASS_SIZES=320x180; fi
for size in $PASS_SIZES; do
  pw=${size%x*}; ph=${size#*x}
  trace="$work/passes.csv"
  : >"$trace"
  # A jittering gaze, so the history is exercised as under an eye tracker.
  for i in $(seq 0 $((FRAMES - 1))); do echo "$i,$((pw / 2 + (i % 3) * 3)),$((ph / 2 - (i % 2) * 2))" >>"$trace"; done
  echo "== passes $size (history, denoiser)"
  timeout 150 "$BIN" render "${scene[@]}" --backend vulkan --resolution "$size" \
    --history --denoise --gaze-trace "$trace" -o "$work/p.png" --stats "$RAW/passes-$size.json" -q \
    2>"$RAW/passes-$size.log" || echo "   failed: $(tail -2 "$RAW/passes-$size.log")"
  rm -f "$work"/p_*.png
  pack
done
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
      timeout 150 "$BIN" render "${scene[@]}" --backend vulkan --traversal "$traversal" \
        --resolution "$size" "${extra[@]}" --gaze-trace "$trace" -o "$work/f.png" \
        --stats "$RAW/$name.json" -q 2>"$RAW/$name.log" || echo "   failed: $(tail -2 "$RAW/$name.log")"
      rm -f "$work"/f_*.png
      pack
    done
  done
done
python3 - "$RAW" "$OUT" <<'PY'
import json, os, statistics, sys
raw, out = sys.argv[1], sys.argv[2]
rows, runs = [], {}
for f in sorted(os.listdir(raw)):
    if not f.endswith(".json") or f.startswith(("passes", "agree")):
        continue
    size, mode, traversal = f[:-5].split("-")
    d = json.load(open(os.path.join(raw, f)))
    frames = d.get("frames") or [d]
    warm = frames[1:] or frames
    ms = statistics.median(x["render_ms"] for x in warm)
    gpu_samples = [x["pass_ms"]["samples"] for x in warm if "samples" in x.get("pass_ms", {})]
    samples = warm[0]["primary_samples"]
    b = d.get("backend_details", {})
    accel = b.get("acceleration_structures") or {}
    runs[(size, mode, traversal)] = ms
    rows.append(dict(size=size, mode=mode, traversal=b.get("traversal", traversal), ms=ms, fps=1e3 / ms,
                     samples_gpu_ms=statistics.median(gpu_samples) if gpu_samples else None,
                     chunks=b.get("chunks"), pipeline_create_ms=b.get("pipeline_create_ms"),
                     mpaths=samples / ms / 1e3, samples=samples, frames=len(frames), upload_ms=b.get("upload_ms"),
                     as_build_ms=accel.get("build_ms"), blas_mb=(accel.get("blas_bytes") or 0) / 2**20,
                     device=d.get("device"), note=b.get("traversal_note")))
for r in rows:
    u = runs.get((r["size"], "uniform", r["traversal"]))
    r["speedup"] = (u / r["ms"]) if (u and r["mode"] == "foveated") else None
gpu = open(os.path.join(raw, "gpu.txt")).read().strip()
lines = [f"GPU: {gpu}", f"Vulkan device: {rows[0]['device'] if rows else '?'}", "",
         "| size | mode | traversal | ms/frame (median warm) | sampling pass GPU ms | fps | M paths/s | speed-up fov. vs uniform | chunks | upload ms | AS build ms | BLAS MiB |",
         "|---|---|---|---|---|---|---|---|---|---|---|---|"]
for r in rows:
    sp = f"{r['speedup']:.1f}x" if r["speedup"] else ""
    ab = f"{r['as_build_ms']:.0f}" if r["as_build_ms"] else ""
    bm = f"{r['blas_mb']:.1f}" if r["blas_mb"] else ""
    up = f"{r['upload_ms']:.0f}" if r["upload_ms"] is not None else ""
    sg = f"{r['samples_gpu_ms']:.2f}" if r["samples_gpu_ms"] is not None else ""
    lines.append(f"| {r['size']} | {r['mode']} | {r['traversal']} | {r['ms']:.2f} | {sg} | {r['fps']:.1f} | {r['mpaths']:.1f} | {sp} | {r['chunks']} | {up} | {ab} | {bm} |")
for pf in sorted(f for f in os.listdir(raw) if f.startswith("passes") and f.endswith(".json")):
    d = json.load(open(os.path.join(raw, pf)))
    frames = (d.get("frames") or [d])[1:] or (d.get("frames") or [d])
    # The frame's order (core's FramePass::ALL), then anything else the stats name.
    names = [n for n in ["samples", "cell_means", "fill", "gbuffer", "cell_albedo", "temporal", "resolve_history",
                         "denoise_input", "denoise_atrous", "denoise_output", "tonemap", "overlay", "read_back"]
             if any(n in f.get("pass_ms", {}) for f in frames)]
    for f in frames:
        for n in f.get("pass_ms", {}):
            if n not in names:
                names.append(n)
    lines += ["", f"Passes with history and the denoiser, {pf[7:-5]}, foveated 32/16/8, {len(frames)} warm frames, median GPU ms:", "",
              "| " + " | ".join(names) + " |", "|" + "---|" * len(names)]
    lines.append("| " + " | ".join(f"{statistics.median(f['pass_ms'][n] for f in frames if n in f.get('pass_ms', {})):.3f}" for n in names) + " |")
agree = os.path.join(raw, "agree.txt")
if os.path.exists(agree):
    lines += ["", "The GPU's frame against the CPU's: " + open(agree).read().strip()]
open(os.path.join(out, "gpu-results.md"), "w").write("\n".join(lines) + "\n")
json.dump(rows, open(os.path.join(out, "gpu-results.json"), "w"), indent=1)
print("\n".join(lines))
PY
cp "$RAW/gpu.txt" "$RAW/devices.txt" "$OUT/" 2>/dev/null
pack
