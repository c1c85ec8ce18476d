#!/usr/bin/env bash
# Speed ratios measured in one run on one map (default: a generated 2048² fbm map):
#   - the default bake against `oiiotool INPUT --printstats` decoding the same file;
#   - the default fit (hierarchical, from binned normals) against Han's per-level EM (every fine
#     normal, at most 10 iterations, seeded from the finer level's lobes: §7.1), both at J = 4,
#     with the mean effective-BRDF error of each over all levels ≥ 1 (from their report.json);
#     and the same two fits without the slot alignment that both run after fitting (--no-align).
# Each command runs ROUNDS times (default 3), the rounds interleaved so that a slow spell of a
# shared machine falls on every method; each time is the fastest of its rounds.
# Usage: examples/speed_ratios.sh [NORMAL_MAP]
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
ndfbake="${NDFBAKE_BUILD_DIR:-$root/build}/native/ndfbake"
rounds=${ROUNDS:-3}
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

per_level=(--method per-level --starts 1 --iterations 10)
[ "$rounds" -ge 1 ] || { echo "speed_ratios.sh: ROUNDS must be at least 1" >&2; exit 2; }
for round in $(seq "$rounds"); do
  # Each time into a variable first: inside echo's argument a failure would not stop the script.
  t=$(seconds oiiotool "$map" --printstats); echo "decode $t" >>"$work/walls"
  t=$(seconds "$ndfbake" bake "$map" --out "$work/default-$round" --quiet); echo "default $t" >>"$work/walls"
  t=$(seconds "$ndfbake" bake "$map" --out "$work/per-level-$round" --quiet "${per_level[@]}")
  echo "per-level $t" >>"$work/walls"
  "$ndfbake" bake "$map" --out "$work/default-unaligned-$round" --quiet --no-align >/dev/null
  "$ndfbake" bake "$map" --out "$work/per-level-unaligned-$round" --quiet --no-align "${per_level[@]}" >/dev/null
done

/usr/bin/python3 - "$work" "$map" "$rounds" <<'PY'
import json, sys
work, path, rounds = sys.argv[1], sys.argv[2], int(sys.argv[3])
wall = {}
for line in open(f"{work}/walls"):
    name, seconds = line.split()
    wall[name] = min(wall.get(name, float("inf")), float(seconds))
def report(name):
    fits = []
    for r in range(1, rounds + 1):
        j = json.load(open(f"{work}/{name}-{r}/report.json"))
        fits.append(j["timings_seconds"]["fit"])
    levels = j["levels"][1:]
    return min(fits), sum(l["error"]["mean"] for l in levels) / len(levels)
fit_default, e_default = report("default")
fit_per_level, e_per_level = report("per-level")
fit_default_unaligned, _ = report("default-unaligned")
fit_per_level_unaligned, _ = report("per-level-unaligned")
decode, bake = wall["decode"], wall["default"]
print(f"map: {path} (fastest of {rounds} rounds)")
print(f"oiiotool --printstats: {decode:.2f} s; default bake: {bake:.2f} s; ratio {bake / decode:.1f}x")
print(f"per-level fit (Han 7.1): {fit_per_level:.2f} s fitting ({wall['per-level']:.2f} s in all), mean error {e_per_level:.4f}")
print(f"default (hierarchical):  {fit_default:.2f} s fitting ({bake:.2f} s in all), mean error {e_default:.4f}")
print(f"default vs per-level: fit {fit_per_level / fit_default:.1f}x faster, error {100 * (e_default / e_per_level - 1):+.1f}%")
print(f"without the slot alignment both run (--no-align): per-level {fit_per_level_unaligned:.2f} s, "
      f"default {fit_default_unaligned:.2f} s, {fit_per_level_unaligned / fit_default_unaligned:.1f}x faster")
PY
