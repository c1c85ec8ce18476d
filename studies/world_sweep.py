"""The demo scene under each of Blender's studio worlds, in EEVEE and Cycles: how bright the far
ground converges against its reference, and ndfbake's image error against naive's, per world.

    python studies/world_sweep.py -- --out DIR [--worlds city,forest,...] [--width 128 --height 72]
            [--samples 16] [--eevee-samples 64] [--converged-samples 128] [--reference-band-samples 4096]
            [--variants "cycles=4,eevee=4;cycles=0,eevee=1"]
    blender -b --factory-startup --python studies/world_sweep.py -- --out DIR ...

For each world: builds examples/demo_scene.py's scene, renders its references and the naive map
once (demo_render.render_plain), bakes every material with the defaults an artist gets (demo_scene's
8 lobes) and renders ndfbake; Cycles' far ground is also rendered at --converged-samples for its
converged brightness (its 16-spp image error counts noise too). The Cycles reference is rendered
at 256 spp and its far regions' band again at --reference-band-samples, which replaces it there
(demo_render.REFERENCE_BAND_SAMPLES says why). Writes DIR/<world>/ (renders,
report.json) and DIR/world_sweep.json, and prints the table docs/rendering.md ("Grazing views")
shows: per world and engine, the far ground's mean luminance over the reference's, and the ratios
ndfbake / naive of the block error (EEVEE) and of the 16-spp pixel RMSE (Cycles) on the far ground
and the far spheres. The issue-24 goals: brightness within 10%, ratios at most 0.5, under at least
6 of the 8 worlds.

EEVEE is measured twice: against its own supersampled render of the point-sampled maps, and
against the Cycles reference (which is EEVEE Next's figure: docs/rendering.md, "EEVEE Next's
reference"); brightness is the far ground's mean luminance over that reference's.

--variants measures other grazing narrowings than the add-on's (nodes.default_grazing_narrowing) on the
same references, one bake each: `cycles=C` narrows Cycles' lobes with constant C (0: Cycles Lobes
Widened, no narrowing), `eevee=C` EEVEE's; this is how the constants were chosen (docs/rendering.md,
"Grazing views").
"""
import argparse
import json
import os
import sys
import time

import bpy

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "examples"))  # the demo
import demo_scene  # noqa: E402
import demo_build  # noqa: E402
import demo_render  # noqa: E402
import image_error  # noqa: E402

BRIGHTNESS_GOAL = 0.10      # the far ground's converged mean luminance within 10% of the reference's
RATIO_GOAL = 0.5            # ndfbake's error at most half of naive's
REGIONS = ("ground_far", "spheres_far")


def sweep_world(out, world, width, height, samples, eevee_samples, converged_samples, band_samples, variants,
                log=print):
    """One world: {variant: {engine: {"brightness": far-ground mean over the reference's,
    "naive_brightness", "ratio": {region: ndfbake / naive}}}}."""
    scene_info = demo_build.fresh_scene(out, width, height, world=world)
    scene = bpy.context.scene
    renders = os.path.join(out, "renders")
    masks = demo_render.region_masks(scene, scene_info["ground"], scene_info["far_spheres"])
    images, info = demo_render.render_plain(scene, renders, scene_info["materials"], samples=samples,
                                            eevee_samples=eevee_samples, log=log)
    if band_samples:
        demo_render.converge_reference_band(scene, renders, images, info, masks, REGIONS, band_samples, log)
    results = {}
    for name, narrowing in variants.items():
        results[name] = _measure_variant(scene, renders, masks, dict(images), narrowing, samples, eevee_samples,
                                         converged_samples, log)
    with open(os.path.join(out, "report.json"), "w") as f:
        json.dump({"world": world, "results": results, "renders": info}, f, indent=2)
    return results


def _measure_variant(scene, renders, masks, images, narrowing, samples, eevee_samples, converged_samples, log):
    """Bakes with the grazing constants `narrowing` ({"cycles": C, "eevee": C}; None: the add-on's),
    renders ndfbake and measures it against the plain renders in `images`."""
    from ndfbake.shading import nodes
    settings = {}
    if narrowing is not None:
        settings["grazing_narrowing"] = {nodes.EEVEE_BSDF: narrowing["eevee"],
                                         "BSDF": narrowing["cycles"] or nodes.CYCLES_GRAZING_NARROWING}
        settings["cycles_lobes"] = nodes.NARROWED if narrowing["cycles"] else nodes.WIDENED
    bakes = demo_scene.bake_all(scene, **settings)
    failed = [b for b in bakes if "summary" not in b]
    if failed:
        raise RuntimeError("bakes failed: %s" % failed)
    baked, _ = demo_render.render_baked(scene, renders, samples, eevee_samples, log)
    images.update(baked)
    converged = demo_render.render(scene, "CYCLES", os.path.join(renders, "cycles_ndfbake_converged.exr"),
                                   converged_samples, seed=2)
    errors = demo_render.measure(images, masks)
    far = masks["ground_far"]
    result = {}
    for figure, table in errors.items():  # demo_render.FIGURES
        reference = table["ground_far"]["reference"]["mean"]
        mean = (image_error.luminance(converged)[far].mean() if figure == "cycles"
                else table["ground_far"]["ndfbake"]["mean"])
        result[figure] = {
            "brightness": float(mean / reference),
            "naive_brightness": float(table["ground_far"]["naive"]["mean"] / reference),
            "ratio": {region: table[region]["ratio_rmse" if figure == "cycles" else "ratio_block"]
                      for region in REGIONS}}
    return result
