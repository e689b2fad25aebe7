#!/usr/bin/env python3
"""`mra transfer` on a CT volume: give a blurred volume the fine texture of another region.

From ct_pancreas_256_stack.tif (../shared/corpus/volumes, path overridable with MRA_CORPUS):
truth = slices 0-63, example = slices 70-133 (another part of the body), base = truth
blurred by a Gaussian (sigma 1.5 voxels). `mra transfer --levels 2` replaces the base's
finest two levels of details with the example's, three ways (matched = the method,
copy = same place without matching, none = details dropped). Reported: PSNR against the
truth (peak = the truth's range), the std of the 7-point Laplacian (roughness) and its
ratio to the example's, the seam ratio and the wall time of the mra run.
Run from the repository root:  cargo build --release && python3 benches/volume_transfer.py
"""
import json, os, subprocess, tempfile, time
import numpy as np
import tifffile
from scipy import ndimage

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CORPUS = os.environ.get("MRA_CORPUS", os.path.join(ROOT, "..", "shared", "corpus"))
MRA = os.path.join(ROOT, "target", "release", "mra")


def lap_std(v):
    c = v[1:-1, 1:-1, 1:-1]
    l = (v[:-2, 1:-1, 1:-1] + v[2:, 1:-1, 1:-1] + v[1:-1, :-2, 1:-1] + v[1:-1, 2:, 1:-1]
         + v[1:-1, 1:-1, :-2] + v[1:-1, 1:-1, 2:] - 6 * c)
    return l.std()


def psnr(a, b):
    return 10 * np.log10((b.max() - b.min()) ** 2 / np.mean((a - b) ** 2))


def main():
    v = tifffile.imread(os.path.join(CORPUS, "volumes", "ct_pancreas_256_stack.tif")).astype(np.float64)
    truth, example = v[0:64], v[70:134]
    base = ndimage.gaussian_filter(truth, 1.5)
    ex_rough = lap_std(example)
    print("| volume | PSNR vs truth (dB) | Laplacian std | / example's | seam ratio | time (s) |")
    print("|---|---|---|---|---|---|")
    print(f"| truth (slices 0-63) | – | {lap_std(truth):.1f} | {lap_std(truth) / ex_rough:.2f} | – | – |")
    print(f"| example (slices 70-133) | – | {ex_rough:.1f} | 1.00 | – | – |")
    print(f"| base (truth blurred, σ 1.5) | {psnr(base, truth):.2f} | {lap_std(base):.1f} | "
          f"{lap_std(base) / ex_rough:.2f} | – | – |")
    with tempfile.TemporaryDirectory() as tmp:
        bp, ep = os.path.join(tmp, "base.tif"), os.path.join(tmp, "ex.tif")
        tifffile.imwrite(bp, base.astype(np.float32))
        tifffile.imwrite(ep, example.astype(np.float32))
        for det in ["matched", "copy", "none"]:
            op = os.path.join(tmp, det + ".tif")
            t = time.perf_counter()
            r = subprocess.run([MRA, "transfer", "--from", ep, "--to", bp, "-o", op, "--levels", "2",
                                "--details", det, "--json"], check=True, capture_output=True, text=True)
            secs = time.perf_counter() - t
            rep = json.loads(r.stdout)
            g = tifffile.imread(op).astype(np.float64)
            print(f"| transfer, {det} | {psnr(g, truth):.2f} | {lap_std(g):.1f} | {lap_std(g) / ex_rough:.2f} | "
                  f"{rep['seam_ratio']:.3f} | {secs:.1f} |")


if __name__ == "__main__":
    main()
