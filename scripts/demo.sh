#!/usr/bin/env bash
# The main job: installs dependencies, builds, generates a woven-fabric normal map, bakes its
# filtered lobe pyramid and prints the report's summary; then builds the Blender demo scene
# (examples/demo_scene.py: a receding metal plane and spheres in an HDR world), renders it naive
# and with ndfbake in EEVEE and Cycles beside references, and prints the image errors.
# Output goes to ./demo-output (the scene in ./demo-output/scene: renders, montage.png, report).
set -euo pipefail
# Debian's own tools first: a Python manager's shims ahead of /usr/bin (pyenv's cmake, ctest, python3)
# would hand the scripts its interpreter, and Debian's Blender would find that Python's home, not its own.
export PATH=/usr/sbin:/usr/bin:/sbin:/bin:$PATH
root=$(cd "$(dirname "$0")/.." && pwd)
bash "$root/scripts/install-deps.sh"
bash "$root/scripts/build.sh"
build="${NDFBAKE_BUILD_DIR:-$root/build}"
ndfbake="$build/native/ndfbake"
out="$root/demo-output"
mkdir -p "$out"
"$ndfbake" synth weave --size 512 --out "$out/weave.png"
"$ndfbake" bake "$out/weave.png" --out "$out/weave-lobes" --brdf ggx:0.4
python3 "$root/examples/summarize_report.py" "$out/weave-lobes/report.json"
# The same bake refined for its BRDF (docs/fit.md, "Refining for the BRDF"): lower error, longer fit.
echo
echo "The same, refined for ggx:0.4 (--refine):"
"$ndfbake" bake "$out/weave.png" --out "$out/weave-lobes-refined" --brdf ggx:0.4 --refine --quiet
python3 "$root/examples/summarize_report.py" "$out/weave-lobes-refined/report.json"

# The Blender scene in the newest supported Blender, 5.0 as the bpy module (install-bpy.sh; a couple
# of minutes on two cores). Blender's own chatter goes to scene.log; the report is printed from
# report.txt.
blender_python=${NDFBAKE_CACHE:-$HOME/.cache/ndfbake}/bpy-5.0/bin/python
if [ ! -x "$blender_python" ]; then
  echo "demo.sh: Blender 5.0 (bpy) is not installed at $blender_python: see scripts/install-bpy.sh" >&2
  exit 1
fi
echo
echo "Blender demo scene ($("$blender_python" -c 'import bpy; print(bpy.app.version_string)' 2>/dev/null)) -> $out/scene (log: $out/scene.log)"
mkdir -p "$out/scene"
if ! "$blender_python" -B "$root/examples/demo_scene.py" -- \
       --out "$out/scene" --library "$build/native/libndfbake.so" >"$out/scene.log" 2>&1; then
  tail -n 40 "$out/scene.log" >&2
  echo "demo.sh: the Blender demo scene failed (full log: $out/scene.log)" >&2
  exit 1
fi
cat "$out/scene/report.txt"
