#!/usr/bin/env python3
"""A u16 volume written to Zarr stores through dask.array on a 2-worker
dask.distributed.LocalCluster, once per codec, read back and compared with the source:
mra (max_error and lossless) beside Blosc/Zstd and Zstd (lossless), ZFP (numcodecs
ZFPY, fixed accuracy) and SZ3 (pysz, absolute bound) where they install.

The volume is generated chunk by chunk (never whole in memory): a smooth field (sum of
cosines over the axes) scaled to 0..60000 plus Gaussian noise of σ = 40, so that it
compresses like a CT scan rather than like a test pattern. Each row: compressed ratio
(raw bytes / stored chunk bytes), PSNR over the range 65535 and the largest absolute
error against the source, write and read throughput in MB/s of raw data (write time
includes generating the source; the `generate` row gives that time alone), and the peak
resident memory of each worker process (`ru_maxrss` gathered by `Client.run`; the
cluster is started anew for every codec).

Needs: `pip install ./python[dask]` (and `zfpy==1.0.1`, `pysz` for those rows: zfpy
1.0.1.post0's version string makes `import numcodecs` fail). Usage:
  python3 benches/peers/dask_zarr.py [--size 1024] [--chunk 128] [--max-error 4]
      [--memory-limit 2GiB] [--out /tmp/dask_zarr] [--markdown]
"""

import argparse
import os
import resource
import shutil
import sys
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "examples"))
from dask_zarr import source_volume  # noqa: E402  (the example's generator)


def codecs(max_error):
    """(name, numcodecs codec or None for pysz, what) for every codec that imports."""
    import numcodecs
    from mra._numcodecs import Mra

    out = [
        (f"mra max_error={max_error:g}", Mra(max_error=max_error), "lossy"),
        ("mra lossless", Mra(lossless=True), "lossless"),
        ("blosc zstd-5 shuffle", numcodecs.Blosc(cname="zstd", clevel=5, shuffle=numcodecs.Blosc.SHUFFLE), "lossless"),
        ("zstd-5", numcodecs.Zstd(level=5), "lossless"),
    ]
    try:
        import zfpy
        from numcodecs.zfpy import ZFPY

        # fixed-accuracy mode (tolerance on float64 samples); decoded values are
        # rounded back to u16 by the store's dtype cast below
        out.append((f"zfp accuracy={max_error:g}", ("zfp", ZFPY(mode=zfpy.mode_fixed_accuracy, tolerance=max_error)), "lossy"))
    except Exception as e:  # zfpy not installed
        print(f"# zfp skipped: {e}", file=sys.stderr)
    try:
        import pysz  # noqa: F401

        out.append((f"sz3 abs={max_error:g}", ("sz3", max_error), "lossy"))
    except Exception as e:
        print(f"# sz3 skipped: {e}", file=sys.stderr)
    return out


class FloatWrap:
    """A numcodecs-style codec around a float codec for u16 chunks: samples go in as
    float32 (ZFP: float64), come out rounded and clipped to u16."""

    def __init__(self, kind, arg):
        self.kind, self.arg = kind, arg

    def encode(self, a):
        a = np.asarray(a)
        if self.kind == "zfp":
            return self.arg.encode(np.ascontiguousarray(a, dtype=np.float64))
        import pysz

        cfg = pysz.szConfig()
        cfg.errorBoundMode = pysz.szErrorBoundMode.ABS
        cfg.absErrorBound = float(self.arg)
        c, _ = pysz.sz.compress(np.ascontiguousarray(a, dtype=np.float32), cfg)
        head = np.array(a.shape, dtype=np.int64)
        return np.concatenate([np.array([len(a.shape)], np.int64), head]).tobytes() + c.tobytes()

    def decode(self, b, shape):
        if self.kind == "zfp":
            d = self.arg.decode(b)
        else:
            import pysz

            raw = bytes(b)
            nd = int(np.frombuffer(raw[:8], np.int64)[0])
            shp = tuple(int(n) for n in np.frombuffer(raw[8 : 8 + 8 * nd], np.int64))
            d = pysz.sz.decompress(np.frombuffer(raw[8 + 8 * nd :], np.uint8), np.float32, shp)
            d = d[0] if isinstance(d, tuple) else d
        return np.clip(np.round(np.asarray(d).reshape(shape)), 0, 65535).astype(np.uint16)


