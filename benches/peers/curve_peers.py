#!/usr/bin/env python3
"""Curve and surface evaluation speed: mra against SciPy, tinyspline and geomdl, in one run.

Run from the repository root:
    pip install numpy scipy tinyspline geomdl
    python3 benches/peers/curve_peers.py            # runs `cargo bench --bench curve` itself
    python3 benches/peers/curve_peers.py --markdown # the same as a Markdown table

Cases (as in issue 8): 10^6 points of a cubic B-spline with 20 control points (3D, clamped
knots), 10^6 points of the exact NURBS circle, and a 1000 x 1000 grid of a bicubic 10 x 10
patch. Every peer gets the best of several runs; geomdl is timed on 10^4 points and scaled (it
takes about 6 µs per point). Single thread: OMP/BLAS thread counts are pinned to 1.
"""
import os

for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(var, "1")

import subprocess
import sys
import time

import numpy as np

N = 1_000_000
GRID = 1000


def best(f, runs=5):
    t = float("inf")
    for _ in range(runs):
        s = time.perf_counter()
        f()
        t = min(t, time.perf_counter() - s)
    return t


def clamped(n, k):
    seg = n - k + 1
    return np.array([0.0] * k + [i / seg for i in range(1, seg)] + [1.0] * k)


def run_mra():
    root = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
    out = subprocess.run(["cargo", "bench", "--bench", "curve"], cwd=root, capture_output=True, text=True, check=True)
    res = {}
    for line in out.stdout.splitlines():
        if line.startswith("RESULT "):
            _, case, pts, secs, _ = line.split()
            res[case] = int(pts) / float(secs)
    return res


def peers():
    from scipy.interpolate import BSpline
    rng = np.random.default_rng(7)
    res = {}
    u = np.linspace(0.0, 1.0, N)

    # cubic B-spline, 20 control points
    c = rng.uniform(-5, 5, size=(20, 3))
    t = clamped(20, 4)
    spl = BSpline(t, c, 3, extrapolate=False)
    res[("bspline_cubic_20", "SciPy BSpline")] = N / best(lambda: spl(u))
    try:
        import tinyspline as ts
        s = ts.BSpline(20, 3, 3, ts.BSpline.Clamped)
        s.control_points = list(c.ravel())
        s.knots = list(t)
        ul = list(u)
        res[("bspline_cubic_20", "tinyspline eval_all")] = N / best(lambda: s.eval_all(ul), runs=3)
    except Exception as e:  # pragma: no cover
        print("tinyspline unavailable:", e, file=sys.stderr)
    try:
        from geomdl import BSpline as GB
        g = GB.Curve(normalize_kv=False)
        g.degree = 3
        g.ctrlpts = c.tolist()
        g.knotvector = list(t)
        few = list(np.linspace(0, 1, 10_000))
        res[("bspline_cubic_20", "geomdl (10^4 points, scaled)")] = 10_000 / best(lambda: g.evaluate_list(few), runs=2)
    except Exception as e:  # pragma: no cover
        print("geomdl unavailable:", e, file=sys.stderr)

    # exact NURBS circle: homogeneous B-spline, then divide
    r2 = np.sqrt(0.5)
    pts = np.array([(1, 0), (1, 1), (0, 1), (-1, 1), (-1, 0), (-1, -1), (0, -1), (1, -1), (1, 0)], float)
    w = np.array([1, r2, 1, r2, 1, r2, 1, r2, 1])
    hom = np.column_stack([pts * w[:, None], w])
    tk = np.array([0, 0, 0, .25, .25, .5, .5, .75, .75, 1, 1, 1.0])
    circ = BSpline(tk, hom, 2, extrapolate=False)

    def scipy_circle():
        h = circ(u)
        return h[:, :2] / h[:, 2:3]

    res[("nurbs_circle", "SciPy BSpline (homogeneous + divide)")] = N / best(scipy_circle)
    try:
        from geomdl import NURBS
        g = NURBS.Curve(normalize_kv=False)
        g.degree = 2
        g.ctrlptsw = hom.tolist()
        g.knotvector = list(tk)
        few = list(np.linspace(0, 1, 10_000))
        res[("nurbs_circle", "geomdl (10^4 points, scaled)")] = 10_000 / best(lambda: g.evaluate_list(few), runs=2)
    except Exception as e:  # pragma: no cover
        print("geomdl unavailable:", e, file=sys.stderr)

    # bicubic 10x10 patch on a 1000x1000 grid: design matrices + tensor product
    net = rng.uniform(-5, 5, size=(10, 10, 3))
    tp = clamped(10, 4)
    g1 = np.linspace(0, 1, GRID)

    def numpy_grid():
        B = BSpline.design_matrix(g1, tp, 3).toarray()  # 1000 x 10
        tmp = np.tensordot(B, net, axes=(1, 0))  # 1000 x 10 x 3
        return np.einsum("vj,ujc->uvc", B, tmp, optimize=True)

    res[("patch_bicubic_10x10_grid_1000", "NumPy design-matrix tensor product")] = GRID * GRID / best(numpy_grid)
    B = BSpline.design_matrix(g1, tp, 3).toarray()

    def numpy_products_only():
        tmp = np.tensordot(B, net, axes=(1, 0))
        return np.einsum("vj,ujc->uvc", B, tmp, optimize=True)

    res[("patch_bicubic_10x10_grid_1000", "NumPy tensor product (matrices precomputed)")] = GRID * GRID / best(numpy_products_only)
    return res


