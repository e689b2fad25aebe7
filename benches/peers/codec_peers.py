#!/usr/bin/env python3
"""Rate-distortion of `mra encode` against peers, timed in the same run.

  images : Kodak at 0.25/0.5/1/2 bpp vs JPEG and WebP (Pillow, quality bisected to the
           largest file within the budget) and JPEG 2000 (OpenJPEG `opj_compress -r`,
           if installed: apt-get install libopenjp2-tools)
  volumes: CT at 1/2/4 bits/voxel vs ZFP fixed rate (`pip install zfpy`, if available)
  keep   : the notes' Figure 9.19 protocol -- PSNR after keeping 1/2/5/10/20% of the
           details, no quantization -- for mra's haar/chaikin/cubic (examples/keep_psnr)
           next to PyWavelets haar, db2, bior4.4 (`pip install PyWavelets`)

Usage (from the repository root, after `cargo build --release --examples`):
  python3 benches/peers/codec_peers.py [--corpus ../shared/corpus] [--images 4] [--parts images,volumes,keep]
PSNR = 10 log10(peak^2 / MSE) over all samples, peak 255 for images, max-min for volumes.
"""
import argparse, io, json, os, shutil, subprocess, sys, tempfile, time
import numpy as np
from PIL import Image

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
MRA = os.path.join(ROOT, "target", "release", "mra")
KEEP = os.path.join(ROOT, "target", "release", "examples", "keep_psnr")


def psnr(a, b, peak):
    mse = np.mean((a.astype(np.float64) - b.astype(np.float64)) ** 2)
    return float("inf") if mse == 0 else 10 * np.log10(peak * peak / mse)


def run(cmd):
    t = time.perf_counter()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    return time.perf_counter() - t


def mra_image(path, bpp, tmp):
    enc, out = os.path.join(tmp, "a.mra"), os.path.join(tmp, "a.png")
    te = run([MRA, "encode", path, "-o", enc, "--bpp", str(bpp)])
    td = run([MRA, "decode", enc, "-o", out])
    return os.path.getsize(enc), np.asarray(Image.open(out)), te, td


def pillow(img, fmt, bpp, npix):
    """Largest quality whose file fits in bpp; returns (bytes, decoded, enc s, dec s)."""
    best = None
    lo, hi = 1, 100
    while lo <= hi:
        q = (lo + hi) // 2
        buf = io.BytesIO()
        t = time.perf_counter()
        img.save(buf, fmt, quality=q)
        te = time.perf_counter() - t
        if buf.tell() * 8 / npix <= bpp:
            best = (q, buf.getvalue(), te)
            lo = q + 1
        else:
            hi = q - 1
    if best is None:
        return None
    q, data, te = best
    t = time.perf_counter()
    dec = np.asarray(Image.open(io.BytesIO(data)).convert("RGB"))
    return len(data), dec, te, time.perf_counter() - t


def openjpeg(path, bpp, tmp, img):
    if not shutil.which("opj_compress"):
        return None
    src, j2k, out = os.path.join(tmp, "s.ppm"), os.path.join(tmp, "s.j2k"), os.path.join(tmp, "s2.ppm")
    img.save(src)
    ratio = 24.0 / bpp
    te = run(["opj_compress", "-i", src, "-o", j2k, "-r", str(ratio), "-I"])
    td = run(["opj_decompress", "-i", j2k, "-o", out])
    return os.path.getsize(j2k), np.asarray(Image.open(out)), te, td


def images(corpus, n):
    files = sorted(f for f in os.listdir(os.path.join(corpus, "images/kodak")) if f.endswith(".png"))[:n]
    rates = [0.25, 0.5, 1.0, 2.0]
    table = {}
    with tempfile.TemporaryDirectory() as tmp:
        for f in files:
            path = os.path.join(corpus, "images/kodak", f)
            img = Image.open(path).convert("RGB")
            ref = np.asarray(img)
            npix = ref.shape[0] * ref.shape[1]
            for b in rates:
                res = {
                    "mra": mra_image(path, b, tmp),
                    "jpeg": pillow(img, "JPEG", b, npix),
                    "webp": pillow(img, "WEBP", b, npix),
                    "openjpeg": openjpeg(path, b, tmp, img),
                }
                for k, r in res.items():
                    if r is None:
                        continue
                    size, dec, te, td = r
                    table.setdefault((k, b), []).append((size * 8 / npix, psnr(ref, dec, 255), te, td))
            print(f"  {f} done", file=sys.stderr)
    print(f"\n## Kodak ({len(files)} images): mean bpp / PSNR (dB) / encode s / decode s\n")
    print("| codec | target bpp | bpp | PSNR | enc s | dec s |\n|---|---|---|---|---|---|")
    for (k, b), rows in sorted(table.items(), key=lambda x: (x[0][1], x[0][0])):
        m = np.mean(np.array(rows), axis=0)
        print(f"| {k} | {b} | {m[0]:.3f} | {m[1]:.2f} | {m[2]:.3f} | {m[3]:.3f} |")


