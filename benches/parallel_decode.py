#!/usr/bin/env python3
"""The whole-process speed-up of `mra decode` on 2 threads against 1 (issue 52's parallel
target: at least 1.8x): the corpus flower (2268x1512 RGB) encoded at 1 bpp
(`mra encode --bpp 1`, the default one-piece 3.0 file), decoded to PNG and to NRRD with
RAYON_NUM_THREADS=1 and =2, wall-clock seconds best of N runs each (the two settings
alternated, so that a change of load hits both). Prints the load average before and
after beside the ratio: the figure means something only on a quiet machine.

    python3 benches/parallel_decode.py [--reps 7] [--input FILE] [--bpp 1]

Needs ../shared/corpus (or MRA_CORPUS) unless --input is given; MRA names the binary
(default target/release/mra).
"""
import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time

MRA = os.environ.get("MRA", "target/release/mra")
CORPUS = os.environ.get("MRA_CORPUS", "../shared/corpus")


def find_flower():
    p = os.path.join(CORPUS, "images", "large", "flower_foveon_rgb8.png")
    return p if os.path.exists(p) else None


def timed(args, threads):
    env = dict(os.environ, RAYON_NUM_THREADS=str(threads))
    t = time.perf_counter()
    p = subprocess.run([MRA] + args, capture_output=True, text=True, env=env)
    dt = time.perf_counter() - t
    if p.returncode != 0:
        sys.exit(f"mra {' '.join(args)} failed:\n{p.stderr[-2000:]}")
    return dt


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--reps", type=int, default=7)
    ap.add_argument("--input")
    ap.add_argument("--bpp", default="1")
    a = ap.parse_args()
    src = a.input or find_flower()
    if not src or not os.path.exists(src):
        sys.exit(f"no flower image under {CORPUS} (give --input)")
    tmp = tempfile.mkdtemp(prefix="mra-par-")
    try:
        f = os.path.join(tmp, "f.mra")
        subprocess.run([MRA, "encode", src, "-o", f, "--bpp", a.bpp, "--quiet"], check=True, capture_output=True)
        print(f"{src}: {os.path.getsize(f):,} bytes at --bpp {a.bpp}")
        load0 = os.getloadavg()
        for ext in ("png", "nrrd"):
            out = os.path.join(tmp, "out." + ext)
            args = ["decode", f, "-o", out, "--quiet"]
            timed(args, 2)  # warm the page cache
            best = {1: float("inf"), 2: float("inf")}
            for _ in range(a.reps):
                for n in (1, 2):
                    best[n] = min(best[n], timed(args, n))
            print(
                f"decode to {ext}: 1 thread {best[1]:.3f} s, 2 threads {best[2]:.3f} s, "
                f"ratio {best[1] / best[2]:.2f}x (best of {a.reps})",
                flush=True,
            )
        load1 = os.getloadavg()
        print(f"load average before {load0[0]:.2f} {load0[1]:.2f} {load0[2]:.2f}, "
              f"after {load1[0]:.2f} {load1[1]:.2f} {load1[2]:.2f} on {os.cpu_count()} CPUs")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
