#!/usr/bin/env python3
"""Upscaling quality and speed: mra against OpenImageIO, scikit-image, SciPy and Pillow.

For every data set: crop to a multiple of F, make the low-resolution input by one of two
protocols, upscale back ×F with every method, round/clip to the original sample type, and
report PSNR and SSIM against the original plus the time of the upscale alone.

  - block: the exact F×F(×F) block mean (what the area mode assumes)
  - filtered: OpenImageIO's resize with its lanczos3 filter widened to the reduction (its own
    default when shrinking), a properly filtered downscale; 2-D data only (images, DEMs)

`--edges` adds the staircase measure: straight edges at six angles (each pixel the mean of
16×16 sub-samples of a half-plane, 40 / 220), made small by both protocols, upscaled ×4; the
along-edge ripple is the RMS of the result minus its mean at the same distance to the edge
(1/16-pixel bins, pixels within 3 px of the edge): a result that depends only on the
distance to the edge has none, a staircase of notches is all ripple.

  - mra: `mra upscale LOW -o OUT --factor F --mode M [--clamp C] --json` (the compute time it
    prints excludes file I/O; the wall time of the whole process is listed too)
  - OpenImageIO ImageBufAlgo.resize: lanczos3, catmull-rom, bspline (images, DEMs)
  - scikit-image transform.resize(order=3) (mode 'reflect', no anti-aliasing)
  - SciPy ndimage.zoom(order=3, grid_mode=True, mode='grid-mirror')
  (best of 3 runs for mra, OpenImageIO, Pillow; one run for scikit-image and SciPy)
  - Pillow Image.resize(LANCZOS) per channel in mode 'F' (images, DEMs)

Usage (from the repository root, after `cargo build --release`):
  python3 benches/peers/upscale_peers.py [--kodak N] [--json out.json] [--quick]
      [--protocols block,filtered] [--large] [--edges]
Needs: pip install OpenImageIO scikit-image scipy pillow tifffile pynrrd
"""
import argparse, json, os, subprocess, sys, tempfile, time
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CORPUS = os.environ.get("MRA_CORPUS", os.path.join(ROOT, "..", "shared", "corpus"))
if not os.path.isdir(CORPUS):
    CORPUS = "/work/shared/corpus"
MRA = os.environ.get("MRA_BIN") or os.path.join(os.environ.get("CARGO_TARGET_DIR", os.path.join(ROOT, "target")), "release", "mra")

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


