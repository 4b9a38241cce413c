#!/usr/bin/env python3
"""Compares a fovea render with a Mitsuba render of the same peer-kit scene, tile by tile.

Usage (with the peer kit's venv, which has numpy and mitsuba for reading EXR):
    $PEER_WORK/venv/bin/python scripts/peer-tiles.py FOVEA.exr MITSUBA.exr [TILES]

Prints each image's mean linear RGB and a TILES x TILES grid (default 8) of fovea / Mitsuba ratios of the
tiles' mean radiance (sum of RGB). Both images must have the same size, divisible by TILES.
"""
import sys

import mitsuba as mi
import numpy as np


def load(path):
    bitmap = mi.Bitmap(path).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32)
    return np.array(bitmap, dtype=np.float64)


def main():
    if len(sys.argv) not in (3, 4):
        sys.exit(__doc__)
    mi.set_variant("scalar_rgb")
    ours, theirs = load(sys.argv[1]), load(sys.argv[2])
    tiles = int(sys.argv[3]) if len(sys.argv) == 4 else 8
    if ours.shape != theirs.shape:
        sys.exit(f"sizes differ: {ours.shape[:2]} and {theirs.shape[:2]}")
    h, w, _ = ours.shape
    if h % tiles or w % tiles:
        sys.exit(f"{w}x{h} is not divisible into {tiles}x{tiles} tiles")

    def tile_means(img):
        return img.reshape(tiles, h // tiles, tiles, w // tiles, 3).mean(axis=(1, 3)).sum(axis=-1)

    np.set_printoptions(precision=2, suppress=True, linewidth=160)
    for name, img in (("fovea  ", ours), ("mitsuba", theirs)):
        print(f"mean RGB {name}", " ".join(f"{c:.4f}" for c in img.mean(axis=(0, 1))))
    print("tile ratios (fovea / mitsuba, rows top to bottom):")
    print(tile_means(ours) / np.maximum(tile_means(theirs), 1e-9))


if __name__ == "__main__":
    main()
