#!/usr/bin/env python3
"""Reference values for `mra compare` (tests/metrics.rs).

Makes (once, with --make-pairs) a set of small generated image pairs under
tests/reference/compare/ -- 8-bit, 16-bit, float; gray and RGB; a volume -- written
by imageio (PNG), tifffile (TIFF) and pynrrd (NRRD), then computes for every pair

  * scikit-image: peak_signal_noise_ratio (default data range, or the case's
    data_range), mean_squared_error, structural_similarity (7x7 uniform window,
    channel_axis=-1 for RGB, data_range as documented in src/metrics.rs);
  * OpenImageIO: ImageBufAlgo.compare(A, B).PSNR / rms_error / maxerror

and writes tests/reference/compare_fixture.json.

Usage:
  pip install scikit-image OpenImageIO imageio tifffile pynrrd
  python3 tests/reference/compare_reference.py [--make-pairs] [--check]

--check recomputes the values and exits 1 if they differ from the committed fixture
by more than 1e-9 (relative), without rewriting it.
"""
import json
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
PAIRS = os.path.join(HERE, "compare")
FIXTURE = os.path.join(HERE, "compare_fixture.json")


def ramp(h, w, c=1):
    y, x = np.mgrid[0:h, 0:w].astype(np.float64)
    base = 0.5 + 0.5 * np.cos(np.pi * ((x - w / 2) ** 2 + (y - h / 2) ** 2) / max(h, w))
    chans = [base, x / (w - 1), y / (h - 1), 1 - base]
    out = np.stack(chans[:c], axis=-1)
    return out if c > 1 else out[..., 0]


# name, file extension, dtype, shape (h, w[, c]) or (d, h, w), noise sigma, data_range
CASES = [
    ("u8_gray", "png", "uint8", (48, 64), 8.0, None),
    ("u8_rgb", "png", "uint8", (40, 48, 3), 12.0, None),
    ("u16_gray", "png", "uint16", (64, 64), 900.0, None),
    ("u16_rgb", "tif", "uint16", (32, 40, 3), 2000.0, None),
    ("u16_range4095", "png", "uint16", (40, 40), 30.0, 4095.0),
    ("f32_gray", "tif", "float32", (48, 48), 0.03, None),
    ("f32_rgb", "tif", "float32", (40, 32, 3), 0.05, None),
    ("f32_signed", "tif", "float32", (40, 40), 0.02, None),
    ("f32_hdr", "tif", "float32", (36, 44), 0.1, None),
    ("i16_signed", "tif", "int16", (40, 40), 500.0, None),
    ("u8_identical", "png", "uint8", (32, 32), 0.0, None),
    ("u8_volume", "nrrd", "uint8", (16, 20, 24), 10.0, None),
]


def make_pair(name, ext, dtype, shape, sigma, rng):
    if len(shape) == 3 and ext == "nrrd":
        d, h, w = shape
        z = np.linspace(0, 1, d)[:, None, None]
        a = 0.5 * ramp(h, w)[None] + 0.4 * z
    else:
        a = ramp(*shape[:2], *(shape[2:] or (1,)))
    if dtype == "uint8":
        a = np.round(a * 255)
        lo, hi = 0, 255
    elif dtype == "uint16":
        scale = 4095 if name == "u16_range4095" else 65535
        a = np.round(a * scale)
        lo, hi = 0, scale
    elif dtype == "int16":
        a = np.round((a - 0.5) * 60000)
        lo, hi = -32768, 32767
    elif name == "f32_signed":
        a = 2 * a - 1
        lo, hi = -1, 1
    elif name == "f32_hdr":
        a = 4 * a
        lo, hi = 0, 4
    else:
        lo, hi = 0, 1
    b = a + rng.normal(0, sigma, a.shape) if sigma else a.copy()
    b = np.clip(b, lo, hi)
    if not np.issubdtype(np.dtype(dtype), np.floating):
        b = np.round(b)
    return a.astype(dtype), b.astype(dtype)


def write(path, arr, ext):
    if ext == "png":
        import imageio.v3 as iio
        iio.imwrite(path, arr)
    elif ext == "tif":
        import tifffile
        tifffile.imwrite(path, arr, photometric="rgb" if arr.ndim == 3 else "minisblack")
    elif ext == "nrrd":
        import nrrd
        nrrd.write(path, arr, {"encoding": "raw", "endian": "little"}, index_order="C")


def read(path, ext):
    if ext == "png":
        import imageio.v3 as iio
        return iio.imread(path)
    if ext == "tif":
        import tifffile
        return tifffile.imread(path)
    import nrrd
    data, _ = nrrd.read(path, index_order="C")
    return data


