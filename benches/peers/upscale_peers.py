#!/usr/bin/env python3
"""Upscaling quality and speed: mra against OpenImageIO, scikit-image, SciPy and Pillow.

For every data set: crop to a multiple of F, downscale by exact block mean (F = 2, 4),
upscale back with every method, round/clip to the original sample type, and report
PSNR and SSIM against the original plus the time of the upscale alone.

  - mra: `mra upscale LOW -o OUT --factor F --mode M [--clamp C] --report` (the compute time it
    prints excludes file I/O; the wall time of the whole process is listed too)
  - OpenImageIO ImageBufAlgo.resize: lanczos3, catmull-rom, bspline (images, DEMs)
  - scikit-image transform.resize(order=3) (mode 'reflect', no anti-aliasing)
  - SciPy ndimage.zoom(order=3, grid_mode=True, mode='grid-mirror')
  (best of 3 runs for mra, OpenImageIO, Pillow; one run for scikit-image and SciPy)
  - Pillow Image.resize(LANCZOS) per channel in mode 'F' (images, DEMs)

Usage (from the repository root, after `cargo build --release`):
  python3 benches/peers/upscale_peers.py [--kodak N] [--json out.json] [--quick]
Needs: pip install OpenImageIO scikit-image scipy pillow tifffile pynrrd
"""
import argparse, json, os, subprocess, sys, tempfile, time
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CORPUS = os.environ.get("MRA_CORPUS", os.path.join(ROOT, "..", "shared", "corpus"))
if not os.path.isdir(CORPUS):
    CORPUS = "/work/shared/corpus"
MRA = os.path.join(ROOT, "target", "release", "mra")

import tifffile, nrrd
from skimage.metrics import peak_signal_noise_ratio, structural_similarity
from skimage.transform import resize as sk_resize
from scipy import ndimage
from PIL import Image
import OpenImageIO as oiio


