#!/usr/bin/env python3
"""PyWavelets' filter banks that mra's schemes share: bior2.2 (CDF 5/3, mra `linear`), bior2.4
(CDF 9/3, mra `linear-wide`) and bior4.4 (CDF 9/7, mra `cdf97`). Writes tests/reference/pywt_filters.json; with --check, compares
a fresh extraction with the committed file (exit 1 on a difference).

pywt's convention: dec_lo/dec_hi are applied as convolutions (reversed correlation rows), rec_lo/rec_hi
are the synthesis filters; all carry a factor sqrt(2) against mra's (A rows sum to 1, P columns to 2).
"""
import json
import sys
from pathlib import Path

import pywt

OUT = Path(__file__).with_name("pywt_filters.json")


def extract():
    out = {"pywt_version": pywt.__version__}
    for name in ("bior2.2", "bior2.4", "bior4.4"):
        w = pywt.Wavelet(name)
        out[name] = {k: [float(x) for x in getattr(w, k)] for k in ("dec_lo", "dec_hi", "rec_lo", "rec_hi")}
    return out


if __name__ == "__main__":
    fresh = extract()
    if "--check" in sys.argv:
        old = json.loads(OUT.read_text())
        fresh.pop("pywt_version"), old.pop("pywt_version", None)
        if fresh != old:
            print("pywt_filters.json differs from PyWavelets", pywt.__version__)
            sys.exit(1)
        print("pywt_filters.json matches PyWavelets", pywt.__version__)
    else:
        OUT.write_text(json.dumps(fresh, indent=1) + "\n")
