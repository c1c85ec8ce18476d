#!/bin/bash
# Copies the add-on's library folder to a fresh place (as the add-on's zip installs it), runs the
# bake-from-pixels program there with an empty environment, then reads one of its lobe textures
# back with the full library's command line (`ndfbake info`): the channels and ndfbake:* attributes
# must be those the full library writes.
#
# Another platform's build runs through a LAUNCHER given after the arguments (qemu-user for
# Linux on ARM, wine for Windows), with the variables it needs as NAME=VALUE before it; a Windows
# program gets Windows paths. With --compare HOST_FOLDER HOST_PROGRAM, the same bake is made with
# this machine's library, and every lobe texture must match it (OpenImageIO's idiff, within
# COMPARE_TOLERANCE: the platforms' libm differ in the last bits of exp and sin).
# Usage: run_in_empty_environment.sh <addon folder> <bake_from_pixels program> <ndfbake command line>
#            [--compare <host addon folder> <host program>] [-- LAUNCHER...]
set -eu
folder=$1 program=$2 cli=$3
shift 3
compare_folder= compare_program=
if [ "${1:-}" = --compare ]; then compare_folder=$2 compare_program=$3; shift 3; fi
[ "${1:-}" = -- ] && shift
launcher=("$@")
COMPARE_TOLERANCE=1e-5

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cp -r "$folder" "$work/ndfbake"
library=$(ls "$work/ndfbake" | grep -E '^(lib)?ndfbake\.(so|dll|dylib)$')
library_arg=$work/ndfbake/$library out_arg=$work/out
if [[ "$program" == *.exe ]]; then
    # winepath with the launcher's own variables (its WINEPREFIX).
    variables=()
    for word in "${launcher[@]}"; do [[ "$word" == *=* ]] && variables+=("$word"); done
    to_windows() { env -i "${variables[@]}" PATH=/usr/bin:/bin winepath -w "$1" 2>/dev/null; }
    library_arg=$(to_windows "$library_arg") out_arg=$(to_windows "$out_arg")
fi
env -i "${launcher[@]}" "$program" "$library_arg" "$out_arg"

info=$("$cli" info "$work/out/level00_lobe0.exr")
echo "$info"
for expected in "format: openexr" "size: 64x64" "channels: 4" "pixel type: half" "compression: rle" \
                "ndfbake:level: 0" "ndfbake:lobe: 0" "ndfbake:lobe_slots: 2" "ndfbake:source: bumps (Blender image)" \
                "ndfbake:format_version: 1" "ndfbake:content: vmf lobe: R = alpha, GBA = alpha * r"; do
    grep -qxF "$expected" <<<"$info" || { echo "FAIL: ndfbake info lacks '$expected'"; exit 1; }
done
grep -q '"format": "memory"' "$work/out/report.json" || { echo "FAIL: report.json input format"; exit 1; }

if [ -n "$compare_folder" ]; then
    cp -r "$compare_folder" "$work/host"
    env -i "$compare_program" "$work/host/$(ls "$work/host" | grep -E '^libndfbake\.so$')" "$work/host-out" >/dev/null
    compared=0
    for file in "$work/host-out"/*.exr; do
        name=$(basename "$file")
        idiff -q -fail "$COMPARE_TOLERANCE" -warn "$COMPARE_TOLERANCE" "$file" "$work/out/$name" >/dev/null ||
            { echo "FAIL: $name differs from this machine's bake by more than $COMPARE_TOLERANCE:";
              idiff -fail "$COMPARE_TOLERANCE" "$file" "$work/out/$name"; exit 1; }
        compared=$((compared + 1))
    done
    echo "$compared lobe textures equal to this machine's bake within $COMPARE_TOLERANCE"
fi
echo "PASS run_in_empty_environment"
