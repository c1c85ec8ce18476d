#!/usr/bin/env bash
# Installs Debian 13's Blender (4.3.2: a full binary, Mesa 25, OpenImageIO 2.5, no OSL) into a
# Debian 13 (trixie) chroot, cached at $NDFBAKE_DEBIAN13_ROOT (default /var/cache/ndfbake/debian13)
# and reused (scripts/install-chroot.sh). The tests run in it what the bpy module cannot (a real
# window under Xvfb) and load the add-on's library in a Blender whose system libraries are not
# Debian 12's (scripts/debian13-blender.sh runs a command there). Run as root.
set -euo pipefail
root=${NDFBAKE_DEBIAN13_ROOT:-/var/cache/ndfbake/debian13}
# python3-venv: the bpy module of Blender 5.1 and later (CPython 3.13) lives here too
# (scripts/install-bpy-debian13.sh); assimp-testmodels: test_tangents' real meshes.
bash "$(dirname "$0")/install-chroot.sh" trixie "$root" blender python3-numpy xvfb xauth libegl1 libegl-mesa0 \
  python3-venv assimp-testmodels
echo "== install-debian13-blender.sh: $(chroot "$root" blender --version 2>/dev/null | head -1)"
