#!/usr/bin/env bash
# Writes the seed corpora of the fuzz targets into tests/fuzz/corpus/ (the files are committed;
# rerun only to regenerate them). Needs oiiotool (openimageio-tools) and python3.
#   decode:  small normal maps like the test fixtures in every format and layout the decoder
#            handles (8/16-bit, half/float, 2/3/4 channels, 1 and 5 for the refusals), plus
#            headers claiming 100000 x 100000 pixels; each file is prefixed with the selector byte
#            fuzz_decode.cpp reads (extension index 0..7, +0x10 DirectX, +0x20 linearize sRGB).
#   bake, tangent: a few byte strings of different lengths (FuzzedDataProvider input).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
out="$here/corpus"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$out/decode" "$out/bake" "$out/tangent"

# Extension order of fuzz_decode.cpp's kExtensions.
declare -A index=([png]=0 [exr]=1 [tga]=2 [tif]=3 [jpg]=4 [bmp]=5 [hdr]=6 [psd]=7)

seed() {  # seed NAME EXT FLAGS FILE
  local byte=$(( ${index[$2]} + $3 ))
  { printf "\\$(printf '%03o' "$byte")"; cat "$4"; } > "$out/decode/$1"
}

# A tilted-normal gradient as the source of every layout.
oiiotool --pattern fill:topleft=0.3,0.4,0.9:topright=0.7,0.4,0.9:bottomleft=0.3,0.6,0.9:bottomright=0.7,0.6,0.95 8x8 3 \
  -o "$tmp/src.exr"
make() {  # make NAME EXT TYPE CHANNELS FLAGS [extra oiiotool args]
  local name=$1 ext=$2 type=$3 channels=$4 flags=$5
  shift 5
  local chans
  case $channels in
    1) chans="--ch R" ;; 2) chans="--ch R,G" ;; 3) chans="" ;;
    4) chans="--ch R,G,B,A=1.0" ;; 5) chans="--ch R,G,B,A=1.0,Z=0.5" ;;
  esac
  oiiotool "$tmp/src.exr" $chans -d "$type" "$@" -o "$tmp/$name.$ext"
  seed "$name" "$ext" "$flags" "$tmp/$name.$ext"
}
make png_rgb8 png uint8 3 0
make png_rgb16 png uint16 3 0x10
make png_xy8 png uint8 2 0
make png_rgba8 png uint8 4 0x20
make png_grey png uint8 1 0
make exr_half_rgb exr half 3 0 --compression none
make exr_float_rgba exr float 4 0 --compression zip
make exr_half_xy exr half 2 0x10 --compression piz
make exr_five exr half 5 0
make tga_rgb tga uint8 3 0
make tga_rgba_rle tga uint8 4 0 --compression rle
make tif_rgb16 tif uint16 3 0
make tif_float tif float 3 0
make tif_five tif uint8 5 0
make jpg_rgb jpg uint8 3 0
make bmp_rgb bmp uint8 3 0
make hdr_rgb hdr float 3 0

# Headers that claim 100000 x 100000 pixels (no pixel data), as in tests/native/hostile_fixtures.h.
python3 - "$tmp" <<'PY'
import struct, sys, zlib
tmp = sys.argv[1]
def chunk(t, d): return struct.pack('>I', len(d)) + t + d + struct.pack('>I', zlib.crc32(t + d) & 0xffffffff)
png = b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', 100000, 100000, 8, 2, 0, 0, 0)) \
    + chunk(b'IDAT', zlib.compress(b'\0' * 4)) + chunk(b'IEND', b'')
open(f'{tmp}/huge.png', 'wb').write(png)
def attr(n, t, v): return n.encode() + b'\0' + t.encode() + b'\0' + struct.pack('<i', len(v)) + v
ch = b''.join(c + b'\0' + struct.pack('<iB3xii', 1, 0, 1, 1) for c in (b'B', b'G', b'R')) + b'\0'
win = struct.pack('<4i', 0, 0, 99999, 99999)
exr = b'\x76\x2f\x31\x01' + struct.pack('<i', 2) + attr('channels', 'chlist', ch) \
    + attr('compression', 'compression', b'\0') + attr('dataWindow', 'box2i', win) \
    + attr('displayWindow', 'box2i', win) + attr('lineOrder', 'lineOrder', b'\0') \
    + attr('pixelAspectRatio', 'float', struct.pack('<f', 1)) \
    + attr('screenWindowCenter', 'v2f', struct.pack('<2f', 0, 0)) \
    + attr('screenWindowWidth', 'float', struct.pack('<f', 1)) + b'\0' + b'\0' * 64
open(f'{tmp}/huge.exr', 'wb').write(exr)
PY
seed png_huge_header png 0 "$tmp/huge.png"
seed exr_huge_header exr 0 "$tmp/huge.exr"

python3 - "$out" <<'PY'
import random, sys
out = sys.argv[1]
rng = random.Random(6)
for target in ('bake', 'tangent'):
    for i, n in enumerate((16, 64, 256, 1024)):
        open(f'{out}/{target}/seed_{i}', 'wb').write(bytes(rng.randrange(256) for _ in range(n)))
PY
ls -la "$out"/*
