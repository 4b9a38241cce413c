#!/usr/bin/env python3
"""Writes a synthetic eye-tracker gaze trace: timed `t,x,y` lines, x and y normalised to the image
(origin top-left), sampled at 120 Hz, for `fovea report|render|view --gaze-trace FILE --gaze-normalized`.

Fixations joined by saccades, and within each fixation what a real tracker reports: Gaussian noise of
0.15 degrees RMS (Tobii Pro Spectrum to TX300 span 0.06-0.26), a drift of 0.3 degrees per second and
a 0.5 degree microsaccade about every 0.7 s. Degrees are converted with the default display of fovea
(70.848 cm wide, seen from 60 cm: 61.0 degrees across). Deterministic (seeded).

    python3 scripts/gaze-trace.py > assets/gaze/saccades-2s.csv
"""
import math
import random
import sys

RATE_HZ = 120.0
WIDTH_DEG = 2.0 * math.degrees(math.atan(35.424 / 60.0))  # 61.0
ASPECT = 16.0 / 9.0
# (start s, end s, fixation x, y); the gap between fixations is a 50 ms saccade.
FIXATIONS = [(0.0, 0.6, 0.5, 0.5), (0.65, 1.3, 0.25, 0.35), (1.35, 2.0, 0.7, 0.6)]


def main():
    rng = random.Random(34)
    deg_x = 1.0 / WIDTH_DEG  # normalised x per degree (near the centre)
    deg_y = deg_x * ASPECT  # normalised y per degree
    print("t,x,y")
    drift = [0.0, 0.0]
    heading = rng.uniform(0.0, 2.0 * math.pi)
    next_micro = 0.7
    n = int(2.0 * RATE_HZ) + 1
    for i in range(n):
        t = i / RATE_HZ
        current = None
        for k, (start, end, fx, fy) in enumerate(FIXATIONS):
            if start <= t <= end:
                current = (fx, fy)
                if t - start < 1.0 / RATE_HZ:
                    drift = [0.0, 0.0]  # a saccade lands on the target
            elif k + 1 < len(FIXATIONS) and end < t < FIXATIONS[k + 1][0]:
                # In flight: linear between the two fixations.
                s = (t - end) / (FIXATIONS[k + 1][0] - end)
                nx, ny = FIXATIONS[k + 1][2], FIXATIONS[k + 1][3]
                current = (fx + s * (nx - fx), fy + s * (ny - fy))
        x, y = current
        heading += rng.gauss(0.0, 0.3)
        drift[0] += 0.3 / RATE_HZ * math.cos(heading)
        drift[1] += 0.3 / RATE_HZ * math.sin(heading)
        if t >= next_micro:
            angle = rng.uniform(0.0, 2.0 * math.pi)
            drift[0] += 0.5 * math.cos(angle)
            drift[1] += 0.5 * math.sin(angle)
            next_micro += 0.7
        nx = x + (drift[0] + rng.gauss(0.0, 0.15)) * deg_x
        ny = y + (drift[1] + rng.gauss(0.0, 0.15)) * deg_y
        print(f"{t:.5f},{nx:.6f},{ny:.6f}")


if __name__ == "__main__":
    sys.exit(main())
