#!/usr/bin/env python3
"""Speed and peak memory of the whole process as a user runs it: `mra encode --bpp B` /
`mra decode` against `opj_compress -r` / `opj_decompress` (OpenJPEG 9/7 at the same rate) on
images, and against SZ3 (`pysz`, absolute error bound chosen to land on mra's bits per
voxel) on a 256³ u16 CT volume.

Images: both read the PNG and write PPM (no PNG encoder in the decode time; `--out png`
measures PNG output instead). Each time is the best wall time of `--repeat` runs (default
3), the peak RSS the largest `Maximum resident set size` of `/usr/bin/time -v` over them.
SZ3 runs in this Python process (its time excludes the interpreter start; its memory is
measured in a child running the same call under `/usr/bin/time -v`).

The volume is the corpus CT (`volumes/ct_pancreas_256.nrrd`, 256×256×134 int16) mirrored
along z to 256 planes and shifted to u16, written as raw little-endian samples.

Needs: opj_compress/opj_decompress (libopenjp2-tools), `pip install pysz numpy`.
Usage (from the repository root, after `cargo build --release`):
  python3 benches/peers/codec_speed.py [--corpus ../shared/corpus] [--mra BIN] [--bpp 1]

The effort ladder (`--ladder`): the flower and kodim01 read as PPM and written as PPM, at
`--bpp`, `mra encode --effort N` for each of `--efforts` (default 1, 4 = the default, 7)
and OpenJPEG, each on `RAYON_NUM_THREADS` / `-threads` of each of `--threads` (default 1
and 2): bytes, PSNR (`mra compare`), best encode and decode wall, and the load average
before and after (ratios within one run are what to read on a shared machine):
  python3 benches/peers/codec_speed.py --ladder [--efforts 1,4,7] [--threads 1,2]
"""
import argparse, gzip, os, re, subprocess, sys, tempfile, time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def timed(cmd, repeat, env=None):
    """(best wall seconds, peak RSS in MB) of `cmd` run `repeat` times."""
    best, rss = float("inf"), 0.0
    for _ in range(repeat):
        t = time.perf_counter()
        p = subprocess.run(["/usr/bin/time", "-v"] + cmd, stdout=subprocess.DEVNULL,
                           stderr=subprocess.PIPE, text=True, env=env)
        dt = time.perf_counter() - t
        if p.returncode != 0:
            sys.exit(f"failed: {' '.join(cmd)}\n{p.stderr[-2000:]}")
        best = min(best, dt)
        m = re.search(r"Maximum resident set size \(kbytes\): (\d+)", p.stderr)
        rss = max(rss, int(m.group(1)) / 1024.0 if m else float("nan"))
    return best, rss


def read_nrrd_gzip(path):
    import numpy as np
    data = open(path, "rb").read()
    head, _, body = data.partition(b"\n\n")
    fields = dict(l.split(": ", 1) for l in head.decode().splitlines() if ": " in l)
    sizes = [int(s) for s in fields["sizes"].split()]
    assert fields["type"] == "int16" and fields["encoding"] == "gzip", fields
    a = np.frombuffer(gzip.decompress(body), dtype="<i2")
    return a.reshape(sizes[::-1]).copy()  # (z, y, x), writable


def volume(corpus, tmp):
    import numpy as np
    v = read_nrrd_gzip(os.path.join(corpus, "volumes", "ct_pancreas_256.nrrd"))
    z = np.concatenate([v, v[::-1]], axis=0)[:256]
    u = (z.astype(np.int32) - int(z.min())).astype("<u2")
    path = os.path.join(tmp, "ct256.raw")
    u.tofile(path)
    return u, path


SZ_CHILD = r"""
import sys, numpy as np, pysz
raw, e, mode = sys.argv[1], float(sys.argv[2]), sys.argv[3]
u = np.fromfile(raw, dtype="<u2").reshape(256, 256, 256)
cfg = pysz.szConfig(); cfg.errorBoundMode = pysz.szErrorBoundMode.ABS; cfg.absErrorBound = e
c, _ = pysz.sz.compress(u.astype(np.float32), cfg)
if mode == "d":
    d = pysz.sz.decompress(c, np.float32, u.shape)
"""


