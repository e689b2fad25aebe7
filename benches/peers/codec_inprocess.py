#!/usr/bin/env python3
"""The codec in process (the Python package) against SZ3 (`pysz`) on the corpus CT and
against imagecodecs' HTJ2K and OpenJPEG lossless, side by side in one run.

1. Lossy, the corpus CT (`volumes/ct_pancreas_256.nrrd`, 256×256×134 int16) at `--bpp`
   (default 1) bits per voxel: `mra.encode(ct, bpp=B, effort=N)` for each of `--efforts`
   and `mra.decode`, against SZ3 with its absolute bound searched (bisection on log E) to
   mra's bits at that effort. SZ3 gets the samples as float32 and its decode is rounded
   back to int16; both conversions are in its times (a user holding int16 needs them).
   PSNR is `10 log10(R² / MSE)` with R the samples' peak-to-peak range.
2. Lossless: `mra.encode(a, lossless=True, effort=N)` against
   `imagecodecs.htj2k_encode(a, level=0)` (reversible HTJ2K) and
   `imagecodecs.jpeg2k_encode(a, level=0)` (OpenJPEG reversible 5/3) on Kodak images and
   the corpus' 16-bit gray images, and the CT slice by slice for the peers. Every decode is
   checked bit-exact.

Times are the best wall time of `--repeat` calls (time.perf_counter) and, in brackets,
the best CPU time of the process (`time.process_time`: user + system of every thread),
the figure to read on a machine shared with other work (wall times there swing 3× between
calls); the load average before and after is printed. mra runs on `RAYON_NUM_THREADS` threads (all cores by
default), SZ3 and OpenJPEG on one, HTJ2K on one.

Needs: the `mra` package (`pip install ./python`), `pip install pysz imagecodecs numpy pillow`.
Usage (repository root):
  python3 benches/peers/codec_inprocess.py [--corpus ../shared/corpus] [--efforts 1,4,7]
      [--bpp 1] [--repeat 3] [--no-lossy] [--no-lossless] [--kodak 4]
"""
import argparse, os, sys, time
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from codec_speed import read_nrrd_gzip  # noqa: E402  (the corpus CT as (z, y, x) int16)


class Time(float):
    """Best wall seconds, with `.cpu` the best CPU seconds of the process (every thread:
    user + system, `time.process_time`), the figure to read on a shared machine."""


def best(f, repeat):
    """(best seconds as a [`Time`], last result) of `f()` called `repeat` times."""
    t_best, c_best, out = float("inf"), float("inf"), None
    for _ in range(repeat):
        t, c = time.perf_counter(), time.process_time()
        out = f()
        c_best = min(c_best, time.process_time() - c)
        t_best = min(t_best, time.perf_counter() - t)
    t = Time(t_best)
    t.cpu = c_best
    return t, out


def secs(t):
    return f"{t:.3f} ({t.cpu:.3f} CPU)"


def psnr(a, d, rng):
    mse = np.mean((d.astype(np.float64) - a.astype(np.float64)) ** 2)
    return float("inf") if mse == 0 else 10 * np.log10(rng**2 / mse)


def sz3_codec(e):
    import pysz
    cfg = pysz.szConfig()
    cfg.errorBoundMode = pysz.szErrorBoundMode.ABS
    cfg.absErrorBound = e

    def enc(a):
        c, _ = pysz.sz.compress(a.astype(np.float32), cfg)
        return c

    def dec(c, a):
        d = pysz.sz.decompress(c, np.float32, a.shape)
        d = d[0] if isinstance(d, tuple) else d
        return np.round(d).astype(a.dtype)

    return enc, dec


def sz3_at_bits(a, bits):
    """The SZ3 absolute bound whose size is `bits` per voxel (bisection on log E)."""
    lo, hi = 1e-2, 1e4
    for _ in range(16):
        mid = (lo * hi) ** 0.5
        enc, _ = sz3_codec(mid)
        b = enc(a).size * 8 / a.size
        lo, hi = (lo, mid) if b < bits else (mid, hi)
    return hi  # the smaller file side: at or under `bits`


