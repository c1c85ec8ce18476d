#!/bin/bash
# Copies the add-on's library folder to a fresh place (as the add-on's zip installs it), runs the
# bake-from-pixels program there with an empty environment, then reads one of its lobe textures
# back with the full library's command line (`ndfbake info`): the channels and ndfbake:* attributes
# must be those the full library writes.
# Usage: run_in_empty_environment.sh <addon folder> <bake_from_pixels program> <ndfbake command line>
set -eu
folder=$1 program=$2 cli=$3
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cp -r "$folder" "$work/ndfbake"
env -i "$program" "$work/ndfbake/libndfbake.so" "$work/out"

info=$("$cli" info "$work/out/level00_lobe0.exr")
echo "$info"
for expected in "format: openexr" "size: 64x64" "channels: 4" "pixel type: half" "compression: rle" \
                "ndfbake:level: 0" "ndfbake:lobe: 0" "ndfbake:lobe_slots: 2" "ndfbake:source: bumps (Blender image)" \
                "ndfbake:format_version: 1" "ndfbake:content: vmf lobe: R = alpha, GBA = alpha * r"; do
    grep -qxF "$expected" <<<"$info" || { echo "FAIL: ndfbake info lacks '$expected'"; exit 1; }
done
grep -q '"format": "memory"' "$work/out/report.json" || { echo "FAIL: report.json input format"; exit 1; }
echo "PASS run_in_empty_environment"
