#!/usr/bin/env python3
"""Reference values for tests/curve.rs and tests/surface.rs from geomdl (NURBS-Python).

Run:  pip install geomdl && python3 tests/reference/geomdl_curves.py
Writes tests/reference/geomdl_curves.json and tests/reference/geomdl_surfaces.json.

Random (seeded) curves and surfaces of orders 2..5 on uniform, clamped and non-uniform knot
sequences (with multiple interior knots), rational and not, in 2D and 3D; evaluated at random
parameters, at every knot of the valid range, and 1e-9 on either side of each knot (exactness
near knots: nothing may be snapped). Curves also carry derivatives up to order 2.
"""
import json
import os
import random

import geomdl
from geomdl import BSpline, NURBS

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = HERE
rng = random.Random(20261122)


def knot_vector(kind, n, k):
    m = n + k
    if kind == "uniform":
        return [float(i) for i in range(m)]
    if kind == "clamped":
        seg = n - k + 1
        return [0.0] * k + [i / seg for i in range(1, seg)] + [1.0] * k
    # non-uniform, clamped ends, random interior with some repeated knots (multiplicity < k)
    interior = sorted(rng.uniform(0.0, 4.0) for _ in range(n - k))
    if len(interior) >= 2 and k >= 3:
        j = rng.randrange(len(interior) - 1)
        interior[j + 1] = interior[j]
    start = rng.uniform(-1.0, 0.0)
    end = 4.0 + rng.uniform(0.5, 1.0)
    if kind == "nonuniform-open":
        lo = [start - rng.uniform(0.1, 1.0) for _ in range(k - 1)]
        hi = [end + rng.uniform(0.1, 1.0) for _ in range(k - 1)]
        return sorted(lo) + [start] + interior + [end] + sorted(hi)
    return [start] * k + interior + [end] * k


def params_for(knots, n, k, count):
    a, b = knots[k - 1], knots[n]
    ps = [rng.uniform(a, b) for _ in range(count)] + [a, b]
    for t in knots[k - 1 : n + 1]:
        ps.append(t)
        for eps in (1e-9, -1e-9):
            if a <= t + eps <= b:
                ps.append(t + eps)
    return ps


def curves():
    out = []
    for k in (2, 3, 4, 5):
        for kind in ("uniform", "clamped", "nonuniform", "nonuniform-open"):
            for rational in (False, True):
                dim = rng.choice((2, 3))
                n = rng.randint(k, k + 6)
                pts = [[round(rng.uniform(-10, 10), 4) for _ in range(dim)] for _ in range(n)]
                knots = knot_vector(kind, n, k)
                w = [round(rng.uniform(0.3, 3.0), 4) for _ in range(n)] if rational else None
                c = NURBS.Curve(normalize_kv=False) if rational else BSpline.Curve(normalize_kv=False)
                c.degree = k - 1
                if rational:
                    c.ctrlptsw = [[p[i] * wi for i in range(dim)] + [wi] for p, wi in zip(pts, w)]
                else:
                    c.ctrlpts = pts
                c.knotvector = knots
                ps = params_for(knots, n, k, 6)
                vals, ders = [], []
                for u in ps:
                    vals.append(list(c.evaluate_single(u)))
                    ders.append([list(d) for d in c.derivatives(u, order=2)])
                out.append(
                    dict(order=k, kind=kind, rational=rational, dim=dim, points=pts, weights=w,
                         knots=knots, params=ps, values=vals, derivatives=ders)
                )
    return out


def insertions():
    """Knot insertion (Boehm) by geomdl: a knot inserted 1..k-1 times into random curves."""
    from geomdl import operations
    out = []
    for k in (2, 3, 4, 5):
        for kind in ("clamped", "nonuniform"):
            for rational in (False, True):
                dim = 2
                n = rng.randint(k + 1, k + 5)
                pts = [[round(rng.uniform(-10, 10), 4) for _ in range(dim)] for _ in range(n)]
                knots = knot_vector(kind, n, k)
                w = [round(rng.uniform(0.3, 3.0), 4) for _ in range(n)] if rational else None
                c = NURBS.Curve(normalize_kv=False) if rational else BSpline.Curve(normalize_kv=False)
                c.degree = k - 1
                if rational:
                    c.ctrlptsw = [[p[i] * wi for i in range(dim)] + [wi] for p, wi in zip(pts, w)]
                else:
                    c.ctrlpts = pts
                c.knotvector = knots
                a, b = knots[k - 1], knots[n]
                u = rng.uniform(a + 0.1 * (b - a), b - 0.1 * (b - a))
                times = rng.randint(1, k - 1) if k > 1 else 1
                operations.insert_knot(c, [u], [times])
                res = [list(p) for p in c.ctrlpts]
                out.append(dict(order=k, kind=kind, rational=rational, dim=dim, points=pts, weights=w,
                                knots=knots, u=u, times=times, new_knots=list(c.knotvector), new_points=res,
                                new_weights=list(c.weights) if rational else None))
    return out


def surfaces():
    out = []
    for (ku, kv) in ((2, 2), (3, 4), (4, 4), (5, 3), (4, 2)):
        for kind in ("clamped", "nonuniform", "uniform"):
            for rational in (False, True):
                nu, nv = rng.randint(ku, ku + 4), rng.randint(kv, kv + 4)
                net = [[[round(rng.uniform(-5, 5), 4) for _ in range(3)] for _ in range(nv)] for _ in range(nu)]
                w = [[round(rng.uniform(0.3, 3.0), 4) for _ in range(nv)] for _ in range(nu)] if rational else None
                tu, tv = knot_vector(kind, nu, ku), knot_vector(kind, nv, kv)
                s = NURBS.Surface(normalize_kv=False) if rational else BSpline.Surface(normalize_kv=False)
                s.degree_u, s.degree_v = ku - 1, kv - 1
                flat = []
                for i in range(nu):
                    for j in range(nv):
                        p = net[i][j]
                        if rational:
                            wi = w[i][j]
                            flat.append([p[0] * wi, p[1] * wi, p[2] * wi, wi])
                        else:
                            flat.append(p)
                s.set_ctrlpts(flat, nu, nv)
                s.knotvector_u, s.knotvector_v = tu, tv
                pu = params_for(tu, nu, ku, 4)
                pv = params_for(tv, nv, kv, 4)
                uv = [(rng.choice(pu), rng.choice(pv)) for _ in range(20)]
                vals = [list(s.evaluate_single(p)) for p in uv]
                out.append(dict(order_u=ku, order_v=kv, kind=kind, rational=rational, nu=nu, nv=nv,
                                net=net, weights=w, knots_u=tu, knots_v=tv,
                                params=[list(p) for p in uv], values=vals))
    return out


if __name__ == "__main__":
    os.makedirs(OUT, exist_ok=True)
    meta = {"generator": "tests/reference/geomdl_curves.py", "geomdl": geomdl.__version__}
    with open(os.path.join(OUT, "geomdl_curves.json"), "w") as f:
        json.dump(dict(meta, curves=curves(), insertions=insertions()), f)
    with open(os.path.join(OUT, "geomdl_surfaces.json"), "w") as f:
        json.dump(dict(meta, surfaces=surfaces()), f)
    print("wrote", OUT)