def exactness():
    """Largest deviation from SciPy (de Boor, no snapping) at parameters 5e-5 from each interior
    knot: tinyspline snaps such parameters onto the knot; mra must not."""
    from scipy.interpolate import BSpline
    import tempfile
    rng = np.random.default_rng(11)
    c = rng.uniform(-5, 5, size=(20, 3))
    t = clamped(20, 4)
    spl = BSpline(t, c, 3)
    us = np.array([x + e for x in t[4:-4] for e in (-5e-5, 5e-5)])
    want = spl(us)
    out = {}
    try:
        import tinyspline as ts
        s = ts.BSpline(20, 3, 3, ts.BSpline.Clamped)
        s.control_points = list(c.ravel())
        s.knots = list(t)
        got = np.array(s.eval_all(list(us))).reshape(-1, 3)
        out["tinyspline"] = float(np.abs(got - want).max())
    except Exception as e:  # pragma: no cover
        print("tinyspline unavailable:", e, file=sys.stderr)
    root = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
    with tempfile.TemporaryDirectory() as d:
        pts = os.path.join(d, "c.csv")
        np.savetxt(pts, c, delimiter=",", fmt="%.17g")
        at = ",".join(repr(float(u)) for u in us)
        r = subprocess.run(["cargo", "run", "--release", "-q", "--", "curve", "eval", "--order", "4", "--at", at, pts],
                           cwd=root, capture_output=True, text=True, check=True)
        got = np.loadtxt(r.stdout.splitlines(), delimiter=",").reshape(-1, 3)
        out["mra"] = float(np.abs(got - want).max())
    return out


def main():
    ours = run_mra()  # same run: mra first, then the peers
    theirs = peers()
    md = "--markdown" in sys.argv
    cases = ["bspline_cubic_20", "nurbs_circle", "patch_bicubic_10x10_grid_1000"]
    if md:
        print("| case | implementation | M points/s | ns/point | mra speed-up |")
        print("|---|---|---:|---:|---:|")
    for case in cases:
        rows = [("mra", ours.get(case, float("nan")))]
        if case + "_basis_path" in ours:
            rows.append(("mra, basis-function path (no power form)", ours[case + "_basis_path"]))
        rows += [(k[1], v) for k, v in theirs.items() if k[0] == case]
        for name, rate in rows:
            sp = ours.get(case, float("nan")) / rate
            if md:
                print(f"| {case} | {name} | {rate / 1e6:.1f} | {1e9 / rate:.1f} | {sp:.1f}x |")
            else:
                print(f"{case:32s} {name:48s} {rate / 1e6:9.1f} Mpts/s {1e9 / rate:9.2f} ns/pt   mra x{sp:.2f}")
    ex = exactness()
    print()
    for name, err in ex.items():
        print(f"max |error| vs SciPy at knots ± 5e-5: {name:12s} {err:.3e}")


if __name__ == "__main__":
    main()
