#!/usr/bin/env python3
"""What the eye sees of temporal reuse: FovVideoVDP over a gaze trace, the eye moving and still.

For each configuration (uniform and foveated, with history and optionally the denoiser) this renders the
bundled Lost Empire frame by frame with `fovea render --gaze-trace TRACE --history` twice, once over the
saccade trace and once with the gaze held at the centre for as many frames, and scores each sequence with
FovVideoVDP 1.2.2 (Mantiuk et al. 2021) against a converged reference, with the per-frame gaze as the
fixation (the report's display model: sRGB, 200 cd/m2, 1000:1). It also prints the median frame time and,
for the still gaze, each region's relMSE on the last frame. A benchmark, run by hand; figures go to
docs/performance.md.

    python3 scripts/bench-eye.py [--fovea target/release/fovea] [--resolution 480x270]
        [--display-cm 17.712x9.963] [--fps 30] [--backend cpu] [--out bench-eye] [--configs NAME,...]
        [--render-args "--fov 16.43"] [--windows 0:10,10:61] [--curve] [--keep]
        [--frames 31] [--camera-path assets/camera/lost_empire_pan-2s.csv]

The default image and display give 28.4 pixels per degree, as 1920x1080 on the default display does.
With --camera-path every run follows the path (its first frames, one a frame of the sequence) and each
frame is scored against its own converged reference, rendered once over the path and kept in --out.
It needs FovVideoVDP's environment (`bash scripts/setup-fvvdp.sh`) and installs the OpenEXR package into
it if missing (the frames are read as linear EXR and tone-mapped as fovea's tone map does).
"""
import argparse
import hashlib
import json
import math
import os
import re
import shlex
import statistics
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
VENV = Path(os.environ.get("FOVEA_FVVDP_VENV", Path.home() / ".cache/fovea/fvvdp-venv"))
DEFAULT_CONFIGS = [
    "uniform-1-history", "uniform-2-history", "32-16-8-history", "8-4-16-history", "4-4-16-history",
    "32-16-8-history-denoised", "uniform-1-history-denoised", "8-4-16-history-denoised",
]
CONFIG_NAME = re.compile(r"(?:uniform-(\d+)|(\d+)-(\d+)-(\d+))(-history)?(-denoised)?")


def config_args(name):
    """`fovea render` options of a configuration named `uniform-N[-history][-denoised]` (N spp in every
    pixel) or `F-I-P[-history][-denoised]` (the fovea's spp a pixel, the ring's a 2x2 block, the
    periphery's a 4x4 block); None if the name is neither."""
    m = CONFIG_NAME.fullmatch(name)
    if not m or any(g is not None and int(g) == 0 for g in m.groups()[:4]):
        return None
    uniform, fovea, ring, periphery, history, denoised = m.groups()
    args = ["--uniform", "--spp", f"{uniform},{uniform},{uniform}"] if uniform else \
        ["--spp", f"{fovea},{ring},{periphery}"]
    return args + (["--history"] if history else []) + (["--denoise"] if denoised else [])
