#!/usr/bin/env bash
# Installs Debian 13's Blender (4.3.2: a full binary, Mesa 25, OpenImageIO 2.5, no OSL) into a
# Debian 13 (trixie) chroot, cached at $NDFBAKE_DEBIAN13_ROOT (default /var/cache/ndfbake/debian13)
# and reused (scripts/install-chroot.sh). The tests run in it what the bpy module cannot (a real
# window under Xvfb) and load the add-on's library in a Blender whose system libraries are not
# Debian 12's (scripts/debian13-blender.sh runs a command there). Run as root.
set -euo pipefail
root=${NDFBAKE_DEBIAN13_ROOT:-/var/cache/ndfbake/debian13}
bash "$(dirname "$0")/install-chroot.sh" trixie "$root" blender python3-numpy xvfb xauth libegl1 libegl-mesa0
echo "== install-debian13-blender.sh: $(chroot "$root" blender --version 2>/dev/null | head -1)"
