#!/usr/bin/env python3
"""One transform against tiles on huge rasters (docs/tiles.md, "One transform at any
size"): a 16384² u16 image (4×4 `mra generate terrain` of 4096²) and a 1024³ u16
volume (64 terrains of 1024², each 16 planes thick: the phantom would be exact at
1 bpp; `--first N`: the first terrain N planes thick, the last 16 − N, so that no
change of terrain lies on a face of the 128³ tiles, which do not code the changes on
their faces), raw files in a temporary folder (/dev/shm when it has room), coded at `--bpp 1`
as one transform streamed (format 3.2, the default of both), with `--tile` (2.x tiles
of 1024² / 128³), and `--lossless` (tiled); decoded to raw. Prints per file: format version,
bytes, bits per position, PSNR (chunked, `examples/raw_psnr.rs`, peak 65535), encode
and decode wall s / CPU s / peak RSS MiB (`/usr/bin/time -v`), decode MB/s of samples.
Everything is removed at the end (`HUGE_TMP=dir`: the temporary folder there).

Run from the repository root after
`cargo build --release && cargo build --release --example raw_psnr`:
    python3 benches/huge.py [--skip-image] [--skip-volume] [--skip-lossless] [--skip-tiles]
                            [--threads N] [--first N] [--rate "--max-error 5"]
                            [--volume 512x512x264] [--tiles 128,1024]
`--rate` replaces `--bpp 1` (the rate of the one-transform and tiled rows); `--volume
XxYxZ` (X = Y) builds the volume of terrains of X² instead of 1024³; `--tiles` lists the
tile extents of the tiled rows (default: 1024 for the image, 128 for the volume).
"""
import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile

MRA = os.environ.get("MRA", "target/release/mra")
PSNR = os.environ.get("RAW_PSNR", "target/release/examples/raw_psnr")


def timed(args, env):
    """Run under /usr/bin/time -v: (stdout, wall s, CPU s, peak MiB)."""
    p = subprocess.run(["/usr/bin/time", "-v"] + args, capture_output=True, text=True, env=env)
    if p.returncode != 0:
        sys.exit(f"{' '.join(args)} failed:\n{p.stderr[-3000:]}")
    e = p.stderr
    m = re.search(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): (\S+)", e).group(1).split(":")
    wall = sum(float(x) * 60 ** i for i, x in enumerate(reversed(m)))
    cpu = sum(float(x) for x in re.findall(r"(?:User|System) time \(seconds\): ([\d.]+)", e))
    rss = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", e).group(1)) / 1024
    return p.stdout, wall, cpu, rss


def scratch():
    if os.environ.get("HUGE_TMP"):
        return tempfile.mkdtemp(prefix="mra-huge-", dir=os.environ["HUGE_TMP"])
    try:
        st = os.statvfs("/dev/shm")
        if st.f_bavail * st.f_frsize >= 8 * 2**30:
            return tempfile.mkdtemp(prefix="mra-huge-", dir="/dev/shm")
    except OSError:
        pass
    return tempfile.mkdtemp(prefix="mra-huge-")


def one(label, raw, dims, rate, tile, tmp, env):
    f = os.path.join(tmp, "f.mra")
    back = os.path.join(tmp, "back.raw")
    extra = ["--tile", tile] if tile else []
    _, ew, ec, er = timed([MRA, "encode", raw, "--dims", dims, "--dtype", "u16", "-o", f,
                           *rate, *extra], env)
    size = os.path.getsize(f)
    _, dw, dc, dr = timed([MRA, "decode", f, "-o", back], env)
    info = subprocess.run([MRA, "info", f, "--json"], capture_output=True, text=True).stdout
    ver = re.search(r'"version": *"([^"]*)"', info)
    n = os.path.getsize(raw)
    psnr = subprocess.run([PSNR, raw, back], capture_output=True, text=True).stdout.strip()
    bpp = size * 8 / (n / 2)
    print(f"| {label} | {' '.join(rate + extra)} | {ver.group(1) if ver else '?'} | {size:,} B, "
          f"{bpp:.4f} bpp | {psnr} | {ew:.1f} / {ec:.1f} / {er:.0f} | {dw:.1f} / {dc:.1f} / "
          f"{dr:.0f} | {n / 1e6 / dw:.1f} |", flush=True)
    os.remove(f)
    os.remove(back)


def mosaic(raw, tmp):
    """A 16384² u16 image: 4×4 terrains of 4096² (`mra generate terrain`, seeds 1–16;
    one of 16384² would take about 5 GB to generate)."""
    parts = []
    for k in range(16):
        p = os.path.join(tmp, f"t{k}.raw")
        subprocess.run([MRA, "generate", "terrain", "-o", p, "--size", "4096", "--dtype", "u16",
                        "--seed", str(k + 1)], check=True, capture_output=True)
        parts.append(p)
    with open(raw, "wb") as out:
        for ty in range(4):
            files = [open(parts[ty * 4 + tx], "rb") for tx in range(4)]
            for _ in range(4096):
                for f in files:
                    out.write(f.read(8192))
            for f in files:
                f.close()
    for p in parts:
        os.remove(p)


def run(label, raw, dims, tile, args, tmp, env):
    rate = args.rate.split()
    # one transform: the default layout of both
    one(label, raw, dims, rate, None, tmp, env)
    if not args.skip_tiles:
        for t in args.tiles.split(",") if args.tiles else [tile]:
            one(label, raw, dims, rate, t, tmp, env)
    if not args.skip_lossless:
        one(label, raw, dims, ["--lossless"], None, tmp, env)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--skip-image", action="store_true")
    ap.add_argument("--skip-volume", action="store_true")
    ap.add_argument("--skip-lossless", action="store_true")
    ap.add_argument("--skip-tiles", action="store_true")
    ap.add_argument("--threads", default="2")
    ap.add_argument("--first", type=int, default=16, help="planes of the first terrain")
    ap.add_argument("--rate", default="--bpp 1")
    ap.add_argument("--volume", default="1024x1024x1024")
    ap.add_argument("--tiles", default=None)
    args = ap.parse_args()
    if not 1 <= args.first <= 16:
        sys.exit("--first: 1 to 16 planes")
    env = dict(os.environ, RAYON_NUM_THREADS=args.threads)
    tmp = scratch()
    try:
        print("| raster | options | format | file | PSNR | encode wall s / CPU s / peak MiB "
              "| decode wall s / CPU s / peak MiB | decode MB/s |")
        print("|---|---|---|---|---|---|---|---|")
        if not args.skip_image:
            raw = os.path.join(tmp, "img.raw")
            mosaic(raw, tmp)
            run("16384² u16", raw, "16384x16384", "1024", args, tmp, env)
            os.remove(raw)
        if not args.skip_volume:
            part = os.path.join(tmp, "part.raw")
            raw = os.path.join(tmp, "vol.raw")
            side, _, depth = (int(x) for x in args.volume.split("x"))
            with open(raw, "wb") as out:
                left, k = depth, 0
                while left > 0:
                    subprocess.run([MRA, "generate", "terrain", "-o", part, "--size", str(side),
                                    "--dtype", "u16", "--seed", str(101 + k)], check=True,
                                   capture_output=True)
                    with open(part, "rb") as src:
                        plane = src.read()
                    # the first terrain --first planes thick, the others 16
                    thick = min(args.first if k == 0 else 16, left)
                    for _ in range(thick):
                        out.write(plane)
                    left, k = left - thick, k + 1
            os.remove(part)
            run(f"{args.volume.replace('x', '×')} u16", raw, args.volume, "128", args, tmp, env)
            os.remove(raw)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
