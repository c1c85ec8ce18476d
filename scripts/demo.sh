#!/usr/bin/env bash
# The main job: installs dependencies, builds, generates a woven-fabric normal map, bakes its
# filtered lobe pyramid and prints the report's summary. Output goes to ./demo-output.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
bash "$root/scripts/install-deps.sh"
bash "$root/scripts/build.sh"
ndfbake="${NDFBAKE_BUILD_DIR:-$root/build}/native/ndfbake"
out="$root/demo-output"
mkdir -p "$out"
"$ndfbake" synth weave --size 512 --out "$out/weave.png"
"$ndfbake" bake "$out/weave.png" --out "$out/weave-lobes" --brdf ggx:0.4
python3 "$root/examples/summarize_report.py" "$out/weave-lobes/report.json"