SCORER = r'''
import json, math, sys, numpy as np, torch, pyfvvdp, OpenEXR
job = json.load(open(sys.argv[1]))
def read(p):
    with OpenEXR.File(p) as f:
        ch = f.channels()
        a = ch["RGBA"].pixels if "RGBA" in ch else ch["RGB"].pixels
        return np.asarray(a, dtype=np.float32)[..., :3]
def tonemap(c):
    c = np.nan_to_num(c, nan=0.0, posinf=1e30, neginf=0.0).clip(0, 1e30)
    l = 0.2126 * c[..., 0] + 0.7152 * c[..., 1] + 0.0722 * c[..., 2]
    c = (c / (1.0 + l)[..., None]).clip(0, 1)
    s = np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1 / 2.4) - 0.055)
    return (s * 255.0 + 0.5).astype(np.uint8)
frames = [read(p) for p in job["frames"]]
test = np.stack([tonemap(f) for f in frames])
n, h, w, _ = test.shape
# One reference for a still camera, or one a frame along a camera path.
references = [read(p) for p in job["references"]]
if len(references) == 1:
    refs = np.ascontiguousarray(np.broadcast_to(tonemap(references[0]), (n, h, w, 3)))
else:
    assert len(references) == n, (len(references), n)
    refs = np.stack([tonemap(r) for r in references])
ref = references[-1]
d = job["display"]
geometry = pyfvvdp.fvvdp_display_geometry((w, h), distance_m=d["distance_cm"] / 100.0,
    diagonal_size_inches=math.hypot(d["width_cm"], d["height_cm"]) / 2.54)
photometry = pyfvvdp.fvvdp_display_photo_eotf(200.0, contrast=1000.0, EOTF="sRGB")
fv = pyfvvdp.fvvdp(display_photometry=photometry, display_geometry=geometry, foveated=True,
    heatmap=None, device=torch.device("cuda" if torch.cuda.is_available() else "cpu"), quiet=True)
fix = torch.tensor(np.asarray(job["fixations"], dtype=np.float32) - 0.5)
q, _ = fv.predict(test, refs, dim_order="FHWC", frames_per_second=job["fps"], fixation_point=fix)
# relMSE by region on the last frame, around its gaze.
last, g = frames[-1].astype(np.float64), job["fixations"][-1]
yy, xx = np.mgrid[0:h, 0:w]
dist = np.hypot(xx + 0.5 - g[0], yy + 0.5 - g[1])
rel = ((last - ref) ** 2 / (ref.astype(np.float64) ** 2 + 1e-2)).mean(-1)
r1, r2 = job["radii"]
# JOD of parts of the sequence (--windows), to see which frames cost the score.
windows = {}
for a, b in job.get("windows", []):
    qw, _ = fv.predict(test[a:b], refs[a:b], dim_order="FHWC", frames_per_second=job["fps"],
                       fixation_point=fix[a:b])
    windows[f"{a}:{b}"] = float(qw)
# The periphery's relMSE on every frame, around that frame's gaze (--curve).
curve = []
if job.get("curve"):
    for i, (f, gz) in enumerate(zip(frames, job["fixations"])):
        r_ = references[i if len(references) > 1 else 0].astype(np.float64)
        dd = np.hypot(xx + 0.5 - gz[0], yy + 0.5 - gz[1])
        rr = ((f.astype(np.float64) - r_) ** 2 / (r_ ** 2 + 1e-2)).mean(-1)
        curve.append(float(rr[dd >= job["radii"][1]].mean()) if (dd >= job["radii"][1]).any() else None)
out = {"jod": float(q), "windows": windows, "curve_periphery": curve, "relmse_all": float(rel.mean()),
       "relmse_fovea": float(rel[dist < r1].mean()) if (dist < r1).any() else None,
       "relmse_periphery": float(rel[dist >= r2].mean()) if (dist >= r2).any() else None}
print(json.dumps(out))
'''


def run(cmd):
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"failed: {' '.join(map(str, cmd))}\n{r.stderr}")
    return r


def render_reference(fovea, display, spp, args):
    """A converged uniform render (seed 99, the CPU backend) with `display` and more `args`."""
    run([fovea, "render", *display, "--uniform", "--spp", f"{spp},{spp},{spp}", "--seed", "99",
         "--backend", "cpu", *args])


