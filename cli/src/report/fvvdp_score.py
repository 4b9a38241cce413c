"""Scores one test sequence against its reference with FovVideoVDP (pyfvvdp), for `fovea report`.

Usage: python fvvdp_score.py JOB.json. The job names raw 8-bit sRGB RGB files (frames x height x width
x 3, row-major, top row first), the frame rate, one fixation per frame in pixels (origin top-left) and
the display (size in cm, distance in cm, peak luminance, contrast). A reference of one frame serves
every frame (a still camera). Prints one JSON line: {"jod": ..., "info": ..., "seconds": ...}.
"""
import json
import math
import os
import sys
import time

import numpy as np
import torch
import pyfvvdp


def main():
    with open(sys.argv[1]) as f:
        job = json.load(f)
    torch.set_num_threads(max(1, os.cpu_count() or 1))
    w, h, n = job["width"], job["height"], job["frames"]
    test = np.fromfile(job["test"], dtype=np.uint8).reshape(n, h, w, 3)
    ref = np.fromfile(job["reference"], dtype=np.uint8)
    ref_frames = ref.size // (h * w * 3)
    ref = ref.reshape(ref_frames, h, w, 3)
    if ref_frames == 1 and n > 1:
        ref = np.ascontiguousarray(np.broadcast_to(ref, (n, h, w, 3)))
    d = job["display"]
    diagonal_in = math.hypot(d["width_cm"], d["height_cm"]) / 2.54
    geometry = pyfvvdp.fvvdp_display_geometry(
        (w, h), distance_m=d["distance_cm"] / 100.0, diagonal_size_inches=diagonal_in
    )
    photometry = pyfvvdp.fvvdp_display_photo_eotf(
        d["peak_cd_m2"], contrast=d["contrast"], EOTF="sRGB"
    )
    fv = pyfvvdp.fvvdp(
        display_photometry=photometry,
        display_geometry=geometry,
        foveated=True,
        heatmap=None,
        device=torch.device("cpu"),
        quiet=True,
    )
    fixations = np.asarray(job["fixations"], dtype=np.float32).reshape(n, 2)
    start = time.time()
    q, _stats = fv.predict(
        test,
        ref,
        dim_order="FHWC",
        frames_per_second=job["fps"],
        fixation_point=torch.tensor(fixations),
    )
    print(
        json.dumps(
            {
                "jod": float(q),
                "info": fv.get_info_string().strip('"'),
                "seconds": time.time() - start,
            }
        )
    )


if __name__ == "__main__":
    main()
