#!/usr/bin/env python3
"""Usage: python3 benches/codeblocks_rd.py MRA_BINARY CORPUS_DIR

Kodak 13-24: mra encode --bpp B --format 2 (one stream per band) vs the default
(format 3.x, code-blocks with per-block RDO), both one piece. Prints the mean bpp and
PSNR of each per rate, BD-rate and BD-PSNR (Bjontegaard, cubic in log rate, over the
common range) of the mean curves."""
import json, os, subprocess, sys, math
MRA = sys.argv[1]
CORPUS = sys.argv[2]
OUT = os.path.join(os.environ.get("TMPDIR", "/tmp"), "mra_codeblocks_rd")
os.makedirs(OUT, exist_ok=True)
RATES = [0.25, 0.5, 1.0, 2.0]
def run(*a):
    return subprocess.run([MRA, *a], check=True, capture_output=True, text=True).stdout
rows = {}
for b in RATES:
    ra = rb = pa = pb = 0; n = 0
    for k in range(13, 25):
        src = f"{CORPUS}/images/kodak/kodim{k:02}.png"
        npx = 768 * 512
        got = []
        for name, extra in (("a", ["--format", "2"]), ("b", [])):
            f = f"{OUT}/{name}{k}_{b}.mra"
            run("encode", src, "-o", f, "--bpp", str(b), "--tile", "whole", "--quiet", *extra)
            run("decode", f, "-o", f"{OUT}/{name}.png", "--quiet")
            p = json.loads(run("compare", src, f"{OUT}/{name}.png", "--json", "--quiet"))["psnr"]
            got.append((os.path.getsize(f) * 8 / npx, p))
        ra += got[0][0]; pa += got[0][1]; rb += got[1][0]; pb += got[1][1]; n += 1
    rows[b] = (ra / n, rb / n, pa / n, pb / n)
    print(f"bpp {b}: format 2 {ra/n:.4f} bpp {pa/n:.3f} dB, 3.x {rb/n:.4f} bpp {pb/n:.3f} dB", flush=True)
def fit(xs, ys):
    # cubic through 4 points: solve Vandermonde
    n = len(xs); A = [[x ** j for j in range(n)] + [y] for x, y in zip(xs, ys)]
    for i in range(n):
        piv = max(range(i, n), key=lambda r: abs(A[r][i])); A[i], A[piv] = A[piv], A[i]
        for r in range(n):
            if r != i:
                f = A[r][i] / A[i][i]
                A[r] = [u - f * v for u, v in zip(A[r], A[i])]
    return [A[i][n] / A[i][i] for i in range(n)]
def integ(c, lo, hi):
    return sum(cj * (hi ** (j + 1) - lo ** (j + 1)) / (j + 1) for j, cj in enumerate(c))
la = [math.log10(rows[b][0]) for b in RATES]; lb = [math.log10(rows[b][1]) for b in RATES]
pa = [rows[b][2] for b in RATES]; pb = [rows[b][3] for b in RATES]
lo, hi = max(min(la), min(lb)), min(max(la), max(lb))
ca, cb = fit(la, pa), fit(lb, pb)
bd_psnr = (integ(cb, lo, hi) - integ(ca, lo, hi)) / (hi - lo)
plo, phi = max(min(pa), min(pb)), min(max(pa), max(pb))
ra_, rb_ = fit(pa, la), fit(pb, lb)
bd_rate = (10 ** ((integ(rb_, plo, phi) - integ(ra_, plo, phi)) / (phi - plo)) - 1) * 100
print(f"BD-PSNR of 3.x vs format 2: {bd_psnr:+.4f} dB; BD-rate {bd_rate:+.3f}%")
