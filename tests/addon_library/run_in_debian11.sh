#!/bin/bash
# The add-on's library on a Linux older than Debian 12: Debian 11 (glibc 2.31, GCC 10's libstdc++)
# in a chroot (scripts/install-debian11-runtime.sh). Copies the add-on's library folder to a fresh
# place (as the add-on's zip installs it); in the chroot, with an empty environment but
# NDFBAKE_LIBRARY, Debian 11's Python loads it through the add-on's own ctypes module and bakes
# (bake_with_native.py); then the full library's command line (`ndfbake info`, here) reads a lobe
# texture back: the channels and ndfbake:* attributes must be those the full library writes.
# Usage: run_in_debian11.sh <chroot> <checkout> <addon folder> <ndfbake command line>
set -eu
root=$1 checkout=$2 folder=$3 cli=$4
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
chmod 755 "$work"
cp -r "$folder" "$work/ndfbake"
echo "ldd in Debian 11:"
bash "$checkout/scripts/in-chroot.sh" "$root" "$work" -- ldd "$work/ndfbake/libndfbake.so"
bash "$checkout/scripts/in-chroot.sh" "$root" "$work" "$checkout" -- env -i NDFBAKE_LIBRARY="$work/ndfbake/libndfbake.so" \
    /usr/bin/python3 -B "$checkout/tests/addon_library/bake_with_native.py" "$checkout/addon" "$work/out"

info=$("$cli" info "$work/out/level00_lobe0.exr")
echo "$info"
for expected in "format: openexr" "size: 32x32" "channels: 4" "pixel type: half" "ndfbake:level: 0" \
                "ndfbake:lobe: 0" "ndfbake:lobe_slots: 2" "ndfbake:source: facets" "ndfbake:format_version: 1"; do
    grep -qxF "$expected" <<<"$info" || { echo "FAIL: ndfbake info lacks '$expected'"; exit 1; }
done
echo "PASS run_in_debian11"
