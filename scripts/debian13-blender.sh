#!/usr/bin/env bash
# Runs a command in the Debian 13 chroot (scripts/install-debian13-blender.sh) with the given
# folders (the checkout, the build folder) visible at their own paths (scripts/in-chroot.sh). Run
# as root.
#   bash scripts/debian13-blender.sh FOLDER... -- COMMAND [ARG...]
set -euo pipefail
exec bash "$(dirname "$0")/in-chroot.sh" "${NDFBAKE_DEBIAN13_ROOT:-/var/cache/ndfbake/debian13}" "$@"
