#!/usr/bin/env python3
"""Quality and speed of `mra terrain synth` on real DEMs against a plain cubic upscale.

Cases (shared corpus; every base is a 512x512 truth region smoothed (Gaussian sigma 1 cell) and
block-averaged by 4 to 128x128, so the output of `--levels 2` has the truth's 92 m cells):
  White Mts       truth N44W072 rows/cols 600-1112, example N44W072 rows/cols 60-572
  White Mts swap  the two regions swapped
  Kauai <- NH     truth N22W160 (Kaua'i and its coast, voids filled) rows 689-1201 cols 250-762,
                  example N44W072 rows/cols 60-572
  NH <- Boulder   truth as White Mts, example srtmgl3_boulder_co.asc (240x144, ~80 m cells)
  NH <- Helens    truth as White Mts, example mt_st_helens_30m_f32.tif (317x460, 30 m cells),
                  `--example-cell 30 --any-units` beside a base of 370 m cells
Metrics, each on the whole field, result against the example at the output's cell (Helens
resampled from 30 m to 92.6 m cells):
  W1 ratio    Wasserstein-1 distance of the slope-magnitude histograms (m/m, the cell in metres)
              to the example's, divided by the same for the cubic upscale; target <= 0.5
  rough       std of the 5-point Laplacian per cell^2 (m/m^2), ratio to the example's; 0.8-1.25
  beta        radially averaged power-spectrum slope, finest octave (k in [N/4, N/2]);
              target within 0.2 of the example's
  fidelity    PSNR (peak = base range) of the result's 4x4 block means against the base;
              target >= 40 dB
  seam        mra's seam ratio (second differences on patch borders / elsewhere); <= 1.05
Speed: a 1024x1024 result (--levels 3) from the first case's 128x128 base, wall time and peak
memory (ru_maxrss of the child) of one run; targets <= 1 s and <= 10x the output's f32 bytes.
Run from the repository root:  cargo build --release && python3 benches/terrain_quality.py [--seed N]
Options after `--` go to every `mra terrain synth`.
"""
import json, os, subprocess, sys, tempfile, time
import numpy as np
import tifffile
from scipy import ndimage
from scipy.stats import wasserstein_distance

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CORPUS = os.environ.get("MRA_CORPUS", os.path.join(ROOT, "..", "shared", "corpus"))
MRA = os.path.join(ROOT, "target", "release", "mra")
EXTRA = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []  # more mra options
SEED = int(sys.argv[sys.argv.index("--seed") + 1]) if "--seed" in sys.argv else 1
CELL = 92.6  # SRTM3 cell N-S, metres; the bases' output cell


def hgt(name):
    a = np.fromfile(os.path.join(CORPUS, "terrain", name), ">i2").reshape(1201, 1201).astype(np.float64)
    bad = a < -1000
    if bad.any():  # fill voids from the nearest valid sample (only for making a test base)
        idx = ndimage.distance_transform_edt(bad, return_distances=False, return_indices=True)
        a = a[tuple(idx)]
    return a


def asc(name):
    with open(os.path.join(CORPUS, "terrain", name)) as f:
        hdr = [next(f) for _ in range(6)]
    return np.loadtxt(os.path.join(CORPUS, "terrain", name), skiprows=6)


def cases():
    nh, ka = hgt("N44W072.hgt"), hgt("N22W160.hgt")
    a, b = nh[600:1112, 600:1112], nh[60:572, 60:572]
    boulder = os.path.join(CORPUS, "terrain", "srtmgl3_boulder_co.asc")
    helens = os.path.join(CORPUS, "terrain", "mt_st_helens_30m_f32.tif")
    yield "White Mts", a, b, None, CELL, []
    yield "White Mts swap", b, a, None, CELL, []
    yield "Kauai <- NH", ka[689:1201, 250:762], b, None, CELL, []
    # the bases have no spacing: --example-cell is in base cells (4 x 92.6 m)
    yield "NH <- Boulder", a, asc("srtmgl3_boulder_co.asc"), boulder, CELL, ["--example-cell", "0.25"]
    yield "NH <- Helens", a, tifffile.imread(helens).astype(np.float64), helens, 30.0, \
        ["--example-cell", str(30.0 / (4 * CELL))]


def slope(g, cell):
    gy, gx = np.gradient(g, cell)
    return np.hypot(gx, gy).ravel()


def lap_std(g, cell):
    l = g[:-2, 1:-1] + g[2:, 1:-1] + g[1:-1, :-2] + g[1:-1, 2:] - 4 * g[1:-1, 1:-1]
    return l.std() / cell ** 2


