"""The OSL variant against the stock-node group and the naive normal map on the demo scene, in
Cycles on the CPU: image error against a many-sample reference, render time, and the noise of a
render at --samples (docs/osl.md, "On the demo scene").

    python studies/osl_comparison.py -- --out DIR [--width W --height H] [--reference-samples N]
                                         [--samples N] [--library PATH]
    (the bpy module; or blender -b --factory-startup --python-exit-code 1 --python ... -- ...)

The scene is examples/demo_scene.py's (build_scene, its regions and image_error's pixel RMSE in
linear light). The reference: the unbaked scene at --reference-samples with Open Shading Language
off (with it on, Cycles reads image files through OpenImageIO's texture system, which MIP-maps
the plain normal map and so filters the reference too). Then, each at --samples with two seeds:
naive (the unbaked scene) with OSL off and on, the stock-node group (a bake with the defaults:
the scene camera's level of detail, Cycles Lobes Narrowed) with OSL on and off, and the OSL variant
(shader OSL, a re-bake). Error: pixel RMSE against the reference per region (ground_far,
spheres_far, all), seed 0. Noise: the RMSE between the two seeds' renders per region, divided by
√2 (one render's per-pixel standard deviation). Time: the wall time of bpy.ops.render.render,
scene sync and shader compilation included, the mean of the two seeds. Into DIR: the scene, the
lobe folders, renders/*.exr, report.json and report.txt (also printed).
"""
import argparse
import json
import math
import os
import sys
import time

sys.dont_write_bytecode = True

import bpy  # noqa: E402

EXAMPLES = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "examples")  # the demo
if EXAMPLES not in sys.path:
    sys.path.insert(0, EXAMPLES)
import demo_scene  # noqa: E402
import demo_build  # noqa: E402
import demo_render  # noqa: E402
import image_error  # noqa: E402

REGIONS = ("ground_far", "spheres_far", "all")


def _arguments():
    parser = argparse.ArgumentParser(prog="studies/osl_comparison.py --",
                                     description="The OSL variant vs the stock-node group and naive on the demo scene.")
    parser.add_argument("--out", required=True)
    parser.add_argument("--width", type=int, default=320)
    parser.add_argument("--height", type=int, default=180)
    parser.add_argument("--reference-samples", type=int, default=256)
    parser.add_argument("--samples", type=int, default=16)
    parser.add_argument("--library", help="libndfbake.so (default $NDFBAKE_LIBRARY or build/native/libndfbake.so)")
    return demo_build.script_arguments(parser)


def run(out, width, height, reference_samples, samples, log=print):
    out = os.path.abspath(out)
    info = demo_build.fresh_scene(out, width, height)
    scene = bpy.context.scene
    scene.cycles.shading_system = True
    masks = demo_render.region_masks(scene, info["ground"], info["far_spheres"])
    renders = os.path.join(out, "renders")
    os.makedirs(renders, exist_ok=True)

    def render(name, n, seed):
        start = time.perf_counter()
        pixels = demo_render.render(scene, "CYCLES", os.path.join(renders, "%s-%d.exr" % (name, seed)), n, seed=seed)
        return pixels, time.perf_counter() - start

    # The reference with OSL off: with it on, Cycles reads an image file's texture through
    # OpenImageIO's texture system, which MIP-maps the plain normal map (automip) and so filters
    # the reference itself (naive OSL below).
    scene.cycles.shading_system = False
    reference, reference_seconds = render("reference", reference_samples, 1)
    log("  reference %d spp (OSL off): %.1f s" % (reference_samples, reference_seconds))
    rows = {}

    def measure(name):
        (a, ta), (b, tb) = render(name, samples, 0), render(name, samples, 2)
        row = {"seconds": round((ta + tb) / 2, 2)}
        for region in REGIONS:
            row[region] = image_error.pixel_rmse(a, reference, masks[region])
            row["noise " + region] = image_error.pixel_rmse(a, b, masks[region]) / math.sqrt(2.0)
        rows[name] = row
        log("  %-16s %s" % (name, ", ".join("%s %.4f" % (k, v) for k, v in row.items())))

    measure("naive SVM")
    scene.cycles.shading_system = True
    measure("naive OSL")
    bakes = {"nodes": demo_scene.bake_all(scene)}
    measure("stock nodes OSL")
    scene.cycles.shading_system = False
    measure("stock nodes SVM")
    scene.cycles.shading_system = True
    bakes["osl"] = demo_scene.bake_all(scene, shader="OSL")
    measure("OSL variant")
    failed = [b for group in bakes.values() for b in group if "error" in b]

    lines = ["OSL comparison on the demo scene, %dx%d, Cycles CPU (SVM: Open Shading Language off; OSL: on); "
             "reference %d spp (SVM), others %d spp" % (width, height, reference_samples, samples),
             "  %-16s %-26s | %-26s | %8s" % ("", "error: ground_far  spheres_far  all",
                                                "noise: ground_far spheres_far  all", "render s")]
    for name, row in rows.items():
        lines.append("  %-16s %8.4f %8.4f %8.4f | %8.4f %8.4f %8.4f | %8.2f" % (
            name, *(row[r] for r in REGIONS), *(row["noise " + r] for r in REGIONS), row["seconds"]))
    lines.append("  error: pixel RMSE (linear RGB) vs the reference (seed 0); noise: RMSE between two seeds / sqrt 2; "
                 "render s: wall time with sync and shader compilation, mean of two")
    lines += ["  bake %s: %s" % (kind, b.get("summary") or "[%s] %s" % (b.get("error"), b.get("message")))
              for kind, group in bakes.items() for b in group]
    text = "\n".join(lines)
    report = {"width": width, "height": height, "reference_samples": reference_samples, "samples": samples,
              "reference_seconds": round(reference_seconds, 2), "rows": rows, "bakes": bakes,
              "regions": {k: int(v.sum()) for k, v in masks.items()}}
    with open(os.path.join(out, "report.json"), "w") as f:
        json.dump(report, f, indent=2)
    with open(os.path.join(out, "report.txt"), "w") as f:
        f.write(text + "\n")
    log(text)
    return 1 if failed else 0


def main():
    args = _arguments()
    demo_build.import_addon(args.library)
    return run(args.out, args.width, args.height, args.reference_samples, args.samples)


if __name__ == "__main__":
    demo_scene.run_as_script(main)
