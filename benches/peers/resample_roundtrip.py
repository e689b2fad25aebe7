#!/usr/bin/env python3
"""Downscale x2 then upscale x2, each tool with its own defaults, on the 24 Kodak images: mean
RGB PSNR against the original (8-bit, peak 255), and the same for a zone plate, side by side.

  - mra:          mra downscale IN -o LOW.png [--scheme S]; mra upscale LOW.png -o OUT.png --factor 2
  - OpenImageIO:  ImageBufAlgo.resize to half size and back (its default filter), as oiiotool --resize
  - scikit-image: transform.rescale(0.5, anti_aliasing=True, order=3), then rescale(2, order=3)

With --aliasing, the zone plate's aliasing instead: RMS deviation from grey of each tool's
half-size plate where the fine frequency lies above the coarse Nyquist (0.30-0.50 cycles per
sample; near the edge centres), and RMS error against the ideal reduced plate in the passband
(below 0.15); and with --lowpass A1,A2,... the same plus the Kodak round trip for mra's default
followed by an extra coarse low-pass (a, 1-2a, a) per axis (applied here to mra's f32 output).

Usage (from the repository root, after `cargo build --release`):
  python3 benches/peers/resample_roundtrip.py [--kodak N] [--schemes haar,chaikin-wide,...] [--json F]
  python3 benches/peers/resample_roundtrip.py --aliasing [--schemes default,haar,cdf97] [--lowpass 0,1/32,1/16]
Needs: pip install numpy OpenImageIO scikit-image imageio
"""
import argparse, json, os, subprocess, sys, tempfile
import numpy as np
import imageio.v3 as iio

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CORPUS = os.environ.get("MRA_CORPUS", os.path.join(ROOT, "..", "shared", "corpus"))
MRA = os.path.join(ROOT, "target", "release", "mra")


def psnr(a, b):
    mse = np.mean((a.astype(np.float64) - b.astype(np.float64)) ** 2)
    return 10 * np.log10(255.0 ** 2 / mse) if mse > 0 else float("inf")


def mra_roundtrip(path, tmp, scheme):
    low, out = os.path.join(tmp, "low.png"), os.path.join(tmp, "out.png")
    cmd = [MRA, "downscale", path, "-o", low]
    if scheme != "default":
        cmd += ["--scheme", scheme]
    subprocess.run(cmd, check=True, capture_output=True)
    subprocess.run([MRA, "upscale", low, "-o", out, "--factor", "2"], check=True, capture_output=True)
    return iio.imread(low), iio.imread(out)


