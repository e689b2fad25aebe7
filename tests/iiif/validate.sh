#!/usr/bin/env bash
# The IIIF validator (iiif-validator from PyPI) at Image API 3.0, level 2, against `mra serve`
# on loopback, over the validator's test image coded losslessly.
#
#   bash tests/iiif/validate.sh            # uses target/release/mra (MRA=… to override)
#
# Creates a venv in target/venv (VENV=… to override) with iiif-validator and Pillow.
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
mra="${MRA:-$root/target/release/mra}"
venv="${VENV:-$root/target/venv}"
if [ ! -x "$venv/bin/iiif-validate.py" ]; then
    python3 -m venv "$venv"
    "$venv/bin/pip" install -q "iiif-validator==1.0.5"
fi
work="$(mktemp -d)"
server=""
cleanup() { [ -n "$server" ] && kill "$server" 2>/dev/null; rm -rf "$work"; }
trap cleanup EXIT
id=67352ccc-d1b0-11e1-89ae-279075081939.mra
"$venv/bin/python" "$root/tests/iiif/validator_image.py" "$work/square.png"
mkdir "$work/served"
"$mra" encode "$work/square.png" -o "$work/served/$id" --lossless
"$mra" serve "$work/served" --bind 127.0.0.1:0 > "$work/serve.log" &
server=$!
for _ in $(seq 100); do grep -q "http://" "$work/serve.log" && break; sleep 0.1; done
addr="$(sed -n 's#.*http://\([^/]*\)/.*#\1#p' "$work/serve.log" | head -1)"
[ -n "$addr" ] || { echo "mra serve did not start"; exit 1; }
# every level-2 test of Image API 3.0 (the validator exits with the number of failures)
"$venv/bin/iiif-validate.py" -s "$addr" -p iiif/3 -i "$id" --version=3.0 --level=2 -v
# and the optional features the server lists in extraFeatures: mirroring
"$venv/bin/iiif-validate.py" -s "$addr" -p iiif/3 -i "$id" --version=3.0 -v \
    --test rot_mirror --test rot_mirror_180 --test linkheader_profile
