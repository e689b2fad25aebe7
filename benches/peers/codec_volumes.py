#!/usr/bin/env python3
"""The codec on every corpus volume and DEM against SZ3 (`pysz`), SPERR (its `sperr3d` /
`sperr2d` commands), ZFP (`zfpy`), OpenJPEG and Zstd/Blosc, in three tables:

1. fixed rates 0.5 / 1 / 2 bits per sample: PSNR of `mra encode --bpp B` (at each effort of
   `--efforts`), of SPERR's fixed-rate mode (its `--bpp` lowered until the file, header
   included, is within B), of ZFP's fixed-rate mode and of SZ3
   with its absolute bound searched (bisection) to the same rate;
2. `--max-error E` (E = 0.5, 1, 2, 5, 10, metres on DEMs): bits per sample of mra (at each
   effort) and of SZ3 and SPERR (its point-wise error mode, `--pwe E`) at the same absolute
   bound, and the largest error each decodes with;
3. lossless: bits per sample of `mra encode --lossless`, OpenJPEG reversible 5/3 (slice by
   slice through imagecodecs), Zstd (level 19) and Blosc (zstd, byte shuffle, level 9) on the
   raw samples. Every lossless result is checked bit-exact.

Peers get the samples as stored (voids included: the SRTM tiles' -32768, the ESRI grid's
nodata) as float32 for SZ3 and ZFP, their output rounded back to the sample type. PSNR is
`10 log10(R² / MSE)` with R the peak-to-peak range of the samples, over all samples.

Needs: `pip install pysz zfpy imagecodecs numpy`; SPERR is built from its source (CMake; its
`sperr3d` and `sperr2d` in one folder, given as `--sperr DIR`; without it the SPERR columns
say so). Usage (repository root, after `cargo build --release`):
  python3 benches/peers/codec_volumes.py [--corpus ../shared/corpus] [--mra BIN] [--only NAME]
      [--sperr DIR] [--efforts default,9] [--tables rate,max-error,lossless]
"""
import argparse, json, os, subprocess, sys, tempfile
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

DATA = [  # name, path under the corpus, DEM (errors in metres)
    ("CT 256×256×134 i16", "volumes/ct_pancreas_256.nrrd", False),
    ("CT crop 256×256×64 u16", "volumes/ct_pancreas_crop_256x256x64_u16le.raw", False),
    ("MRI 197×233×189 u8", "volumes/mni152_t1_2009a_1mm.nii.gz", False),
    ("SRTM N22W160 i16 (voids)", "terrain/N22W160.hgt", True),
    ("SRTM N44W072 i16", "terrain/N44W072.hgt", True),
    ("Mt St Helens f32", "terrain/mt_st_helens_30m_f32.tif", True),
    ("Boulder ASC i32 (nodata)", "terrain/srtmgl3_boulder_co.asc", True),
]
RAW_ARGS = ["--dims", "256x256x64", "--dtype", "u16"]
DTYPES = {"u8": "<u1", "i8": "<i1", "u16": "<u2", "i16": "<i2", "u32": "<u4", "i32": "<i4", "f32": "<f4", "f64": "<f8"}


def run(cmd):
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)


class Item:
    def __init__(self, mra, path, tmp):
        self.mra, self.path, self.tmp = mra, path, tmp
        self.extra = RAW_ARGS if path.endswith(".raw") else []
        info = json.loads(subprocess.run([mra, "info", path, "--json"] + self.extra, check=True,
                                         capture_output=True, text=True).stdout)
        self.dims, self.dtype = info["dims"], info["dtype"]
        raw = os.path.join(tmp, "src.raw")
        run([mra, "convert", path, "-o", raw] + self.extra)
        self.a = np.fromfile(raw, dtype=DTYPES[self.dtype]).reshape(self.dims[::-1])
        self.n = self.a.size
        self.f = self.a.astype(np.float32)
        self.range = float(self.f.max() - self.f.min())

    def psnr(self, d):
        mse = np.mean((d.astype(np.float64) - self.a.astype(np.float64)) ** 2)
        return float("inf") if mse == 0 else 10 * np.log10(self.range**2 / mse)

    def back(self, d):
        if np.issubdtype(self.a.dtype, np.integer):
            info = np.iinfo(self.a.dtype)
            return np.clip(np.round(d), info.min, info.max).astype(self.a.dtype)
        return d.astype(self.a.dtype)

    def mra_run(self, args, effort="default"):
        enc, out = os.path.join(self.tmp, "v.mra"), os.path.join(self.tmp, "v.raw")
        eff = [] if effort == "default" else ["--effort", str(effort)]
        run([self.mra, "encode", self.path, "-o", enc] + self.extra + args + eff)
        run([self.mra, "decode", enc, "-o", out])
        d = np.fromfile(out, dtype=DTYPES[self.dtype]).reshape(self.a.shape)
        return os.path.getsize(enc) * 8 / self.n, d