def lossy(a, mra, efforts, bpp, repeat):
    rng = float(a.max()) - float(a.min())
    print(f"CT {'×'.join(map(str, a.shape[::-1]))} {a.dtype}, --bpp {bpp:g}, in process, best of {repeat}\n")
    print("| coder | bits/voxel | PSNR dB | encode s (CPU s) | decode s (CPU s) | encode MB/s | decode MB/s | encode vs SZ3 (CPU) | decode vs SZ3 (CPU) | PSNR − SZ3 |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    mb = a.nbytes / 1e6
    for e in efforts:
        te, c = best(lambda: mra.encode(a, bpp=bpp, effort=e), repeat)
        td, d = best(lambda: mra.decode(c), repeat)
        assert d.dtype == a.dtype and d.shape == a.shape
        bits = len(c) * 8 / a.size
        p = psnr(a, d, rng)
        eb = sz3_at_bits(a, bits)
        enc, dec = sz3_codec(eb)
        se, sc = best(lambda: enc(a), repeat)
        sd, sdd = best(lambda: dec(sc, a), repeat)
        sbits = sc.size * 8 / a.size
        sp = psnr(a, sdd, rng)
        print(f"| mra effort {e} | {bits:.3f} | {p:.2f} | {secs(te)} | {secs(td)} | {mb / te:.0f} | {mb / td:.0f} | "
              f"{se / te:.2f}× ({se.cpu / te.cpu:.2f}×) | {sd / td:.2f}× ({sd.cpu / td.cpu:.2f}×) | {p - sp:+.2f} dB |")
        print(f"| SZ3 E={eb:.3g} | {sbits:.3f} | {sp:.2f} | {secs(se)} | {secs(sd)} | {mb / se:.0f} | {mb / sd:.0f} | | | |")


def lossless_rows(name, a, mra, efforts, repeat, slices):
    """Rows (coder, bits/sample, encode s, decode s) for `a`; `slices`: peers per 2-D slice."""
    import imagecodecs as ic
    rows = []
    n = a.size
    for e in efforts:
        te, c = best(lambda: mra.encode(a, lossless=True, effort=e), repeat)
        td, d = best(lambda: mra.decode(c), repeat)
        assert np.array_equal(d, a), f"mra not exact on {name}"
        rows.append((f"mra effort {e}", len(c) * 8 / n, te, td))
    planes = list(a) if slices else [a]
    for label, encf, decf in (("HTJ2K", lambda p: ic.htj2k_encode(p, level=0), ic.htj2k_decode),
                              ("OpenJPEG 5/3", lambda p: ic.jpeg2k_encode(p, level=0), ic.jpeg2k_decode)):
        te, cs = best(lambda: [encf(p) for p in planes], repeat)
        td, ds = best(lambda: [decf(x) for x in cs], repeat)
        assert all(np.array_equal(np.asarray(x).reshape(p.shape), p) for x, p in zip(ds, planes)), \
            f"{label} not exact on {name}"
        rows.append((label, sum(len(x) for x in cs) * 8 / n, te, td))
    return rows


def lossless(corpus, mra, efforts, repeat, kodak):
    from PIL import Image
    items = []
    kdir = os.path.join(corpus, "images", "kodak")
    for f in sorted(x for x in os.listdir(kdir) if x.endswith(".png"))[:kodak]:
        items.append((f, np.asarray(Image.open(os.path.join(kdir, f))), False))
    hdir = os.path.join(corpus, "images", "highbit")
    for f in sorted(x for x in os.listdir(hdir) if x.endswith(".png")):
        g = np.asarray(Image.open(os.path.join(hdir, f)))
        if g.ndim == 2:
            items.append((f, g.astype(np.uint16), False))
    items.append(("CT 256×256×134 i16", read_nrrd_gzip(os.path.join(corpus, "volumes", "ct_pancreas_256.nrrd")), True))
    print(f"\nLossless, in process, best of {repeat} (Kodak RGB as one array channels last; "
          "the CT slice by slice for the peers)\n")
    print("| input | coder | bits/sample | encode s (CPU s) | decode s (CPU s) | decode vs HTJ2K (CPU) | bits vs OpenJPEG |")
    print("|---|---|---|---|---|---|---|")
    for name, a, vol in items:
        # mra takes channels last through the package's keyword
        global_mra = mra
        if a.ndim == 3 and not vol:
            class M:
                encode = staticmethod(lambda x, **k: global_mra.encode(x, channels_last=True, **k))
                decode = staticmethod(global_mra.decode)
            m = M
        else:
            m = mra
        rows = lossless_rows(name, a, m, efforts, repeat, vol)
        ht = next(r for r in rows if r[0] == "HTJ2K")
        oj = next(r for r in rows if r[0] == "OpenJPEG 5/3")
        for coder, bits, te, td in rows:
            print(f"| {name} | {coder} | {bits:.3f} | {secs(te)} | {secs(td)} | {ht[3] / td:.2f}× "
                  f"({ht[3].cpu / td.cpu:.2f}×) | {bits / oj[1]:.3f} |")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--corpus", default=os.path.join(ROOT, "..", "shared", "corpus"))
    ap.add_argument("--efforts", default="1,4,7")
    ap.add_argument("--bpp", type=float, default=1.0)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--kodak", type=int, default=4, help="Kodak images in the lossless table")
    ap.add_argument("--no-lossy", action="store_true")
    ap.add_argument("--no-lossless", action="store_true")
    a = ap.parse_args()
    import mra
    efforts = [int(e) for e in a.efforts.split(",")]
    load0 = os.getloadavg()[0]
    if not a.no_lossy:
        ct = read_nrrd_gzip(os.path.join(a.corpus, "volumes", "ct_pancreas_256.nrrd"))
        lossy(ct, mra, efforts, a.bpp, a.repeat)
    if not a.no_lossless:
        lossless(a.corpus, mra, efforts, a.repeat, a.kodak)
    print(f"\nload average {load0:.1f} before, {os.getloadavg()[0]:.1f} after; "
          f"RAYON_NUM_THREADS={os.environ.get('RAYON_NUM_THREADS', 'unset')}", file=sys.stderr)


if __name__ == "__main__":
    main()