def write_read(client, arr, path, codec, chunk):
    """Store ``arr`` with ``codec`` (timed), read it back as a dask array (timed through
    the comparison). Float peers go through per-block encode/decode to files."""
    import dask.array as da
    import zarr

    if isinstance(codec, tuple):
        # float peers: each block coded to its own file (what a Zarr store holds)
        wrap = FloatWrap(*codec)
        os.makedirs(path, exist_ok=True)

        def put(block, block_info=None):
            loc = block_info[0]["chunk-location"]
            data = wrap.encode(block)
            with open(os.path.join(path, "_".join(map(str, loc))), "wb") as f:
                f.write(data)
            return np.array([len(data)], dtype=np.int64).reshape((1,) * block.ndim)

        t = time.perf_counter()
        sizes = arr.map_blocks(put, dtype=np.int64, chunks=(1,) * arr.ndim).sum().compute()
        t_write = time.perf_counter() - t

        def get(block_info=None):
            info = block_info[None]
            loc = info["chunk-location"]
            with open(os.path.join(path, "_".join(map(str, loc))), "rb") as f:
                return wrap.decode(f.read(), info["chunk-shape"])

        back = da.map_blocks(get, dtype=np.uint16, chunks=arr.chunks)
        return t_write, int(sizes), back

    z = zarr.create_array(
        store=path, shape=arr.shape, chunks=(chunk,) * arr.ndim, dtype=arr.dtype,
        compressors=codec, zarr_format=2, fill_value=0, overwrite=True,
    )
    t = time.perf_counter()
    da.store(arr, z, lock=False, compute=True)
    t_write = time.perf_counter() - t
    stored = sum(
        os.path.getsize(os.path.join(d, f))
        for d, _, fs in os.walk(path)
        for f in fs
        if not f.startswith(".") and f != "zarr.json"
    )
    return t_write, stored, da.from_zarr(path)


def errors(a, b):
    """(MSE, max |a − b|) of two dask arrays, computed chunk by chunk."""
    import dask.array as da

    d = a.astype(np.float64) - b.astype(np.float64)
    return da.compute((d * d).mean(), abs(d).max())


def peak_rss(client):
    """Peak resident memory of each worker process, MiB."""
    return sorted(v / 1024 for v in client.run(lambda: resource.getrusage(resource.RUSAGE_SELF).ru_maxrss).values())


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--size", type=int, default=1024, help="edge of the cube (1024: 2 GiB of u16)")
    ap.add_argument("--chunk", type=int, default=128)
    ap.add_argument("--max-error", type=float, default=4.0)
    ap.add_argument("--memory-limit", default="2GiB", help="per worker")
    ap.add_argument("--out", default="/tmp/mra_dask_zarr")
    ap.add_argument("--only", default=None, help="substring: run only matching codecs")
    a = ap.parse_args()

    from dask.distributed import Client, LocalCluster

    shape = (a.size,) * 3
    raw_mb = np.prod(shape) * 2 / 1e6
    rows = []
    for name, codec, kind in [("generate", None, "-")] + codecs(a.max_error):
        if a.only and a.only not in name and name != "generate":
            continue
        with LocalCluster(n_workers=2, threads_per_worker=1, memory_limit=a.memory_limit,
                          processes=True, dashboard_address=None) as cluster, Client(cluster) as client:
            src = source_volume(shape, a.chunk)
            if codec is None:
                t = time.perf_counter()
                src.sum().compute()
                rows.append((name, kind, "-", "-", "-", f"{raw_mb / (time.perf_counter() - t):.1f}", "-",
                             " / ".join(f"{m:.0f}" for m in peak_rss(client))))
                continue
            path = os.path.join(a.out, name.replace(" ", "_").replace("=", ""))
            shutil.rmtree(path, ignore_errors=True)
            t_write, stored, back = write_read(client, src, path, codec, a.chunk)
            t = time.perf_counter()
            mse, emax = errors(src, back)
            t_read = time.perf_counter() - t
            psnr = float("inf") if mse == 0 else 10 * np.log10(65535.0**2 / mse)
            rows.append((name, kind, f"{np.prod(shape) * 2 / stored:.2f}",
                         "inf" if psnr == float("inf") else f"{psnr:.2f}", f"{emax:g}",
                         f"{raw_mb / t_write:.1f}", f"{raw_mb / t_read:.1f}",
                         " / ".join(f"{m:.0f}" for m in peak_rss(client))))
            shutil.rmtree(path, ignore_errors=True)
        print(" | ".join(rows[-1]), file=sys.stderr, flush=True)
    print(f"\n{a.size}³ u16 ({raw_mb / 1e3:.2f} GB raw), chunks {a.chunk}³, LocalCluster 2 workers × 1 thread, "
          f"memory_limit {a.memory_limit} each\n")
    print("| codec | kind | ratio | PSNR dB | max error | write MB/s | read+compare MB/s | worker peak RSS MiB |")
    print("|---|---|---|---|---|---|---|---|")
    for r in rows:
        print("| " + " | ".join(r) + " |")


if __name__ == "__main__":
    main()
