#!/usr/bin/env bash
# Runs the Windows CPython 3.11 with the Windows bpy of Blender SERIES under wine, headless
# (scripts/install-windows-runtime.sh installs both into $NDFBAKE_WINDOWS_CACHE, default
# /var/cache/ndfbake/windows):
#   bash scripts/windows-bpy.sh SERIES script.py -- ARGS...     (or SERIES -c CODE ..., as python)
# Arguments that are absolute Linux paths of something that exists, or whose folder exists, are
# passed as Windows paths (drive Z: is /, so /a/b is Z:\a\b, as `winepath -w` writes it); so are the
# environment variables that hold paths (BLENDER_USER_*, NDFBAKE_LIBRARY). Everything else goes
# as it is. Python's exit status is this script's. No display is needed: bpy runs in the
# background and wine starts no window for a console program.
set -euo pipefail
if [ $# -lt 1 ]; then
  echo "usage: $0 SERIES script.py [-- ARGS...]" >&2
  exit 2
fi
series=$1
shift
cache=${NDFBAKE_WINDOWS_CACHE:-/var/cache/ndfbake/windows}
if [ ! -f "$cache/python/python.exe" ] || [ ! -f "$cache/bpy-$series/bpy/__init__.pyd" ]; then
  echo "$0: no Windows Python or bpy $series in $cache (bash scripts/install-windows-runtime.sh $series)" >&2
  exit 2
fi
export WINEPREFIX=$cache/prefix WINEARCH=win64
export WINEDEBUG=${WINEDEBUG:--all}
# No Mono or Gecko installer prompt should the prefix ever be updated.
export WINEDLLOVERRIDES=${WINEDLLOVERRIDES:-mscoree,mshtml=}
if [ "$(readlink "$WINEPREFIX/dosdevices/z:")" != / ]; then
  echo "$0: drive Z: of $WINEPREFIX is not /" >&2
  exit 2
fi

# A Linux path as Windows sees it through drive Z: (what `winepath -w` prints, without starting wine).
windows_path() {
  local p
  p=$(realpath -m -- "$1")
  p=${p//\//\\}
  printf 'Z:%s' "$p"
}

args=()
for a in "$@"; do
  if [[ $a == /* ]] && { [ -e "$a" ] || [ -d "$(dirname -- "$a")" ]; }; then
    args+=("$(windows_path "$a")")
  else
    args+=("$a")
  fi
done
for v in BLENDER_USER_RESOURCES BLENDER_USER_CONFIG BLENDER_USER_SCRIPTS BLENDER_USER_EXTENSIONS \
         BLENDER_USER_DATAFILES BLENDER_SYSTEM_SCRIPTS NDFBAKE_LIBRARY; do
  if [[ ${!v:-} == /* ]]; then
    export "$v=$(windows_path "${!v}")"
  fi
done

# The bpy of this series and numpy on sys.path (the embeddable Python has no ._pth file here, so
# PYTHONPATH works, and the tests' child Pythons inherit it), and wine-site/sitecustomize.py, which
# works around what wine 8.0 lacks (install-windows-runtime.sh); no user site-packages.
export PYTHONPATH="$(windows_path "$cache/wine-site");$(windows_path "$cache/bpy-$series");$(windows_path "$cache/site-packages")"
export PYTHONNOUSERSITE=1
# Output reaches a Linux pipe: UTF-8 whatever the console code page.
export PYTHONIOENCODING=utf-8
# Nothing to draw on: no X display (wine would otherwise connect to one for nothing).
unset DISPLAY WAYLAND_DISPLAY

# Python under wine 8 cannot open a standard stream that is a regular file (init_sys_streams:
# "[WinError 6] Invalid handle"): a redirected one goes through a pipe and cat.
pipes=()
if [ -f /proc/self/fd/0 ]; then exec 0< <(cat); fi
if [ -f /proc/self/fd/1 ]; then exec 1> >(cat); pipes+=($!); fi
if [ -f /proc/self/fd/2 ]; then exec 2> >(cat >&2); pipes+=($!); fi
if [ ${#pipes[@]} = 0 ]; then
  exec wine "$cache/python/python.exe" "${args[@]}"
fi
status=0
wine "$cache/python/python.exe" "${args[@]}" || status=$?
exec 1>&- 2>&-  # cat sees the end of its pipe, writes the rest and exits
wait "${pipes[@]}" || true
exit "$status"
