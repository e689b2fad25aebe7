#!/usr/bin/env python3
"""Bits per voxel of `mra encode --max-error E` against SZ3 (`pysz`, absolute error
bound on the samples as float32, decoded values rounded back to the integer type) on the
corpus CT crop, for E = 0.5, 1, 2, 5, 10; the largest error of each is printed too.

Needs: `pip install pysz numpy`. Usage (from the repository root, after `cargo build --release`):
  python3 benches/peers/codec_max_error.py [--corpus ../shared/corpus] [--mra BIN]
"""
import argparse, os, subprocess, tempfile
import numpy as np
import pysz

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--corpus", default=os.path.join(ROOT, "..", "shared", "corpus"))
    ap.add_argument("--mra", default=os.path.join(ROOT, "target", "release", "mra"))
    a = ap.parse_args()
    raw = os.path.join(a.corpus, "volumes", "ct_pancreas_crop_256x256x64_u16le.raw")
    vol = np.fromfile(raw, dtype="<u2").reshape(64, 256, 256)
    f = vol.astype(np.float32)
    print("| E | SZ3 bits/voxel | SZ3 max error | mra bits/voxel | mra max error |\n|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        enc, out = os.path.join(tmp, "v.mra"), os.path.join(tmp, "v.raw")
        for e in [0.5, 1, 2, 5, 10]:
            cfg = pysz.szConfig()
            cfg.errorBoundMode = pysz.szErrorBoundMode.ABS
            cfg.absErrorBound = e
            c, _ = pysz.sz.compress(f, cfg)
            d = pysz.sz.decompress(c, np.float32, f.shape)
            d = d[0] if isinstance(d, tuple) else d
            sz_err = np.abs(np.round(d) - vol).max()
            subprocess.run([a.mra, "encode", raw, "--dims", "256x256x64", "--dtype", "u16", "-o", enc,
                            "--max-error", str(e)], check=True, stdout=subprocess.DEVNULL)
            subprocess.run([a.mra, "decode", enc, "-o", out], check=True, stdout=subprocess.DEVNULL)
            m = np.fromfile(out, dtype="<u2").reshape(vol.shape)
            mra_err = np.abs(m.astype(np.int64) - vol).max()
            print(f"| {e} | {c.size * 8 / vol.size:.3f} | {sz_err:g} | {os.path.getsize(enc) * 8 / vol.size:.3f} | {mra_err:g} |")


if __name__ == "__main__":
    main()
