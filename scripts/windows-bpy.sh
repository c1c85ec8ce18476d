#!/usr/bin/env bash
# Runs the Windows CPython 3.11 with the Windows bpy of Blender SERIES under wine, headless (under
# xvfb-run where no DISPLAY is set, for OpenGL; scripts/install-windows-runtime.sh installs Python
# and bpy into $NDFBAKE_WINDOWS_CACHE, default /var/cache/ndfbake/windows):
#   bash scripts/windows-bpy.sh SERIES script.py -- ARGS...     (or SERIES -c CODE ..., as python)
# Arguments that are absolute Linux paths of something that exists, or whose folder exists, are
# passed as Windows paths (drive Z: is /, so /a/b is Z:\a\b, as `winepath -w` writes it); so are the
# environment variables that hold paths (BLENDER_USER_*, NDFBAKE_LIBRARY). Everything else goes
# as it is. Python's exit status is this script's (a crash: the exception code's low byte, as
# 5 for an access violation; the prefix has no crash debugger).
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

# Drawing (EEVEE, the gpu module) needs OpenGL, which wine gets from an X display: without one,
# Blender's first EEVEE render crashes. So without DISPLAY this runs itself under xvfb-run (Mesa's
# llvmpipe; EEVEE renders as fast as Linux bpy's does); NDFBAKE_WINE_HEADLESS=1 runs with no X
# at all (all but EEVEE and the gpu module work).
if [ "${NDFBAKE_WINE_HEADLESS:-0}" = 1 ]; then
  unset DISPLAY WAYLAND_DISPLAY
elif [ -z "${DISPLAY:-}" ] && command -v xvfb-run >/dev/null; then
  exec xvfb-run -a -s "-screen 0 1280x800x24" bash "$0" "$series" "$@"
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

# What wine 8.0 lacks, worked around in every Windows Python started here (sitecustomize.py):
# written once per version into wine-site-<hash of it>/ of the cache, so checkouts with different
# versions of this script can share the cache.
sitecustomize=$(cat <<'PYTHON'
"""Wine 8.0 (Debian 12) fixes for Blender's Windows builds, loaded by every Windows Python that
scripts/windows-bpy.sh starts (which writes it).

Blender 5.0 maps image files with VirtualAlloc2(MEM_RESERVE_PLACEHOLDER) + MapViewOfFile3 when
kernelbase.dll exports both (BLI_mmap.cc); wine 8.0 exports them but refuses placeholders
(ERROR_INVALID_PARAMETER), so every image file load fails ("couldn't get mapping"). Hiding the
MapViewOfFile3 export from GetProcAddress sends Blender to its fallback (CreateFileMapping +
MapViewOfFile, as on Windows before 10 1803; Blender 4.2 maps files so always). Only under wine.
And TEMP is the run's own folder (_own_temp)."""


def _hide_map_view_of_file3():
    import ctypes
    from ctypes import wintypes
    kernel32 = ctypes.WinDLL("kernel32", use_last_error=True)
    kernel32.GetModuleHandleW.restype = ctypes.c_void_p
    kernel32.GetModuleHandleW.argtypes = [wintypes.LPCWSTR]
    ntdll = kernel32.GetModuleHandleW("ntdll.dll")
    kernel32.GetProcAddress.restype = ctypes.c_void_p
    kernel32.GetProcAddress.argtypes = [ctypes.c_void_p, ctypes.c_char_p]
    if not ntdll or not kernel32.GetProcAddress(ntdll, b"wine_get_version"):
        return  # real Windows: placeholders work
    base = kernel32.GetModuleHandleW("kernelbase.dll")
    if not base:
        return
    u32 = lambda address: ctypes.c_uint32.from_address(address).value
    nt = base + u32(base + 0x3C)
    export_rva = u32(nt + 24 + 112)  # PE32+ optional header: DataDirectory[EXPORT]
    if not export_rva:
        return
    exports = base + export_rva
    count, names = u32(exports + 24), base + u32(exports + 32)
    for i in range(count):
        name = base + u32(names + 4 * i)
        if ctypes.string_at(name) == b"MapViewOfFile3":
            # "MapViewOfFile2" sorts just before: the name table stays sorted for the binary search.
            old = wintypes.DWORD()
            kernel32.VirtualProtect.argtypes = [ctypes.c_void_p, ctypes.c_size_t, wintypes.DWORD,
                                                ctypes.POINTER(wintypes.DWORD)]
            if kernel32.VirtualProtect(name, 16, 0x04, ctypes.byref(old)):  # PAGE_READWRITE
                ctypes.memmove(name + 13, b"2", 1)
                kernel32.VirtualProtect(name, 16, old.value, ctypes.byref(old))
            return


def _own_temp():
    """The TEMP folder scripts/windows-bpy.sh made for this run (wine sets TEMP from its registry,
    over the environment it is given). Blender names its session folder there blender_<letter><pid>,
    26 names per process id, and wine gives each process one of the same few ids: the folders that
    quick exits (os._exit) leave would soon take all 26, in a TEMP shared by every run."""
    import os
    temp = os.environ.get("NDFBAKE_WINE_TEMP")
    if temp:
        os.environ["TEMP"] = os.environ["TMP"] = temp


try:
    _hide_map_view_of_file3()
    _own_temp()
except Exception as e:  # never stop Python from starting
    import sys
    print("sitecustomize (wine fixes):", e, file=sys.stderr)
PYTHON
)
site_dir=$cache/wine-site-$(printf '%s\n' "$sitecustomize" | sha1sum | cut -c1-12)
if [ ! -f "$site_dir/sitecustomize.py" ]; then
  new_site=$(mktemp -d "$cache/.wine-site.XXXXXX")
  printf '%s\n' "$sitecustomize" >"$new_site/sitecustomize.py"
  chmod 755 "$new_site"
  mv -T "$new_site" "$site_dir" 2>/dev/null || rm -rf "$new_site"  # another run was first
