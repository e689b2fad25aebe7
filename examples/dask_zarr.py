#!/usr/bin/env python3
"""A volume beyond one process's comfort, through Zarr and Dask with the mra codec.

A u16 cube is generated chunk by chunk as a dask array, written to a Zarr store whose
chunks are coded by `mra.Mra` (every sample within `--max-error` of the source) on a
`dask.distributed.LocalCluster` of 2 single-thread workers, read back and compared with
the source, chunk by chunk: no process ever holds the whole volume.

Needs: `pip install ./python[dask]`. Usage:
  python3 examples/dask_zarr.py [--size 512] [--chunk 128] [--max-error 4] [--store /tmp/v.zarr]
The benchmark beside the peers (Blosc/Zstd, ZFP, SZ3) is benches/peers/dask_zarr.py.
"""

import argparse
import time

import numpy as np


def source_volume(shape, chunk, seed=0):
    """A dask array of ``shape`` (u16, chunks ``chunk``³): a smooth field, the sum of
    cosines along the axes scaled to 0..60000, plus Gaussian noise of σ = 40 drawn per
    chunk from ``seed`` and the chunk's position (so any chunk is reproducible alone)."""
    import dask.array as da

    def block(block_info=None):
        info = block_info[None]
        (z0, z1), (y0, y1), (x0, x1) = info["array-location"]
        z, y, x = np.ogrid[z0:z1, y0:y1, x0:x1]
        n = np.array(shape, dtype=np.float64)
        f = (np.cos(3 * np.pi * z / n[0]) + np.cos(5 * np.pi * y / n[1] + 1)
             + np.cos(7 * np.pi * x / n[2] + 2)) / 3  # [-1, 1]
        rng = np.random.default_rng([seed, *info["chunk-location"]])
        f = 30000 + 29000 * f + 40 * rng.standard_normal(f.shape)
        return np.clip(np.round(f), 0, 65535).astype(np.uint16)

    chunks = tuple(tuple([chunk] * (n // chunk) + ([n % chunk] if n % chunk else [])) for n in shape)
    return da.map_blocks(block, dtype=np.uint16, chunks=chunks)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--size", type=int, default=512)
    ap.add_argument("--chunk", type=int, default=128)
    ap.add_argument("--max-error", type=float, default=4.0)
    ap.add_argument("--store", default="/tmp/mra_dask_example.zarr")
    a = ap.parse_args()

    import dask.array as da
    import zarr
    from dask.distributed import Client, LocalCluster

    from mra import Mra  # the numcodecs codec (also found by id "mra" through its entry point)

    shape = (a.size,) * 3
    with LocalCluster(n_workers=2, threads_per_worker=1, memory_limit="2GiB",
                      dashboard_address=None) as cluster, Client(cluster):
        src = source_volume(shape, a.chunk)
        z = zarr.create_array(store=a.store, shape=shape, chunks=(a.chunk,) * 3, dtype="u2",
                              compressors=Mra(max_error=a.max_error), zarr_format=2,
                              fill_value=0, overwrite=True)
        t = time.perf_counter()
        da.store(src, z, lock=False)
        t_write = time.perf_counter() - t
        back = da.from_zarr(a.store)
        d = abs(back.astype(np.int32) - src.astype(np.int32))
        emax, mse = da.compute(d.max(), (d.astype(np.float64) ** 2).mean())
    print(f"{a.size}³ u16 written in {t_write:.1f} s, max error {emax} (bound {a.max_error}), "
          f"PSNR {10 * np.log10(65535**2 / mse):.2f} dB")
    assert emax <= a.max_error


if __name__ == "__main__":
    main()
