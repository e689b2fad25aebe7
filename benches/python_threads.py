#!/usr/bin/env python3
"""Two Python threads decoding at once against one: the wall time of N decodes in one
thread and of the same N split over two threads; best of `--rounds` interleaved rounds.
The GIL is released inside `mra.decode`, but a decode already spreads its bands over the
library's rayon pool, which both Python threads share: the threads gain only where one
decode leaves cores idle (small arrays), and with `RAYON_NUM_THREADS=1` they queue on the
pool's one thread. Run it on an otherwise idle machine.

Needs the package (`pip install ./python`). Usage:
    python3 benches/python_threads.py [--shape 64,256,256] [--decodes 8] [--rounds 3]
"""
import argparse
import threading
import time

import numpy as np

import mra


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--shape", default="64,256,256")
    ap.add_argument("--decodes", type=int, default=8)
    ap.add_argument("--rounds", type=int, default=3)
    a = ap.parse_args()
    shape = tuple(int(s) for s in a.shape.split(","))
    rng = np.random.default_rng(0)
    grids = np.meshgrid(*[np.linspace(0, 6, n) for n in shape], indexing="ij")
    x = 20000 + 10000 * sum(np.sin(g) for g in grids) + rng.normal(0, 40, shape)
    data = mra.encode(np.clip(x, 0, 65535).astype(np.uint16), max_error=2)
    mra.decode(data)  # warm up

    def run(n):
        for _ in range(n):
            mra.decode(data)

    one, two = [], []
    for _ in range(a.rounds):
        t = time.perf_counter()
        run(a.decodes)
        one.append(time.perf_counter() - t)
        ts = [threading.Thread(target=run, args=(a.decodes // 2,)) for _ in range(2)]
        t = time.perf_counter()
        for th in ts:
            th.start()
        for th in ts:
            th.join()
        two.append(time.perf_counter() - t)
    print(f"{a.decodes} decodes of {shape} u16 ({len(data)} bytes): one thread {min(one):.3f} s, "
          f"two threads {min(two):.3f} s, ratio {min(one) / min(two):.2f}")


if __name__ == "__main__":
    main()
