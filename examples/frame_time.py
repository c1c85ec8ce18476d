"""Frame time of the demo scene, plain against baked, in EEVEE and Cycles, measured in one run.

    blender -b --factory-startup --python examples/frame_time.py -- --out DIR
            [--width W --height H] [--eevee-samples N] [--samples N] [--lobes 1,4,8] [--repeats R]
            [--dielectric]
    python examples/frame_time.py -- --out DIR ...        (Blender as the bpy module)

Builds examples/demo_scene.py's scene (five normal-mapped metal materials), renders it plain (the
materials as the artist made them), then bakes it with 1, 4 and 8 lobes at most and renders it
again. Every variant is rendered once to warm up (EEVEE compiles its shaders, Cycles its kernels
and the scene; that time is printed apart) and then timed over R renders, the fastest kept.
--dielectric sets every material's Metallic to 0 first (plain and baked alike), where a bake
draws the diffuse once beneath specular-only lobes (addon/ndfbake/shading/specular_split.py). Prints
a table of seconds per frame and the ratio to plain, per engine, and writes DIR/frame_time.json.
"""
import argparse
import json
import os
import sys
import time

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import demo_scene  # noqa: E402
import demo_build  # noqa: E402
import demo_render  # noqa: E402


def time_renders(scene, engine, samples, directory, repeats):
    """(first render's seconds, fastest of `repeats` renders after it)."""
    path = os.path.join(directory, "frame.exr")
    start = time.perf_counter()
    demo_render.render(scene, engine, path, samples)
    first = time.perf_counter() - start
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        demo_render.render(scene, engine, path, samples)
        best = min(best, time.perf_counter() - start)
    return first, best


def measure(out, width, height, eevee_samples, samples, lobe_counts, repeats, dielectric=False, log=print):
    scene_dir = os.path.join(out, "scene")
    os.makedirs(scene_dir, exist_ok=True)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene_info = demo_build.build_scene(scene_dir, width, height)
    scene = bpy.context.scene
    if dielectric:
        for name in scene_info["materials"]:
            bpy.data.materials[name].node_tree.nodes["Principled BSDF"].inputs["Metallic"].default_value = 0.0
    engines = {"EEVEE": demo_build.eevee_engine(), "Cycles": "CYCLES"}
    rows = []

    def run(variant):
        for name, engine in engines.items():
            n = eevee_samples if name == "EEVEE" else samples
            first, best = time_renders(scene, engine, n, scene_dir, repeats)
            rows.append({"engine": name, "variant": variant, "samples": n, "first_seconds": round(first, 3),
                         "seconds": round(best, 3)})
            log("  %-6s %-8s %3d samples: %.2f s a frame (first render %.2f s)" % (name, variant, n, best, first))

    log("frame_time.py: Blender %s, %dx%d, %d materials" % (bpy.app.version_string, width, height,
                                                          len(scene_info["materials"])))
    run("plain")
    for lobes in lobe_counts:
        bakes = demo_scene.bake_all(scene, max_lobes=lobes)
        failed = [b for b in bakes if "error" in b]
        if failed:
            raise RuntimeError("bake with %d lobes failed: %s" % (lobes, failed))
        run("%d lobes" % lobes)
    plain = {r["engine"]: r["seconds"] for r in rows if r["variant"] == "plain"}
    for r in rows:
        r["ratio"] = round(r["seconds"] / plain[r["engine"]], 2)
    report = {"blender": bpy.app.version_string, "width": width, "height": height, "dielectric": dielectric,
              "rows": rows}
    with open(os.path.join(out, "frame_time.json"), "w") as f:
        json.dump(report, f, indent=1)
    log("\n| engine | variant | samples | seconds a frame | ratio to plain | first render (s) |")
    log("|---|---|---:|---:|---:|---:|")
    for r in rows:
        log("| %s | %s | %d | %.2f | %.2f | %.1f |" % (r["engine"], r["variant"], r["samples"], r["seconds"],
                                                     r["ratio"], r["first_seconds"]))
    return report


def _arguments():
    parser = argparse.ArgumentParser(prog="examples/frame_time.py", description=__doc__.split("\n")[0])
    parser.add_argument("--out", required=True, help="output folder")
    parser.add_argument("--width", type=int, default=320)
    parser.add_argument("--height", type=int, default=180)
    parser.add_argument("--eevee-samples", type=int, default=16)
    parser.add_argument("--samples", type=int, default=16, help="Cycles samples per pixel")
    parser.add_argument("--lobes", default="1,4,8", help="comma-separated maximum lobe counts to bake")
    parser.add_argument("--repeats", type=int, default=2, help="timed renders per variant (fastest kept)")
    parser.add_argument("--dielectric", action="store_true", help="the materials with Metallic 0 (plain and baked)")
    parser.add_argument("--library", help="libndfbake.so (default $NDFBAKE_LIBRARY or build/native/libndfbake.so)")
    return demo_build.script_arguments(parser)


def main():
    args = _arguments()
    demo_build.import_addon(args.library)
    measure(args.out, args.width, args.height, args.eevee_samples, args.samples,
            [int(n) for n in args.lobes.split(",")], args.repeats, args.dielectric)
    return 0


if __name__ == "__main__":
    demo_scene.run_as_script(main)
