#!/usr/bin/env python3
"""docs/figures/terrain_compare.png: base | example | result | cubic upscale, hillshaded by
`mra terrain render` with one sun (315 deg / 45 deg) and one cell (92.6 m, the output's).

The case is the first of benches/terrain_quality.py: truth = N44W072 rows/cols 600-1112, base =
truth smoothed (Gaussian sigma 1 cell) and block-averaged by 4 (128x128, shown at 4x with nearest
cells, shaded with its own 370 m cell), example = N44W072 rows/cols 60-572, result =
`mra terrain synth --levels 2 --seed 1`, cubic = scipy zoom order 3 of the base.
Run from the repository root:  cargo build --release && python3 docs/figures/terrain_figure.py
"""
import os, subprocess, sys, tempfile
import numpy as np
import tifffile
from PIL import Image
from scipy import ndimage

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CORPUS = os.environ.get("MRA_CORPUS", os.path.join(ROOT, "..", "shared", "corpus"))
MRA = os.path.join(ROOT, "target", "release", "mra")
OUT = os.path.join(ROOT, "docs", "figures", "terrain_compare.png")
CELL = 92.6


def render(tmp, name, g, cell):
    p, png = os.path.join(tmp, name + ".tif"), os.path.join(tmp, name + ".png")
    tifffile.imwrite(p, g.astype(np.float32))
    subprocess.run([MRA, "terrain", "render", p, "-o", png, "--cell", str(cell)], check=True)
    return np.asarray(Image.open(png))


def main():
    a = np.fromfile(os.path.join(CORPUS, "terrain", "N44W072.hgt"), ">i2").reshape(1201, 1201).astype(np.float64)
    truth, example = a[600:1112, 600:1112], a[60:572, 60:572]
    base = ndimage.gaussian_filter(truth, 1.0).reshape(128, 4, 128, 4).mean(axis=(1, 3))
    with tempfile.TemporaryDirectory() as tmp:
        bp, ep, op = (os.path.join(tmp, n) for n in ("b.tif", "e.tif", "o.tif"))
        tifffile.imwrite(bp, base.astype(np.float32))
        tifffile.imwrite(ep, example.astype(np.float32))
        subprocess.run([MRA, "terrain", "synth", "--base", bp, "--example", ep, "-o", op, "--levels", "2",
                        "--seed", "1", "--any-units"], check=True)
        result = tifffile.imread(op).astype(np.float64)
        cubic = ndimage.zoom(base, 4, order=3, mode="nearest", grid_mode=True)
        pics = [np.kron(render(tmp, "base", base, 4 * CELL), np.ones((4, 4), np.uint8)),
                render(tmp, "example", example, CELL), render(tmp, "result", result, CELL),
                render(tmp, "cubic", cubic, CELL)]
    gap = np.full((512, 8), 255, np.uint8)
    row = np.concatenate([x for p in pics for x in (p, gap)][:-1], axis=1)
    Image.fromarray(row).save(OUT, optimize=True)
    print(OUT, file=sys.stderr)


if __name__ == "__main__":
    main()
