"""Is EEVEE's supersampled render of the fine normals a reference? The demo scene's far ground and far
spheres, their mean luminance in each render that bears on it (docs/rendering.md, "EEVEE Next's
reference").

    python studies/eevee_reference_study.py -- --out DIR [--world interior] [--width 128 --height 72]
    blender -b --factory-startup --python studies/eevee_reference_study.py -- --out DIR ...

Renders, all of the demo scene as examples/demo_scene.py builds it:
- Cycles, 512 spp: the bumpy maps (the reference of ../shared/DESIGN.md) and the maps flattened
  (Normal Map Strength 0): how much the bumps change what the regions reflect;
- EEVEE, the maps point-sampled ('Closest') at 8x8 the resolution, box-downsampled (the EEVEE
  reference of demo_render.render_plain), and at 1x with 256 TAA samples;
- EEVEE, the flattened maps at 1x and at 8x8 (what EEVEE does with a smooth surface at this size);
- EEVEE naive (64 TAA samples) and ndfbake (the add-on's defaults, 8 lobes); naive again with the
  film's filter_size at 0.5 instead of 1.5, and ndfbake with 1 lobe, each beside Cycles' render
  of the same bake;
- EEVEE Next's film applied to the truth: Cycles at 8x8 the resolution (box pixel filter, 32 spp
  a subpixel) reconstructed at 1x as EEVEE Next's film reconstructs its samples (eevee_next_film):
  with its Gaussian pixel filter alone, and with its luma weighting too.
Prints a table of the regions' mean luminance in each, and writes DIR/eevee_reference_study.json.
"""
import argparse
import json
import os
import sys

import bpy
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "examples"))  # the demo
import demo_build  # noqa: E402
import demo_render  # noqa: E402
import demo_scene  # noqa: E402
import image_error  # noqa: E402

SUPERSAMPLING = 8
EEVEE_SAMPLES = 64
CYCLES_SAMPLES = 512
SUBPIXEL_SAMPLES = 32  # Cycles samples a subpixel of the 8x8 render that eevee_next_film reconstructs
# EEVEE Next's film (Blender's eevee_film_lib / eevee_defines): a sample at distance d from a pixel's
# centre counts with the weight exp(-d^2 / (2 (SIGMA_PER_RADIUS r)^2)) within the radius r =
# filter_size ("a Gaussian fitted to Blackman-Harris"), times 1 / (LUMA_BIAS + luma) (Karis 2014's
# flicker reduction, with a larger bias), luma the Y of YCoCg: (R + 2G + B) / 4 at exposure 0.
SIGMA_PER_RADIUS = 0.284
LUMA_BIAS = 4.0


def eevee_next_film(supersampled, factor, filter_size, luma_weighted=True):
    """Pixels (H, W, 3) reconstructed from `supersampled` (H·factor, W·factor, 3; each subpixel
    taken as a sample at its centre) with EEVEE Next's pixel filter and, if `luma_weighted`, its
    luma weighting."""
    height, width = supersampled.shape[0] // factor, supersampled.shape[1] // factor
    sigma = SIGMA_PER_RADIUS * filter_size
    luma = (supersampled[..., 0] + 2.0 * supersampled[..., 1] + supersampled[..., 2]) / 4.0
    sample_weight = 1.0 / (LUMA_BIAS + luma) if luma_weighted else np.ones_like(luma)
    total, weights = np.zeros((height, width, 3)), np.zeros((height, width))
    reach = int(np.ceil(filter_size))
    for sy in range(factor):
        for sx in range(factor):
            oy, ox = (sy + 0.5) / factor - 0.5, (sx + 0.5) / factor - 0.5  # from its own pixel's centre
            samples, weight = supersampled[sy::factor, sx::factor], sample_weight[sy::factor, sx::factor]
            for dy in range(-reach, reach + 1):
                for dx in range(-reach, reach + 1):
                    d2 = (oy - dy) ** 2 + (ox - dx) ** 2  # to the centre of the pixel (dy, dx) away
                    if d2 > filter_size * filter_size:
                        continue
                    w = np.exp(-0.5 * d2 / (sigma * sigma)) * weight
                    src = (slice(max(0, -dy), height - max(0, dy)), slice(max(0, -dx), width - max(0, dx)))
                    dst = (slice(max(0, dy), height - max(0, -dy)), slice(max(0, dx), width - max(0, -dx)))
                    total[dst] += w[src][..., None] * samples[src]
                    weights[dst] += w[src]
    return (total / weights[..., None]).astype(np.float32)


