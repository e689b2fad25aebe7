"""Kodak x2/x4 speed, side by side in one run: an older mra binary (argv[1], default
/tmp/mra_before), this checkout's target/release/mra, and OpenImageIO resize (best of 3
each, every 4th Kodak image). Run from the repository root:
  python3 benches/peers/upscale_speed_ab.py /path/to/old/mra
"""
import os, sys, glob, tempfile, numpy as np
sys.path.insert(0, "benches/peers")
import upscale_peers as P
from PIL import Image
files = sorted(glob.glob(os.path.join(os.environ.get("MRA_CORPUS", "../shared/corpus"), "images/kodak/*.png")))[::4]
res = {}
AFTER = P.MRA
load0 = os.getloadavg()[0]
with tempfile.TemporaryDirectory() as tmp:
    for f in (2, 4):
        for fn in files:
            x = np.asarray(Image.open(fn).convert("RGB"), dtype=np.float32)
            _, low = P.block_mean(x, f, 2)
            for name, binary in (("before", sys.argv[1] if len(sys.argv) > 1 else "/tmp/mra_before"), ("after", AFTER)):
                P.MRA = binary
                best = min(P.mra_upscale(low, f, "area", "chaikin", tmp, 2)[1] for _ in range(3))
                res.setdefault((f, name), []).append(best)
            P.MRA = AFTER
            for filt in ("lanczos3", "catmull-rom", "bspline"):
                _, t = P.timed(lambda: P.oiio_resize(low, f, filt), 3) if hasattr(P, "timed") else (None, None)
                res.setdefault((f, filt), []).append(t)
for k, v in res.items():
    print(k, "mean %.4f s over %d" % (np.mean(v), len(v)))
for f in (2, 4):
    cr = np.mean(res[(f, "catmull-rom")])
    print("x%d: before %.2fx, after %.2fx OpenImageIO catmull-rom's time (after / before %.2fx)"
          % (f, np.mean(res[(f, "before")]) / cr, np.mean(res[(f, "after")]) / cr,
             np.mean(res[(f, "after")]) / np.mean(res[(f, "before")])))
print("load average %.2f -> %.2f" % (load0, os.getloadavg()[0]))