def volumes(corpus):
    raw = os.path.join(corpus, "volumes/ct_pancreas_crop_256x256x64_u16le.raw")
    vol = np.fromfile(raw, dtype="<u2").reshape(64, 256, 256)
    peak = float(vol.max()) - float(vol.min())
    print("\n## CT crop 256x256x64 u16: bits/voxel / PSNR (peak = max - min) / enc s / dec s\n")
    print("| codec | target | bits/voxel | PSNR | enc s | dec s |\n|---|---|---|---|---|---|")
    try:
        import zfpy
    except ImportError:
        zfpy = None
    with tempfile.TemporaryDirectory() as tmp:
        for b in [1, 2, 4]:
            enc, out = os.path.join(tmp, "v.mra"), os.path.join(tmp, "v.nrrd")
            te = run([MRA, "encode", raw, "--dims", "256x256x64", "--dtype", "u16", "-o", enc, "--bpp", str(b)])
            td = run([MRA, "decode", enc, "-o", os.path.join(tmp, "v.raw")])
            dec = np.fromfile(os.path.join(tmp, "v.raw"), dtype="<u2").reshape(vol.shape)
            print(f"| mra | {b} | {os.path.getsize(enc) * 8 / vol.size:.3f} | {psnr(vol, dec, peak):.2f} | {te:.3f} | {td:.3f} |")
            if zfpy is not None:
                f = vol.astype(np.float32)
                t = time.perf_counter()
                c = zfpy.compress_numpy(f, rate=b)
                te = time.perf_counter() - t
                t = time.perf_counter()
                d = zfpy.decompress_numpy(c)
                td = time.perf_counter() - t
                d = np.clip(np.round(d), 0, 65535)
                print(f"| zfp | {b} | {len(c) * 8 / vol.size:.3f} | {psnr(vol, d, peak):.2f} | {te:.3f} | {td:.3f} |")
    if zfpy is None:
        print("\n(zfpy not installed: ZFP rows skipped)")


def keep(corpus):
    import pywt
    path = os.path.join(corpus, "images/kodak/kodim23.png")
    img = np.asarray(Image.open(path).convert("L")).astype(np.float64)
    gray = os.path.join(tempfile.gettempdir(), "mra_keep_gray.png")
    Image.fromarray(img.astype(np.uint8)).save(gray)
    ps = [1, 2, 5, 10, 20]
    print("\n## Figure 9.19 protocol: kodim23 gray, 5 levels, PSNR (dB) after keeping P% of details\n")
    print("| transform | " + " | ".join(f"{p}%" for p in ps) + " |\n|---|" + "---|" * len(ps))
    out = subprocess.run([KEEP, gray] + [str(p) for p in ps], check=True, capture_output=True, text=True).stdout
    for line in out.strip().splitlines():
        print(line)
    for w in ["haar", "db2", "bior4.4"]:
        row = []
        for p in ps:
            c = pywt.wavedec2(img, w, mode="periodization", level=5)
            arr, sl = pywt.coeffs_to_array(c)
            a0 = sl[0]
            mask = np.ones(arr.shape, bool)
            mask[a0] = False
            det = np.abs(arr[mask])
            k = int(round(p / 100 * det.size))
            t = np.sort(det)[-k] if k > 0 else np.inf
            arr2 = arr.copy()
            arr2[mask & (np.abs(arr) < t)] = 0
            rec = pywt.waverec2(pywt.array_to_coeffs(arr2, sl, output_format="wavedec2"), w, mode="periodization")
            rec = np.clip(np.round(rec[: img.shape[0], : img.shape[1]]), 0, 255)
            row.append(psnr(img, rec, 255))
        print(f"| pywt {w} | " + " | ".join(f"{v:.2f}" for v in row) + " |")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--corpus", default=os.path.join(ROOT, "..", "shared", "corpus"))
    ap.add_argument("--images", type=int, default=24)
    ap.add_argument("--parts", default="images,volumes,keep")
    a = ap.parse_args()
    parts = a.parts.split(",")
    if "images" in parts:
        images(a.corpus, a.images)
    if "volumes" in parts:
        volumes(a.corpus)
    if "keep" in parts:
        keep(a.corpus)


if __name__ == "__main__":
    main()
