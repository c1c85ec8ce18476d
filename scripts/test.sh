#!/usr/bin/env bash
# The test command: installs dependencies, builds, and runs every test under ctest.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
bash "$root/scripts/install-deps.sh"
bash "$root/scripts/build.sh"
cd "${NDFBAKE_BUILD_DIR:-$root/build}"
ctest --output-on-failure -j "$(nproc)"
