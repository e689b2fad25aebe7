#!/usr/bin/env python3
"""Peak memory of `mra.encode` and `mra.compare` from Python: a C-contiguous array is read
where it is (no copy), a Fortran-ordered one is gathered once in C order. Each case runs
in a fresh process; the figure is the peak resident set above the process's peak before
the call (the array and the package loaded), against the array's size.

Needs the package (`pip install ./python`). Usage:
    python3 benches/python_memory.py [--shape 256,256,256] [--rate quality=60]
"""
import argparse
import json
import subprocess
import sys

CHILD = r"""
import json, resource, sys
import numpy as np
import mra
shape = tuple(json.loads(sys.argv[1])); order = sys.argv[2]; call = sys.argv[3]
kind, value = sys.argv[4].split("=")
# built a slice at a time, so that the peak before the call is the array itself
a = np.empty(shape, np.uint16, order=order)
rest = np.meshgrid(*[np.linspace(0, 6, n, dtype=np.float32) for n in shape[1:]], indexing="ij")
base = 20000 + 8000 * sum(np.sin(x) for x in rest)
for z in range(shape[0]):
    a[z] = (base + 8000 * np.sin(6.0 * z / shape[0])).astype(np.uint16)
del rest, base
b = a.copy(order=order) if call == "compare" else None
mra.encode(np.zeros((8, 8), np.uint16), quality=50)  # load everything once
before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
if call == "encode":
    mra.encode(a, **{kind: float(value)})
else:
    mra.compare(a, b)
after = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
print(json.dumps({"before": before / 1024, "after": after / 1024, "array": a.nbytes / 2**20}))
"""


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--shape", default="256,256,256")
    ap.add_argument("--rate", default="quality=60")
    a = ap.parse_args()
    shape = [int(s) for s in a.shape.split(",")]
    print(f"| call | array order | array MiB | peak above before MiB |")
    print("|---|---|---|---|")
    for call in ["encode", "compare"]:
        for order in ["C", "F"]:
            out = subprocess.run(
                [sys.executable, "-c", CHILD, json.dumps(shape), order, call, a.rate],
                capture_output=True,
                text=True,
                check=True,
            ).stdout
            r = json.loads(out)
            label = "C (read in place)" if order == "C" else "Fortran (gathered)"
            print(f"| {call} | {label} | {r['array']:.0f} | {r['after'] - r['before']:.0f} |")


if __name__ == "__main__":
    main()