fi

# The bpy of this series and numpy on sys.path (the embeddable Python has no ._pth file here, so
# PYTHONPATH works, and the tests' child Pythons inherit it), and the sitecustomize.py; no user
# site-packages.
export PYTHONPATH="$(windows_path "$site_dir");$(windows_path "$cache/bpy-$series");$(windows_path "$cache/site-packages")"
export PYTHONNOUSERSITE=1
# Output reaches a Linux pipe: UTF-8 whatever the console code page.
export PYTHONIOENCODING=utf-8

# A TEMP folder of this run's own, C:\ndfbake-temp\run.*, deleted after it: Blender's session
# folders in a TEMP that every run shares would soon take all the names it tries (the
# sitecustomize.py above sets TEMP from NDFBAKE_WINE_TEMP: wine sets TEMP itself).
mkdir -p "$WINEPREFIX/drive_c/ndfbake-temp"
run_temp=$(mktemp -d "$WINEPREFIX/drive_c/ndfbake-temp/run.XXXXXX")
trap 'rm -rf "$run_temp"' EXIT
export NDFBAKE_WINE_TEMP="C:\\ndfbake-temp\\${run_temp##*/}"

# Python under wine 8 cannot open a standard stream that is a regular file (init_sys_streams:
# "[WinError 6] Invalid handle"): a redirected one goes through a pipe and cat.
pipes=()
if [ -f /proc/self/fd/0 ]; then exec 0< <(cat); fi
if [ -f /proc/self/fd/1 ]; then exec 1> >(cat); pipes+=($!); fi
if [ -f /proc/self/fd/2 ]; then exec 2> >(cat >&2); pipes+=($!); fi
status=0
wine "$cache/python/python.exe" "${args[@]}" || status=$?
if [ ${#pipes[@]} -gt 0 ]; then
  exec 1>&- 2>&-  # cat sees the end of its pipe, writes the rest and exits
  wait "${pipes[@]}" || true
fi
exit "$status"
