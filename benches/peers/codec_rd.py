#!/usr/bin/env python3
"""Rate-distortion of `mra encode` on photographs against OpenJPEG, WebP, JPEG XL and AVIF.

Mean RGB PSNR (peak 255, MSE over all samples of an image, then the mean over images) at
0.25 / 0.5 / 1 / 2 bpp on the Kodak images, and the Bjontegaard delta PSNR over that
range against OpenJPEG (9/7, `opj_compress -r`, the rate control JPEG 2000 users run).
Every peer gets the largest file within the budget: OpenJPEG by its own rate control,
WebP (method 6), JPEG XL (effort 7) and AVIF (speed 6) by bisection on their quality
(where even the lowest quality is over the budget, that file counts at its own rate).

Needs: `apt-get install libopenjp2-tools`, `pip install imagecodecs pillow numpy`.
Usage (from the repository root, after `cargo build --release`):
  python3 benches/peers/codec_rd.py [--corpus ../shared/corpus] [--images 24]
      [--codecs mra,openjpeg,webp,jpegxl,avif] [--json out.json] [--plot out.png] [--mra BIN]
      [-- extra mra encode arguments]
"""
import argparse, json, os, shutil, subprocess, sys, tempfile
from concurrent.futures import ProcessPoolExecutor
import numpy as np
from PIL import Image, ImageDraw

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
MRA = os.path.join(ROOT, "target", "release", "mra")
RATES = [0.25, 0.5, 1.0, 2.0]


def psnr(a, b):
    mse = np.mean((a.astype(np.float64) - b.astype(np.float64)) ** 2)
    return float("inf") if mse == 0 else 10 * np.log10(255.0 ** 2 / mse)


def bisect(encode, decode, bpp, npix, lo, hi, integer=True, rounds=8):
    """Best quality q in [lo, hi] (larger = bigger file) whose file fits the budget; the
    smallest file (over the budget, counted at its own rate) when none fits."""
    best = None
    floor = encode(lo)
    for _ in range(rounds if not integer else 64):
        if (integer and lo > hi) or (not integer and hi - lo < 1e-3):
            break
        q = (lo + hi) // 2 if integer else (lo + hi) / 2
        data = encode(q)
        if len(data) * 8 / npix <= bpp:
            best = data
            lo = q + 1 if integer else q
        else:
            hi = q - 1 if integer else q
    if best is None:
        best = floor
    return len(best), decode(best)


def run_mra(path, ref, bpp, extra, tmp):
    enc, out = os.path.join(tmp, "a.mra"), os.path.join(tmp, "a.png")
    subprocess.run([MRA, "encode", path, "-o", enc, "--bpp", str(bpp)] + extra, check=True, stdout=subprocess.DEVNULL)
    subprocess.run([MRA, "decode", enc, "-o", out], check=True, stdout=subprocess.DEVNULL)
    return os.path.getsize(enc), np.asarray(Image.open(out).convert("RGB"))


def run_openjpeg(path, ref, bpp, extra, tmp):
    src, j2k, out = (os.path.join(tmp, n) for n in ("s.ppm", "s.j2k", "o.ppm"))
    Image.fromarray(ref).save(src)
    subprocess.run(["opj_compress", "-i", src, "-o", j2k, "-r", str(24.0 / bpp), "-I"], check=True, stdout=subprocess.DEVNULL)
    subprocess.run(["opj_decompress", "-i", j2k, "-o", out], check=True, stdout=subprocess.DEVNULL)
    return os.path.getsize(j2k), np.asarray(Image.open(out))


def run_webp(path, ref, bpp, extra, tmp):
    import imagecodecs as ic
    npix = ref.shape[0] * ref.shape[1]
    return bisect(lambda q: ic.webp_encode(ref, level=q, method=6, lossless=False), ic.webp_decode, bpp, npix, 0, 100)


def run_jpegxl(path, ref, bpp, extra, tmp):
    import imagecodecs as ic
    npix = ref.shape[0] * ref.shape[1]
    # distance 25 (smallest) .. 0.05; bisect on -distance so that larger = bigger file
    r = bisect(lambda q: ic.jpegxl_encode(ref, effort=7, distance=-q), ic.jpegxl_decode, bpp, npix, -25.0, -0.05, integer=False, rounds=14)
    return r


def run_avif(path, ref, bpp, extra, tmp):
    import imagecodecs as ic
    npix = ref.shape[0] * ref.shape[1]
    return bisect(lambda q: ic.avif_encode(ref, level=q, speed=6), ic.avif_decode, bpp, npix, 0, 100)


RUNNERS = {"mra": run_mra, "openjpeg": run_openjpeg, "webp": run_webp, "jpegxl": run_jpegxl, "avif": run_avif}


def one_image(args):
    path, codecs, extra, mra = args
    global MRA
    MRA = mra
    ref = np.asarray(Image.open(path).convert("RGB"))
    npix = ref.shape[0] * ref.shape[1]
    rows = {}
    with tempfile.TemporaryDirectory() as tmp:
        for c in codecs:
            for b in RATES:
                r = RUNNERS[c](path, ref, b, extra, tmp)
                if r is not None:
                    size, dec = r
                    rows[f"{c}@{b}"] = (size * 8 / npix, psnr(ref, dec[..., :3]))
    return rows