def oiio_roundtrip(x):
    import OpenImageIO as oiio
    h, w = x.shape[:2]
    c = x.shape[2] if x.ndim == 3 else 1
    src = oiio.ImageBuf(x.astype(np.float32) / 255.0)
    low = oiio.ImageBufAlgo.resize(src, roi=oiio.ROI(0, w // 2, 0, h // 2, 0, 1, 0, c))
    back = oiio.ImageBufAlgo.resize(low, roi=oiio.ROI(0, w, 0, h, 0, 1, 0, c))
    y = back.get_pixels(oiio.FLOAT).reshape(x.shape)
    return np.clip(np.round(y * 255.0), 0, 255).astype(np.uint8)


def skimage_roundtrip(x):
    from skimage.transform import rescale
    ca = 2 if x.ndim == 3 else None
    low = rescale(x.astype(np.float64), 0.5, anti_aliasing=True, order=3, channel_axis=ca)
    back = rescale(low, 2, order=3, channel_axis=ca)
    back = back[: x.shape[0], : x.shape[1]]
    return np.clip(np.round(back), 0, 255).astype(np.uint8)


def zone_plate(n=512):
    y, x = np.mgrid[0:n, 0:n].astype(np.float64) - n / 2
    return np.round(127.5 + 127.5 * np.cos(np.pi * (x * x + y * y) / n)).astype(np.uint8)


def smooth(x, a):
    """(a, 1 - 2a, a) along each axis, half-sample symmetric ends."""
    for ax in (0, 1):
        p = np.pad(x, [(1, 1) if i == ax else (0, 0) for i in range(x.ndim)], mode="symmetric")
        def sh(o):
            t = [slice(None)] * x.ndim
            t[ax] = slice(1 + o, p.shape[ax] - 1 + o)
            return p[tuple(t)]
        x = a * sh(-1) + (1 - 2 * a) * sh(0) + a * sh(1)
    return x


def mra_low_f32(img, tmp):
    """mra's default downscale of `img` (u8) computed in f32 (no rounding)."""
    src, f, low = (os.path.join(tmp, n) for n in ("l.png", "l_f.tif", "l_low.tif"))
    iio.imwrite(src, img)
    subprocess.run([MRA, "convert", src, "-o", f, "--dtype-out", "f32"], check=True, capture_output=True)
    subprocess.run([MRA, "downscale", f, "-o", low], check=True, capture_output=True)
    return iio.imread(low).astype(np.float64)


def aliasing(files, schemes, lowpass):
    n = 512
    z = zone_plate(n)
    m = n // 2
    yy, xx = np.mgrid[0:m, 0:m] * 2 + 0.5 - n / 2  # coarse cell centres on the fine grid
    r = np.hypot(yy, xx)
    stop = (r > 0.30 * n) & (r < 0.50 * n)
    edge = stop & ((np.abs(yy) < 0.06 * n) | (np.abs(xx) < 0.06 * n))
    pas = r < 0.15 * n
    ideal = 127.5 + 127.5 * np.cos(np.pi * r * r / n)

    def row(name, low, extra=""):
        a = np.sqrt(np.mean((low[stop] - 127.5) ** 2))
        e = np.sqrt(np.mean((low[edge] - 127.5) ** 2))
        p = np.sqrt(np.mean((low[pas] - ideal[pas]) ** 2))
        print(f"| {name} | {a:.2f} | {e:.2f} | {p:.2f} |{extra}")

    q = lambda x: np.clip(np.round(x), 0, 255).astype(np.uint8)
    with tempfile.TemporaryDirectory() as tmp:
        zp = os.path.join(tmp, "zone.png")
        iio.imwrite(zp, z)
        print("| downscale x2 of a 512² zone plate | aliased RMS, 0.30-0.50 | at the edge centres | passband RMS error |")
        print("|---|---|---|---|")
        for s in schemes:
            low, _ = mra_roundtrip(zp, tmp, s)
            row(f"mra {s}", low.astype(np.float64))
        from skimage.transform import rescale
        row("scikit-image rescale", rescale(z.astype(np.float64), 0.5, anti_aliasing=True, order=3))
        import OpenImageIO as oiio
        buf = oiio.ImageBuf(z.astype(np.float32)[..., None] / 255.0)
        low = oiio.ImageBufAlgo.resize(buf, roi=oiio.ROI(0, m, 0, m, 0, 1, 0, 1))
        row("OpenImageIO resize", low.get_pixels(oiio.FLOAT).reshape(m, m) * 255.0)
        if not lowpass:
            return
        zl = mra_low_f32(z, tmp)
        kodak = [(x, mra_low_f32(x, tmp)) for x in (iio.imread(f) for f in files)]
        print()
        print(f"| extra low-pass a | aliased RMS | at the edge centres | passband RMS error | {len(files)} Kodak round trip (dB) |")
        print("|---|---|---|---|---|")
        for a in lowpass:
            ps = []
            lo, up = os.path.join(tmp, "kl.png"), os.path.join(tmp, "ku.png")
            for x, l in kodak:
                iio.imwrite(lo, q(smooth(l, a)))
                subprocess.run([MRA, "upscale", lo, "-o", up, "--factor", "2"], check=True, capture_output=True)
                ps.append(psnr(x, iio.imread(up)))
            row(f"{a:.4f}", q(smooth(zl, a)).astype(np.float64), f" {np.mean(ps):.2f} |")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--aliasing", action="store_true")
    ap.add_argument("--lowpass", default="", help="comma-separated a values, fractions allowed (1/32)")
    ap.add_argument("--kodak", type=int, default=24)
    ap.add_argument("--schemes", default="default")
    ap.add_argument("--json")
    ap.add_argument("--zone-plate", help="write the zone plate and mra's half-size result here (prefix)")
    a = ap.parse_args()
    files = [os.path.join(CORPUS, "images", "kodak", f"kodim{i:02d}.png") for i in range(1, a.kodak + 1)]
    schemes = a.schemes.split(",")
    if a.aliasing:
        from fractions import Fraction
        lowpass = [float(Fraction(t)) for t in a.lowpass.split(",") if t]
        return aliasing(files, schemes, lowpass)
    res = {f"mra {s}": [] for s in schemes}
    res["OpenImageIO resize"] = []
    res["scikit-image rescale"] = []
    with tempfile.TemporaryDirectory() as tmp:
        for f in files:
            x = iio.imread(f)
            for s in schemes:
                _, y = mra_roundtrip(f, tmp, s)
                res[f"mra {s}"].append(psnr(x, y))
            res["OpenImageIO resize"].append(psnr(x, oiio_roundtrip(x)))
            res["scikit-image rescale"].append(psnr(x, skimage_roundtrip(x)))
        if a.zone_plate:
            z = zone_plate()
            zp = os.path.join(tmp, "zone.png")
            iio.imwrite(zp, z)
            low, _ = mra_roundtrip(zp, tmp, schemes[0])
            iio.imwrite(a.zone_plate + "_input.png", z)
            iio.imwrite(a.zone_plate + "_mra_half.png", low)
    print(f"| downscale x2 + upscale x2, {len(files)} Kodak images | mean PSNR (dB) | min | max |")
    print("|---|---|---|---|")
    for k, v in res.items():
        print(f"| {k} | {np.mean(v):.2f} | {np.min(v):.2f} | {np.max(v):.2f} |")
    if a.json:
        json.dump({k: v for k, v in res.items()}, open(a.json, "w"), indent=1)


if __name__ == "__main__":
    main()
