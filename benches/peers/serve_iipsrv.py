"""Tile serving speed: `mra serve` against iipsrv (Debian `iipimage-server`, FastCGI behind
lighttpd) over a pyramid TIFF made by `vips tiffsave --tile --pyramid`, same image, same
256² IIIF tile requests (a random pan/zoom trace), 8 concurrent clients with keep-alive,
loopback only. Prints file sizes and PSNR of both codings, then p50/p99 latency and
throughput of each server, as markdown table rows.

usage: python3 benches/peers/serve_iipsrv.py [--size 8192] [--requests 4000] [--clients 8] [--mra-tile 256]
       [--blocks] [--warm] [--work DIR] [--rounds N] [--split] [--floor] [--threads]

--rounds N measures the two servers N times, alternating, each round a new trace (the
servers keep what they cached). --split prints, for `mra serve`, the latency by what each
request did, from the answer's `Server-Timing` header (kept answer, or render: the level
read, where its window came from, resampled or not) with the server's own time. --floor adds,
after each round, what the client measures against a server that does nothing: the round's
answers as static files served by lighttpd, and mra serve asked the same trace again (all
kept). Each client is a process of its own (--threads: threads of one process, which wait for
each other's interpreter lock).
needs: apt-get install iipimage-server lighttpd libvips-tools; MRA (default target/release/mra)
"""
import argparse
import hashlib
import http.client
import json
import multiprocessing
import os
import random
import shutil
import socket
import subprocess
import sys
import tempfile
import threading
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
IIPSRV = "/usr/lib/iipimage-server/iipsrv.fcgi"
TILE = 256


def sh(*args, **kw):
    return subprocess.run(args, check=True, capture_output=True, text=True, **kw).stdout


