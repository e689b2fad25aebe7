#!/usr/bin/env python3
"""Engine throughput next to PyWavelets, measured in one run.

    pip install pywavelets numpy
    python3 benches/peers/pywavelets_peer.py [--quick]

Times PyWavelets `wavedec2` + `waverec2` (bior2.2, mode symmetric, 5 levels) on a
4096x4096 float32 image, then runs `cargo bench --bench engine` (mra forward + inverse,
5 levels, the same size, each run next to a plain copy of the buffer) and prints one
table.
"""
import json, os, subprocess, sys, time
import numpy as np
import pywt

quick = "--quick" in sys.argv
n = 1024 if quick else 4096
reps = 3 if quick else 5
img = (np.arange(n * n, dtype=np.float64) * 2654435761 % 1000).astype(np.float32).reshape(n, n) * 0.25

def bench(f):
    """(best, median) seconds of `reps` runs after a warm-up run."""
    f()
    ts = []
    for _ in range(reps):
        t = time.perf_counter(); f(); ts.append(time.perf_counter() - t)
    ts.sort()
    return ts[0], ts[len(ts) // 2]

def pywt_roundtrip():
    c = pywt.wavedec2(img, "bior2.2", mode="symmetric", level=5)
    pywt.waverec2(c, "bior2.2", mode="symmetric")

t_best, t_pywt = bench(pywt_roundtrip)
mb = img.nbytes / 1e6
env = dict(os.environ)
if quick:
    env["MRA_BENCH_QUICK"] = "1"
root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
out = subprocess.run(["cargo", "bench", "--bench", "engine"], cwd=root, env=env,
                     capture_output=True, text=True, check=True).stdout
rows = [json.loads(l) for l in out.splitlines() if l.startswith("{")]
shape = f"{n}x{n}"
p_best, p_med = mb / t_best, mb / t_pywt
print(f"PyWavelets {pywt.__version__} bior2.2 symmetric 5 levels {shape} f32: best {t_best*1e3:.0f} ms = {p_best:.0f} MB/s, "
      f"median {t_pywt*1e3:.0f} ms = {p_med:.0f} MB/s")
print("best of the runs / median of the runs (mra against PyWavelets' and the copy's of the same statistic)")
print(f"{'scheme':<8} {'boundary':<14} {'mra MB/s':>15} {'x PyWavelets':>15} {'% of copy':>15}")
for r in rows:
    if r["shape"] != shape:
        continue
    print(f"{r['scheme']:<8} {r['boundary']:<14} {r['mb_per_s_best']:>7.0f}/{r['mb_per_s']:<7.0f} "
          f"{r['mb_per_s_best'] / p_best:>6.1f}x/{r['mb_per_s'] / p_med:<6.1f}x "
          f"{100 * r['mb_per_s_best'] / r['copy_mb_per_s_best']:>6.1f}%/{100 * r['mb_per_s'] / r['copy_mb_per_s']:<6.1f}%")
# the copy is timed between every case's runs (its speed moves with the machine's load)
copies = [r["copy_mb_per_s_best"] for r in rows if r["shape"] == shape]
print(f"copy (best, per case): {min(copies):.0f}-{max(copies):.0f} MB/s; "
      f"PyWavelets is {100 * p_best / max(copies):.1f}-{100 * p_best / min(copies):.1f}% of copy (best)")
# context only (the target is against the plain copy): the same copy split over all threads
par = [r["copy_all_threads_mb_per_s_best"] for r in rows if "copy_all_threads_mb_per_s_best" in r]
if par:
    print(f"the copy split over {rows[0]['threads']} threads (best, per case): {min(par):.0f}-{max(par):.0f} MB/s")
for r in rows:
    if r["shape"] != shape:
        print(f"3D {r['shape']} {r['levels']} levels {r['scheme']:<8} {r['boundary']:<14} "
              f"{r['mb_per_s_best']:>7.0f}/{r['mb_per_s']:<7.0f} MB/s "
              f"({100 * r['mb_per_s_best'] / r['copy_mb_per_s_best']:.1f}%/{100 * r['mb_per_s'] / r['copy_mb_per_s']:.1f}% of copy)")
