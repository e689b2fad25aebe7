#!/usr/bin/env python3
"""`mra transfer` on an image: give a blurred kodim13 the fine texture of kodim01.

Both Kodak images (../shared/corpus/images/kodak, path overridable with MRA_CORPUS) as gray
(ITU-R 601 luma). Base = kodim13 down- and up-sampled by 4 with cubic splines (scipy zoom).
`mra transfer --levels 2` replaces the base's two finest levels of details with kodim01's.
Reported: PSNR against the original kodim13 (peak 255), std of the 5-point Laplacian, seam ratio.
Run from the repository root:  cargo build --release && python3 benches/image_transfer.py
"""
import json, os, subprocess, tempfile
import numpy as np
import tifffile
import imageio.v3 as iio
from scipy import ndimage

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CORPUS = os.environ.get("MRA_CORPUS", os.path.join(ROOT, "..", "shared", "corpus"))
MRA = os.path.join(ROOT, "target", "release", "mra")


def gray(name):
    rgb = iio.imread(os.path.join(CORPUS, "images", "kodak", name + ".png")).astype(np.float64)
    return rgb @ np.array([0.299, 0.587, 0.114])


def lap_std(g):
    return (g[:-2, 1:-1] + g[2:, 1:-1] + g[1:-1, :-2] + g[1:-1, 2:] - 4 * g[1:-1, 1:-1]).std()


def psnr(a, b):
    return 10 * np.log10(255.0 ** 2 / np.mean((a - b) ** 2))


def main():
    orig, ex = gray("kodim13"), gray("kodim01")
    small = ndimage.zoom(orig, 0.25, order=3)
    base = ndimage.zoom(small, (orig.shape[0] / small.shape[0], orig.shape[1] / small.shape[1]), order=3)
    print("| | PSNR vs original kodim13 | std of Laplacian | seam ratio |")
    print("|---|---|---|---|")
    print(f"| original | – | {lap_std(orig):.1f} | – |")
    print(f"| blurred (the base) | {psnr(base, orig):.2f} dB | {lap_std(base):.1f} | – |")
    with tempfile.TemporaryDirectory() as tmp:
        bp, ep, op = (os.path.join(tmp, n) for n in ["base.tif", "ex.tif", "out.tif"])
        tifffile.imwrite(bp, base.astype(np.float32))
        tifffile.imwrite(ep, ex.astype(np.float32))
        for det in ["matched", "copy"]:
            r = subprocess.run([MRA, "transfer", "--from", ep, "--to", bp, "-o", op, "--levels", "2",
                                "--details", det, "--json"], check=True, capture_output=True, text=True)
            g = tifffile.imread(op).astype(np.float64)
            print(f"| transferred, {det} | {psnr(g, orig):.2f} dB | {lap_std(g):.1f} | "
                  f"{json.loads(r.stdout)['seam_ratio']:.3f} |")
    print(f"| example (kodim01) | – | {lap_std(ex):.1f} | – |")


if __name__ == "__main__":
    main()
