#!/usr/bin/env python3
"""Whole-process isosurface timing: `mra volume isosurface` against scikit-image's
read + `marching_cubes` + binary PLY write, on the same 256³ float32 NRRD, in one run.

The field is the "noise" field of benches/peers/solid_peers.py (many small surfaces,
about 1.5 M triangles at level 0). Each side is timed as a whole (process start to file
written), best of `--reps` runs; on a shared machine compare the ratio.

    pip install scikit-image numpy pynrrd
    cargo build --release && python3 benches/peers/isosurface_peer.py
"""
import argparse
import os
import subprocess
import sys
import tempfile
import time

import nrrd
import numpy as np
from skimage import measure


def field(n):
    k, j, i = np.meshgrid(*(np.arange(n, dtype=np.float64),) * 3, indexing="ij")
    v = np.sin(0.11 * i) * np.cos(0.13 * j) + np.sin(0.07 * k + 0.3 * np.sin(0.05 * i))
    return v.astype(np.float32)


def write_ply(path, verts, faces):
    """Binary little-endian PLY: float x y z, uchar/int face lists (one write)."""
    header = (
        "ply\nformat binary_little_endian 1.0\n"
        f"element vertex {len(verts)}\n"
        "property float x\nproperty float y\nproperty float z\n"
        f"element face {len(faces)}\n"
        "property list uchar int vertex_indices\nend_header\n"
    ).encode()
    f = np.empty(len(faces), dtype=[("n", "u1"), ("i", "<i4", (3,))])
    f["n"] = 3
    f["i"] = faces
    with open(path, "wb") as out:
        out.write(header + np.ascontiguousarray(verts, dtype="<f4").tobytes() + f.tobytes())


def skimage_pipeline(src, dst):
    v, _ = nrrd.read(src, index_order="C")
    verts, faces, _, _ = measure.marching_cubes(v, 0.0)
    # scikit-image gives (z, y, x) for a C-ordered array; PLY wants x, y, z
    write_ply(dst, verts[:, ::-1], faces)
    return len(faces)


def best(f, reps):
    b, out = float("inf"), None
    for _ in range(reps):
        t = time.perf_counter()
        out = f()
        b = min(b, time.perf_counter() - t)
    return b, out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mra", default=os.path.join("target", "release", "mra"))
    ap.add_argument("--size", type=int, default=256)
    ap.add_argument("--reps", type=int, default=3)
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as d:
        src = os.path.join(d, "noise.nrrd")
        nrrd.write(src, field(a.size), index_order="C")
        sk, tris = best(lambda: skimage_pipeline(src, os.path.join(d, "sk.ply")), a.reps)
        print(f"scikit-image read + marching_cubes + PLY write: {sk:.3f} s, {tris} triangles")
        rows = []
        for extra in ([], ["--open"]):
            cmd = [a.mra, "volume", "isosurface", src, "--level", "0", "-o",
                   os.path.join(d, "mra.ply")] + extra
            t, _ = best(lambda: subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL), a.reps)
            name = " ".join(["mra volume isosurface"] + extra)
            rows.append((name, t))
            print(f"{name}: {t:.3f} s whole process, {sk / t:.2f}x scikit-image's pipeline")
    return 0


if __name__ == "__main__":
    sys.exit(main())
