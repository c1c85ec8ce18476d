#!/usr/bin/env bash
# Speed ratios measured in one run on one map (default: a generated 2048² fbm map):
#   - the default bake against `oiiotool INPUT --printstats` decoding the same file;
#   - the default fit (hierarchical, from binned normals) against Han's per-level EM (every fine
#     normal, at most 10 iterations, seeded from the finer level's lobes: §7.1), both at J = 4,
#     with the mean effective-BRDF error of each over all levels ≥ 1 (from their report.json).
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

seconds() {  # runs "$@" (its errors shown, a failure ends the script), prints its wall time
  local start=$EPOCHREALTIME
  "$@" >/dev/null || return $?
  awk -v a="$start" -v b="$EPOCHREALTIME" 'BEGIN { printf "%.3f", b - a }'
}

decode=$(seconds oiiotool "$map" --printstats)
bake=$(seconds "$ndfbake" bake "$map" --out "$work/default" --quiet)
per_level=$(seconds "$ndfbake" bake "$map" --out "$work/per-level" --quiet --method per-level --starts 1 --iterations 10)

/usr/bin/python3 - "$work" "$map" "$decode" "$bake" "$per_level" <<'PY'
import json, sys
work, path, decode, bake, per_level = sys.argv[1], sys.argv[2], *map(float, sys.argv[3:])
def report(name):
    r = json.load(open(f"{work}/{name}/report.json"))
    levels = r["levels"][1:]
    return r["timings_seconds"]["fit"], sum(l["error"]["mean"] for l in levels) / len(levels)
fit_default, e_default = report("default")
fit_per_level, e_per_level = report("per-level")
print(f"map: {path}")
print(f"oiiotool --printstats: {decode:.2f} s; default bake: {bake:.2f} s; ratio {bake / decode:.1f}x")
print(f"per-level fit (Han 7.1): {fit_per_level:.2f} s fitting ({per_level:.2f} s in all), mean error {e_per_level:.4f}")
print(f"default (hierarchical):  {fit_default:.2f} s fitting ({bake:.2f} s in all), mean error {e_default:.4f}")
print(f"default vs per-level: fit {fit_per_level / fit_default:.1f}x faster, error {100 * (e_default / e_per_level - 1):+.1f}%")
PY
