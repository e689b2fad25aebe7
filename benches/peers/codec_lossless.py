#!/usr/bin/env python3
"""Lossless bits per pixel of `mra encode --lossless` against OpenJPEG (reversible 5/3,
`opj_compress` defaults), WebP lossless (method 6) and PNG (Pillow, optimize), on the
Kodak images and the 16-bit gray images of the corpus. Every file is decoded and checked
bit-exact.

Needs: `apt-get install libopenjp2-tools`, `pip install imagecodecs pillow numpy`.
Usage (from the repository root, after `cargo build --release`):
  python3 benches/peers/codec_lossless.py [--corpus ../shared/corpus] [--images 24] [--mra BIN]
      [--sets kodak,gray16] [--per-image]
"""
import argparse, io, os, subprocess, sys, tempfile
import numpy as np
from PIL import Image

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def bits(path, mra, tmp):
    ref = np.asarray(Image.open(path))
    npix = ref.shape[0] * ref.shape[1]
    out = {}
    enc, dec = os.path.join(tmp, "a.mra"), os.path.join(tmp, "a.png")
    subprocess.run([mra, "encode", path, "-o", enc, "--lossless"], check=True, stdout=subprocess.DEVNULL)
    subprocess.run([mra, "decode", enc, "-o", dec], check=True, stdout=subprocess.DEVNULL)
    assert np.array_equal(np.asarray(Image.open(dec)), ref), f"mra not exact on {path}"
    out["mra"] = os.path.getsize(enc) * 8 / npix
    src = os.path.join(tmp, "s.png" if ref.dtype != np.uint8 else "s.ppm")
    Image.open(path).save(src) if ref.dtype != np.uint8 else Image.fromarray(ref).save(src)
    j2k, back = os.path.join(tmp, "s.j2k"), os.path.join(tmp, "b.png")
    subprocess.run(["opj_compress", "-i", src, "-o", j2k], check=True, stdout=subprocess.DEVNULL)
    subprocess.run(["opj_decompress", "-i", j2k, "-o", back], check=True, stdout=subprocess.DEVNULL)
    assert np.array_equal(np.asarray(Image.open(back)).astype(ref.dtype), ref), f"openjpeg not exact on {path}"
    out["openjpeg"] = os.path.getsize(j2k) * 8 / npix
    buf = io.BytesIO()
    Image.open(path).save(buf, "PNG", optimize=True)
    out["png"] = buf.tell() * 8 / npix
    if ref.dtype == np.uint8:
        import imagecodecs as ic
        w = ic.webp_encode(ref, lossless=True, method=6, level=100)
        assert np.array_equal(ic.webp_decode(w), ref)
        out["webp"] = len(w) * 8 / npix
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--corpus", default=os.path.join(ROOT, "..", "shared", "corpus"))
    ap.add_argument("--images", type=int, default=24)
    ap.add_argument("--mra", default=os.path.join(ROOT, "target", "release", "mra"))
    ap.add_argument("--sets", default="kodak,gray16", help="comma-separated: kodak, gray16")
    ap.add_argument("--per-image", action="store_true", help="a row per image as well")
    a = ap.parse_args()
    wanted = set(a.sets.split(","))
    kodak = os.path.join(a.corpus, "images", "kodak")
    sets = {
        "kodak": sorted(os.path.join(kodak, f) for f in os.listdir(kodak) if f.endswith(".png"))[: a.images],
        "gray16": sorted(
            os.path.join(a.corpus, "images", "highbit", f)
            for f in os.listdir(os.path.join(a.corpus, "images", "highbit"))
            if f.endswith(".png") and np.asarray(Image.open(os.path.join(a.corpus, "images", "highbit", f))).ndim == 2
        ),
    }
    names = {"kodak": "Kodak (RGB u8)", "gray16": "16-bit gray"}
    keys = ("mra", "openjpeg", "webp", "png")
    cell = lambda v: "—" if np.isnan(v) else f"{v:.3f}"
    print("| set | images | mra | OpenJPEG 5/3 | WebP lossless | PNG |\n|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for key, files in sets.items():
            if key not in wanted:
                continue
            rows = [bits(f, a.mra, tmp) for f in files]
            if a.per_image:
                for f, r in zip(files, rows):
                    cells = " | ".join(cell(r.get(k, float("nan"))) for k in keys)
                    print(f"| {os.path.basename(f)} | 1 | {cells} |")
            mean = lambda k: np.mean([r[k] for r in rows]) if all(k in r for r in rows) else float("nan")
            cells = " | ".join(cell(mean(k)) for k in keys)
            print(f"| {names[key]} | {len(files)} | {cells} |")
    print("\n(bits per pixel, mean over the images; every file decoded bit-exact)")


if __name__ == "__main__":
    main()
