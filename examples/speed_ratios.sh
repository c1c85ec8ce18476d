#!/usr/bin/env bash
# Speed ratios measured in one run on one map (default: a generated 2048² fbm map):
#   - the default bake against `oiiotool INPUT --printstats` decoding the same file;
#   - the hierarchical fit against the per-level fit (10 EM iterations, as in Han §7.1), with the
#     mean effective-BRDF error of each over all levels ≥ 1 (from their report.json).
# Usage: examples/speed_ratios.sh [NORMAL_MAP]
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
ndfbake="${NDFBAKE_BUILD_DIR:-$root/build}/native/ndfbake"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
map=${1:-}
if [ -z "$map" ]; then
  map="$work/fbm2048.png"
  "$ndfbake" synth fbm --size 2048 --out "$map"
fi

seconds() {  # runs "$@" quietly, prints its wall time
  local start=$EPOCHREALTIME
  "$@" >/dev/null 2>&1
  awk -v a="$start" -v b="$EPOCHREALTIME" 'BEGIN { printf "%.3f", b - a }'
}

decode=$(seconds oiiotool "$map" --printstats)
bake=$(seconds "$ndfbake" bake "$map" --out "$work/default" --quiet)
per_level=$(seconds "$ndfbake" bake "$map" --out "$work/per-level" --quiet --method per-level --iterations 10 --tolerance 0)
hierarchical=$(seconds "$ndfbake" bake "$map" --out "$work/hierarchical" --quiet --method hierarchical --tolerance 0)

/usr/bin/python3 - "$work" "$map" "$decode" "$bake" "$per_level" "$hierarchical" <<'PY'
import json, sys
work, path, decode, bake, per_level, hierarchical = sys.argv[1], sys.argv[2], *map(float, sys.argv[3:])
def mean_error(name):
    levels = json.load(open(f"{work}/{name}/report.json"))["levels"][1:]
    return sum(l["error"]["mean"] for l in levels) / len(levels)
e_per_level, e_hier = mean_error("per-level"), mean_error("hierarchical")
print(f"map: {path}")
print(f"oiiotool --printstats: {decode:.2f} s; default bake: {bake:.2f} s; ratio {bake / decode:.1f}x")
print(f"per-level fit (10 iterations): {per_level:.2f} s, mean error {e_per_level:.4f}")
print(f"hierarchical fit:              {hierarchical:.2f} s, mean error {e_hier:.4f}")
print(f"hierarchical vs per-level: {per_level / hierarchical:.2f}x faster, error {100 * (e_hier / e_per_level - 1):+.1f}%")
PY
