#!/usr/bin/env bash
# Installs Debian 11 (bullseye: glibc 2.31, GCC 10's libstdc++, Python 3.9) with Python and numpy
# into a chroot, cached at $NDFBAKE_DEBIAN11_ROOT (default /var/cache/ndfbake/debian11) and reused:
# a Linux older than Debian 12, where the tests load the add-on's library through the add-on's own
# ctypes module and bake (scripts/in-chroot.sh runs a command there). Run as root. Packages come
# from the mirror this machine's apt uses.
set -euo pipefail
root=${NDFBAKE_DEBIAN11_ROOT:-/var/cache/ndfbake/debian11}
packages=(python3-minimal python3-numpy)
# The marker holds the package list it was made with: a chroot made for another list is made anew.
if [ -x "$root/usr/bin/python3" ] && [ "$(cat "$root/.ndfbake-complete" 2>/dev/null)" = "${packages[*]}" ]; then
  exit 0
fi
echo "== install-debian11-runtime.sh: Debian 11 with Python into $root"
mirror=$(apt-get indextargets --format '$(REPO_URI) $(RELEASE)' 'Created-By: Packages' |
         awk '$2 !~ /-(security|updates)$/ {print $1; exit}')
rm -rf "$root"
mkdir -p "$(dirname "$root")"
debootstrap --variant=minbase bullseye "$root" "${mirror%/}" >/dev/null
cp /etc/resolv.conf "$root/etc/resolv.conf"
chroot "$root" apt-get update -qq
DEBIAN_FRONTEND=noninteractive chroot "$root" apt-get install -y -qq --no-install-recommends "${packages[@]}" >/dev/null
echo "${packages[*]}" >"$root/.ndfbake-complete"
echo "== install-debian11-runtime.sh: $(chroot "$root" ldd --version | head -1), $(chroot "$root" python3 --version)"
