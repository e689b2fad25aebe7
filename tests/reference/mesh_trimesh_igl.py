#!/usr/bin/env python3
"""Reference fixtures for the mesh module from trimesh and libigl.

Writes tests/reference/mesh_trimesh_igl.json with, for a few small generated meshes (closed,
irregular valences, and one with a boundary):
  - trimesh.remesh.subdivide_loop (Loop's weights)        -> compared to mra Loop to 1e-12
  - igl.loop (Warren's weights)                            -> compared to mra loop-warren to 1e-12
  - igl.per_vertex_normals UNIFORM / AREA / ANGLE          -> compared to 1e-12
  - igl.cotmatrix (as triplets)                            -> compared to 1e-12

Rerun:  pip install trimesh libigl numpy scipy && python3 tests/reference/mesh_trimesh_igl.py
"""
import json
import os

import igl
import numpy as np
import trimesh

HERE = os.path.dirname(os.path.abspath(__file__))


def bumpy(V, amp=0.1):
    """Deterministic perturbation so no two vertices are symmetric."""
    k = np.arange(len(V))[:, None] * np.array([[1.3, 2.1, 0.7]])
    return V + amp * np.sin(k + np.array([[0.3, 1.1, 2.3]]))


def octa_sphere():
    V = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], float)
    F = np.array([[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]])
    m = trimesh.Trimesh(V, F, process=False).subdivide()  # midpoint split: valences 4 and 6
    return bumpy(np.asarray(m.vertices)), np.asarray(m.faces)


def cube_tris():
    V = np.array([[(i & 1), (i >> 1) & 1, (i >> 2) & 1] for i in range(8)], float)
    Q = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]]
    F = []
    for q in Q:  # fan diagonals give valences 3 to 6
        F += [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]
    return bumpy(V, 0.05), np.array(F)


def open_grid(n=4):
    V = np.array([[i, j, 0.0] for j in range(n + 1) for i in range(n + 1)], float)
    F = []
    for j in range(n):
        for i in range(n):
            a, b, c, d = j * (n + 1) + i, j * (n + 1) + i + 1, (j + 1) * (n + 1) + i + 1, (j + 1) * (n + 1) + i
            F += [[a, b, c], [a, c, d]] if (i + j) % 2 == 0 else [[a, b, d], [b, c, d]]
    return bumpy(V, 0.08), np.array(F)


def mesh_json(V, F):
    return {"V": np.asarray(V, float).tolist(), "F": np.asarray(F, int).tolist()}


out = {"generator": f"trimesh {trimesh.__version__}, libigl (pip) {getattr(igl, '__version__', '?')}", "meshes": {}}
for name, (V, F) in {"octa_sphere": octa_sphere(), "cube_tris": cube_tris(), "open_grid": open_grid()}.items():
    V = np.ascontiguousarray(V, float)
    F = np.ascontiguousarray(F, np.int64)
    entry = {"input": mesh_json(V, F)}
    TV, TF = trimesh.remesh.subdivide_loop(V, F, iterations=1)
    entry["trimesh_loop"] = mesh_json(TV, TF)
    IV, IF = igl.loop(V, F, 1)
    entry["igl_loop"] = mesh_json(IV, IF)
    W = igl.PerVertexNormalsWeightingType
    for key, w in [("uniform", W.PER_VERTEX_NORMALS_WEIGHTING_TYPE_UNIFORM),
                   ("area", W.PER_VERTEX_NORMALS_WEIGHTING_TYPE_AREA),
                   ("angle", W.PER_VERTEX_NORMALS_WEIGHTING_TYPE_ANGLE)]:
        entry["igl_normals_" + key] = igl.per_vertex_normals(V, F, w).tolist()
    L = igl.cotmatrix(V, F).tocoo()
    entry["igl_cotmatrix"] = [[int(i), int(j), float(x)] for i, j, x in zip(L.row, L.col, L.data)]
    out["meshes"][name] = entry

with open(os.path.join(HERE, "mesh_trimesh_igl.json"), "w") as f:
    json.dump(out, f)
print("wrote", os.path.join(HERE, "mesh_trimesh_igl.json"))
