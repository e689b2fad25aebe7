#!/usr/bin/env python3
"""Quality of `mra terrain synth` on real DEMs, next to two naive baselines.

For each DEM a 512x512 region A is cut (the "truth") and a different 512x512 region B is
the example. The base is A smoothed (Gaussian, sigma 1 cell) and block-averaged by 4
(128x128). `mra terrain synth --levels 2` refines it back to 512x512 three ways:
  matched  - the method (details from patches matched by coarse neighbourhood),
  copy     - the example's details copied at the same positions (no matching),
  none     - subdivision alone (no details).
Metrics (result vs example B unless noted):
  fidelity  PSNR (peak = base range) of the result reduced to the base resolution
            against the base; target >= 40 dB. Two reductions: "MRA" = A^L then the
            corner-aligned resampling (mra's own, reported in --json), "gauss" = an
            independent one (Gaussian sigma 2, linear sampling at the base's positions),
  W1 slope  Wasserstein-1 distance of slope-magnitude histograms (gradient per cell),
  rough     std of the 5-point Laplacian, as a ratio to the example's,
  beta      radially averaged power-spectrum slope over the finest octave
            (k in [N/4, N/2]), next to the example's,
  seam      mean |second difference| across the finest patch borders / elsewhere (1 = no seams).
Run from the repository root:  cargo build --release && python3 benches/terrain_quality.py [--seed N]
"""
import json, os, subprocess, sys, tempfile
import numpy as np
import tifffile
from scipy import ndimage
from scipy.stats import wasserstein_distance

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CORPUS = os.environ.get("MRA_CORPUS", os.path.join(ROOT, "..", "shared", "corpus"))
MRA = os.path.join(ROOT, "target", "release", "mra")
EXTRA = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []  # more mra options
SEED = int(sys.argv[sys.argv.index("--seed") + 1]) if "--seed" in sys.argv else 1


def hgt(name):
    return np.fromfile(os.path.join(CORPUS, "terrain", name), ">i2").reshape(1201, 1201).astype(np.float64)


def cases():
    a = hgt("N44W072.hgt")
    yield "N44W072 (White Mts)", a[600:1112, 600:1112], a[60:572, 60:572]
    yield "N44W072 swapped", a[60:572, 60:572], a[600:1112, 600:1112]
    yield "N44W072 (NE vs SW)", a[40:552, 640:1152], a[640:1152, 40:552]


def slope(g):
    gy, gx = np.gradient(g)
    return np.hypot(gx, gy).ravel()


def lap_std(g):
    l = g[:-2, 1:-1] + g[2:, 1:-1] + g[1:-1, :-2] + g[1:-1, 2:] - 4 * g[1:-1, 1:-1]
    return l.std()


def spectrum_slope(g):
    n = g.shape[0]
    f = np.abs(np.fft.fftshift(np.fft.fft2((g - g.mean()) * np.outer(np.hanning(n), np.hanning(n))))) ** 2
    y, x = np.indices(f.shape) - n // 2
    r = np.hypot(x, y).astype(int)
    p = np.bincount(r.ravel(), f.ravel()) / np.bincount(r.ravel())
    k = np.arange(len(p))
    sel = (k >= n // 4) & (k <= n // 2)
    return np.polyfit(np.log(k[sel]), np.log(p[sel]), 1)[0]


def reduce_to(g, n):
    m = g.shape[0]
    s = ndimage.gaussian_filter(g, 2.0)
    u = np.arange(n) * (m - 1) / (n - 1)
    yy, xx = np.meshgrid(u, u, indexing="ij")
    return ndimage.map_coordinates(s, [yy, xx], order=1)


def highpass(path, tmp, levels=2):
    """The finest `levels` levels of the file's MRA (F - P^L A^L F, chaikin), by mra itself."""
    hp = os.path.join(tmp, "hp.tif")
    subprocess.run([MRA, "terrain", "highpass", path, "-o", hp, "--levels", str(levels)], check=True,
                   capture_output=True)
    return tifffile.imread(hp).astype(np.float64)


def realism(g, ghp, example, ehp):
    """Full-field W1 (as before) and the three realism figures on the finest levels."""
    return {"W1 full": wasserstein_distance(slope(g), slope(example)),
            "W1 slope": wasserstein_distance(slope(ghp), slope(ehp)),
            "rough": lap_std(ghp) / lap_std(ehp), "beta": spectrum_slope(ghp)}


def main():
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for name, truth, example in cases():
            base = ndimage.gaussian_filter(truth, 1.0).reshape(128, 4, 128, 4).mean(axis=(1, 3))
            bp, ep = os.path.join(tmp, "base.tif"), os.path.join(tmp, "ex.tif")
            tifffile.imwrite(bp, base.astype(np.float32))
            tifffile.imwrite(ep, example.astype(np.float32))
            ehp = highpass(ep, tmp)
            tp = os.path.join(tmp, "truth.tif")
            tifffile.imwrite(tp, truth.astype(np.float32))
            ref = {"beta": spectrum_slope(ehp)}
            tr = {"method": "truth (region A)", "fidelity": float("nan"), "fidelity MRA": float("nan"),
                  "seam": float("nan")}
            tr.update(realism(truth, highpass(tp, tmp), example, ehp))
            out = [tr]
            for det in ["matched", "copy", "none"]:
                op = os.path.join(tmp, det + ".tif")
                r = subprocess.run([MRA, "terrain", "synth", "--base", bp, "--example", ep, "-o", op,
                                    "--levels", "2", "--seed", str(SEED), "--details", det, "--json"] + EXTRA,
                                   check=True, capture_output=True, text=True)
                rep = json.loads(r.stdout)
                g = tifffile.imread(op).astype(np.float64)
                red = reduce_to(g, 128)
                fid = 10 * np.log10((base.max() - base.min()) ** 2 / np.mean((red - base) ** 2))
                o = {"method": det, "fidelity": fid, "fidelity MRA": rep["fidelity_psnr"],
                     "seam": rep["seam_ratio"]}
                o.update(realism(g, highpass(op, tmp), example, ehp))
                out.append(o)
            for o in out:
                o["case"] = name
                o["beta example"] = ref["beta"]
                rows.append(o)
                print(json.dumps(o), file=sys.stderr)
    print("| case | details | fidelity PSNR dB (MRA / gauss) | W1 slope, finest levels (full field) | "
          "roughness / example | spectrum slope (example) | seam ratio | beats none & copy |")
    print("|---|---|---|---|---|---|---|---|")
    for o in rows:
        win = ""
        if o["method"] == "matched":
            base = [r for r in rows if r["case"] == o["case"] and r["method"] in ("copy", "none")]
            err = lambda r: (r["W1 slope"], abs(r["rough"] - 1), abs(r["beta"] - r["beta example"]))
            win = " / ".join("yes" if all(err(o)[i] < err(b)[i] for b in base) else "no" for i in range(3))
        print(f"| {o['case']} | {o['method']} | {o['fidelity MRA']:.1f} / {o['fidelity']:.1f} | "
              f"{o['W1 slope']:.2f} ({o['W1 full']:.2f}) | {o['rough']:.2f} | "
              f"{o['beta']:.2f} ({o['beta example']:.2f}) | {o['seam']:.3f} | {win} |")


if __name__ == "__main__":
    main()
