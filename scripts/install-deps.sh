#!/usr/bin/env bash
# Installs what ndfbake needs on Debian 12: Debian's own packages, then Blender 4.2, 4.5 and 5.0 as
# the bpy module from PyPI (scripts/install-bpy.sh; NDFBAKE_BPY_SERIES="4.5" installs fewer, "" none),
# Debian 13's Blender 4.3 in a chroot (scripts/install-debian13-blender.sh) and Blender 5.2 and 5.3
# as the bpy module there (scripts/install-bpy-debian13.sh; NDFBAKE_DEBIAN13_BPY_SERIES), wine with a
# Windows CPython and the Windows bpy of 4.2 and 5.0 (scripts/install-windows-runtime.sh;
# NDFBAKE_WINDOWS_BPY_SERIES), the receding-surface benchmark's real normal maps out of Debian's
# game packages (scripts/install-normal-maps.sh), Debian 11 with Python in
# another (scripts/install-debian11-runtime.sh), and the add-on library's toolchain
# (scripts/install-addon-toolchain.sh). Run as root.
set -euo pipefail
packages=(build-essential cmake pkg-config libopenimageio-dev libopenexr-dev openimageio-tools
          libgtest-dev python3 python3-venv blender assimp-testmodels
          xvfb xauth             # xvfb-run (the window, viewport and GLSL tests); xvfb only recommends
                                 # xauth, and recommends are not installed
          python3-numpy          # the add-on's level of detail, the demo's and tests' image error (Debian's
                                 # Blender does not depend on it)
          python3-matplotlib     # examples/plot_bench.py, the bench chart
          glslang-tools          # compiles the bakes' ndfbake.glsl in the tests
          libegl1 libegl-mesa0   # EEVEE in `blender -b` renders through surfaceless EGL (Mesa)
          libxrender1 libxi6 libxfixes3 libxkbcommon0 libsm6 libgl1  # what the bpy wheels link
          clang libclang-rt-14-dev   # clang + libFuzzer: the fuzz targets (scripts/fuzz.sh)
          debootstrap            # the Debian 13 and 11 chroots (install-debian13-blender.sh, install-debian11-runtime.sh)
          lld-14                 # ld64.lld links the macOS add-on libraries (native/cmake/zig_darwin_link.py)
          llvm                   # llvm-objdump, -nm, -readelf read every platform's library (check_platform_library.py)
          qemu-user libc6-arm64-cross)  # the Linux-on-ARM library bakes under qemu-aarch64 with Debian's arm64 glibc
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

# Blender 4.2+ (bpy wheels) and Debian 13's 4.3 (chroot): the tests of a version that did not install
# are skipped with a message (tests/CMakeLists.txt), so a failure here (PyPI or the archive out of
# reach, no mount rights for the chroot) warns and the rest still runs.
bash "$(dirname "$0")/install-bpy.sh" ${NDFBAKE_BPY_SERIES-4.2 4.5 5.0} ||
  echo "WARNING: install-bpy.sh failed: the Blender tests of the bpy series it missed are skipped" >&2
bash "$(dirname "$0")/install-debian13-blender.sh" ||
  echo "WARNING: install-debian13-blender.sh failed: the Debian 13 Blender tests are skipped" >&2
bash "$(dirname "$0")/install-bpy-debian13.sh" ${NDFBAKE_DEBIAN13_BPY_SERIES-5.2 5.3} ||
  echo "WARNING: install-bpy-debian13.sh failed: the Blender tests of the bpy series it missed are skipped" >&2
bash "$(dirname "$0")/install-windows-runtime.sh" ${NDFBAKE_WINDOWS_BPY_SERIES-4.2 5.0} ||
  echo "WARNING: install-windows-runtime.sh failed: the Windows Blender tests of the series it missed are skipped" >&2
bash "$(dirname "$0")/install-normal-maps.sh" ||
  echo "WARNING: install-normal-maps.sh failed: the receding-surface test will fail for want of its map" >&2
bash "$(dirname "$0")/install-debian11-runtime.sh" ||
  echo "WARNING: install-debian11-runtime.sh failed: the add-on library's Debian 11 test is disabled" >&2
# zig and the Debian sources that build the add-on's library for glibc 2.28. Without them the build
# still succeeds, with a gcc-built add-on library that needs glibc 2.36 (CMake warns), so a
# failure here (PyPI or the archive out of reach) is a warning, not the end of the install.
bash "$(dirname "$0")/install-addon-toolchain.sh" ||
  echo "WARNING: install-addon-toolchain.sh failed: the add-on library will need glibc 2.36" >&2
