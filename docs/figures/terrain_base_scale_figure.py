#!/usr/bin/env python3
"""docs/figures/terrain_base_scale.png: base | example | result | cubic upscale for a smooth base at
`--base-scale 16`, hillshaded by `mra terrain render` with one sun (315 deg / 45 deg) and one cell
(92.6 m, the output's).

The case is the "smooth base" of benches/terrain_quality.py's landform table: a smooth random field
(128x128, 740.8 m cells), example N44W072 rows 801-1201, cols 857-1201 (400x344), result =
`mra terrain synth --levels 3 --base-scale 16 --seed 1` (1024x1024), cubic = scipy zoom order 3 of
the base. Shown: the top-left 512x512 output cells of the result and the cubic upscale, the same
64x64 base cells at 8x (nearest cells, shaded with the base's own cell), the whole example.
Run from the repository root:  cargo build --release && python3 docs/figures/terrain_base_scale_figure.py
"""
import os, subprocess, sys, tempfile
import numpy as np
import tifffile
from PIL import Image
from scipy import ndimage

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "benches"))
import terrain_quality as tq  # noqa: E402

MRA = os.environ.get("MRA_BIN", os.path.join(ROOT, "target", "release", "mra"))
OUT = os.path.join(ROOT, "docs", "figures", "terrain_base_scale.png")
CELL = tq.CELL


def render(tmp, name, g, cell):
    p, png = os.path.join(tmp, name + ".tif"), os.path.join(tmp, name + ".png")
    tifffile.imwrite(p, g.astype(np.float32))
    subprocess.run([MRA, "terrain", "render", p, "-o", png, "--cell", str(cell)], check=True)
    return np.asarray(Image.open(png).convert("L"))


def main():
    name, base, example = next(tq.landform_cases())
    with tempfile.TemporaryDirectory() as tmp:
        bp, ep, op = (os.path.join(tmp, n) for n in ("b.tif", "e.tif", "o.tif"))
        tifffile.imwrite(bp, base.astype(np.float32))
        tifffile.imwrite(ep, example.astype(np.float32))
        subprocess.run([MRA, "terrain", "synth", "--base", bp, "--example", ep, "-o", op, "--levels", "3",
                        "--base-scale", "16", "--seed", "1", "--any-units"], check=True)
        result = tifffile.imread(op).astype(np.float64)
        cubic = ndimage.zoom(base, 8, order=3, mode="nearest", grid_mode=True)
        ex = np.full((512, 512), 255, np.uint8)
        e = render(tmp, "example", example, CELL)
        ex[:e.shape[0], :e.shape[1]] = e
        pics = [np.kron(render(tmp, "base", base, 8 * CELL)[:64, :64], np.ones((8, 8), np.uint8)), ex,
                render(tmp, "result", result, CELL)[:512, :512], render(tmp, "cubic", cubic, CELL)[:512, :512]]
    gap = np.full((512, 8), 255, np.uint8)
    row = np.concatenate([x for p in pics for x in (p, gap)][:-1], axis=1)
    Image.fromarray(row).save(OUT, optimize=True)
    print(OUT, file=sys.stderr)


if __name__ == "__main__":
    main()
