#!/usr/bin/env python3
"""PSNR of `mra denoise` next to scikit-image `denoise_wavelet` (BayesShrink, soft).

Inputs (from ../shared/corpus, path overridable with MRA_CORPUS): three Kodak images as
8-bit gray (ITU-R 601 luma) and a CT crop (ct_pancreas_256.nrrd, 64 slices, HU window
[-1000, 1000] mapped to [0, 255]). Gaussian noise of sigma = 5, 10, 20 on that 8-bit
scale is added (seeded), the noisy data are written as float32 TIFF (no rounding or
clipping, so both tools see the same samples), and both denoisers estimate sigma
themselves. scikit-image gets the data divided by 255 (its float range) with its
defaults (wavelet db1, levels = max - 3, rescale_sigma=True) and, second, wavelet sym4
(a stronger peer). PSNR uses peak 255. mra runs with its defaults (cycle spinning over 2 shifts per axis;
levels 4 for haar, chosen by SURE for chaikin/cubic), and haar once more with
--shifts 1 (one decimated transform, the like of scikit-image's). Run from the repository root:

    cargo build --release && python3 benches/peers/denoise_skimage.py [--json out.json]
"""
import json, os, subprocess, sys, tempfile, time
import numpy as np
import tifffile
import imageio.v3 as iio
from skimage.restoration import denoise_wavelet

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CORPUS = os.environ.get("MRA_CORPUS", os.path.join(ROOT, "..", "shared", "corpus"))
MRA = os.path.join(ROOT, "target", "release", "mra")


def psnr(a, b):
    return 10 * np.log10(255.0 ** 2 / np.mean((a - b) ** 2))


def images():
    for name in ["kodim01", "kodim13", "kodim23"]:
        rgb = iio.imread(os.path.join(CORPUS, "images", "kodak", name + ".png")).astype(np.float64)
        yield name, rgb @ np.array([0.299, 0.587, 0.114])


def ct():
    path = os.path.join(CORPUS, "volumes", "ct_pancreas_256_stack.tif")
    v = tifffile.imread(path).astype(np.float64) - 1000.0  # HU, (z, y, x)
    z0 = v.shape[0] // 2 - 32
    v = v[z0:z0 + 64]
    return "ct_pancreas 64x256x256", np.clip((v + 1000.0) / 2000.0, 0, 1) * 255.0


def run_mra(noisy, tmp, args):
    src, dst = os.path.join(tmp, "noisy.tif"), os.path.join(tmp, "out.tif")
    tifffile.imwrite(src, noisy.astype(np.float32))
    t = time.perf_counter()
    subprocess.run([MRA, "denoise", src, "-o", dst] + args, check=True, capture_output=True)
    return tifffile.imread(dst).astype(np.float64), time.perf_counter() - t


def main():
    rows = []
    rng = np.random.default_rng(2026)
    data = list(images()) + [ct()]
    configs = [
        ("mra haar 1 shift", ["--scheme", "haar", "--shifts", "1"]),
        ("mra haar", ["--scheme", "haar"]),
        ("mra chaikin", ["--scheme", "chaikin"]),
        ("mra cubic", ["--scheme", "cubic"]),
    ]
    with tempfile.TemporaryDirectory() as tmp:
        for name, clean in data:
            for sigma in [5, 10, 20]:
                noisy = clean + sigma * rng.standard_normal(clean.shape)
                row = {"data": name, "sigma": sigma, "noisy": psnr(noisy, clean)}
                for label, args in configs:
                    out, secs = run_mra(noisy, tmp, args)
                    row[label] = psnr(out, clean)
                    row[label + " s"] = secs
                for wav in ["db1", "sym4"]:
                    t = time.perf_counter()
                    sk = denoise_wavelet(noisy / 255.0, method="BayesShrink", mode="soft",
                                         wavelet=wav, rescale_sigma=True) * 255.0
                    row["skimage " + wav] = psnr(sk, clean)
                    row["skimage " + wav + " s"] = time.perf_counter() - t
                rows.append(row)
                print(json.dumps(row), file=sys.stderr)
    cols = ["noisy", "mra haar 1 shift", "mra haar", "mra chaikin", "mra cubic", "skimage db1", "skimage sym4"]
    print("| data | σ | " + " | ".join(cols) + " | mra haar − sym4 |")
    print("|---|---|" + "---|" * (len(cols) + 1))
    for r in rows:
        print(f"| {r['data']} | {r['sigma']} | " + " | ".join(f"{r[c]:.2f}" for c in cols)
              + f" | {r['mra haar'] - r['skimage sym4']:+.2f} |")
    tcols = [c + " s" for c in cols[1:]]
    print()
    print("| data | " + " | ".join(c[:-2] + " (s)" for c in tcols) + " |")
    print("|---|" + "---|" * len(tcols))
    for r in rows:
        if r["sigma"] == 10:
            print(f"| {r['data']} | " + " | ".join(f"{r[c]:.2f}" for c in tcols) + " |")
    if "--json" in sys.argv:
        with open(sys.argv[sys.argv.index("--json") + 1], "w") as f:
            json.dump(rows, f, indent=1)


if __name__ == "__main__":
    main()
