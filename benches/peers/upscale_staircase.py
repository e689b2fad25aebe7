#!/usr/bin/env python3
"""The ×4 staircase figure of docs/upscale.md: crops of a slanted edge, enlarged with
nearest neighbour, side by side: the original, mra (an older binary, optional), mra (this
checkout), OpenImageIO lanczos3. The low-resolution input is the filtered protocol of
upscale_peers.py (OpenImageIO resize, lanczos3 widened by the reduction).

Usage (from the repository root, after `cargo build --release`):
  python3 benches/peers/upscale_staircase.py [--old OLD_MRA] [-o docs/figures/upscale_staircase.png]
Needs: pip install OpenImageIO pillow tifffile
"""
import argparse, os, sys
import numpy as np
from PIL import Image

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import upscale_peers as up  # noqa: E402

F = 4
# (file under the corpus, _, top, left, size) of the original: a straight edge, a parrot's
# feathers, a mudguard's rim
CROPS = [("synthetic edge 30°", None, 112, 112, 32), ("images/kodak/kodim23.png", None, 229, 170, 32),
         ("images/kodak/kodim05.png", None, 224, 528, 32)]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--old", help="an older mra binary to show beside this one")
    ap.add_argument("-o", "--output", default=os.path.join(up.ROOT, "docs", "figures", "upscale_staircase.png"))
    ap.add_argument("--zoom", type=int, default=6)
    args = ap.parse_args()
    binaries = ([("mra (before)", args.old)] if args.old else []) + [("mra", up.MRA)]
    rows = []
    import tempfile
    with tempfile.TemporaryDirectory() as tmp:
        for name, _, top, left, size in CROPS:
            if name.startswith("synthetic"):
                x, _ = up.edge_image(30)
            else:
                x = np.asarray(Image.open(os.path.join(up.CORPUS, name)).convert("RGB")).astype(np.float64)
            x, low = up.filtered(x, F)
            outs = [x]
            for _, path in binaries:
                up.MRA = path
                outs.append(up.mra_upscale(low, F, "area", "chaikin", tmp, 2)[0])
            outs.append(up.oiio_resize(low, F, "lanczos3"))
            tiles = []
            for o in outs:
                c = np.clip(np.round(o[top:top + size, left:left + size]), 0, 255).astype(np.uint8)
                if c.ndim == 2:
                    c = np.repeat(c[..., None], 3, axis=2)
                tiles.append(np.asarray(Image.fromarray(c).resize((size * args.zoom,) * 2, Image.NEAREST)))
                tiles.append(np.full((size * args.zoom, 6, 3), 255, np.uint8))
            rows.append(np.concatenate(tiles[:-1], axis=1))
            rows.append(np.full((6, rows[-1].shape[1], 3), 255, np.uint8))
    Image.fromarray(np.concatenate(rows[:-1], axis=0)).save(args.output, optimize=True)
    print("columns: original,", ", ".join(b[0] for b in binaries) + ", OpenImageIO lanczos3 ->", args.output)


if __name__ == "__main__":
    main()
