#!/usr/bin/env bash
# Installs Debian 13's Blender (4.3.2: a full binary, Mesa 25, OpenImageIO 2.5, no OSL) into a
# Debian 13 (trixie) chroot, cached at $NDFBAKE_DEBIAN13_ROOT (default /var/cache/ndfbake/debian13)
# and reused. The tests run in it what the bpy module cannot (a real window under Xvfb) and load the
# add-on's library in a Blender whose system libraries are not Debian 12's
# (scripts/debian13-blender.sh runs a command there). Run as root. Packages come from the mirror
# this machine's apt uses.
set -euo pipefail
root=${NDFBAKE_DEBIAN13_ROOT:-/var/cache/ndfbake/debian13}
packages=(blender python3-numpy xvfb xauth libegl1 libegl-mesa0)
# The marker holds the package list it was made with: a chroot made for another list is made anew.
if [ -x "$root/usr/bin/blender" ] && [ "$(cat "$root/.ndfbake-complete" 2>/dev/null)" = "${packages[*]}" ]; then
  exit 0
fi
echo "== install-debian13-blender.sh: Debian 13 with Blender into $root"
mirror=$(apt-get indextargets --format '$(REPO_URI) $(RELEASE)' 'Created-By: Packages' |
         awk '$2 !~ /-(security|updates)$/ {print $1; exit}')
rm -rf "$root"
mkdir -p "$(dirname "$root")"
debootstrap --variant=minbase trixie "$root" "${mirror%/}" >/dev/null
cp /etc/resolv.conf "$root/etc/resolv.conf"
chroot "$root" apt-get update -qq
DEBIAN_FRONTEND=noninteractive chroot "$root" apt-get install -y -qq --no-install-recommends "${packages[@]}" >/dev/null
echo "${packages[*]}" >"$root/.ndfbake-complete"
echo "== install-debian13-blender.sh: $(chroot "$root" blender --version 2>/dev/null | head -1)"