def sz3(f, e):
    import pysz
    cfg = pysz.szConfig()
    cfg.errorBoundMode = pysz.szErrorBoundMode.ABS
    cfg.absErrorBound = e
    c, _ = pysz.sz.compress(f, cfg)
    d = pysz.sz.decompress(c, np.float32, f.shape)
    return c.size * 8 / f.size, (d[0] if isinstance(d, tuple) else d)


def sz3_at_rate(it, bits):
    lo, hi = 1e-3, it.range
    best = None
    for _ in range(18):
        e = np.sqrt(lo * hi)
        b, d = sz3(it.f, e)
        if b > bits:
            lo = e
        else:
            hi, best = e, (b, d)
        if best and abs(best[0] - bits) / bits < 0.01:
            break
    return best


def sperr(it, sperr_dir, mode, q):
    """SPERR on the samples as float32 (`mode` `bpp` or `pwe`, value `q`): (bits per sample,
    decoded float32 array), or None without `--sperr`."""
    if not sperr_dir:
        return None
    src, bs, out = (os.path.join(it.tmp, n) for n in ("sp.f32", "sp.bin", "sp.out"))
    it.f.tofile(src)
    dims = [str(d) for d in it.f.shape[::-1]]  # fastest-varying first
    exe = os.path.join(sperr_dir, "sperr3d" if it.f.ndim == 3 else "sperr2d")
    run([exe, src, "-c", "--ftype", "32", "--dims"] + dims + [f"--{mode}", str(q), "--bitstream", bs])
    run([exe, bs, "-d", "--decomp_f", out])
    d = np.fromfile(out, dtype=np.float32).reshape(it.f.shape)
    return os.path.getsize(bs) * 8 / it.n, d


def sperr_at_rate(it, sperr_dir, bits):
    """SPERR's fixed-rate mode held to the budget as mra and SZ3 are (its file counts a
    header its `--bpp` leaves out): the rate asked lowered until the file is within it."""
    q = bits
    for _ in range(5):
        s = sperr(it, sperr_dir, "bpp", q)
        if s is None or s[0] <= bits:
            return s
        q *= bits / s[0] * 0.999
    return s


def zfp_at_rate(it, bits):
    import zfpy
    c = zfpy.compress_numpy(it.f, rate=bits)
    return len(c) * 8 / it.n, zfpy.decompress_numpy(c)


def fixed_rates(it, name, rows, a):
    for bits in [0.5, 1, 2]:
        ms = []
        for eff in a.efforts:
            mb, md = it.mra_run(["--bpp", str(bits)], eff)
            ms.append(f"{it.psnr(md):.2f} ({mb:.3f})")
        s = sz3_at_rate(it, bits)
        sp = sperr_at_rate(it, a.sperr, bits)
        spr = f"{it.psnr(it.back(sp[1])):.2f} ({sp[0]:.3f})" if sp else "n/a"
        if it.a.ndim == 2 and bits < 1:
            z = "n/a (zfpy aborts below 1 bit in 2-D)"
        else:
            zb, zd = zfp_at_rate(it, bits)
            z = f"{it.psnr(it.back(zd)):.2f} ({zb:.3f})"
        sz = f"{it.psnr(it.back(s[1])):.2f} ({s[0]:.3f})" if s else "n/a"
        rows.append(f"| {name} | {bits} | {' | '.join(ms)} | {sz} | {spr} | {z} |")


