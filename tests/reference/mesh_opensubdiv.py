#!/usr/bin/env python3
"""Reference fixtures from OpenSubdiv (uniform refinement, Far API, double precision weights).

OpenSubdiv has no Python binding: this script builds the committed C++ program osd_refine.cpp
against Debian's libosd-dev, feeds it small generated meshes (closed, mixed polygons, with
boundaries, with infinitely sharp creases and corners; boundary mode VTX_BOUNDARY_EDGE_ONLY)
and writes tests/reference/mesh_opensubdiv.json, which the Rust tests compare to 1e-12.

Rerun:  apt-get install libosd-dev g++ && python3 tests/reference/mesh_opensubdiv.py
"""
import json
import math
import os
import subprocess
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))


def bumpy(V, amp):
    return [[x + amp * math.sin(1.3 * i + 0.3), y + amp * math.sin(2.1 * i + 1.1), z + amp * math.sin(0.7 * i + 2.3)]
            for i, (x, y, z) in enumerate(V)]


def cube():
    V = [[float(i & 1), float((i >> 1) & 1), float((i >> 2) & 1)] for i in range(8)]
    F = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]]
    return V, F


def prism(n=5):
    V = [[math.cos(2 * math.pi * i / n), math.sin(2 * math.pi * i / n), z] for z in (0.0, 1.0) for i in range(n)]
    F = [list(range(n - 1, -1, -1)), list(range(n, 2 * n))]
    F += [[i, (i + 1) % n, n + (i + 1) % n, n + i] for i in range(n)]
    return bumpy(V, 0.05), F


def pyramid():
    V = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0.5, 0.5, 1.0]]
    F = [[0, 3, 2, 1], [0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]]
    return bumpy(V, 0.03), F


def grid(n, m, tris=False):
    V = [[float(i), float(j), 0.0] for j in range(m + 1) for i in range(n + 1)]
    F = []
    for j in range(m):
        for i in range(n):
            a, b = j * (n + 1) + i, j * (n + 1) + i + 1
            c, d = (j + 1) * (n + 1) + i + 1, (j + 1) * (n + 1) + i
            if tris:
                F += [[a, b, c], [a, c, d]] if (i + j) % 2 == 0 else [[a, b, d], [b, c, d]]
            else:
                F.append([a, b, c, d])
    return bumpy(V, 0.08), F


def octa_sphere():
    V = [[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]]
    F = [[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]]
    return bumpy([[float(x) for x in v] for v in V], 0.1), F


def tri_cube():
    V, Q = cube()
    F = []
    for q in Q:
        F += [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]
    return bumpy(V, 0.05), F


def run(exe, scheme, levels, V, F, creases=(), corners=()):
    lines = [f"{scheme} {levels} {len(V)} {len(F)} {len(creases)} {len(corners)}"]
    lines += ["%.17g %.17g %.17g" % tuple(v) for v in V]
    lines += [" ".join(map(str, [len(f)] + list(f))) for f in F]
    lines += [f"{a} {b}" for a, b in creases]
    lines += [str(c) for c in corners]
    out = subprocess.run([exe], input="\n".join(lines) + "\n", capture_output=True, text=True, check=True).stdout
    toks = out.split("\n")
    nv, nf = map(int, toks[0].split())
    RV = [[float(x) for x in toks[1 + i].split()] for i in range(nv)]
    RF = [[int(x) for x in toks[1 + nv + i].split()][1:] for i in range(nf)]
    return {"V": RV, "F": RF}


def main():
    tmp = tempfile.mkdtemp()
    exe = os.path.join(tmp, "osd_refine")
    subprocess.run(["g++", "-O2", "-std=c++14", os.path.join(HERE, "osd_refine.cpp"), "-losdCPU", "-o", exe], check=True)
    cases = []

    def add(name, scheme, levels, mesh, creases=(), corners=()):
        V, F = mesh
        cases.append({"name": name, "scheme": scheme, "levels": levels, "input": {"V": V, "F": F},
                      "creases": [list(c) for c in creases], "corners": list(corners),
                      "output": run(exe, scheme, levels, V, F, creases, corners)})

    cube_edges = [(0, 1), (1, 3), (3, 2), (2, 0), (4, 5), (5, 7), (7, 6), (6, 4), (0, 4), (1, 5), (2, 6), (3, 7)]
    add("cc_cube_2", "catmark", 2, (bumpy(cube()[0], 0.05), cube()[1]))
    add("cc_prism_mixed", "catmark", 2, prism())
    add("cc_pyramid_tris_and_quad", "catmark", 1, pyramid())
    add("cc_open_grid", "catmark", 2, grid(4, 3))
    add("cc_open_grid_crease_corner", "catmark", 2, grid(4, 3), creases=[(6, 7), (7, 8), (8, 13)], corners=[0, 17])
    add("cc_cube_sharp_edges", "catmark", 2, (bumpy(cube()[0], 0.05), cube()[1]), creases=cube_edges[:7])
    add("cc_octa_triangles", "catmark", 1, octa_sphere())
    add("loop_octa_2", "loop", 2, octa_sphere())
    add("loop_tri_cube", "loop", 1, tri_cube())
    add("loop_open_grid", "loop", 2, grid(4, 3, tris=True))
    add("loop_tri_cube_creases_corner", "loop", 2, tri_cube(), creases=cube_edges[:6], corners=[7])
    with open(os.path.join(HERE, "mesh_opensubdiv.json"), "w") as f:
        json.dump({"generator": "OpenSubdiv 3.5 (Debian libosd-dev), osd_refine.cpp", "cases": cases}, f)
    print("wrote", len(cases), "cases")


main()
