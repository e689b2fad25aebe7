#!/usr/bin/env python3
"""What tiles cost and buy (docs/tiles.md): the rate-distortion loss of tiling against the
one-piece file (Kodak at 1 bpp, the corpus CT at 1 bit/voxel), and on a generated
16384² u16 image and 1024³ u16 volume (2 GiB each, written under the temporary folder
a slab at a time and removed after): peak RSS and time of encode and decode (streamed,
raw in and out), 1 thread against 2, per-sample speed against a one-piece 512² / 256³
crop, and a region decode's bytes read (`mra decode --json` `bytes_read`) and time.

The thread count is RAYON_NUM_THREADS, the coding threads of the pool: "1" is one
worker with the command's own thread waiting for it at every step (one busy core);
with "2" the command's own thread also reads (encode) or writes (decode) beside the two
workers. The big files go to /dev/shm when it has room for them, so that the times are
those of the coding and not of the disk.

Run from the repository root after `cargo build --release`:
    python3 benches/tiles.py [--kodak N] [--skip-rd] [--skip-image] [--skip-volume] [--bpp]
Needs ../shared/corpus (or MRA_CORPUS) for the Kodak and CT rows and the CT the volume
is made of, numpy for the big inputs.
"""
import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
import time

MRA = os.environ.get("MRA", "target/release/mra")
CORPUS = os.environ.get("MRA_CORPUS", "../shared/corpus")


CPU = {}


def run(args, env=None):
    """Run mra under /usr/bin/time -v: (stdout, seconds, peak RSS in MiB); the CPU seconds
    (user + system) of the run are left in CPU["last"]."""
    e = dict(os.environ)
    e.update(env or {})
    t = time.time()
    p = subprocess.run(["/usr/bin/time", "-v", MRA] + args, capture_output=True, text=True, env=e)
    dt = time.time() - t
    if p.returncode != 0:
        sys.exit(f"mra {' '.join(args)} failed:\n{p.stderr[-2000:]}")
    m = re.search(r"Maximum resident set size \(kbytes\): (\d+)", p.stderr)
    cpu = sum(float(x) for x in re.findall(r"(?:User|System) time \(seconds\): ([\d.]+)", p.stderr))
    CPU["last"] = cpu
    return p.stdout, dt, int(m.group(1)) / 1024 if m else float("nan")


def scratch_dir():
    """A folder for the big files: /dev/shm when it has room for them (a file system in
    memory: the times are those of the coding, not of the disk's write-back), else the
    temporary folder."""
    shm = "/dev/shm"
    try:
        st = os.statvfs(shm)
        if st.f_bavail * st.f_frsize >= 6 * 2**30:
            return tempfile.mkdtemp(prefix="mra-tiles-", dir=shm)
    except OSError:
        pass
    return tempfile.mkdtemp(prefix="mra-tiles-")


def psnr(a, b, extra=()):
    out, _, _ = run(["compare", a, b, "--json", "--quiet", *extra])
    return json.loads(out)["psnr"]


def rd(src, tiles, rate, extra_cmp, tmp):
    """(bits per position, PSNR) of src coded at `rate` with each tile setting."""
    rows = {}
    for t in tiles:
        f = os.path.join(tmp, "t.mra")
        ext = ".nrrd" if src.endswith(".nrrd") else ".png"
        back = os.path.join(tmp, "back" + ext)
        out, _, _ = run(["encode", src, "-o", f, *rate, "--tile", t, "--json"])
        bpp = json.loads(out)["bits_per_position"]
        run(["decode", f, "-o", back])
        rows[t] = (bpp, psnr(src, back, extra_cmp))
    return rows


def uptime():
    return subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()


def gen_image(path, n):
    """A n×n u16 image, written a band of 1024 rows at a time: smooth relief (sines at
    several scales) plus noise, so that no band repeats another."""
    import numpy as np

    rng = np.random.default_rng(1)
    x = np.arange(n, dtype=np.float32)
    with open(path, "wb") as fh:
        for r0 in range(0, n, 1024):
            y = np.arange(r0, min(r0 + 1024, n), dtype=np.float32)[:, None]
            band = (20000 + 12000 * np.sin(x / 900.0) * np.cos(y / 700.0)
                    + 3000 * np.sin((x + 2 * y) / 97.0) + 800 * np.cos((3 * x - y) / 23.0)
                    + rng.normal(0, 300, (len(y), n)).astype(np.float32))
            fh.write(np.clip(band, 0, 65535).astype("<u2").tobytes())