def max_errors(it, name, rows, a):
    for e in [0.5, 1, 2, 5, 10]:
        ms, mbs = [], []
        for eff in a.efforts:
            mb, md = it.mra_run(["--max-error", str(e)], eff)
            me = np.abs(md.astype(np.float64) - it.a).max()
            assert me <= e, f"mra over the bound on {name} at E = {e}: {me}"
            ms.append(f"{mb:.3f} ({me:g})")
            mbs.append(mb)
        sb, sd = sz3(it.f, e)
        se = np.abs(sd.astype(np.float64) - it.a).max()  # SZ3's own bound, before rounding
        sp = sperr(it, a.sperr, "pwe", e)
        spr = "n/a"
        if sp:  # SPERR's own bound too, before rounding
            spr = f"{sp[0]:.3f} ({np.abs(sp[1].astype(np.float64) - it.a).max():g})"
        peers = [sb] + ([sp[0]] if sp else [])
        won = "yes" if min(mbs) < min(peers) else "no"
        rows.append(f"| {name} | {e:g} | {' | '.join(ms)} | {sb:.3f} ({se:g}) | {spr} | {won} |")


def lossless(it, name, rows):
    import imagecodecs as ic
    mb, md = it.mra_run(["--lossless"])
    assert np.array_equal(md, it.a), f"mra not exact on {name}"
    raw = it.a.tobytes()
    zs = len(ic.zstd_encode(raw, level=19)) * 8 / it.n
    bl = len(ic.blosc_encode(raw, level=9, compressor="zstd", typesize=it.a.itemsize, shuffle=1)) * 8 / it.n
    j2 = "n/a"
    if it.a.dtype != np.float32:
        sl = it.a if it.a.ndim == 3 else it.a[None]
        tot = 0
        for s in sl:
            # OpenJPEG codes unsigned or signed integers up to 16 bits (i32 grids fit i16 here)
            s2 = s.astype(np.int16) if s.dtype == np.int32 else s
            c = ic.jpeg2k_encode(s2, level=0, reversible=True)
            assert np.array_equal(ic.jpeg2k_decode(c).astype(s.dtype), s), f"OpenJPEG not exact on {name}"
            tot += len(c)
        j2 = f"{tot * 8 / it.n:.3f}"
    best = min([zs, bl] + ([float(j2)] if j2 != "n/a" else []))
    rows.append(f"| {name} | {mb:.3f} | {j2} | {zs:.3f} | {bl:.3f} | {'yes' if mb <= best else 'no'} |")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--corpus", default=os.path.join(ROOT, "..", "shared", "corpus"))
    ap.add_argument("--mra", default=os.path.join(ROOT, "target", "release", "mra"))
    ap.add_argument("--only", default=None, help="run the data sets whose name contains this")
    ap.add_argument("--tables", default="rate,max-error,lossless")
    ap.add_argument("--sperr", default=None, help="folder holding SPERR's sperr3d and sperr2d")
    ap.add_argument("--efforts", default="default", help="mra efforts, comma-separated: default or 1-9")
    a = ap.parse_args()
    a.efforts = a.efforts.split(",")
    if not a.sperr:
        print("SPERR columns skipped: no --sperr DIR (build SPERR with CMake, give its bin folder)",
              file=sys.stderr)
    tables = a.tables.split(",")
    rate, maxe, loss = [], [], []
    with tempfile.TemporaryDirectory() as tmp:
        for name, rel, _dem in DATA:
            if a.only and a.only not in name:
                continue
            print(f"{name} ...", file=sys.stderr, flush=True)
            it = Item(a.mra, os.path.join(a.corpus, rel), tmp)
            if "rate" in tables:
                fixed_rates(it, name, rate, a)
            if "max-error" in tables:
                max_errors(it, name, maxe, a)
            if "lossless" in tables:
                lossless(it, name, loss)
    mras = " | ".join(f"mra {'default' if e == 'default' else 'effort ' + e}" for e in a.efforts)
    bars = "---|" * len(a.efforts)
    if rate:
        print("PSNR (dB) at a fixed rate, (bits per sample) in brackets\n")
        print(f"| data | bits | {mras} | SZ3 | SPERR | ZFP |\n|---|---|{bars}---|---|---|")
        print("\n".join(rate) + "\n")
    if maxe:
        print("bits per sample at a guaranteed maximum error E\n")
        print("(largest error in brackets)\n")
        print(f"| data | E | {mras} | SZ3 | SPERR | mra fewer |\n|---|---|{bars}---|---|---|")
        print("\n".join(maxe) + "\n")
    if loss:
        print("lossless bits per sample\n")
        print("| data | mra | OpenJPEG 5/3 | Zstd 19 | Blosc zstd 9 | mra smallest |\n|---|---|---|---|---|---|")
        print("\n".join(loss))


if __name__ == "__main__":
    main()
