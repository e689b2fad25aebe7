#!/usr/bin/env python3
"""Peers for benches/solid.rs: scikit-image marching_cubes and (if installed) VTK's
vtkFlyingEdges3D on the same 256³ fields, on 1 and 2 threads, then runs `cargo bench --bench
solid` (which times mra on 1 and 2 threads) in the same session so both are timed together.
Best of 7 runs each; on a shared machine compare the ratios, not the absolute times.

    pip install scikit-image vtk
    python3 benches/peers/solid_peers.py
"""
import subprocess
import time

import numpy as np
from skimage import measure


def field(name, n=256):
    k, j, i = np.meshgrid(*(np.arange(n, dtype=np.float64),) * 3, indexing="ij")
    c = (n - 1) / 2.0
    if name == "sphere":
        v = 0.35 * (n - 1) - np.sqrt((i - c) ** 2 + (j - c) ** 2 + (k - c) ** 2)
    else:
        v = np.sin(0.11 * i) * np.cos(0.13 * j) + np.sin(0.07 * k + 0.3 * np.sin(0.05 * i))
    return v.astype(np.float32)


def best(f, reps=7):
    b, out = float("inf"), None
    for _ in range(reps):
        t = time.perf_counter()
        out = f()
        b = min(b, time.perf_counter() - t)
    return b, out


for name in ["sphere", "noise"]:
    v = field(name)
    s, (verts, faces, _, _) = best(lambda: measure.marching_cubes(v, 0.0))
    print(f"skimage marching_cubes {name} 256^3: {s * 1e3:.1f} ms, {len(faces)} triangles")
    try:
        import vtk
        from vtk.util import numpy_support

        img = vtk.vtkImageData()
        img.SetDimensions(256, 256, 256)
        arr = numpy_support.numpy_to_vtk(v.ravel(), deep=True)
        img.GetPointData().SetScalars(arr)
        for threads in (1, 2):
            vtk.vtkSMPTools.Initialize(threads)
            fe = vtk.vtkFlyingEdges3D()
            fe.SetInputData(img)
            fe.SetValue(0, 0.0)
            fe.ComputeNormalsOff()
            s, _ = best(lambda: (fe.Modified(), fe.Update()))
            print(f"vtk FlyingEdges3D {name} 256^3, {threads} thread(s): {s * 1e3:.1f} ms, "
                  f"{fe.GetOutput().GetNumberOfCells()} triangles")
    except ImportError:
        print("vtk not installed (pip install vtk): FlyingEdges skipped")

subprocess.run(["cargo", "bench", "--bench", "solid"], check=False)