def bd_psnr(r1, p1, r2, p2):
    """Bjontegaard delta PSNR of curve 2 over curve 1 (cubic in log10 rate)."""
    l1, l2 = np.log10(r1), np.log10(r2)
    f1, f2 = np.polyfit(l1, p1, 3), np.polyfit(l2, p2, 3)
    lo, hi = max(l1.min(), l2.min()), min(l1.max(), l2.max())
    i1 = np.polyval(np.polyint(f1), hi) - np.polyval(np.polyint(f1), lo)
    i2 = np.polyval(np.polyint(f2), hi) - np.polyval(np.polyint(f2), lo)
    return (i2 - i1) / (hi - lo)


def plot(curves, path):
    """PSNR against bpp, log rate axis, drawn with Pillow."""
    w, h, m = 720, 480, 60
    img = Image.new("RGB", (w, h), "white")
    d = ImageDraw.Draw(img)
    pts = [p for c in curves.values() for p in c if np.isfinite(p[1])]
    lo_r, hi_r = np.log2(min(p[0] for p in pts)), np.log2(max(p[0] for p in pts))
    lo_p, hi_p = np.floor(min(p[1] for p in pts)), np.ceil(max(p[1] for p in pts))
    X = lambda r: m + (np.log2(r) - lo_r) / (hi_r - lo_r) * (w - 2 * m)
    Y = lambda p: h - m - (p - lo_p) / (hi_p - lo_p) * (h - 2 * m)
    d.rectangle([m, m, w - m, h - m], outline="black")
    for b in RATES:
        d.text((X(b) - 10, h - m + 8), f"{b}", fill="black")
    for p in range(int(lo_p), int(hi_p) + 1, 2):
        d.text((m - 30, Y(p) - 6), f"{p}", fill="black")
    d.text((w // 2 - 60, h - 25), "bits per pixel (log)", fill="black")
    d.text((8, m - 30), "mean RGB PSNR (dB), Kodak", fill="black")
    colours = ["#d62728", "#1f77b4", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b"]
    for k, (name, c) in enumerate(curves.items()):
        col = colours[k % len(colours)]
        xy = [(X(r), Y(p)) for r, p in c]
        d.line(xy, fill=col, width=3 if name == "mra" else 2)
        for x, y in xy:
            d.ellipse([x - 3, y - 3, x + 3, y + 3], fill=col)
        d.text((m + 10, m + 10 + 16 * k), name, fill=col)
    img.save(path)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--corpus", default=os.path.join(ROOT, "..", "shared", "corpus"))
    ap.add_argument("--images", type=int, default=24)
    ap.add_argument("--codecs", default="mra,openjpeg,webp,jpegxl,avif")
    ap.add_argument("--json")
    ap.add_argument("--plot")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--mra", default=None, help="the mra binary (default: target/release/mra)")
    ap.add_argument("extra", nargs="*", help="extra mra encode arguments (after --)")
    a = ap.parse_args()
    codecs = a.codecs.split(",")
    a.mra = a.mra or MRA
    if "openjpeg" in codecs and not shutil.which("opj_compress"):
        sys.exit("opj_compress not found: apt-get install libopenjp2-tools")
    kodak = os.path.join(a.corpus, "images", "kodak")
    files = sorted(os.path.join(kodak, f) for f in os.listdir(kodak) if f.endswith(".png"))[: a.images]
    with ProcessPoolExecutor(a.jobs) as ex:
        per = list(ex.map(one_image, [(f, codecs, a.extra, a.mra) for f in files]))
    curves = {}
    for c in codecs:
        pts = []
        for b in RATES:
            v = [p[f"{c}@{b}"] for p in per if f"{c}@{b}" in p]
            if len(v) == len(per):
                pts.append(tuple(np.mean(np.array(v), axis=0)))
        if len(pts) == len(RATES):
            curves[c] = pts
    ref = curves.get("openjpeg")
    print(f"Kodak, {len(files)} images: mean bpp / mean RGB PSNR (dB); BD-PSNR over 0.25-2 bpp vs OpenJPEG\n")
    print("| codec | " + " | ".join(f"{b} bpp" for b in RATES) + " | BD-PSNR vs OpenJPEG |")
    print("|---|" + "---|" * (len(RATES) + 1))
    out = {}
    for c, pts in curves.items():
        bd = bd_psnr(*np.array(ref).T, *np.array(pts).T) if ref else float("nan")
        out[c] = {"points": pts, "bd_psnr_vs_openjpeg": bd}
        cells = " | ".join(f"{r:.3f} / {p:.2f}" for r, p in pts)
        print(f"| {c} | {cells} | {bd:+.2f} dB |")
    if a.json:
        json.dump(out, open(a.json, "w"), indent=1)
    if a.plot:
        plot(curves, a.plot)


if __name__ == "__main__":
    main()
