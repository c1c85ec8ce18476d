#!/usr/bin/env bash
# Installs Blender 5.1 and later as the bpy module (official builds from PyPI) into the Debian 13
# chroot (scripts/install-debian13-blender.sh): their wheels are for CPython 3.13, which Debian 13
# has and this machine's Debian 12 does not. One venv per series at /opt/bpy-SERIES in the chroot,
# kept and reused where its bpy imports. pip inside the chroot does not trust this machine's
# certificate chain, so the wheels are downloaded here (a pip of our own, for CPython 3.13 and
# every manylinux the chroot's glibc runs) into the chroot, installed from there without the
# index, then deleted.
#   bash scripts/install-bpy-debian13.sh SERIES...      (install-deps.sh names 5.2 5.3)
# Run as root, after install-debian13-blender.sh.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=${NDFBAKE_DEBIAN13_ROOT:-/var/cache/ndfbake/debian13}
cache=${NDFBAKE_CACHE:-$HOME/.cache/ndfbake}
[ -x "$root/usr/bin/python3" ] || { echo "no Debian 13 chroot at $root (scripts/install-debian13-blender.sh)" >&2; exit 1; }
in_chroot() { bash "$here/in-chroot.sh" "$root" /tmp -- "$@"; }
# pip download takes the platform tags literally (no older manylinux implied): name each one the
# chroot's glibc (2.41 in Debian 13) runs, from manylinux2014 (2.17) up.
glibc=$(chroot "$root" getconf GNU_LIBC_VERSION)   # "glibc 2.41"
glibc_minor=${glibc##*.}
platforms=(--platform manylinux2014_x86_64)
for minor in $(seq 17 "$glibc_minor"); do platforms+=(--platform "manylinux_2_${minor}_x86_64"); done
for s in "$@"; do
  venv=/opt/bpy-$s
  if [ -x "$root$venv/bin/python" ] && in_chroot "$venv/bin/python" -c \
       "import bpy, sys; sys.exit(bpy.app.version[:2] != tuple(map(int, '$s'.split('.'))))" >/dev/null 2>&1; then
    continue
  fi
  echo "== install-bpy-debian13.sh: bpy $s into $root$venv"
  downloader=$cache/wheel-download
  [ -x "$downloader/bin/pip" ] || /usr/bin/python3 -m venv "$downloader"
  wheels=/var/tmp/ndfbake-wheels-$s   # a path inside the chroot
  rm -rf "$root$wheels" "$root$venv"
  "$downloader/bin/pip" download -q --disable-pip-version-check --only-binary=:all: --python-version 3.13 \
    --implementation cp "${platforms[@]}" -d "$root$wheels" "bpy==$s.*"
  # An empty environment there: this machine's pip settings (PIP_FIND_LINKS, ...) name its own folders.
  chroot "$root" /usr/bin/env -i PATH=/usr/bin:/bin HOME=/root python3 -m venv "$venv"
  chroot "$root" /usr/bin/env -i PATH=/usr/bin:/bin HOME=/root "$venv/bin/pip" install -q \
    --disable-pip-version-check --no-index --find-links "$wheels" "bpy==$s.*"
  rm -rf "$root$wheels"
  in_chroot "$venv/bin/python" -c \
    "import bpy; print('== install-bpy-debian13.sh: Blender', bpy.app.version_string, 'OSL' if bpy.app.build_options.cycles_osl else 'no OSL')"
done