def format_table(results):
    """results: {world: {engine: ...}} of one variant."""
    lines = ["| world | engine | far ground brightness (ndfbake / naive, × reference) | ratio far ground |"
             " ratio far spheres | goals met |", "|---|---|---:|---:|---:|---|"]
    names = {"eevee": "EEVEE vs its own reference", "cycles": "Cycles", "eevee_cycles": "EEVEE vs Cycles' reference"}
    met = dict.fromkeys(names, 0)
    for world, by_engine in results.items():
        for engine, r in by_engine.items():
            bright_ok = abs(r["brightness"] - 1.0) <= BRIGHTNESS_GOAL
            ratios_ok = all(v <= RATIO_GOAL for v in r["ratio"].values())
            met[engine] += bright_ok and ratios_ok
            lines.append("| %s | %s | %.2f / %.2f | %.2f | %.2f | %s |" % (
                world, names[engine], r["brightness"], r["naive_brightness"],
                r["ratio"]["ground_far"], r["ratio"]["spheres_far"],
                "both" if bright_ok and ratios_ok else "brightness" if bright_ok else "ratios" if ratios_ok
                else "neither"))
    lines.append("")
    lines.append("worlds meeting both goals: " + ", ".join("%s %d of %d" % (names[k], n, len(results))
                                                            for k, n in met.items()))
    return "\n".join(lines)


def main():
    parser = argparse.ArgumentParser(prog="studies/world_sweep.py --")
    parser.add_argument("--out", required=True)
    parser.add_argument("--worlds", default=",".join(demo_build.world_names()))
    parser.add_argument("--width", type=int, default=128)
    parser.add_argument("--height", type=int, default=72)
    parser.add_argument("--samples", type=int, default=16, help="Cycles samples of the naive and ndfbake renders")
    parser.add_argument("--eevee-samples", type=int, default=64)
    parser.add_argument("--converged-samples", type=int, default=128,
                        help="Cycles samples of the render whose far ground gives the converged brightness")
    parser.add_argument("--reference-band-samples", type=int, default=demo_render.REFERENCE_BAND_SAMPLES,
                        help="Cycles samples of the reference's far regions (0: leave them at 256)")
    parser.add_argument("--variants", default="",
                        help="';'-separated cycles=C,eevee=C grazing constants to measure besides the add-on's")
    args = demo_build.script_arguments(parser)
    variants = {"add-on": None}
    for text in filter(None, args.variants.split(";")):
        variants[text] = {key: float(value) for key, value in (item.split("=") for item in text.split(","))}
    out = os.path.abspath(args.out)
    started = time.perf_counter()
    results = {}
    for world in args.worlds.split(","):
        start = time.perf_counter()
        results[world] = sweep_world(os.path.join(out, world), world, args.width, args.height, args.samples,
                                     args.eevee_samples, args.converged_samples, args.reference_band_samples,
                                     variants)
        print("world_sweep: %s in %.0f s: %s" % (world, time.perf_counter() - start, results[world]), flush=True)
    table = "\n\n".join("%s:\n%s" % (name, format_table({w: r[name] for w, r in results.items()}))
                          for name in variants)
    with open(os.path.join(out, "world_sweep.json"), "w") as f:
        json.dump({"blender": bpy.app.version_string, "width": args.width, "height": args.height,
                   "samples": args.samples, "eevee_samples": args.eevee_samples,
                   "converged_samples": args.converged_samples,
                   "reference_band_samples": args.reference_band_samples, "results": results}, f, indent=2)
    print("world_sweep.py: Blender %s, %dx%d, %.0f s\n%s" % (bpy.app.version_string, args.width, args.height,
                                                             time.perf_counter() - started, table), flush=True)


if __name__ == "__main__":
    demo_scene.run_as_script(main)