def filtered(x, f):
    """The filtered protocol: OpenImageIO resize (lanczos3, widened by the reduction) of the
    crop to a multiple of f; returns the crop (float64) and the low-resolution input."""
    h, w = (x.shape[0] // f) * f, (x.shape[1] // f) * f
    x = x[:h, :w].astype(np.float64)
    c = 1 if x.ndim == 2 else x.shape[2]
    buf = oiio.ImageBuf(oiio.ImageSpec(w, h, c, "float"))
    buf.set_pixels(oiio.ROI(), np.ascontiguousarray(x.reshape(h, w, c), dtype=np.float32))
    out = oiio.ImageBufAlgo.resize(buf, filtername="lanczos3", roi=oiio.ROI(0, w // f, 0, h // f, 0, 1, 0, c))
    return x, out.get_pixels(oiio.FLOAT).reshape((h // f, w // f) + x.shape[2:])


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
    cmd = [MRA, "upscale", src, "-o", dst, "--factor", str(f), "--mode", mode, "--scheme", scheme, "--json", "--quiet", *extra]
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
    only = set(args.only.split(",")) if args.only else {"image", "photo", "volume", "heightmap"}
    for item in _datasets(args):
        if item[0] in only:
            yield item


def _datasets(args):
    kodak = sorted(os.listdir(os.path.join(CORPUS, "images", "kodak")))[: args.kodak]
    for name in kodak:
        yield "image", name, np.asarray(Image.open(os.path.join(CORPUS, "images", "kodak", name)).convert("RGB")), 2
    if args.large:
        # photographs never used to tune mra (2268×1512 RGB, 3008×2000 gray)
        for name in ["flower_foveon_rgb8.png", "leaves_iso_1600_gray8.png"]:
            yield "photo", name, np.asarray(Image.open(os.path.join(CORPUS, "images", "large", name))), 2
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
    ap.add_argument("--only", help="comma-separated kinds: image (Kodak), photo (--large), volume, heightmap")
    ap.add_argument("--no-speed", action="store_true", help="skip the 256³ speed case")
    ap.add_argument("--speed-only", action="store_true", help="only the 256³ speed case")
    ap.add_argument("--summarize", nargs="+", help="print the summary of JSON-lines logs of earlier runs")
    ap.add_argument("--protocols", default="block,filtered",
                    help="comma-separated low-resolution protocols: block (block mean), filtered (OpenImageIO lanczos3)")
    ap.add_argument("--large", action="store_true", help="add the two large corpus photographs")
    ap.add_argument("--edges", action="store_true", help="add the along-edge ripple (staircase) measure on straight edges")
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
            for f, protocol in [(int(s), p) for s in args.factors.split(",") for p in args.protocols.split(",")]:
                if protocol == "filtered" and spatial != 2:
                    continue
                ref, low = block_mean(x, f, spatial) if protocol == "block" else filtered(x, f)
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
                    row = dict(kind=kind, protocol=protocol, data=name, factor=f, method=label, psnr=psnr, ssim=ssim, seconds=secs, wall=wall)
                    rows.append(row)
                    print(json.dumps(row), flush=True)
    if args.edges and not args.speed_only:
        rows += edge_rows(args)
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


EDGE_N, EDGE_F, EDGE_ANGLES = 256, 4, [20, 30, 37, 53, 60, 70]


def edge_image(angle):
    """A half-plane through the centre, normal at `angle`: 16×16 sub-samples per pixel."""
    n, ss = EDGE_N, 16
    nx, ny = np.cos(np.deg2rad(angle)), np.sin(np.deg2rad(angle))
    g = (np.arange(n * ss) + 0.5) / ss - n / 2
    yy, xx = np.meshgrid(g, g, indexing="ij")
    cover = ((xx * nx + yy * ny) > 0).reshape(n, ss, n, ss).mean(axis=(1, 3))
    c = np.arange(n) + 0.5 - n / 2
    y, x = np.meshgrid(c, c, indexing="ij")
    return 40.0 + 180.0 * cover, x * nx + y * ny


def ripple(u, d, band=3.0, margin=16, width=1 / 16):
    """Along-edge ripple: RMS of u minus its mean over the same distance bin."""
    m = np.zeros_like(d, bool)
    m[margin:-margin, margin:-margin] = True
    m &= np.abs(d) <= band
    k = np.floor((d[m] + band) / width).astype(int)
    v = u[m].astype(np.float64)
    prof = np.bincount(k, v) / np.maximum(np.bincount(k), 1)
    return float(np.sqrt(np.mean((v - prof[k]) ** 2)))


def edge_rows(args):
    """Ripple and PSNR of every method on straight edges ×4, both protocols."""
    rows, f = [], EDGE_F
    with tempfile.TemporaryDirectory() as tmp:
        for protocol in args.protocols.split(","):
            for angle in EDGE_ANGLES:
                x, d = edge_image(angle)
                ref, low = block_mean(x, f, 2) if protocol == "block" else filtered(x, f)
                methods = {}
                for pair in args.mra.split(","):
                    scheme, mode, *clamp = pair.split(":")
                    label = f"mra {scheme} {mode}" + (f" clamp={clamp[0]}" if clamp else "")
                    methods[label] = lambda s=scheme, m=mode, c=clamp: mra_upscale(low, f, m, s, tmp, 2, ("--clamp", c[0]) if c else ())[0]
                if not args.no_peers:
                    for filt in ["lanczos3", "catmull-rom"]:
                        methods[f"oiio {filt}"] = lambda filt=filt: oiio_resize(low, f, filt)
                    methods["skimage order 3"] = lambda: sk(low, f, 2)
                for label, fn in methods.items():
                    out = to_type(fn(), np.uint8).astype(np.float64)
                    psnr = peak_signal_noise_ratio(ref, out, data_range=255.0)
                    row = dict(kind="edges", protocol=protocol, data=f"edge {angle}°", factor=f, method=label,
                               ripple=ripple(out, d), psnr=psnr)
                    rows.append(row)
                    print(json.dumps(row), flush=True)
    return rows


def summarize(rows):
    """Mean per kind × protocol × factor × method, the edge ripple, and the speed rows."""
    print("\n| kind | protocol | factor | method | mean PSNR dB | mean SSIM | mean time s |")
    print("|---|---|---|---|---|---|---|")
    prot = lambda r: r.get("protocol", "block")
    keys = sorted({(r["kind"], prot(r), r["factor"], r["method"]) for r in rows if "ssim" in r})
    for k in keys:
        sel = [r for r in rows if (r["kind"], prot(r), r["factor"], r["method"]) == k]
        print(f"| {k[0]} | {k[1]} | ×{k[2]} | {k[3]} | {np.mean([r['psnr'] for r in sel]):.3f} | {np.mean([r['ssim'] for r in sel]):.4f} | {np.mean([r['seconds'] for r in sel]):.4f} |")
    edges = [r for r in rows if r["kind"] == "edges"]
    if edges:
        print("\n| edges ×4 | protocol | method | mean along-edge ripple | mean PSNR dB |")
        print("|---|---|---|---|---|")
        for k in sorted({(prot(r), r["method"]) for r in edges}):
            sel = [r for r in edges if (prot(r), r["method"]) == k]
            print(f"| | {k[0]} | {k[1]} | {np.mean([r['ripple'] for r in sel]):.3f} | {np.mean([r['psnr'] for r in sel]):.2f} |")
    for r in rows:
        if r["kind"] == "speed":
            print(f"\nspeed {r['data']} ×2: mra {r['seconds']:.2f} s (process wall {r['wall']:.2f} s), "
                  f"SciPy zoom order 3 {r['scipy_zoom_seconds']:.2f} s, ratio {r['speedup']:.1f}×")


if __name__ == "__main__":
    main()