def oiio_buf(arr, volume):
    import OpenImageIO as oiio
    x = arr[..., None] if (arr.ndim == 2 or volume) else arr
    types = {"uint8": "uint8", "uint16": "uint16", "int16": "int16", "float32": "float"}
    if x.ndim == 4:
        d, h, w, c = x.shape
    else:
        d, (h, w, c) = 1, x.shape
    spec = oiio.ImageSpec(w, h, c, types[str(arr.dtype)])
    spec.depth = d
    buf = oiio.ImageBuf(spec)
    ok = buf.set_pixels(oiio.ROI(0, w, 0, h, 0, d, 0, c), x)
    if not ok:
        raise RuntimeError(buf.geterror())
    return buf


def skimage_ssim_range(a, given):
    if given is not None:
        return given
    if np.issubdtype(a.dtype, np.floating):
        # mra's PSNR range for floats (skimage requires one for SSIM)
        lo, hi = float(a.min()), float(a.max())
        if hi > 1 or lo < -1:
            return hi - lo
        return 1.0 if lo >= 0 else 2.0
    info = np.iinfo(a.dtype)
    return float(info.max) - float(info.min)


def compute(name, ext, given):
    import OpenImageIO as oiio
    from skimage.metrics import (mean_squared_error, peak_signal_noise_ratio,
                                 structural_similarity)
    a = read(os.path.join(PAIRS, f"{name}_a.{ext}"), ext)
    b = read(os.path.join(PAIRS, f"{name}_b.{ext}"), ext)
    rgb = a.ndim == 3 and ext != "nrrd"
    mse = float(mean_squared_error(a, b))
    data_range = given
    if data_range is None and np.issubdtype(a.dtype, np.floating) and (a.max() > 1 or a.min() < -1):
        data_range = float(a.max()) - float(a.min())  # skimage would raise: mra's fallback
    if mse == 0:
        psnr = None
    else:
        psnr = float(peak_signal_noise_ratio(a, b, data_range=data_range))
    ssim_r = skimage_ssim_range(a, given)
    ssim = float(structural_similarity(a, b, data_range=ssim_r, channel_axis=-1 if rgb else None))
    out = {
        "name": name,
        "a": f"compare/{name}_a.{ext}",
        "b": f"compare/{name}_b.{ext}",
        "data_range": given,
        "skimage": {"mse": mse, "psnr": psnr, "ssim": ssim, "ssim_data_range": ssim_r},
    }
    if given is None:
        r = oiio.ImageBufAlgo.compare(oiio_buf(a, not rgb and a.ndim == 3), oiio_buf(b, not rgb and a.ndim == 3), 1e-12, 1e-12)
        out["oiio"] = {
            "psnr": None if r.rms_error == 0 else float(r.PSNR),
            "rms_error": float(r.rms_error),
            "max_error": float(r.maxerror),
        }
    return out


def main():
    make = "--make-pairs" in sys.argv
    check = "--check" in sys.argv
    if make:
        os.makedirs(PAIRS, exist_ok=True)
        rng = np.random.default_rng(20260522)
        for name, ext, dtype, shape, sigma, _ in CASES:
            a, b = make_pair(name, ext, dtype, shape, sigma, rng)
            write(os.path.join(PAIRS, f"{name}_a.{ext}"), a, ext)
            write(os.path.join(PAIRS, f"{name}_b.{ext}"), b if sigma else a, ext)
    import OpenImageIO
    import skimage
    result = {
        "about": "written by tests/reference/compare_reference.py; do not edit",
        "versions": {"scikit-image": skimage.__version__, "OpenImageIO": OpenImageIO.__version__,
                     "numpy": np.__version__},
        "cases": [compute(name, ext, given) for name, ext, _, _, _, given in CASES],
    }
    if check:
        with open(FIXTURE) as f:
            old = json.load(f)
        bad = []
        for o, n in zip(old["cases"], result["cases"]):
            for lib in ("skimage", "oiio"):
                for k, v in n.get(lib, {}).items():
                    w = o.get(lib, {}).get(k)
                    if (v is None) != (w is None) or (v is not None and abs(v - w) > 1e-9 * max(1, abs(v))):
                        bad.append(f"{n['name']}.{lib}.{k}: fixture {w}, now {v}")
        if bad:
            print("compare fixture differs:\n  " + "\n  ".join(bad))
            sys.exit(1)
        print(f"compare fixture agrees ({len(result['cases'])} cases)")
        return
    with open(FIXTURE, "w") as f:
        json.dump(result, f, indent=1)
        f.write("\n")
    print(f"wrote {FIXTURE}")


if __name__ == "__main__":
    main()
