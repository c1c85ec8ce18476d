#!/usr/bin/env bash
# Runs a command in the chroot at ROOT (one of install-debian13-blender.sh's or
# install-debian11-runtime.sh's) with the given folders visible at their own paths, in a mount
# namespace of its own so that nothing stays mounted afterwards. Run as root.
#   bash scripts/in-chroot.sh ROOT FOLDER... -- COMMAND [ARG...]
set -euo pipefail
[ $# -gt 0 ] || { echo "usage: $0 ROOT FOLDER... -- COMMAND [ARG...]" >&2; exit 2; }
root=$(realpath "$1"); shift
folders=()
while [ $# -gt 0 ] && [ "$1" != "--" ]; do folders+=("$(realpath "$1")"); shift; done
[ "${1-}" = "--" ] && shift
[ $# -gt 0 ] && [ ${#folders[@]} -gt 0 ] || { echo "usage: $0 ROOT FOLDER... -- COMMAND [ARG...]" >&2; exit 2; }
binds=""
for f in "${folders[@]}"; do
  binds+="mkdir -p '$root$f' && mount --bind '$f' '$root$f' && "
done
# The command runs in the first folder; environment variables pass through.
exec unshare -m bash -c "${binds}mount -t proc proc '$root/proc' && mount --bind /dev '$root/dev' &&
  exec chroot '$root' /usr/bin/env -C '${folders[0]}' \"\$@\"" "$(basename "$root")" "$@"
