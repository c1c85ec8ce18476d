"""EEVEE Next's scene-linear render depends on the view's exposure: the demo scene's far ground and
far spheres (mean luminance of the EXR, which no view setting should change), naive and baked,
at several exposures, with the world's sun extracted (Blender's default) and not
(docs/rendering.md, "Open problems"). The cause is EEVEE Next's film: it weights each sample of the
Combined pass by 1 / (4 + luma * s) with s = exposure squared (Blender's pow2f), so 0 averages and
any other exposure, above or below, darkens sparkly pixels (studies/eevee_far_spheres.py shows
the symmetry about 0).

    python studies/eevee_exposure_study.py -- --out DIR [--world interior] [--samples 64]
    blender -b --factory-startup --python studies/eevee_exposure_study.py -- --out DIR ...

Every render is of the same scene (examples/demo_build.py at 128x72) with the same samples; only
`view_settings.exposure` and, in the last rows, `World.sun_threshold` change. Cycles' reference
(512 spp) is printed for scale.
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

EXPOSURES = (-4.0, demo_build.EXPOSURE, 0.0, 2.0)
CYCLES_SAMPLES = 512


def main():
    parser = argparse.ArgumentParser(prog="studies/eevee_exposure_study.py --")
    parser.add_argument("--out", required=True)
    demo_build.add_world_option(parser)
    parser.add_argument("--samples", type=int, default=64)
    args = demo_build.script_arguments(parser)
    out = os.path.abspath(args.out)
    info, scene, masks = demo_render.study_scene(out, args.world)
    path = os.path.join(out, "render.exr")

    def means(engine, samples):
        luminance = image_error.luminance(demo_render.render(scene, engine, path, samples, seed=1))
        return luminance[masks["ground_far"]].mean(), luminance[masks["spheres_far"]].mean()

    reference = means("CYCLES", CYCLES_SAMPLES)
    rows = []

    def sweep(label):
        for sun_threshold in (scene.world.sun_threshold, 0.0):
            previous, scene.world.sun_threshold = scene.world.sun_threshold, sun_threshold
            for exposure in EXPOSURES:
                scene.view_settings.exposure = exposure
                rows.append((label, sun_threshold, exposure) + means(demo_build.eevee_engine(), args.samples))
                print("  rendered %s, sun threshold %g, exposure %g" % rows[-1][:3], flush=True)
            scene.world.sun_threshold = previous
        scene.view_settings.exposure = demo_build.EXPOSURE

    sweep("naive")
    if any("summary" not in b for b in demo_scene.bake_all(scene)):
        raise RuntimeError("bakes failed")
    sweep("ndfbake")
    print("%s, 128x72, Blender %s, EEVEE %d samples: mean luminance far ground / far spheres"
          % (args.world, bpy.app.version_string, args.samples))
    print("  Cycles reference (%d spp): %.3f / %.3f" % ((CYCLES_SAMPLES,) + reference))
    print("  %-8s %13s %9s %11s %12s" % ("render", "sun threshold", "exposure", "ground_far", "spheres_far"))
    for label, sun_threshold, exposure, ground, spheres in rows:
        print("  %-8s %13g %9g %11.3f %12.3f" % (label, sun_threshold, exposure, ground, spheres))


if __name__ == "__main__":
    main()
