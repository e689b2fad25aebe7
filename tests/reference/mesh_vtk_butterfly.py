#!/usr/bin/env python3
"""Reference fixture from VTK's vtkButterflySubdivisionFilter (modified butterfly, Zorin et al.).

Writes tests/reference/mesh_vtk_butterfly.json for small closed triangle meshes with valences
3 to 6 (and one with a boundary, where VTK uses the 4-point rule on boundary edges). VTK
stores the points as float32, so the Rust test compares to 1e-6 relative.

Rerun:  pip install vtk && python3 tests/reference/mesh_vtk_butterfly.py
"""
import json
import math
import os

import vtk
from vtk.util.numpy_support import vtk_to_numpy

HERE = os.path.dirname(os.path.abspath(__file__))


def bumpy(V, amp):
    return [[x + amp * math.sin(1.3 * i + 0.3), y + amp * math.sin(2.1 * i + 1.1), z + amp * math.sin(0.7 * i + 2.3)]
            for i, (x, y, z) in enumerate(V)]


def octa():
    V = [[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]]
    F = [[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]]
    return bumpy([[float(x) for x in v] for v in V], 0.1), F


def tri_cube():
    V = [[float(i & 1), float((i >> 1) & 1), float((i >> 2) & 1)] for i in range(8)]
    Q = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]]
    F = []
    for q in Q:
        F += [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]
    return bumpy(V, 0.05), F


def icosahedron():
    t = (1 + 5 ** 0.5) / 2
    V = [[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t], [0, -1, -t], [0, 1, -t],
         [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]]
    F = [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4], [11, 10, 2],
         [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9], [4, 9, 5],
         [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]]
    return bumpy([[float(x) for x in v] for v in V], 0.1), F


def run(V, F, levels):
    pts = vtk.vtkPoints()
    pts.SetDataTypeToDouble()
    for v in V:
        pts.InsertNextPoint(*v)
    cells = vtk.vtkCellArray()
    for f in F:
        cells.InsertNextCell(len(f), f)
    pd = vtk.vtkPolyData()
    pd.SetPoints(pts)
    pd.SetPolys(cells)
    flt = vtk.vtkButterflySubdivisionFilter()
    flt.SetInputData(pd)
    flt.SetNumberOfSubdivisions(levels)
    flt.Update()
    out = flt.GetOutput()
    RV = vtk_to_numpy(out.GetPoints().GetData()).astype(float).tolist()
    conn = vtk_to_numpy(out.GetPolys().GetConnectivityArray()).reshape(-1, 3).tolist()
    return {"V": RV, "F": conn}


cases = []
for name, (V, F), levels in [("octahedron", octa(), 1), ("octahedron_2", octa(), 2), ("tri_cube", tri_cube(), 1),
                             ("icosahedron", icosahedron(), 2)]:
    cases.append({"name": name, "levels": levels, "input": {"V": V, "F": F}, "output": run(V, F, levels)})
with open(os.path.join(HERE, "mesh_vtk_butterfly.json"), "w") as f:
    json.dump({"generator": "VTK " + vtk.vtkVersion.GetVTKVersion(), "cases": cases}, f)
print("wrote", len(cases), "cases")