def trace(size, n, seed):
    """n IIIF tile requests (region, size) at random levels and places."""
    rng = random.Random(seed)
    depth = 0
    while (size >> depth) > TILE:
        depth += 1
    out = []
    for _ in range(n):
        k = rng.randint(0, depth)
        span = TILE << k
        tiles = -(-size // span)
        cx, cy = rng.randrange(tiles), rng.randrange(tiles)
        x, y = cx * span, cy * span
        w, h = min(span, size - x), min(span, size - y)
        out.append(f"{x},{y},{w},{h}/{-(-w // (1 << k))},/0/default.jpg")
    return out


def parse_timing(v):
    """A `Server-Timing` value as (what, {name: ms})."""
    what, durs = "?", {}
    for part in (v or "").split(","):
        fields = [f.strip() for f in part.split(";")]
        name = fields[0]
        for f in fields[1:]:
            if f.startswith("dur="):
                durs[name] = float(f[4:])
            elif f.startswith("desc="):
                what = f"{name} {f[5:].strip(chr(34))}"
        if name == "kept":
            what = "kept"
    return what, durs


def _client(host, port, prefix, chunk, want_timing, start, out):
    """One client: its requests in order over one keep-alive connection, after `start`
    (a barrier); puts (first start, last end, [(latency, Server-Timing)], errors, connections reopened) on `out`."""
    c = http.client.HTTPConnection(host, port, timeout=60)
    c.connect()
    c.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    mine, errors, reopened = [], [], 0
    start.wait()
    t_first = time.perf_counter()
    for r in chunk:
        # http.client opens a new connection when the server closed the last one
        reopened += c.sock is None
        t = time.perf_counter()
        c.request("GET", prefix + r)
        resp = c.getresponse()
        body = resp.read()
        lat = time.perf_counter() - t
        mine.append((lat, resp.getheader("Server-Timing") if want_timing else None))
        if resp.status != 200 or len(body) < 100:
            errors.append((resp.status, r))
    t_last = time.perf_counter()
    c.close()
    out.put((t_first, t_last, mine, errors, reopened))


def run_clients(host, port, prefix, reqs, clients, timings=None, threads=False):
    """Latencies (s) of every request and the wall time, `clients` clients with keep-alive,
    each a process of its own (so that no client waits for another's interpreter lock;
    `threads`: threads of this process, the bench's old client); with `timings` (a list),
    each request's (latency, Server-Timing header) appended to it."""
    chunks = [reqs[i::clients] for i in range(clients)]
    if threads:
        import queue
        out, start = queue.Queue(), threading.Barrier(clients)
        workers = [threading.Thread(target=_client, args=(host, port, prefix, ch, timings is not None, start, out))
                   for ch in chunks]
    else:
        ctx = multiprocessing.get_context("fork")
        out, start = ctx.Queue(), ctx.Barrier(clients)
        workers = [ctx.Process(target=_client, args=(host, port, prefix, ch, timings is not None, start, out))
                   for ch in chunks]
    for w in workers:
        w.start()
    got = [out.get() for _ in workers]
    for w in workers:
        w.join()
    # perf_counter is the system's monotonic clock: comparable between processes
    wall = max(g[1] for g in got) - min(g[0] for g in got)
    errors = [e for g in got for e in g[3]]
    if errors:
        raise SystemExit(f"{len(errors)} failed requests, first {errors[0]}")
    reopened = sum(g[4] for g in got)
    if reopened:
        print(f"({port}: {reopened} connections reopened: keep-alive not kept)", file=sys.stderr)
    seen = [m for g in got for m in g[2]]
    if timings is not None:
        timings.extend(seen)
    return sorted(lat for lat, _ in seen), wall


def static_copy(host, port, prefix, reqs, folder):
    """Each answer of `reqs` (asked of the server at `port`, one client) saved in `folder`
    under a name of its request; the names, in the order of `reqs`."""
    os.makedirs(folder, exist_ok=True)
    c = http.client.HTTPConnection(host, port, timeout=60)
    names = []
    for r in reqs:
        name = hashlib.sha1(r.encode()).hexdigest()[:16] + ".jpg"
        path = os.path.join(folder, name)
        if not os.path.exists(path):
            c.request("GET", prefix + r)
            resp = c.getresponse()
            body = resp.read()
            if resp.status != 200:
                raise SystemExit(f"{r}: {resp.status} while copying the answers")
            with open(path, "wb") as f:
                f.write(body)
        names.append(name)
    c.close()
    return names


def pct(v, p):
    return v[min(len(v) - 1, int(p / 100 * len(v)))]


def split_table(timings):
    """Latency by what the request did, and where the server's time went."""
    groups = {}
    for lat, hdr in timings:
        what, durs = parse_timing(hdr)
        groups.setdefault(what, []).append((lat * 1e3, durs))
    slow = sorted(lat for lat, _ in timings)
    p99 = pct(slow, 99) * 1e3
    print("\n| mra serve: what the request did | n | ≥ p99 | p50 ms | p99 ms | server total p50 / p99 ms "
          "| queue p50 / p99 | window p50 / p99 | encode p50 / p99 |\n|---|---|---|---|---|---|---|---|---|")
    for what, v in sorted(groups.items(), key=lambda kv: -len(kv[1])):
        lats = sorted(l for l, _ in v)
        d = lambda name: sorted(x.get(name, 0.0) for _, x in v)
        tot = d("total")
        print(f"| {what} | {len(v)} | {sum(l >= p99 for l in lats)} | {pct(lats, 50):.1f} | {pct(lats, 99):.1f} "
              f"| {pct(tot, 50):.2f} / {pct(tot, 99):.2f} "
              + " ".join(f"| {pct(d(n), 50):.2f} / {pct(d(n), 99):.2f}" for n in ("queue", "window", "encode"))
              + " |")


def wait_port(port):
    for _ in range(200):
        try:
            http.client.HTTPConnection("127.0.0.1", port, timeout=1).connect()
            return
        except OSError:
            time.sleep(0.05)
    raise SystemExit(f"nothing listening on {port}")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--size", type=int, default=8192)
    ap.add_argument("--requests", type=int, default=4000)
    ap.add_argument("--clients", type=int, default=8)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--mra-tile", default="256",
                    help="tile extent of the .mra file (mra encode --tile; 'default' for mra's own choice)")
    ap.add_argument("--blocks", action="store_true",
                    help="write the .mra as format 3.0 code-blocks (mra encode --blocks; "
                         "with --mra-tile whole: one piece, each tile request decoding "
                         "only the code-blocks its window needs)")
    ap.add_argument("--warm", action="store_true",
                    help="start mra serve with --warm (the levels the cache keeps decoded "
                         "before serving, as the pyramid TIFF is built before iipsrv serves it)")
    ap.add_argument("--rounds", type=int, default=1,
                    help="measure both servers this many times, alternating, a new trace each round")
    ap.add_argument("--split", action="store_true",
                    help="mra serve's latency by what each request did (its Server-Timing header)")
    ap.add_argument("--threads", action="store_true",
                    help="the clients as threads of one Python process (they then wait for each "
                         "other's interpreter lock, which is most of a tail of a few ms) instead of "
                         "one process each")
    ap.add_argument("--floor", action="store_true",
                    help="after each round, the client's floor: the same trace asked of lighttpd "
                         "serving mra's answers as static files, and of mra serve again (every "
                         "answer then kept)")
    ap.add_argument("--work", help="a folder to keep the generated files in and reuse them "
                    "from on the next run (default: a temporary folder, removed)")
    a = ap.parse_args()
    for tool in ["vips", "lighttpd"]:
        if not shutil.which(tool):
            raise SystemExit(f"{tool} missing: apt-get install iipimage-server lighttpd libvips-tools")
    if not os.path.exists(IIPSRV):
        raise SystemExit("iipsrv missing: apt-get install iipimage-server")
    mra = os.environ.get("MRA", os.path.join(ROOT, "target", "release", "mra"))
    work = a.work or tempfile.mkdtemp(prefix="mra-iipsrv-")
    os.makedirs(work, exist_ok=True)
    procs = []
    try:
        src = os.path.join(work, "src.png")
        if not os.path.exists(src):
            sh(mra, "generate", "strokes", "-o", src, "--size", str(a.size))
        tif = os.path.join(work, "img.tif")
        if not os.path.exists(tif):
            sh("vips", "tiffsave", src, tif, "--tile", "--pyramid", "--compression", "jpeg",
               "--Q", "90", "--tile-width", str(TILE), "--tile-height", str(TILE))
        full = os.path.join(work, "tif_full.png")
        sh("vips", "copy", tif + "[page=0]", full)
        cmp_tif = json.loads(sh(mra, "compare", src, full, "--json"))
        served = os.path.join(work, f"served-{a.mra_tile}{'-blocks' if a.blocks else ''}")
        os.makedirs(served, exist_ok=True)
        coded = os.path.join(served, "img.mra")
        tile = [] if a.mra_tile == "default" else ["--tile", a.mra_tile]
        if a.blocks:
            tile.append("--blocks")
        if not os.path.exists(coded):
            sh(mra, "encode", src, "-o", coded, "--psnr", f"{cmp_tif['psnr']:.2f}", *tile)
        dec = os.path.join(work, "mra_full.png")
        sh(mra, "decode", coded, "-o", dec)
        cmp_mra = json.loads(sh(mra, "compare", src, dec, "--json"))
        print(f"| coding | bytes | PSNR dB |\n|---|---|---|")
        print(f"| pyramid TIFF (vips, JPEG Q90, 256² tiles) | {os.path.getsize(tif)} | {cmp_tif['psnr']:.2f} |")
        print(f"| .mra (--psnr {cmp_tif['psnr']:.2f}, --tile {a.mra_tile}{' --blocks' if a.blocks else ''}) | {os.path.getsize(coded)} | {cmp_mra['psnr']:.2f} |")

        port_iip, port_mra = 18950 + a.seed % 50, 0
        conf = os.path.join(work, "lighttpd.conf")
        with open(conf, "w") as f:
            f.write(f"""server.modules = ("mod_fastcgi")
server.document-root = "{work}"
server.bind = "127.0.0.1"
server.port = {port_iip}
server.max-keep-alive-requests = 100000
fastcgi.server = ( "/fcgi-bin/iipsrv.fcgi" => ((
  "socket" => "{work}/iipsrv.sock", "bin-path" => "{IIPSRV}", "check-local" => "disable",
  "max-procs" => {os.cpu_count() or 2},
  "bin-environment" => ("LOGFILE" => "{work}/iipsrv.log", "VERBOSITY" => "0",
     "MAX_IMAGE_CACHE_SIZE" => "512", "JPEG_QUALITY" => "90", "MAX_CVT" => "4096")
)))
""")
        procs.append(subprocess.Popen(["lighttpd", "-D", "-f", conf]))
        wait_port(port_iip)
        t0 = time.perf_counter()
        srv = subprocess.Popen([mra, "serve", served, "--bind", "127.0.0.1:0"] + (["--warm"] if a.warm else []),
                               stdout=subprocess.PIPE, text=True)
        procs.append(srv)
        port_mra = int(srv.stdout.readline().split("http://")[1].strip().rstrip("/").split(":")[1])
        if a.warm:
            print(f"\nmra serve --warm ready after {time.perf_counter() - t0:.1f} s")

        warm = trace(a.size, 200, a.seed + 1000)
        servers = [
            ("iipsrv (pyramid TIFF)", port_iip, f"/fcgi-bin/iipsrv.fcgi?IIIF={tif}/"),
            ("mra serve (.mra)", port_mra, "/iiif/3/img.mra/"),
        ]
        print(f"\n{a.requests} tile requests, {a.clients} clients, {a.size}² image\n")
        print("| server | p50 ms | p99 ms | tiles/s | load average |\n|---|---|---|---|---|")
        for name, port, prefix in servers:
            run_clients("127.0.0.1", port, prefix, warm, a.clients, threads=a.threads)
        timings = []
        for rnd in range(a.rounds):
            reqs = trace(a.size, a.requests, a.seed + rnd)
            runs = [(name, port, prefix, reqs) for name, port, prefix in servers]
            for name, port, prefix, rr in runs:
                mine = timings if name.startswith("mra") else None
                lat, wall = run_clients("127.0.0.1", port, prefix, rr, a.clients, mine, a.threads)
                load = os.getloadavg()[0]
                print(f"| {name} | {pct(lat, 50) * 1e3:.1f} | {pct(lat, 99) * 1e3:.1f} | {len(lat) / wall:.0f} | {load:.1f} |",
                      flush=True)
            if a.floor:
                # not before the round: the copies would warm the servers' caches
                names = static_copy("127.0.0.1", port_mra, "/iiif/3/img.mra/", reqs, os.path.join(work, "static"))
                for name, port, prefix, rr in [("floor: lighttpd, static files", port_iip, "/static/", names),
                                               ("floor: mra serve, all kept", port_mra, "/iiif/3/img.mra/", reqs)]:
                    lat, wall = run_clients("127.0.0.1", port, prefix, rr, a.clients, threads=a.threads)
                    load = os.getloadavg()[0]
                    print(f"| {name} | {pct(lat, 50) * 1e3:.1f} | {pct(lat, 99) * 1e3:.1f} | {len(lat) / wall:.0f} | {load:.1f} |",
                          flush=True)
        if a.split:
            split_table(timings)
    finally:
        for p in procs:
            p.terminate()
            p.wait()
        if not a.work:
            shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
