#!/usr/bin/env bash
# Regenerates every codec table of docs/codec.md in one run: photographs against OpenJPEG,
# WebP, JPEG XL and AVIF (with the PSNR-bpp plot), lossless images, volumes and DEMs against
# SZ3, SPERR, ZFP, OpenJPEG and Zstd/Blosc, and whole-process speed and memory.
#
# Needs: apt-get install libopenjp2-tools; pip install imagecodecs pillow numpy pysz zfpy
# SPERR: build it from source (CMake) and set SPERR_DIR to the folder of its sperr3d and sperr2d.
# Usage (repository root): [SPERR_DIR=DIR] benches/peers/codec_tables.sh [OUT_DIR] [--corpus DIR]
set -euo pipefail
cd "$(dirname "$0")/../.."
out=${1:-target/codec-tables}
shift || true
mkdir -p "$out"
cargo build --release --quiet
python3 benches/peers/codec_rd.py --plot docs/figures/codec_rd.png --json "$out/rd.json" "$@" | tee "$out/rd.md"
python3 benches/peers/codec_lossless.py "$@" | tee "$out/lossless.md"
python3 benches/peers/codec_volumes.py --efforts default,9 ${SPERR_DIR:+--sperr "$SPERR_DIR"} "$@" | tee "$out/volumes.md"
if [ -f benches/peers/codec_speed.py ]; then
  python3 benches/peers/codec_speed.py "$@" | tee "$out/speed.md"
fi
echo "tables in $out"
