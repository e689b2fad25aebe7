#!/bin/sh
# The one-transform file against tiles on huge rasters (docs/tiles.md, "One transform at
# any size"): a 16384² u16 image and a 1024³ u16 volume made by `mra generate`, coded at
# --bpp 1 by default (one transform streamed, format 3.0) and with --tile (2.x tiles of
# 1024² / 128³), and --lossless (tiled either way). Prints, per file: bytes, bits per
# position, PSNR, encode and decode wall s / CPU s / peak RSS MiB, decode MB/s of samples.
# Run from the repository root after `cargo build --release`:
#   sh benches/huge.sh [image|volume|both] [DIR]
# DIR (default: /dev/shm when it has room, else a temporary folder) holds the inputs
# (512 MiB and 2 GiB) and outputs; everything is removed at the end.
set -e
MRA=${MRA:-target/release/mra}
which=${1:-both}
dir=${2:-}
if [ -z "$dir" ]; then
  if [ "$(df --output=avail -k /dev/shm 2>/dev/null | tail -1)" -gt 7000000 ] 2>/dev/null; then
    dir=$(mktemp -d /dev/shm/mra-huge.XXXXXX)
  else
    dir=$(mktemp -d)
  fi
fi
trap 'rm -rf "$dir"' EXIT

# time -v: wall s / CPU s / peak MiB of a command
timed() {
  /usr/bin/time -v "$@" 2> "$dir/time.txt" > "$dir/out.txt" || { cat "$dir/time.txt"; exit 1; }
  awk -F': ' '/Elapsed \(wall clock\)/ {n=split($2,t,":"); w=(n==3)?t[1]*3600+t[2]*60+t[3]:t[1]*60+t[2]}
              /User time/ {u=$2} /System time/ {s=$2}
              /Maximum resident/ {m=$2/1024}
              END {printf "%.2f / %.2f / %.0f", w, u+s, m}' "$dir/time.txt"
}

one() { # name input samples_bytes encode-args...
  name=$1; input=$2; bytes=$3; shift 3
  enc=$(timed "$MRA" encode "$input" -o "$dir/f.mra" "$@")
  size=$(stat -c %s "$dir/f.mra")
  dec=$(timed "$MRA" decode "$dir/f.mra" -o "$dir/back.nrrd")
  wall=$(echo "$dec" | cut -d/ -f1)
  mbs=$(awk -v b="$bytes" -v w="$wall" 'BEGIN {printf "%.1f", b / 1e6 / w}')
  psnr=$("$MRA" compare "$input" "$dir/back.nrrd" --json --quiet | sed 's/.*"psnr": *\([^,}]*\).*/\1/')
  ver=$("$MRA" info "$dir/f.mra" --json | sed 's/.*"version": *"\([^"]*\)".*/\1/')
  echo "$name | $* | $ver | $size B | PSNR $psnr | encode $enc | decode $dec | $mbs MB/s"
  rm -f "$dir/f.mra" "$dir/back.nrrd"
}

run() { # label input bytes tile
  one "$1" "$2" "$3" --bpp 1
  one "$1" "$2" "$3" --bpp 1 --tile "$4"
  one "$1" "$2" "$3" --lossless
}

if [ "$which" != volume ]; then
  "$MRA" generate image "$dir/img.nrrd" --size 16384 --dtype u16 > /dev/null
  run "16384² u16" "$dir/img.nrrd" $((16384 * 16384 * 2)) 1024
  rm -f "$dir/img.nrrd"
fi
if [ "$which" != image ]; then
  "$MRA" generate volume "$dir/vol.nrrd" --size 1024 --dtype u16 > /dev/null
  run "1024³ u16" "$dir/vol.nrrd" $((1024 * 1024 * 1024 * 2)) 128
  rm -f "$dir/vol.nrrd"
fi