def spectrum_slope(g):
    n = min(g.shape)
    g = g[:n, :n]
    f = np.abs(np.fft.fftshift(np.fft.fft2((g - g.mean()) * np.outer(np.hanning(n), np.hanning(n))))) ** 2
    y, x = np.indices(f.shape) - n // 2
    r = np.hypot(x, y).astype(int)
    p = np.bincount(r.ravel(), f.ravel()) / np.bincount(r.ravel())
    k = np.arange(len(p))
    sel = (k >= n // 4) & (k <= n // 2)
    return np.polyfit(np.log(k[sel]), np.log(p[sel]), 1)[0]


def block_psnr(g, base):
    n, m = base.shape[0], g.shape[0] // base.shape[0]
    red = g.reshape(n, m, n, m).mean(axis=(1, 3))
    return 10 * np.log10((base.max() - base.min()) ** 2 / np.mean((red - base) ** 2))


def cubic(base, m):
    return ndimage.zoom(base, m, order=3, mode="nearest", grid_mode=True)


def run(args):
    """One `mra terrain synth`: its --json report, wall seconds, CPU seconds and peak RSS (KiB, by
    /usr/bin/time: the rusage of a child forked from Python counts the Python image too)."""
    t0 = time.perf_counter()
    p = subprocess.Popen(["/usr/bin/time", "-f", "%M %U %S", MRA, "terrain", "synth"] + args + EXTRA, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         text=True)
    out, err = p.communicate()
    wall = time.perf_counter() - t0
    if p.returncode != 0:
        raise SystemExit(f"mra terrain synth failed ({p.returncode}): {err}")
    rss, user, system = err.strip().splitlines()[-1].split()
    return json.loads(out), wall, float(user) + float(system), int(rss)


def highpass(path, tmp, levels=2):
    """The finest `levels` levels of the file's MRA (F - P^L A^L F, chaikin), by mra itself."""
    hp = os.path.join(tmp, "hp.tif")
    subprocess.run([MRA, "terrain", "highpass", path, "-o", hp, "--levels", str(levels)], check=True,
                   capture_output=True)
    return tifffile.imread(hp).astype(np.float64)


def main():
    rows, speed = [], None
    with tempfile.TemporaryDirectory() as tmp:
        bp, ep, op = (os.path.join(tmp, n) for n in ("base.tif", "ex.tif", "out.tif"))
        for name, truth, example, epath, ecell, eargs in cases():
            base = ndimage.gaussian_filter(truth, 1.0).reshape(128, 4, 128, 4).mean(axis=(1, 3))
            tifffile.imwrite(bp, base.astype(np.float32))
            if epath is None:
                tifffile.imwrite(ep, example.astype(np.float32))
                epath = ep
            rep, _, _, _ = run(["--base", bp, "--example", epath, "-o", op, "--levels", "2", "--seed", str(SEED),
                             "--json", "--any-units"] + eargs)
            g = tifffile.imread(op).astype(np.float64)
            if ecell != CELL:  # the example at the output's cell (what the result should look like)
                example = ndimage.zoom(ndimage.uniform_filter(example, int(CELL / ecell)), ecell / CELL,
                                       order=3, grid_mode=True, mode="nearest")
            ref = {"beta": spectrum_slope(example), "rough": lap_std(example, CELL)}
            es = slope(example, CELL)
            xp = os.path.join(tmp, "exc.tif")
            tifffile.imwrite(xp, example.astype(np.float32))
            ehp = slope(highpass(xp, tmp), CELL)
            cub = cubic(base, 4)
            w_cub = wasserstein_distance(slope(cub, CELL), es)
            for method, h, seam in [("truth", truth, float("nan")), ("cubic", cub, float("nan")),
                                    ("synth", g, rep["seam_ratio"])]:
                w = wasserstein_distance(slope(h, CELL), es)
                hp = os.path.join(tmp, "h.tif")
                tifffile.imwrite(hp, h.astype(np.float32))
                whp = wasserstein_distance(slope(highpass(hp, tmp), CELL), ehp)
                o = {"case": name, "method": method, "W1": w, "W1 ratio": w / w_cub, "W1 fine": whp,
                     "rough": lap_std(h, CELL) / ref["rough"], "beta": spectrum_slope(h), "beta ex": ref["beta"],
                     "fid": block_psnr(h, base), "seam": seam}
                rows.append(o)
                print(json.dumps(o), file=sys.stderr)
            if speed is None:
                rep, t, cpu, rss = run(["--base", bp, "--example", epath, "-o", op, "--levels", "3", "--seed",
                                        str(SEED), "--json", "--any-units"] + eargs)
                speed = (t, cpu, rss * 1024 / (rep["dims"][0] * rep["dims"][1] * 4), rep["dims"])
    print("| case | result | W1 slope (× cubic's) | W1 slope, finest 2 levels | roughness / example | "
          "spectral slope (example) | fidelity, 4×4 block means (dB) | seam ratio | targets met |")
    print("|---|---|---|---|---|---|---|---|---|")
    for o in rows:
        ok = ""
        if o["method"] == "synth":
            t = [o["W1 ratio"] <= 0.5, 0.8 <= o["rough"] <= 1.25, abs(o["beta"] - o["beta ex"]) <= 0.2,
                 o["fid"] >= 40, o["seam"] <= 1.05]
            ok = f"{sum(t)}/5 " + "".join("✓" if v else "✗" for v in t)
        seam = "–" if o["seam"] != o["seam"] else f"{o['seam']:.3f}"
        print(f"| {o['case']} | {o['method']} | {o['W1']:.3f} ({o['W1 ratio']:.2f}×) | {o['W1 fine']:.3f} | "
              f"{o['rough']:.2f} | "
              f"{o['beta']:.2f} ({o['beta ex']:.2f}) | {o['fid']:.1f} | {seam} | {ok} |")
    t, cpu, mem, dims = speed
    print(f"\nSpeed: {dims[1]}x{dims[0]} from 128x128 (--levels 3): {t:.2f} s wall, {cpu:.2f} s CPU (process "
          f"start and TIFF I/O included), peak memory {mem:.1f}x the output's f32 bytes.")


if __name__ == "__main__":
    main()
