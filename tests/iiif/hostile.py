"""Hostile requests against `mra serve`: N (default 10,000) malformed or hostile requests
(path traversal, ..%2f, absolute paths, huge and negative sizes, zero widths, non-numeric
parts, random bytes, very long URLs) while slowloris connections trickle headers. Every
answer must be 4xx (or the connection dropped), a good request every 100 must answer 200,
and the server's peak RSS (VmHWM) must stay under 1 GiB.

usage: python3 tests/iiif/hostile.py [--requests 10000] [--seed 1]
env:   MRA (the binary, default target/release/mra)

Ends with "N passed, N failed" (a pass is one hostile request answered 4xx or dropped).
"""
import argparse
import os
import random
import socket
import subprocess
import sys
import tempfile
import threading
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def request(addr, target, timeout=30.0):
    """Status of GET target (sent verbatim), or 0 when the connection is dropped."""
    try:
        with socket.create_connection(addr, timeout=timeout) as s:
            s.sendall(b"GET " + target + b" HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n")
            data = b""
            while b"\r\n" not in data:
                chunk = s.recv(4096)
                if not chunk:
                    break
                data += chunk
            parts = data.split(b" ", 2)
            return int(parts[1]) if len(parts) > 1 and parts[1].isdigit() else 0
    except (ConnectionError, socket.timeout, OSError):
        return 0


def hostile(rng):
    """One request target that is malformed, unsatisfiable or outside the folder (each
    list holds only values the IIIF grammar or the server's limits refuse)."""
    num = lambda: rng.choice(["-1", "-99999", "99999999999999999999", "1e9", "nan", "inf",
                              "abc", "", "0x10", "%00", "+5", "9" * rng.randint(13, 3000)])
    n = str(rng.randint(0, 2000))
    region = rng.choice([
        f"{num()},{n},{n},{n}", f"{n},{num()},{n},{n}", f"{n},{n},{num()},{n}", f"{n},{n},{n},{num()}",
        f"pct:{num()},0,10,10", "5000,5000,10,10", "0,0,0,0", f"{n},{n},0,{n}", "full,", "%2e%2e",
        "pct:100,0,5,5", "1,2,3", "1,2,3,4,5",
    ])
    size = rng.choice([f"{num()},", f",{num()}", f"!{num()},{n}", f"pct:{num()}", "^max", "^1000,",
                       "99999,99999", "2049,", ",2049", "pct:101", "max,", "!0,0", f"{n},{n},{n}", "0,"])
    rot = rng.choice(["45", "-90", "!", "!!90", "90.5", "360.1", num()])
    qf = rng.choice(["default.gif", "sepia.png", "default", ".jpg", "default.jpg.png", "color.tif",
                     "gray.webp", "default.JPG"])
    bad_ident = rng.choice([
        "..%2fz.mra", "%2e%2e%2fz.mra", "..%2F..%2F..%2Fetc%2Fpasswd", "%2Fetc%2Fpasswd",
        "/etc/passwd", "../z.mra", "z.mra%00", "%ff%fe", "z.mra;z=1", "z.mra;q=9", "nothere.mra",
        "link.mra", "a" * rng.randint(1, 8000), "sub%2F..%2F..%2Fz.mra", "%2e%2e/z.mra",
    ])
    shape = rng.randrange(6)
    if shape == 0:
        # a good identifier with one bad part
        parts = ["full", "max", "0", "default.jpg"]
        i = rng.randrange(4)
        parts[i] = [region, size, rot, qf][i]
        return ("/iiif/3/z.mra/" + "/".join(parts)).encode()
    if shape == 1:
        return f"/iiif/3/{bad_ident}/info.json".encode()
    if shape == 2:
        return f"/iiif/3/{bad_ident}/full/max/0/default.jpg".encode()
    if shape == 3:
        # random printable bytes after the prefix, never a valid request
        junk = bytes(rng.randrange(33, 127) for _ in range(rng.randint(1, 300))).replace(b".mra", b"")
        return b"/iiif/3/" + junk
    if shape == 4:
        w = rng.choice(["5,1", "1,1", "abc,2", "1", "1,2,3", "nan,1", "1,inf", "-inf,0", ",", ""])
        return ("/iiif/3/z.mra/full/max/0/default.jpg?window=" + w).encode()
    return rng.choice([b"/iiif/3/z.mra/full/max/0/default.jpg?" + b"x" * 20000,
                       b"/assets/..%2f..%2fCargo.toml", b"/iiif/3/", b"/iiif/3//info.json",
                       b"/" + b"a/" * 3000, b"/iiif/3/z.mra/full/max/0/default.jpg/extra"])