def gen_volume(path, n):
    """A n³ u16 volume, written a slice at a time: the corpus CT crop (256×256×64 u16)
    tiled, each copy mirrored and shifted by a smooth offset so no two are alike, plus
    noise; a smooth synthetic field where the corpus is absent."""
    import numpy as np

    ct = os.path.join(CORPUS, "volumes/ct_pancreas_crop_256x256x64_u16le.raw")
    rng = np.random.default_rng(2)
    base = None
    if os.path.exists(ct):
        base = np.fromfile(ct, dtype="<u2").reshape(64, 256, 256).astype(np.float32)
    y, x = np.mgrid[0:n, 0:n].astype(np.float32)
    with open(path, "wb") as fh:
        for z in range(n):
            if base is not None:
                zz = z % 128
                sl = base[zz if zz < 64 else 127 - zz]
                s = np.tile(np.concatenate([sl, sl[:, ::-1]], 1), (n // 256, n // 512 + 1))[:n, :n]
            else:
                s = 1000 + 800 * np.sin(x / 37.0 + z / 50.0) * np.cos(y / 41.0)
            s = s + 200 * np.sin(x / 300.0 + z / 200.0) * np.cos(y / 250.0) + rng.normal(0, 20, (n, n))
            fh.write(np.clip(s, 0, 65535).astype("<u2").tobytes())


def crop(src, dims, box, dst):
    """Cut box (slowest first, (start, size) per axis) of a u16 raw file of dims."""
    import numpy as np

    a = np.memmap(src, dtype="<u2", mode="r", shape=tuple(dims))
    sl = tuple(slice(s, s + k) for s, k in box)
    np.ascontiguousarray(a[sl]).tofile(dst)


def big(name, raw, dims, tile_label, rate, region, crop_dims, tmp, bpp, threads=("1", "2")):
    """Encode and decode a big raw file with 1 and 2 threads, a one-piece crop, a region."""
    xyz = "x".join(str(d) for d in reversed(dims))
    f = os.path.join(tmp, name + ".mra")
    back = os.path.join(tmp, name + "_back.raw")
    samples = 1
    for d in dims:
        samples *= d
    print(f"## {name}: {xyz} u16 ({samples * 2 / 2**30:.2f} GiB), {' '.join(rate)}")
    print(f"load before: {uptime()}")
    rows = []
    for t in threads:
        env = {"RAYON_NUM_THREADS": t}
        # the tiles explicitly: over the one-piece limit the default is one transform
        # (benches/huge.py measures it)
        out, te, me = run(["encode", raw, "--dims", xyz, "--dtype", "u16", "-o", f, *rate,
                           "--tile", tile_label, "--json"], env)
        ce = CPU["last"]
        enc = json.loads(out)
        _, td, md = run(["decode", f, "-o", back], env)
        cd = CPU["last"]
        os.remove(back)
        rows.append((t, te, me, td, md, ce, cd))
        print(f"| {t} thread(s) | encode {te:.2f} s ({ce:.2f} s CPU), {me:.0f} MiB "
              f"| decode {td:.2f} s ({cd:.2f} s CPU), {md:.0f} MiB |", flush=True)
    info = json.loads(run(["info", f, "--json"])[0])
    print(f"file: {info['file_bytes']} bytes ({enc['bits_per_position']:.3f} bits/sample), "
          f"{info['tiles']} tiles of {'x'.join(str(t) for t in reversed(info['tile']))}")
    print("| threads | encode s / CPU s / peak MiB | decode s / CPU s / peak MiB |\n|---|---|---|")
    for t, te, me, td, md, ce, cd in rows:
        print(f"| {t} | {te:.2f} / {ce:.2f} / {me:.0f} | {td:.2f} / {cd:.2f} / {md:.0f} |")
    if len(rows) == 2:
        print(f"2 threads against 1: encode {rows[0][1] / rows[1][1]:.2f}x, decode {rows[0][3] / rows[1][3]:.2f}x")
    # one piece: a crop of the same data, 2 threads
    c = os.path.join(tmp, name + "_crop.raw")
    crop(raw, dims, [(d // 3, k) for d, k in zip(dims, crop_dims)], c)
    cxyz = "x".join(str(d) for d in reversed(crop_dims))
    one = os.path.join(tmp, name + "_crop.mra")
    env = {"RAYON_NUM_THREADS": "2"}
    _, tce, _ = run(["encode", c, "--dims", cxyz, "--dtype", "u16", "-o", one, *rate], env)
    _, tcd, _ = run(["decode", one, "-o", os.path.join(tmp, "crop_back.raw")], env)
    cs = 1
    for d in crop_dims:
        cs *= d
    us = lambda t, k: t * 1e9 / k
    print(f"ns per sample (2 threads, process start included): tiled encode {us(rows[-1][1], samples):.1f}, "
          f"decode {us(rows[-1][3], samples):.1f}; one-piece {cxyz}: encode {us(tce, cs):.1f}, decode {us(tcd, cs):.1f}")
    reg = os.path.join(tmp, name + "_region.raw")
    out, tr, mr = run(["decode", f, "-o", reg, "--region", region, "--json"], env)
    got = json.loads(out)["bytes_read"]
    print(f"--region {region}: {tr:.3f} s ({100 * tr / rows[-1][3]:.2f}% of the full decode), peak {mr:.0f} MiB, "
          f"{got} bytes read ({100 * got / info['file_bytes']:.3f}% of the file)")
    if bpp:
        out, tb, mb = run(["encode", raw, "--dims", xyz, "--dtype", "u16", "-o", f, "--bpp", "1", "--json"], env)
        print(f"--bpp 1 (2 threads): {tb:.2f} s, peak {mb:.0f} MiB, {json.loads(out)['bits_per_position']:.4f} bits/sample")
    print(f"load after: {uptime()}")
    for p in [f, c, one, reg]:
        if os.path.exists(p):
            os.remove(p)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--kodak", type=int, default=24, help="images of Kodak to use")
    ap.add_argument("--big", type=int, default=16384, help="side of the generated u16 image")
    ap.add_argument("--volume", type=int, default=1024, help="side of the generated u16 volume")
    ap.add_argument("--skip-rd", action="store_true")
    ap.add_argument("--skip-big", action="store_true")
    ap.add_argument("--skip-image", action="store_true")
    ap.add_argument("--skip-volume", action="store_true")
    ap.add_argument("--bpp", action="store_true", help="also encode the big image at --bpp 1")
    ap.add_argument("--volume-threads", default="1,2", help="thread counts for the volume, e.g. 2")
    ap.add_argument("--volume-raw", help="use this generated volume (kept) instead of making one")
    a = ap.parse_args()
    tmp = scratch_dir()
    print(f"scratch folder: {tmp}")
    kodak = os.path.join(CORPUS, "images/kodak")
    if os.path.isdir(kodak) and not a.skip_rd:
        tiles = ["whole", "512", "256"]
        acc = {t: [0.0, 0.0] for t in tiles}
        for i in range(1, a.kodak + 1):
            r = rd(os.path.join(kodak, f"kodim{i:02}.png"), tiles, ["--bpp", "1"], [], tmp)
            for t in tiles:
                acc[t][0] += r[t][0] / a.kodak
                acc[t][1] += r[t][1] / a.kodak
        print(f"## Kodak ({a.kodak} images), --bpp 1")
        print("| tile | bpp | PSNR dB | ΔPSNR dB |\n|---|---|---|---|")
        for t in tiles:
            print(f"| {t} | {acc[t][0]:.4f} | {acc[t][1]:.3f} | {acc[t][1] - acc['whole'][1]:+.3f} |")
    ct = os.path.join(CORPUS, "volumes/ct_pancreas_256.nrrd")
    if os.path.exists(ct) and not a.skip_rd:
        tiles = ["whole", "128", "64"]
        r = rd(ct, tiles, ["--bpp", "1"], ["--data-range", "2510"], tmp)
        print("## CT 256x256x134 i16, --bpp 1 (PSNR over 2510)")
        print("| tile | bits/voxel | PSNR dB | ΔPSNR dB |\n|---|---|---|---|")
        for t in tiles:
            print(f"| {t} | {r[t][0]:.4f} | {r[t][1]:.3f} | {r[t][1] - r['whole'][1]:+.3f} |")
    sys.stdout.flush()
    if a.skip_big:
        return
    if not a.skip_image:
        n = a.big
        raw = os.path.join(tmp, "image.raw")
        gen_image(raw, n)
        big("image", raw, [n, n], "1024", ["--quality", "60"], "8192:8256,4096:4160", [512, 512], tmp, a.bpp)
        os.remove(raw)
        sys.stdout.flush()
    if not a.skip_volume:
        n = a.volume
        raw = a.volume_raw or os.path.join(tmp, "volume.raw")
        if not a.volume_raw:
            gen_volume(raw, n)
        h = n // 2
        big("volume", raw, [n, n, n], "128", ["--quality", "60"], f"{h}:{h + 64},{h}:{h + 64},{h}:{h + 64}",
            [256, 256, 256], tmp, False, tuple(a.volume_threads.split(",")))
        if not a.volume_raw:
            os.remove(raw)
    os.rmdir(tmp) if not os.listdir(tmp) else None


if __name__ == "__main__":
    main()