def block_mean(x, f, spatial):
    sl = tuple(slice(0, (x.shape[a] // f) * f) if a < spatial else slice(None) for a in range(x.ndim))
    x = x[sl].astype(np.float64)
    shp = []
    for a in range(x.ndim):
        if a < spatial:
            shp += [x.shape[a] // f, f]
        else:
            shp += [x.shape[a]]
    y = x.reshape(shp)
    axes = tuple(2 * a + 1 for a in range(spatial))
    return x, y.mean(axis=axes).astype(np.float32)


def to_type(y, dtype):
    if np.issubdtype(dtype, np.integer):
        info = np.iinfo(dtype)
        return np.clip(np.round(y), info.min, info.max).astype(dtype)
    return y.astype(dtype)


def timed(fn, reps):
    best = float("inf")
    out = None
    for _ in range(reps):
        t = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t)
    return out, best


# ---------- mra through its CLI --------------------------------------------------------

def write_nrrd_f32(path, v):
    with open(path, "wb") as fh:
        z, y, x = v.shape
        fh.write(f"NRRD0004\ntype: float\ndimension: 3\nsizes: {x} {y} {z}\nencoding: raw\nendian: little\n\n".encode())
        fh.write(np.ascontiguousarray(v, dtype="<f4").tobytes())


def mra_upscale(low, f, mode, scheme, tmp, spatial, extra=()):
    ext = "nrrd" if spatial == 3 else "tif"
    src = os.path.join(tmp, f"low.{ext}")
    dst = os.path.join(tmp, f"up.{ext}")
    if spatial == 3:
        write_nrrd_f32(src, low)
    else:
        tifffile.imwrite(src, low)
    cmd = [MRA, "upscale", src, "-o", dst, "--factor", str(f), "--mode", mode, "--scheme", scheme, "--report", "--quiet", *extra]
    t = time.perf_counter()
    r = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - t
    if r.returncode != 0:
        raise RuntimeError(r.stderr)
    compute = json.loads(r.stdout.strip().splitlines()[-1])["compute_seconds"]
    if spatial == 3:
        out, _ = nrrd.read(dst, index_order="C")
    else:
        with tifffile.TiffFile(dst) as t:
            out = t.pages[0].asarray()
    return out.astype(np.float32), compute, wall


# ---------- peers ----------------------------------------------------------------------

def oiio_resize(low, f, filt):
    h, w = low.shape[:2]
    c = 1 if low.ndim == 2 else low.shape[2]
    buf = oiio.ImageBuf(oiio.ImageSpec(w, h, c, "float"))
    buf.set_pixels(oiio.ROI(), np.ascontiguousarray(low.reshape(h, w, c)))
    roi = oiio.ROI(0, w * f, 0, h * f, 0, 1, 0, c)
    out = oiio.ImageBufAlgo.resize(buf, filtername=filt, roi=roi)
    return out.get_pixels(oiio.FLOAT).reshape((h * f, w * f) + low.shape[2:])


def sk(low, f, spatial):
    shape = tuple(s * f if a < spatial else s for a, s in enumerate(low.shape))
    return sk_resize(low, shape, order=3, mode="reflect", anti_aliasing=False, preserve_range=True)


def zoom(low, f, spatial):
    zf = tuple(f if a < spatial else 1 for a in range(low.ndim))
    return ndimage.zoom(low, zf, order=3, grid_mode=True, mode="grid-mirror")


def pil(low, f):
    h, w = low.shape[:2]
    chans = [low] if low.ndim == 2 else [low[..., k] for k in range(low.shape[2])]
    outs = [np.asarray(Image.fromarray(np.ascontiguousarray(c, dtype=np.float32), "F").resize((w * f, h * f), Image.LANCZOS)) for c in chans]
    return outs[0] if low.ndim == 2 else np.stack(outs, axis=-1)


# ---------- data -----------------------------------------------------------------------

def datasets(args):
    only = set(args.only.split(",")) if args.only else {"image", "volume", "heightmap"}
    for item in _datasets(args):
        if item[0] in only:
            yield item


def _datasets(args):
    kodak = sorted(os.listdir(os.path.join(CORPUS, "images", "kodak")))[: args.kodak]
    for name in kodak:
        yield "image", name, np.asarray(Image.open(os.path.join(CORPUS, "images", "kodak", name)).convert("RGB")), 2
    if args.quick:
        return
    v, _ = nrrd.read(os.path.join(CORPUS, "volumes", "ct_pancreas_256.nrrd"), index_order="C")
    yield "volume", "ct_pancreas_256 (HU, int16)", v, 3
    # OpenImageIO decodes the floating-point predictor (tifffile would need imagecodecs)
    helens = oiio.ImageBuf(os.path.join(CORPUS, "terrain", "mt_st_helens_30m_f32.tif")).get_pixels(oiio.FLOAT)
    yield "heightmap", "mt_st_helens_30m_f32", helens.reshape(helens.shape[:2]), 2
    hgt = np.fromfile(os.path.join(CORPUS, "terrain", "N44W072.hgt"), dtype=">i2").reshape(1201, 1201).astype(np.int16)
    yield "heightmap", "N44W072.hgt (int16)", hgt, 2
    asc = np.loadtxt(os.path.join(CORPUS, "terrain", "srtmgl3_boulder_co.asc"), skiprows=6).astype(np.float32)
    yield "heightmap", "srtmgl3_boulder_co.asc", asc, 2


def metrics(ref, out, dtype, channel):
    out = to_type(out, dtype).astype(np.float64)
    ref = ref.astype(np.float64)
    rng = 255.0 if dtype == np.uint8 else float(ref.max() - ref.min())
    psnr = peak_signal_noise_ratio(ref, out, data_range=rng)
    ssim = structural_similarity(ref, out, data_range=rng, channel_axis=2 if channel else None)
    return psnr, ssim


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--kodak", type=int, default=24)
    ap.add_argument("--factors", default="2,4")
    ap.add_argument("--json")
    ap.add_argument("--quick", action="store_true", help="Kodak only")
    ap.add_argument("--mra", default="chaikin:area,chaikin:area:off,cubic:area:off,cubic:interpolate,cubic:control",
                    help="comma-separated scheme:mode[:clamp] to run with mra (clamp: auto, the default, on, off)")
    ap.add_argument("--no-peers", action="store_true", help="mra only")
    ap.add_argument("--only", help="comma-separated kinds: image, volume, heightmap")
    ap.add_argument("--no-speed", action="store_true", help="skip the 256³ speed case")
    ap.add_argument("--speed-only", action="store_true", help="only the 256³ speed case")
    ap.add_argument("--summarize", nargs="+", help="print the summary of JSON-lines logs of earlier runs")
    args = ap.parse_args()
    if args.summarize:
        rows = []
        for path in args.summarize:
            with open(path) as fh:
                rows += [json.loads(l) for l in fh if l.startswith("{")]
        summarize(rows)
        return
    reps = 3
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for kind, name, x, spatial in ([] if args.speed_only else datasets(args)):
            channel = x.ndim > spatial
            for f in [int(s) for s in args.factors.split(",")]:
                ref, low = block_mean(x, f, spatial)
                methods = {}
                for pair in args.mra.split(","):
                    scheme, mode, *clamp = pair.split(":")
                    label = f"mra {scheme} {mode}" + (f" clamp={clamp[0]}" if clamp else "")
                    methods[label] = ("mra", mode, scheme, ("--clamp", clamp[0]) if clamp else ())
                if not args.no_peers:
                    if spatial == 2:
                        for filt in ["lanczos3", "catmull-rom", "bspline"]:
                            methods[f"oiio {filt}"] = ("oiio", filt)
                    methods["skimage order 3"] = ("sk",)
                    methods["scipy zoom 3"] = ("zoom",)
                    if spatial == 2:
                        methods["pillow lanczos"] = ("pil",)
                for label, m in methods.items():
                    wall = None
                    if m[0] == "mra":
                        runs = [mra_upscale(low, f, m[1], m[2], tmp, spatial, m[3]) for _ in range(reps)]
                        out = runs[0][0]
                        secs = min(r[1] for r in runs)
                        wall = min(r[2] for r in runs)
                    elif m[0] == "oiio":
                        out, secs = timed(lambda: oiio_resize(low, f, m[1]), reps)
                    elif m[0] == "sk":
                        out, secs = timed(lambda: sk(low, f, spatial), 1)
                    elif m[0] == "zoom":
                        out, secs = timed(lambda: zoom(low, f, spatial), 1)
                    else:
                        out, secs = timed(lambda: pil(low, f), reps)
                    psnr, ssim = metrics(ref, out, x.dtype, channel)
                    row = dict(kind=kind, data=name, factor=f, method=label, psnr=psnr, ssim=ssim, seconds=secs, wall=wall)
                    rows.append(row)
                    print(json.dumps(row), flush=True)
    # speed: a 256³ float32 volume ×2 (mra compute time vs SciPy zoom order 3)
    if not args.quick and not args.no_peers and not args.no_speed:
        with tempfile.TemporaryDirectory() as tmp:
            rng = np.random.default_rng(1)
            vol = ndimage.gaussian_filter(rng.standard_normal((256, 256, 256)).astype(np.float32), 2.0)
            runs = [mra_upscale(vol, 2, "area", "chaikin", tmp, 3) for _ in range(3)]
            t_mra = min(r[1] for r in runs)
            _, t_zoom = timed(lambda: zoom(vol, 2, 3), 1)
            row = dict(kind="speed", data="256^3 f32", factor=2, method="mra chaikin area", seconds=t_mra, wall=min(r[2] for r in runs), scipy_zoom_seconds=t_zoom, speedup=t_zoom / t_mra)
            rows.append(row)
            print(json.dumps(row), flush=True)
    summarize(rows)
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(rows, fh, indent=1)


def summarize(rows):
    """Mean per kind × factor × method, and the speed rows."""
    print("\n| kind | factor | method | mean PSNR dB | mean SSIM | mean time s |")
    print("|---|---|---|---|---|---|")
    keys = sorted({(r["kind"], r["factor"], r["method"]) for r in rows if "psnr" in r})
    for k in keys:
        sel = [r for r in rows if (r["kind"], r["factor"], r["method"]) == k]
        print(f"| {k[0]} | ×{k[1]} | {k[2]} | {np.mean([r['psnr'] for r in sel]):.3f} | {np.mean([r['ssim'] for r in sel]):.4f} | {np.mean([r['seconds'] for r in sel]):.4f} |")
    for r in rows:
        if r["kind"] == "speed":
            print(f"\nspeed {r['data']} ×2: mra {r['seconds']:.2f} s (process wall {r['wall']:.2f} s), "
                  f"SciPy zoom order 3 {r['scipy_zoom_seconds']:.2f} s, ratio {r['speedup']:.1f}×")


if __name__ == "__main__":
    main()
