#!/usr/bin/env bash
# Runs a command in the Debian 13 chroot (scripts/install-debian13-blender.sh) with the given
# folders (the checkout, the build folder) visible at their own paths, in a mount namespace of its
# own so that nothing stays mounted afterwards. Run as root.
#   bash scripts/debian13-blender.sh FOLDER... -- COMMAND [ARG...]
set -euo pipefail
root=${NDFBAKE_DEBIAN13_ROOT:-/var/cache/ndfbake/debian13}
folders=()
while [ $# -gt 0 ] && [ "$1" != "--" ]; do folders+=("$(realpath "$1")"); shift; done
[ "${1-}" = "--" ] && shift
[ $# -gt 0 ] || { echo "usage: $0 FOLDER... -- COMMAND [ARG...]" >&2; exit 2; }
binds=""
for f in "${folders[@]}"; do
  binds+="mkdir -p '$root$f' && mount --bind '$f' '$root$f' && "
done
# The command runs in the first folder; environment variables pass through.
exec unshare -m bash -c "${binds}mount -t proc proc '$root/proc' && mount --bind /dev '$root/dev' &&
  exec chroot '$root' /usr/bin/env -C '${folders[0]}' \"\$@\"" debian13 "$@"
