"""EEVEE Next's error on the demo scene's far regions against the number of lobes baked: fewer
lobes render the far spheres closer to the Cycles reference (EEVEE Next picks one of several
closures of a kind a sample, which its film's luma weighting darkens) and the far ground much
farther from it (docs/rendering.md, "EEVEE Next's reference").

    python studies/eevee_lobe_count.py -- --out DIR [--lobes 1 2 8] [--world interior]
    blender -b --factory-startup --python studies/eevee_lobe_count.py -- --out DIR ...

The scene is examples/demo_build.py's at 128x72; the reference is Cycles at 512 spp, EEVEE renders
64 samples; the figure is the block error of tests/blender/test_addon_image_error.py over naive's.
"""
import argparse
import os
import sys

import bpy

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "examples"))  # the demo
import demo_build  # noqa: E402
import demo_render  # noqa: E402
import demo_scene  # noqa: E402
import image_error  # noqa: E402

REFERENCE_SAMPLES = 512
EEVEE_SAMPLES = 64
REGIONS = ("ground_far", "spheres_far")


def main():
    parser = argparse.ArgumentParser(prog="studies/eevee_lobe_count.py --")
    parser.add_argument("--out", required=True)
    parser.add_argument("--lobes", type=int, nargs="+", default=[1, 2, 8])
    demo_build.add_world_option(parser)
    args = demo_build.script_arguments(parser)
    out = os.path.abspath(args.out)
    info, scene, masks = demo_render.study_scene(out, args.world)
    engine = demo_build.eevee_engine()
    reference = demo_render.render(scene, "CYCLES", os.path.join(out, "reference.exr"), REFERENCE_SAMPLES, seed=1)
    images = {"naive": demo_render.render(scene, engine, os.path.join(out, "naive.exr"), EEVEE_SAMPLES)}
    for lobes in args.lobes:
        if any("summary" not in b for b in demo_scene.bake_all(scene, max_lobes=lobes)):
            raise RuntimeError("a bake with %d lobes failed" % lobes)
        name = "%d lobes" % lobes
        images[name] = demo_render.render(scene, engine, os.path.join(out, "lobes%d.exr" % lobes), EEVEE_SAMPLES)
    table = image_error.compare(images, reference, {region: masks[region] for region in REGIONS})
    print("%s, 128x72, Blender %s, EEVEE %d samples against Cycles %d spp: mean luminance, block error, "
          "block error over naive's" % (args.world, bpy.app.version_string, EEVEE_SAMPLES, REFERENCE_SAMPLES))
    for region in REGIONS:
        entry = table[region]
        print("  %s (reference %.3f)" % (region, entry["reference"]["mean"]))
        for name in images:
            print("    %-9s %.3f  %.4f  %.3f" % (name, entry[name]["mean"], entry[name]["block"],
                                                image_error.ratio(entry[name]["block"], entry["naive"]["block"])))


if __name__ == "__main__":
    main()