def sz3(u, e, repeat):
    """(bits/voxel, encode s, decode s) of SZ3 at absolute bound `e`, in process."""
    import numpy as np
    import pysz
    f = u.astype(np.float32)
    cfg = pysz.szConfig()
    cfg.errorBoundMode = pysz.szErrorBoundMode.ABS
    cfg.absErrorBound = e
    te = td = float("inf")
    for _ in range(repeat):
        t = time.perf_counter()
        c, _ = pysz.sz.compress(u.astype(np.float32), cfg)
        te = min(te, time.perf_counter() - t)
        t = time.perf_counter()
        d = pysz.sz.decompress(c, np.float32, f.shape)
        d = d[0] if isinstance(d, tuple) else d
        np.round(d).astype("<u2")
        td = min(td, time.perf_counter() - t)
    return c.size * 8 / u.size, te, td


def psnr(mra, a, b):
    """PSNR in dB of `b` against `a` as `mra compare` prints it."""
    out = subprocess.run([mra, "compare", a, b], capture_output=True, text=True).stdout
    m = re.search(r"PSNR[^0-9]*([0-9.]+|inf)", out)
    return float(m.group(1)) if m else float("nan")


def ladder(a):
    """The effort ladder table (module doc)."""
    images = [os.path.join(a.corpus, "images", "large", "flower_foveon_rgb8.png"),
              os.path.join(a.corpus, "images", "kodak", "kodim01.png")]
    efforts = [int(e) for e in a.efforts.split(",")]
    threads = [int(t) for t in a.threads.split(",")]
    load0 = os.getloadavg()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for img in images:
            name = os.path.basename(img).rsplit(".", 1)[0]
            ppm = os.path.join(tmp, name + ".ppm")
            subprocess.run([a.mra, "convert", img, "-o", ppm], check=True, capture_output=True)
            for t in threads:
                env = dict(os.environ, RAYON_NUM_THREADS=str(t))
                for e in efforts:
                    enc, out = os.path.join(tmp, "a.mra"), os.path.join(tmp, "m.ppm")
                    me = timed([a.mra, "encode", ppm, "-o", enc, "--bpp", str(a.bpp),
                                "--effort", str(e), "--quiet"], a.repeat, env)
                    md = timed([a.mra, "decode", enc, "-o", out, "--quiet"], a.repeat, env)
                    rows.append((name, t, f"mra --effort {e}", os.path.getsize(enc),
                                 psnr(a.mra, ppm, out), me, md))
                j2k, out = os.path.join(tmp, "a.j2k"), os.path.join(tmp, "o.ppm")
                oe = timed(["opj_compress", "-i", ppm, "-o", j2k, "-r", str(24.0 / a.bpp),
                            "-threads", str(t)], a.repeat)
                od = timed(["opj_decompress", "-i", j2k, "-o", out, "-threads", str(t)], a.repeat)
                rows.append((name, t, "OpenJPEG", os.path.getsize(j2k), psnr(a.mra, ppm, out), oe, od))
    load1 = os.getloadavg()
    print(f"Whole process, PPM in and out, --bpp {a.bpp:g}, best of {a.repeat}; load average "
          f"{load0[0]:.1f} before, {load1[0]:.1f} after.\n")
    print("| image | threads | coder | bytes | PSNR dB | encode s | decode s | encode vs OpenJPEG | decode vs OpenJPEG |")
    print("|---|---|---|---|---|---|---|---|---|")
    for name, t, what, size, db, me, md in rows:
        opj = next(r for r in rows if r[0] == name and r[1] == t and r[2] == "OpenJPEG")
        print(f"| {name} | {t} | {what} | {size} | {db:.2f} | {me[0]:.3f} | {md[0]:.3f} | "
              f"{opj[5][0] / me[0]:.2f}× | {opj[6][0] / md[0]:.2f}× |")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--corpus", default=os.path.join(ROOT, "..", "shared", "corpus"))
    ap.add_argument("--mra", default=os.path.join(ROOT, "target", "release", "mra"))
    ap.add_argument("--bpp", type=float, default=1.0)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--out", default="ppm", choices=["ppm", "png"])
    ap.add_argument("--no-volume", action="store_true")
    ap.add_argument("--ladder", action="store_true", help="the effort ladder table instead")
    ap.add_argument("--efforts", default="1,4,7")
    ap.add_argument("--threads", default="1,2")
    a = ap.parse_args()
    if a.ladder:
        return ladder(a)
    images = [os.path.join(a.corpus, "images", "kodak", "kodim01.png"),
              os.path.join(a.corpus, "images", "large", "flower_foveon_rgb8.png")]
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for img in images:
            name = os.path.basename(img)
            enc, j2k = os.path.join(tmp, "a.mra"), os.path.join(tmp, "a.j2k")
            o1, o2 = os.path.join(tmp, "m." + a.out), os.path.join(tmp, "o." + a.out)
            me = timed([a.mra, "encode", img, "-o", enc, "--bpp", str(a.bpp)], a.repeat)
            md = timed([a.mra, "decode", enc, "-o", o1], a.repeat)
            oe = timed(["opj_compress", "-i", img, "-o", j2k, "-r", str(24.0 / a.bpp)], a.repeat)
            od = timed(["opj_decompress", "-i", j2k, "-o", o2], a.repeat)
            rows.append((name, f"--bpp {a.bpp:g}", me, md, oe, od, "OpenJPEG"))
        if not a.no_volume:
            import numpy as np
            u, raw = volume(a.corpus, tmp)
            enc, out = os.path.join(tmp, "v.mra"), os.path.join(tmp, "v.raw")
            flags = ["--dims", "256x256x256", "--dtype", "u16"]
            me = timed([a.mra, "encode", raw] + flags + ["-o", enc, "--bpp", str(a.bpp)], a.repeat)
            md = timed([a.mra, "decode", enc, "-o", out], a.repeat)
            bits = os.path.getsize(enc) * 8 / u.size
            # the SZ3 bound whose size is mra's (bisection on log E)
            lo, hi = 1e-2, 1e3
            for _ in range(14):
                mid = (lo * hi) ** 0.5
                b = sz3(u, mid, 1)[0]
                lo, hi = (lo, mid) if b < bits else (mid, hi)
            e = (lo * hi) ** 0.5
            bpv, te, td = sz3(u, e, a.repeat)
            rss = {}
            for mode in "cd":
                p = subprocess.run(["/usr/bin/time", "-v", sys.executable, "-c", SZ_CHILD, raw, str(e), mode],
                                   stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
                m = re.search(r"Maximum resident set size \(kbytes\): (\d+)", p.stderr)
                rss[mode] = int(m.group(1)) / 1024.0 if m else float("nan")
            rows.append(("CT 256³ u16 (32 MB)", f"{bits:.3f} vs {bpv:.3f} bits/voxel (SZ3 E={e:.3g})",
                         me, md, (te, rss["c"]), (td, rss["d"]), "SZ3"))
    print(f"Whole process, best of {a.repeat}, wall seconds and peak RSS (MB); image decode output {a.out.upper()}.\n")
    print("| input | rate | mra encode | peer encode | ratio | mra decode | peer decode | ratio | peer |")
    print("|---|---|---|---|---|---|---|---|---|")
    for name, rate, me, md, pe, pd, peer in rows:
        print(f"| {name} | {rate} | {me[0]:.3f} s, {me[1]:.0f} MB | {pe[0]:.3f} s, {pe[1]:.0f} MB | "
              f"{pe[0] / me[0]:.2f}× | {md[0]:.3f} s, {md[1]:.0f} MB | {pd[0]:.3f} s, {pd[1]:.0f} MB | "
              f"{pd[0] / md[0]:.2f}× | {peer} |")


if __name__ == "__main__":
    main()
