#!/usr/bin/env bash
# Makes a Debian chroot at ROOT: SUITE by debootstrap (minbase) from the mirror this machine's apt
# uses, then PACKAGES (no recommends). Kept and reused where ROOT already holds one made with the
# same packages (its marker file, written last, lists them; each suite has a root of its own); made
# anew otherwise. Run as root.
#   bash scripts/install-chroot.sh SUITE ROOT PACKAGE...
set -euo pipefail
[ $# -ge 3 ] || { echo "usage: $0 SUITE ROOT PACKAGE..." >&2; exit 2; }
suite=$1 root=$2; shift 2
marker="$*"
if [ "$(cat "$root/.ndfbake-complete" 2>/dev/null)" = "$marker" ]; then
  exit 0
fi
echo "== install-chroot.sh: Debian $suite with $* into $root"
mirror=$(apt-get indextargets --format '$(REPO_URI) $(RELEASE)' 'Created-By: Packages' |
         awk '$2 !~ /-(security|updates)$/ {print $1; exit}')
rm -rf "$root"
mkdir -p "$(dirname "$root")"
debootstrap --variant=minbase "$suite" "$root" "${mirror%/}" >/dev/null
cp /etc/resolv.conf "$root/etc/resolv.conf"
chroot "$root" apt-get update -qq
DEBIAN_FRONTEND=noninteractive chroot "$root" apt-get install -y -qq --no-install-recommends "$@" >/dev/null
echo "$marker" >"$root/.ndfbake-complete"