def slowloris(addr, stop):
    """Connections that send a header line every few seconds and never finish."""
    socks = []
    while not stop.is_set():
        try:
            s = socket.create_connection(addr, timeout=5)
            s.sendall(b"GET / HTTP/1.1\r\nHost: x\r\n")
            socks.append(s)
        except OSError:
            pass
        for s in list(socks):
            try:
                s.sendall(b"X-a: b\r\n")
            except OSError:
                socks.remove(s)
        time.sleep(1.0)
    for s in socks:
        s.close()


def rss_peak(pid):
    with open(f"/proc/{pid}/status") as f:
        for line in f:
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) * 1024
    return 0


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--requests", type=int, default=10000)
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    mra = os.environ.get("MRA", os.path.join(ROOT, "target", "release", "mra"))
    rng = random.Random(a.seed)
    work = tempfile.mkdtemp(prefix="mra-hostile-")
    served = os.path.join(work, "served")
    os.makedirs(served)
    subprocess.run([mra, "generate", "zone-plate", "-o", os.path.join(work, "z.png"), "--size", "2048"], check=True)
    subprocess.run([mra, "encode", os.path.join(work, "z.png"), "-o", os.path.join(served, "z.mra"),
                    "--quality", "60", "--tile", "512"], check=True, stdout=subprocess.DEVNULL)
    with open(os.path.join(work, "secret.mra"), "wb") as f:
        f.write(b"secret")
    os.symlink(os.path.join(work, "secret.mra"), os.path.join(served, "link.mra"))
    server = subprocess.Popen([mra, "serve", served, "--bind", "127.0.0.1:0"], stdout=subprocess.PIPE, text=True)
    passed = failed = good_failed = 0
    stop = threading.Event()
    try:
        host, port = server.stdout.readline().split("http://")[1].strip().rstrip("/").split(":")
        addr = (host, int(port))
        loris = threading.Thread(target=slowloris, args=(addr, stop), daemon=True)
        loris.start()
        t = time.time()
        codes = {}
        for i in range(a.requests):
            target = hostile(rng)
            code = request(addr, target)
            codes[code] = codes.get(code, 0) + 1
            if code == 0 or 400 <= code < 500:
                passed += 1
            else:
                failed += 1
                print(f"FAIL {code}: {target[:120]!r}")
            if i % 100 == 0 and request(addr, b"/iiif/3/z.mra/0,0,512,512/256,/0/default.jpg") != 200:
                good_failed += 1
                print(f"FAIL: a good request after {i} hostile ones was not answered 200")
            if server.poll() is not None:
                print("FAIL: the server exited")
                failed += a.requests - i - 1
                break
        peak = rss_peak(server.pid) if server.poll() is None else 0
        print(f"{a.requests} hostile requests in {time.time() - t:.1f} s; answers {dict(sorted(codes.items()))}"
              f" (0 = dropped); peak RSS {peak / 2**20:.0f} MiB; good requests failed: {good_failed}")
        if peak >= 1 << 30:
            print("FAIL: peak RSS over 1 GiB")
            failed += 1
        failed += good_failed
    finally:
        stop.set()
        server.terminate()
        server.wait()
        subprocess.run(["rm", "-rf", work])
    print(f"{passed} passed, {failed} failed")
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
