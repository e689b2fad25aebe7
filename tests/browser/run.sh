#!/usr/bin/env bash
# The viewer's browser test for CI: Selenium (PyPI) in a venv, headless Chromium from Debian.
#
#   apt-get install -y chromium chromium-driver     # once, as root (CI installs it)
#   bash tests/browser/run.sh [--size 16384] [--format jpg|png]
#
# Prints "SKIP: ..." and exits 0 when chromium or chromedriver is absent, or pip cannot
# install Selenium; otherwise one line per view and "N passed, N failed".
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
if ! command -v chromium >/dev/null 2>&1 || ! command -v chromedriver >/dev/null 2>&1; then
    echo "SKIP: chromium and chromium-driver are not installed (apt-get install chromium chromium-driver)"
    exit 0
fi
venv="${VENV:-$root/target/venv}"
if [ ! -x "$venv/bin/python" ] || ! "$venv/bin/python" -c "import selenium, PIL" 2>/dev/null; then
    python3 -m venv "$venv"
    if ! "$venv/bin/pip" install -q "selenium>=4.10" pillow; then
        echo "SKIP: pip could not install selenium and pillow"
        exit 0
    fi
fi
exec "$venv/bin/python" "$root/tests/browser/viewer_psnr.py" "$@"
