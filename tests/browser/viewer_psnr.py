"""The viewer in a real browser: headless Chromium (Selenium) opens `mra serve`'s viewer on a
generated zone plate, zooms to windows at several levels so that one level sample is one
screen pixel, takes a screenshot, and compares it with `mra decode --region --level` of
the same window. Passes when every view's PSNR is at least 40 dB.

usage: python tests/browser/viewer_psnr.py [--size 16384] [--format jpg|png]
env:   MRA (the binary, default target/release/mra), CHROMIUM, CHROMEDRIVER,
       MRA_BROWSER_DATA (where the generated image is kept between runs)

Prints one line per view and a closing "N passed, N failed" line; prints
"SKIP: …" and exits 0 when Chromium, chromedriver or Selenium is absent.
"""
import argparse
import io
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def skip(why):
    print(f"SKIP: {why}")
    sys.exit(0)


def psnr(a, b):
    """PSNR in dB of two same-size 8-bit gray Pillow images (peak 255)."""
    from PIL import ImageChops

    hist = ImageChops.difference(a, b).histogram()
    n = a.width * a.height
    mse = sum(c * d * d for d, c in enumerate(hist)) / n
    return math.inf if mse == 0 else 10 * math.log10(255 * 255 / mse)


def run(*args):
    subprocess.run(args, check=True, stdout=subprocess.DEVNULL)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--size", type=int, default=16384)
    ap.add_argument("--format", default="jpg", choices=["jpg", "png"])
    a = ap.parse_args()
    chromium = os.environ.get("CHROMIUM") or shutil.which("chromium") or shutil.which("chromium-browser")
    driver_bin = os.environ.get("CHROMEDRIVER") or shutil.which("chromedriver")
    if not chromium or not driver_bin:
        skip("chromium and chromium-driver are not installed (apt-get install chromium chromium-driver)")
    try:
        from PIL import Image
        from selenium import webdriver
        from selenium.webdriver.chrome.service import Service
    except ImportError as e:
        skip(f"python packages missing ({e.name}): pip install selenium pillow")
    mra = os.environ.get("MRA", os.path.join(ROOT, "target", "release", "mra"))
    data = os.environ.get("MRA_BROWSER_DATA", os.path.join(ROOT, "target", "browser-data"))
    served = os.path.join(data, "served")
    os.makedirs(served, exist_ok=True)
    name = f"zone{a.size}.mra"
    coded = os.path.join(served, name)
    if not os.path.exists(coded):
        png = os.path.join(data, f"zone{a.size}.png")
        t = time.time()
        run(mra, "generate", "zone-plate", "-o", png, "--size", str(a.size))
        # mra writes to a temporary file and renames it: no partial file is left
        run(mra, "encode", png, "-o", coded, "--quality", "80")
        os.remove(png)
        print(f"made {name} ({os.path.getsize(coded)} bytes) in {time.time() - t:.1f} s")
    server = subprocess.Popen([mra, "serve", served, "--bind", "127.0.0.1:0"],
                              stdout=subprocess.PIPE, text=True)
    profile = tempfile.mkdtemp(prefix="mra-chromium-")
    drv = None
    passed = failed = 0
    try:
        line = server.stdout.readline()
        base = line.split("http://")[1].strip().rstrip("/")
        opts = webdriver.ChromeOptions()
        opts.binary_location = chromium
        for f in ["--headless=new", "--no-sandbox", "--disable-gpu", "--disable-quic",
                  "--no-first-run", "--disable-background-networking",
                  "--disable-component-update", "--disable-sync", "--disable-dev-shm-usage",
                  "--force-device-scale-factor=1", "--window-size=1024,768",
                  f"--user-data-dir={profile}"]:
            opts.add_argument(f)
        drv = webdriver.Chrome(service=Service(executable_path=driver_bin), options=opts)
        drv.set_page_load_timeout(60)
        drv.get(f"http://{base}/viewer.html?id={name}&format={a.format}")
        wait(drv, "return window.viewerReady === true", 60)
        drv.execute_script("document.getElementById('bar').style.display = 'none';"
                           "window.tileFailures = [];"
                           "viewer.addHandler('tile-load-failed', e => window.tileFailures.push("
                           "(e.message || '') + ' ' + (e.tile && e.tile.getUrl ? e.tile.getUrl() : '')));")
        cw, ch = drv.execute_script(
            "return [viewer.container.clientWidth, viewer.container.clientHeight]")
        s = a.size
        # (level, x0, y0): the window's top-left in full-resolution pixels, tile-aligned
        views = [(6, 0, 0), (4, s // 4, s // 4), (2, s // 2, s // 2 - 1024), (0, s // 2 + 256, s // 3 // 256 * 256)]
        for k, x0, y0 in views:
            w, h = cw << k, ch << k
            x0, y0 = min(x0, s - w), min(y0, s - h)
            if x0 < 0 or y0 < 0:
                continue
            drv.execute_script(
                "const vp = viewer.viewport;"
                "vp.fitBounds(vp.imageToViewportRectangle(arguments[0], arguments[1], arguments[2], arguments[3]), true);",
                x0, y0, w, h)
            shot = settled(drv, cw, ch, Image)
            ref_png = os.path.join(profile, f"ref{k}.png")
            run(mra, "decode", coded, "-o", ref_png, "--level", str(k),
                "--region", f"{x0}:{x0 + w},{y0}:{y0 + h}")
            ref = Image.open(ref_png).convert("L")
            failures = drv.execute_script("const f = window.tileFailures; window.tileFailures = []; return f;")
            if failures:
                print(f"level {k}: {len(failures)} tiles failed to load, first: {failures[0]}")
            if ref.size != shot.size:
                print(f"level {k} window {x0},{y0},{w},{h}: sizes {shot.size} vs {ref.size}: FAIL")
                failed += 1
                continue
            p = psnr(shot, ref)
            ok = p >= 40.0
            passed, failed = passed + ok, failed + (not ok)
            print(f"level {k} window {x0},{y0},{w},{h} ({cw}x{ch} screen px, {a.format} tiles): "
                  f"PSNR {p:.2f} dB {'ok' if ok else 'FAIL (< 40 dB)'}")
            if not ok:
                shot.save(os.path.join(data, f"shot{k}.png"))
    finally:
        if drv is not None:
            drv.quit()
        server.terminate()
        server.wait()
        shutil.rmtree(profile, ignore_errors=True)
    print(f"{passed} passed, {failed} failed")
    sys.exit(1 if failed or not passed else 0)


def settled(drv, cw, ch, Image, seconds=180):
    """The screenshot once the view has settled: every tile of the view loaded and two
    screenshots a second apart equal (OpenSeadragon loads and draws over a few frames)."""
    end = time.time() + seconds
    last = None
    while time.time() < end:
        time.sleep(1.0)
        if not drv.execute_script("return viewer.world.getItemAt(0).getFullyLoaded()"
                                  " && viewer.imageLoader.jobsInProgress === 0"):
            continue
        png = drv.get_screenshot_as_png()
        if png == last:
            return Image.open(io.BytesIO(png)).convert("L").crop((0, 0, cw, ch))
        last = png
    raise TimeoutError("the view did not settle")


def wait(drv, script, seconds):
    end = time.time() + seconds
    while time.time() < end:
        if drv.execute_script(script):
            return
        time.sleep(0.1)
    raise TimeoutError(f"timed out: {script}")


if __name__ == "__main__":
    main()
