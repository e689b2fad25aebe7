#!/usr/bin/env python3
"""Usage: python3 benches/effort_rd.py MRA_BINARY CORPUS_DIR [--efforts A,B] [--images 13-24]
                                     [--other MRA_BINARY_B] [--lossless]

Issue 48's ratio rule for the default effort, on Kodak: `mra encode --bpp B --effort E`
at B = 0.25, 0.5, 1, 2 for efforts A (the reference, 7 by default) and B (4 by default),
every image one piece. Prints the mean bpp and PSNR of each per rate and the BD-PSNR and
BD-rate (Bjontegaard: cubic in log rate over the common range of the mean curves) of B
against A. With --other, effort B is encoded by that binary (a before/after of one
effort). With --lossless, also the total bytes of `--lossless` on the same images and
on the two 16-bit images of the corpus (images/highbit), B against A.

Images 13-24 by default: coder 2's trained tables (src/entropy/block/prior.rs) were
counted on Kodak 1-12."""
import argparse, json, math, os, subprocess

ap = argparse.ArgumentParser()
ap.add_argument("mra")
ap.add_argument("corpus")
ap.add_argument("--efforts", default="7,4")
ap.add_argument("--images", default="13-24")
ap.add_argument("--other", default=None)
ap.add_argument("--lossless", action="store_true")
args = ap.parse_args()
ea, eb = args.efforts.split(",")
lo_i, hi_i = (int(v) for v in args.images.split("-"))
bins = {"a": args.mra, "b": args.other or args.mra}
effort = {"a": ea, "b": eb}
OUT = os.path.join(os.environ.get("TMPDIR", "/tmp"), f"mra_effort_rd_{os.getpid()}")
os.makedirs(OUT, exist_ok=True)
RATES = [0.25, 0.5, 1.0, 2.0]


def run(which, *a):
    return subprocess.run([bins[which], *a], check=True, capture_output=True, text=True).stdout


images = [f"{args.corpus}/images/kodak/kodim{k:02}.png" for k in range(lo_i, hi_i + 1)]
rows = {}
for b in RATES:
    acc = {"a": [0.0, 0.0], "b": [0.0, 0.0]}
    for src in images:
        npx = 768 * 512
        for w in ("a", "b"):
            f = f"{OUT}/{w}.mra"
            run(w, "encode", src, "-o", f, "--bpp", str(b), "--effort", effort[w], "--quiet")
            run(w, "decode", f, "-o", f"{OUT}/{w}.png", "--quiet")
            p = json.loads(run(w, "compare", src, f"{OUT}/{w}.png", "--json", "--quiet"))["psnr"]
            acc[w][0] += os.path.getsize(f) * 8 / npx
            acc[w][1] += p
    n = len(images)
    rows[b] = (acc["a"][0] / n, acc["b"][0] / n, acc["a"][1] / n, acc["b"][1] / n)
    r = rows[b]
    print(f"bpp {b}: effort {ea} {r[0]:.4f} bpp {r[2]:.3f} dB, effort {eb}"
          f"{' (other)' if args.other else ''} {r[1]:.4f} bpp {r[3]:.3f} dB", flush=True)


def fit(xs, ys):
    # cubic through 4 points: solve Vandermonde
    n = len(xs)
    A = [[x ** j for j in range(n)] + [y] for x, y in zip(xs, ys)]
    for i in range(n):
        piv = max(range(i, n), key=lambda r: abs(A[r][i]))
        A[i], A[piv] = A[piv], A[i]
        for r in range(n):
            if r != i:
                f = A[r][i] / A[i][i]
                A[r] = [u - f * v for u, v in zip(A[r], A[i])]
    return [A[i][n] / A[i][i] for i in range(n)]


def integ(c, lo, hi):
    return sum(cj * (hi ** (j + 1) - lo ** (j + 1)) / (j + 1) for j, cj in enumerate(c))


la = [math.log10(rows[b][0]) for b in RATES]
lb = [math.log10(rows[b][1]) for b in RATES]
pa = [rows[b][2] for b in RATES]
pb = [rows[b][3] for b in RATES]
lo, hi = max(min(la), min(lb)), min(max(la), max(lb))
ca, cb = fit(la, pa), fit(lb, pb)
bd_psnr = (integ(cb, lo, hi) - integ(ca, lo, hi)) / (hi - lo)
plo, phi = max(min(pa), min(pb)), min(max(pa), max(pb))
ra_, rb_ = fit(pa, la), fit(pb, lb)
bd_rate = (10 ** ((integ(rb_, plo, phi) - integ(ra_, plo, phi)) / (phi - plo)) - 1) * 100
print(f"Kodak {lo_i}-{hi_i}: BD-PSNR of effort {eb} vs effort {ea}: {bd_psnr:+.4f} dB; "
      f"BD-rate {bd_rate:+.3f}%")

if args.lossless:
    sets = {"Kodak": images,
            "16-bit": [f"{args.corpus}/images/highbit/{n}" for n in
                       ("artificial_gray16.png", "flower_foveon_gray16_linear.png")]}
    for name, files in sets.items():
        tot = {"a": 0, "b": 0}
        for src in files:
            for w in ("a", "b"):
                f = f"{OUT}/{w}.mra"
                run(w, "encode", src, "-o", f, "--lossless", "--effort", effort[w], "--quiet")
                tot[w] += os.path.getsize(f)
        print(f"lossless {name}: effort {ea} {tot['a']:,} B, effort {eb} {tot['b']:,} B "
              f"({(tot['b'] / tot['a'] - 1) * 100:+.2f}%)", flush=True)
