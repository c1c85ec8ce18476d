#!/usr/bin/env bash
# Installs Debian 11 (bullseye: glibc 2.31, GCC 10's libstdc++, Python 3.9) with Python and numpy
# into a chroot, cached at $NDFBAKE_DEBIAN11_ROOT (default /var/cache/ndfbake/debian11) and reused
# (scripts/install-chroot.sh): a Linux older than Debian 12, where a test loads the add-on's library
# through the add-on's own ctypes module and bakes (scripts/in-chroot.sh runs a command there).
# Run as root.
set -euo pipefail
root=${NDFBAKE_DEBIAN11_ROOT:-/var/cache/ndfbake/debian11}
bash "$(dirname "$0")/install-chroot.sh" bullseye "$root" python3-minimal python3-numpy
echo "== install-debian11-runtime.sh: $(chroot "$root" ldd --version | head -1), $(chroot "$root" python3 --version)"
