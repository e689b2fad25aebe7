#!/usr/bin/env python3
"""Reference isosurface area and enclosed volume from scikit-image's marching cubes.

Writes tests/reference/solid_skimage.json, read by tests/solid.rs
(`area_and_volume_match_scikit_image`), which rebuilds the same fields in Rust.

    pip install scikit-image numpy
    python3 tests/reference/solid_skimage.py
"""
import json
import os

import numpy as np
from skimage import measure


def field(name, dims):
    nx, ny, nz = dims
    z, y, x = np.meshgrid(np.arange(nz, dtype=np.float64), np.arange(ny, dtype=np.float64),
                          np.arange(nx, dtype=np.float64), indexing="ij")
    c = [(nx - 1) / 2.0, (ny - 1) / 2.0, (nz - 1) / 2.0]
    r = np.sqrt((x - c[0]) ** 2 + (y - c[1]) ** 2 + (z - c[2]) ** 2)
    if name == "sphere":
        v = 0.35 * (nx - 1) - r
    else:  # a bumpy closed blob
        v = np.sin(0.31 * x) * np.cos(0.23 * y) + np.sin(0.17 * z + 0.4) + 3.0 - 0.4 * r
    return v.astype(np.float32)  # indexed [z, y, x], x fastest like the Rust grid


def area_volume(verts, faces):
    a, b, c = verts[faces[:, 0]], verts[faces[:, 1]], verts[faces[:, 2]]
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1).sum()
    vol = np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0
    return float(area), float(vol)


cases = []
for name, dims, spacing, level in [
    ("sphere", [48, 48, 48], [1.0, 1.0, 1.0], 0.0),
    ("blob", [40, 40, 32], [1.0, 0.8, 1.5], 0.0),
]:
    v = field(name, dims)
    verts, faces, _, _ = measure.marching_cubes(v, level, spacing=(spacing[2], spacing[1], spacing[0]))
    verts = verts[:, ::-1]  # (z, y, x) -> (x, y, z)
    area, vol = area_volume(verts, faces)
    cases.append({"name": name, "dims": dims, "spacing": spacing, "level": level,
                  "area": area, "volume": abs(vol), "faces": int(len(faces))})
    print(name, len(faces), "faces, area", area, "volume", abs(vol))

out = os.path.join(os.path.dirname(os.path.abspath(__file__)), "solid_skimage.json")
with open(out, "w") as f:
    json.dump(cases, f, indent=1)