def python_with_exr():
    py = VENV / "bin" / "python"
    if not py.exists():
        sys.exit(f"no FovVideoVDP environment at {VENV}: run bash scripts/setup-fvvdp.sh")
    if subprocess.run([py, "-c", "import OpenEXR"], capture_output=True).returncode != 0:
        run([py, "-m", "pip", "install", "-q", "OpenEXR"])
    return py


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--fovea", default=str(ROOT / "target/release/fovea"))
    ap.add_argument("--resolution", default="480x270")
    ap.add_argument("--display-cm", default="17.712x9.963")
    ap.add_argument("--fps", default="30")
    ap.add_argument("--backend", default="cpu")
    ap.add_argument("--trace", default=str(ROOT / "assets/gaze/saccades-2s.csv"))
    ap.add_argument("--reference-spp", default="512")
    ap.add_argument("--out", default="bench-eye")
    ap.add_argument("--configs", default=",".join(DEFAULT_CONFIGS),
                    help="uniform-N or F-I-P (spp of the fovea a pixel, the ring a 2x2 block, the periphery a "
                         "4x4 block), each optionally -history and then -denoised, e.g. 4-4-16-history")
    ap.add_argument("--windows", default="",
                    help="also score parts of each sequence, as first:end frame ranges, e.g. 0:10,10:61")
    ap.add_argument("--curve", action="store_true",
                    help="print the periphery's relMSE on every frame of each sequence")
    ap.add_argument("--keep", action="store_true", help="keep the frames (they are deleted once scored)")
    ap.add_argument("--render-args", default="",
                    help="more `fovea render` options for every run and the reference, e.g. \"--fov 16.43\"")
    ap.add_argument("--frames", type=int, default=0,
                    help="score only the first N frames of the trace (default: all of it)")
    ap.add_argument("--camera-path", default="",
                    help="a camera path (frame,eye_x,eye_y,eye_z,target_x,target_y,target_z) every run "
                         "follows; each frame is scored against its own reference")
    a = ap.parse_args()
    if a.frames < 0:
        sys.exit(f"--frames: {a.frames} is negative; give a frame count, or 0 for the whole trace")
    windows = []
    for part in filter(None, a.windows.split(",")):
        try:
            first, end = map(int, part.split(":"))
        except ValueError:
            sys.exit(f"--windows: '{part}' is not first:end (two frame numbers, e.g. 0:10)")
        if not 0 <= first < end:
            sys.exit(f"--windows: '{part}' needs 0 <= first < end")
        windows.append((first, end))
    unknown = [c for c in a.configs.split(",") if config_args(c) is None]
    if unknown:
        sys.exit(f"--configs: cannot read {', '.join(unknown)}: give uniform-N or F-I-P (positive sample "
                 f"counts), optionally followed by -history and -denoised, e.g. 4-4-16-history")
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    py = python_with_exr()
    w, h = map(int, a.resolution.split("x"))
    extra = shlex.split(a.render_args)
    display = ["--resolution", a.resolution, "--display-cm", a.display_cm, "-q", *extra]
    common = [*display, "--backend", a.backend]
    # The still gaze: the trace's frame count, the gaze at the centre.
    frames = sum(1 for line in open(a.trace) if line[:1].isdigit())
    fps = float(a.fps)
    duration = (frames - 1) / 120.0  # the bundled traces are sampled at 120 Hz
    n = int(math.floor(duration * fps)) + 1
    trace_path = a.trace
    if a.frames:
        if a.frames > n:
            sys.exit(f"--frames: {a.frames} is more than the trace's {n} frames at {a.fps} fps")
        n = a.frames
        # The trace's samples up to half a frame past the last frame's time, so that it gives n frames
        # (its times are rounded, and a last sample just short of that frame would lose it).
        keep = (n - 0.5) / fps
        lines = open(a.trace).read().splitlines()
        cut = [l for l in lines if not l[:1].isdigit() or float(l.split(",")[0]) <= keep]
        trace_path = out / f"trace-{n}.csv"
        trace_path.write_text("\n".join(cut) + "\n")
    camera = []
    shaped = re.sub(r"[^A-Za-z0-9.]+", "_", " ".join(extra)).strip("_")
    if a.camera_path:
        keys = [l for l in open(a.camera_path).read().splitlines() if l[:1].isdigit()]
        if len(keys) < n:
            sys.exit(f"--camera-path: {a.camera_path} has {len(keys)} frames; the sequence needs {n}")
        text = "frame,eye_x,eye_y,eye_z,target_x,target_y,target_z\n" + "\n".join(keys[:n]) + "\n"
        # Named by the path's frames themselves, so an edited path never meets a stale reference.
        key = f"{Path(a.camera_path).stem}-{n}-{hashlib.sha256(text.encode()).hexdigest()[:10]}"
        camera_file = out / f"camera-{key}.csv"
        camera_file.write_text(text)
        camera = ["--camera-path", str(camera_file)]
        # One reference a frame, rendered once over the path and kept.
        ref_dir = out / f"reference-{a.resolution}-{a.reference_spp}-{key}{'-' + shaped if shaped else ''}"
        ref_stats = ref_dir / "stats.json"
        if not ref_stats.exists():
            ref_dir.mkdir(parents=True, exist_ok=True)
            render_reference(a.fovea, display, a.reference_spp,
                             [*camera, "-o", ref_dir / "ref.exr", "--stats", ref_dir / "partial.json"])
            os.replace(ref_dir / "partial.json", ref_stats)
        references = [f["output"] for f in json.load(open(ref_stats))["frames"]]
        if len(references) != n:
            sys.exit(f"the reference over {camera_file} has {len(references)} frames, not {n}")
    else:
        # The cached reference is named by everything that shapes it, the extra options included.
        reference = out / f"reference-{a.resolution}-{a.reference_spp}{'-' + shaped if shaped else ''}.exr"
        if not reference.exists():
            render_reference(a.fovea, display, a.reference_spp, ["-o", reference])
        references = [str(reference)]
    # The regions' radii on this display, for every configuration's relMSE by region (a uniform run's
    # stats have none: its one region is everything). Named by the display too: the reference is the
    # same image on any display, the radii are not.
    radii_stats = out / f"radii-{a.resolution}-{a.display_cm}{'-' + shaped if shaped else ''}.json"
    if not radii_stats.exists():
        run([a.fovea, "render", *display, "--spp", "1,1,1", "--backend", "cpu", "-o", out / "radii.exr",
             "--stats", radii_stats])
    radii = json.load(open(radii_stats))["radii_px"]
    still = out / "still.csv"
    still.write_text("frame,x,y\n" + "".join(f"{i},{w / 2},{h / 2}\n" for i in range(n)))
    traces = {"saccades": ["--gaze-trace", str(trace_path), "--gaze-normalized", "--trace-fps", a.fps,
                           *camera],
              "still": ["--gaze-trace", str(still), *camera]}
    print(f"| configuration | ms/frame | JOD, saccades | JOD, still | relMSE periphery, still (last frame) |")
    print("|---|---:|---:|---:|---:|")
    for name in a.configs.split(","):
        row = {}
        for trace, args in traces.items():
            d = out / name / trace
            d.mkdir(parents=True, exist_ok=True)
            stats = d / "stats.json"
            run([a.fovea, "render", *common, *config_args(name), *args, "-o", d / "f.exr", "--stats", stats])
            s = json.load(open(stats))
            if len(s["frames"]) != n:
                sys.exit(f"{name}, {trace}: {len(s['frames'])} frames rendered, not {n}")
            job = {
                "references": references,
                "frames": [f["output"] for f in s["frames"]],
                "fixations": [f["gaze"] for f in s["frames"]],
                "fps": fps,
                "radii": radii,
                "windows": [w_ for w_ in windows if w_[1] <= len(s["frames"])],
                "curve": a.curve,
                "display": {"width_cm": float(a.display_cm.split("x")[0]),
                            "height_cm": float(a.display_cm.split("x")[1]), "distance_cm": 60.0},
            }
            job_path = d / "job.json"
            job_path.write_text(json.dumps(job))
            scorer = d / "score.py"
            scorer.write_text(SCORER)
            r = json.loads(run([py, scorer, job_path]).stdout.strip().splitlines()[-1])
            r["ms"] = statistics.median(f["render_ms"] for f in s["frames"])
            row[trace] = r
            if not a.keep:
                for f in job["frames"]:
                    os.remove(f)
        ms = statistics.median([row["saccades"]["ms"], row["still"]["ms"]])
        p = row["still"]["relmse_periphery"]
        periphery = f"{p:.4f}" if p is not None else "- (no periphery)"
        print(f"| {name} | {ms:.0f} | {row['saccades']['jod']:.2f} | {row['still']['jod']:.2f} | "
              f"{periphery} |", flush=True)
        for trace in traces:
            if row[trace]["windows"]:
                parts = ", ".join(f"frames {k}: {v:.2f}" for k, v in row[trace]["windows"].items())
                print(f"  {name}, {trace}: JOD of {parts}", flush=True)
            if row[trace]["curve_periphery"]:
                c = row[trace]["curve_periphery"]
                print(f"  {name}, {trace}: periphery relMSE by frame: "
                      + " ".join(f"{i}:{v:.4f}" for i, v in enumerate(c) if v is not None), flush=True)


if __name__ == "__main__":
    main()