def set_normal_strength(material_names, strength):
    for name in material_names:
        for node in bpy.data.materials[name].node_tree.nodes:
            if node.bl_idname == "ShaderNodeNormalMap":
                node.inputs["Strength"].default_value = strength


def main():
    parser = argparse.ArgumentParser(prog="studies/eevee_reference_study.py --")
    parser.add_argument("--out", required=True)
    demo_build.add_world_option(parser)
    parser.add_argument("--width", type=int, default=128)
    parser.add_argument("--height", type=int, default=72)
    args = demo_build.script_arguments(parser)
    out = os.path.abspath(args.out)
    info = demo_build.fresh_scene(out, args.width, args.height, world=args.world)
    scene, eevee, materials = bpy.context.scene, demo_build.eevee_engine(), info["materials"]
    masks = demo_render.region_masks(scene, info["ground"], info["far_spheres"])
    renders = os.path.join(out, "renders")
    os.makedirs(renders, exist_ok=True)
    images = {}

    def render(name, engine, samples, factor=1):
        pixels = demo_render.render(scene, engine, os.path.join(renders, name + ".exr"), samples,
                                    percentage=100 * factor, seed=1)
        images[name] = image_error.box_downsample(pixels, factor) if factor > 1 else pixels
        print("  rendered %s" % name, flush=True)

    render("cycles bumpy (reference)", "CYCLES", CYCLES_SAMPLES)
    render("eevee naive", eevee, EEVEE_SAMPLES)
    scene.render.filter_size, filter_size = 0.5, scene.render.filter_size
    render("eevee naive, filter_size 0.5", eevee, EEVEE_SAMPLES)
    scene.render.filter_size = filter_size
    pixel_filter = scene.cycles.pixel_filter_type, scene.cycles.filter_width
    scene.cycles.pixel_filter_type, scene.cycles.filter_width = "BOX", 1.0
    truth = demo_render.render(scene, "CYCLES", os.path.join(renders, "cycles_8x8_box.exr"), SUBPIXEL_SAMPLES,
                               percentage=100 * SUPERSAMPLING, seed=1)
    scene.cycles.pixel_filter_type, scene.cycles.filter_width = pixel_filter
    images["cycles 8x8, EEVEE's filter"] = eevee_next_film(truth, SUPERSAMPLING, filter_size, luma_weighted=False)
    images["cycles 8x8, EEVEE's film"] = eevee_next_film(truth, SUPERSAMPLING, filter_size)
    previous = demo_render.set_normal_interpolation(materials, "Closest")
    render("eevee point-sampled 8x8", eevee, 16, SUPERSAMPLING)
    render("eevee point-sampled 1x", eevee, 256)  # 256 point samples a pixel (8x8 at 16 samples: 1,024)
    demo_render.set_normal_interpolation(materials, previous)
    set_normal_strength(materials, 0.0)
    render("cycles flat", "CYCLES", CYCLES_SAMPLES)
    render("eevee flat 8x8", eevee, 16, SUPERSAMPLING)
    render("eevee flat 1x", eevee, EEVEE_SAMPLES)
    set_normal_strength(materials, 1.0)
    bakes = demo_scene.bake_all(scene)
    if any("summary" not in b for b in bakes):
        raise RuntimeError("bakes failed: %s" % bakes)
    render("eevee ndfbake", eevee, EEVEE_SAMPLES)
    render("cycles ndfbake", "CYCLES", CYCLES_SAMPLES)
    if any("summary" not in b for b in demo_scene.bake_all(scene, max_lobes=1)):
        raise RuntimeError("1-lobe bakes failed")
    render("eevee ndfbake, 1 lobe", eevee, EEVEE_SAMPLES)
    render("cycles ndfbake, 1 lobe", "CYCLES", CYCLES_SAMPLES)

    regions = ("ground_far", "spheres_far")
    table = {name: {r: image_error.mean_luminance(pixels, masks[r]) for r in regions} for name, pixels in images.items()}
    print("%s, %dx%d: mean luminance" % (args.world, args.width, args.height))
    print("  %-32s %10s %12s" % ("render", *regions))
    for name, means in table.items():
        print("  %-32s %10.3f %12.3f" % (name, means["ground_far"], means["spheres_far"]))
    with open(os.path.join(out, "eevee_reference_study.json"), "w") as f:
        json.dump({"blender": bpy.app.version_string, "world": args.world, "mean_luminance": table}, f, indent=2)


if __name__ == "__main__":
    main()
