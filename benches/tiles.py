#!/usr/bin/env python3
"""What tiles cost and buy (docs/tiles.md): the rate-distortion loss of tiling against the
one-piece file (Kodak at 1 bpp, the corpus CT at 1 bit/voxel), and on a generated large
image: peak RSS and time of encode and decode, 1 thread against 2, per-sample speed
against a one-piece 512² crop, and a region decode's bytes and time.

Run from the repository root after `cargo build --release`:
    python3 benches/tiles.py [--kodak N] [--big 16384] [--skip-big]
Needs ../shared/corpus (or MRA_CORPUS) for the Kodak and CT rows, numpy for the big image.
"""
import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
import time

MRA = os.environ.get("MRA", "target/release/mra")
CORPUS = os.environ.get("MRA_CORPUS", "../shared/corpus")


def run(args, env=None):
    """Run mra under /usr/bin/time -v: (stdout, seconds, peak RSS in MiB)."""
    e = dict(os.environ)
    e.update(env or {})
    t = time.time()
    p = subprocess.run(["/usr/bin/time", "-v", MRA] + args, capture_output=True, text=True, env=e)
    dt = time.time() - t
    if p.returncode != 0:
        sys.exit(f"mra {' '.join(args)} failed:\n{p.stderr[-2000:]}")
    m = re.search(r"Maximum resident set size \(kbytes\): (\d+)", p.stderr)
    return p.stdout, dt, int(m.group(1)) / 1024 if m else float("nan")


def psnr(a, b, extra=()):
    out, _, _ = run(["compare", a, b, "--json", "--quiet", *extra])
    return json.loads(out)["psnr"]


def rd(src, tiles, rate, extra_cmp, tmp):
    """(bits per position, PSNR) of src coded at `rate` with each tile setting."""
    rows = {}
    for t in tiles:
        f = os.path.join(tmp, "t.mra")
        ext = ".nrrd" if src.endswith(".nrrd") else ".png"
        back = os.path.join(tmp, "back" + ext)
        out, _, _ = run(["encode", src, "-o", f, *rate, "--tile", t, "--json"])
        bpp = json.loads(out)["bits_per_position"]
        run(["decode", f, "-o", back])
        rows[t] = (bpp, psnr(src, back, extra_cmp))
    return rows


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--kodak", type=int, default=24, help="images of Kodak to use")
    ap.add_argument("--big", type=int, default=16384, help="side of the generated u16 image")
    ap.add_argument("--skip-big", action="store_true")
    a = ap.parse_args()
    tmp = tempfile.mkdtemp(prefix="mra-tiles-")
    kodak = os.path.join(CORPUS, "images/kodak")
    if os.path.isdir(kodak):
        tiles = ["whole", "512", "256"]
        acc = {t: [0.0, 0.0] for t in tiles}
        for i in range(1, a.kodak + 1):
            r = rd(os.path.join(kodak, f"kodim{i:02}.png"), tiles, ["--bpp", "1"], [], tmp)
            for t in tiles:
                acc[t][0] += r[t][0] / a.kodak
                acc[t][1] += r[t][1] / a.kodak
        print(f"## Kodak ({a.kodak} images), --bpp 1")
        print("| tile | bpp | PSNR dB | ΔPSNR dB |\n|---|---|---|---|")
        for t in tiles:
            print(f"| {t} | {acc[t][0]:.4f} | {acc[t][1]:.3f} | {acc[t][1] - acc['whole'][1]:+.3f} |")
    ct = os.path.join(CORPUS, "volumes/ct_pancreas_256.nrrd")
    if os.path.exists(ct):
        tiles = ["whole", "128", "64"]
        r = rd(ct, tiles, ["--bpp", "1"], ["--data-range", "2510"], tmp)
        print("## CT 256x256x134 i16, --bpp 1 (PSNR over 2510)")
        print("| tile | bits/voxel | PSNR dB | ΔPSNR dB |\n|---|---|---|---|")
        for t in tiles:
            print(f"| {t} | {r[t][0]:.4f} | {r[t][1]:.3f} | {r[t][1] - r['whole'][1]:+.3f} |")
    if a.skip_big:
        return
    import numpy as np

    n = a.big
    raw = os.path.join(tmp, "big.raw")
    y, x = np.mgrid[0:n:64, 0:n:64].astype(np.float32)
    coarse = 20000 + 12000 * np.sin(x / 900.0) * np.cos(y / 700.0)
    img = np.kron(coarse, np.ones((64, 64), np.float32))[:n, :n]
    rng = np.random.default_rng(1)
    with open(raw, "wb") as fh:
        for r0 in range(0, n, 1024):
            band = img[r0:r0 + 1024] + rng.normal(0, 300, (min(1024, n - r0), n)).astype(np.float32)
            fh.write(np.clip(band, 0, 65535).astype("<u2").tobytes())
    del img
    crop = os.path.join(tmp, "crop.raw")
    with open(raw, "rb") as fh, open(crop, "wb") as fc:
        for r0 in range(512):
            fh.seek(2 * r0 * n)
            fc.write(fh.read(2 * 512))
    big = os.path.join(tmp, "big.mra")
    rows = []
    for threads in ["1", "2"]:
        env = {"RAYON_NUM_THREADS": threads}
        _, te, me = run(["encode", raw, "--dims", f"{n}x{n}", "--dtype", "u16", "-o", big, "--quality", "60"], env)
        _, td, md = run(["decode", big, "-o", os.path.join(tmp, "big_back.raw")], env)
        rows.append((threads, te, me, td, md))
    one = os.path.join(tmp, "crop.mra")
    _, tce, _ = run(["encode", crop, "--dims", "512x512", "--dtype", "u16", "-o", one, "--quality", "60"])
    _, tcd, _ = run(["decode", one, "-o", os.path.join(tmp, "crop_back.raw")])
    info = json.loads(run(["info", big, "--json"])[0])
    reg = os.path.join(tmp, "region.raw")
    _, tr, mr = run(["decode", big, "-o", reg, "--region", "1024:1088,2048:2112"])
    tile_bytes = max(c["bytes"] for c in info["chunks"] if c["kind"] == "TILE")
    head = sum(c["bytes"] for c in info["chunks"] if c["kind"] in ("HEAD", "mETA", "TIDX"))
    print(f"## Generated {n}x{n} u16, --quality 60, tiles {info['tile']} ({info['tiles']} tiles), {info['file_bytes']} bytes")
    print("| threads | encode s | encode peak MiB | decode s | decode peak MiB |\n|---|---|---|---|---|")
    for t, te, me, td, md in rows:
        print(f"| {t} | {te:.2f} | {me:.0f} | {td:.2f} | {md:.0f} |")
    ms = 1e6 / (n * n)
    print(f"per Msample (2 threads): encode {rows[1][1] * ms:.3f} s, decode {rows[1][3] * ms:.3f} s;"
          f" one-piece 512² crop: encode {tce * 1e6 / 512**2:.3f} s, decode {tcd * 1e6 / 512**2:.3f} s (process start included)")
    print(f"thread scaling: encode {rows[0][1] / rows[1][1]:.2f}x, decode {rows[0][3] / rows[1][3]:.2f}x")
    print(f"--region 64x64: {tr:.3f} s ({100 * tr / rows[1][3]:.2f}% of the full decode), peak {mr:.0f} MiB,"
          f" at most {head + tile_bytes} bytes read ({100 * (head + tile_bytes) / info['file_bytes']:.3f}% of the file)")


if __name__ == "__main__":
    main()
