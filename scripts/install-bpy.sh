#!/usr/bin/env bash
# Installs Blender as a Python module (the official `bpy` builds from PyPI), one virtual
# environment per Blender series, cached under $NDFBAKE_CACHE (default ~/.cache/ndfbake) and
# reused: a venv whose bpy imports is left alone. Prints nothing but progress; the venv of series
# S is $NDFBAKE_CACHE/bpy-S, its interpreter bin/python.
#   bash scripts/install-bpy.sh SERIES...       (install-deps.sh names 4.2 4.5 5.0)
# bpy up to 5.0 ships CPython 3.11 wheels only (Debian 12's python3) and needs numpy < 2.
set -euo pipefail
cache=${NDFBAKE_CACHE:-$HOME/.cache/ndfbake}
series=("$@")
python=/usr/bin/python3.11
mkdir -p "$cache"
for s in "${series[@]}"; do
  venv=$cache/bpy-$s
  if [ -x "$venv/bin/python" ] && "$venv/bin/python" -c "import bpy, sys; sys.exit(bpy.app.version[:2] != tuple(map(int, '$s'.split('.'))))" >/dev/null 2>&1; then
    continue
  fi
  echo "== install-bpy.sh: bpy $s into $venv"
  rm -rf "$venv"
  "$python" -m venv "$venv"
  "$venv/bin/python" -m pip install -q --disable-pip-version-check "bpy==$s.*" "numpy<2"
  "$venv/bin/python" -c "import bpy; print('== install-bpy.sh: Blender', bpy.app.version_string, 'OSL' if bpy.app.build_options.cycles_osl else 'no OSL')"
done
