"""Where Cycles' 16-spp error on the demo scene comes from: noise against the same material's
converged render, bias of that render against the reference, under a chosen world and lobe choice.
docs/rendering.md ("Open problems": image error in Cycles under a low sun) quotes its figures.

    blender -b --factory-startup --python-exit-code 1 --python studies/cycles_noise_study.py -- \
        --out DIR [--world NAME] [--sun-lamp] [--reference-samples 512] [--converged-samples 256] \
        [--variants widened,narrowed,narrowed-ggx] [--max-lobes N] [--width 128 --height 72] \
        [--library PATH]

The scene is demo_scene.py's, under Blender's studio world --world (its sun or brightest spot 4
degrees right of the view, as in the demo). --sun-lamp moves a compact sun out of the HDR into an
energy-matched Sun lamp (split_sun), which Cycles samples directly instead of through the world's
luminance map: it separates the renderer's sampling of a small bright source from the material.
For the naive normal maps and then for each lobe variant, the script renders 16 spp with three seeds
and --converged-samples once, and prints per region (far ground, far spheres): rmse16 (the issue's
figure, against the reference), noise (16 spp against the converged render), bias (converged against
the reference; it includes the reference's own noise), block (4x4 mean luminance error at 16 spp,
and of the converged render) and the converged render's mean luminance beside the reference's.
Variants, each a bake of every material: widened and narrowed (the bake's Cycles Lobes setting:
the widened lobes, or the ones narrowed at grazing views), either with -ggx (the lobes'
Multiscatter GGX set to GGX); and flat, no bake: the materials with their normal maps switched off
(Normal Map Strength 0), whose noise column is what a surface as glossy as the material costs
in noise without normals finer than a pixel; and flat-rR (R a roughness, e.g. flat-r0.4): the same
with every Principled BSDF's roughness set to R, the noise a lobe that wide costs. Every row also
prints its noise at the reference's brightness (noise × reference mean / mean: a material scaled to
look as bright as the reference is that much noisier or less noisy, exactly, since scaling a BSDF
scales every sample), the figure to hold against half of naive's rmse16.
"""
import argparse
import contextlib
import json
import math
import os
import sys

import bpy
import mathutils
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "examples"))  # the demo
import demo_scene  # noqa: E402
import demo_build  # noqa: E402
import demo_render  # noqa: E402
import image_error  # noqa: E402

SEEDS = (0, 2, 3)
# The variants (module docstring); all but widened-ggx and flat run by default.
VARIANTS = ("widened", "narrowed", "widened-ggx", "narrowed-ggx", "flat")
DEFAULT_VARIANTS = tuple(v for v in VARIANTS if v not in ("widened-ggx", "flat"))
FLAT_ROUGHNESS_PREFIX = "flat-r"   # flat-r0.4: the flat variant at roughness 0.4
REGIONS = ("ground_far", "spheres_far")
# A sun is the few pixels above SUN_THRESHOLD of the brightest (then the looser fallback); more
# than SUN_MAX_PIXELS there is no compact sun (an overcast sky, a window-lit studio) to split off.
SUN_THRESHOLDS = (0.02, 0.1)
SUN_MAX_PIXELS = 64


def flat_roughness(variant):
    """The roughness a flat-rR variant names, None for any other variant; ValueError if R is not a
    roughness in [0, 1]."""
    if not variant.startswith(FLAT_ROUGHNESS_PREFIX):
        return None
    roughness = float(variant[len(FLAT_ROUGHNESS_PREFIX):])
    if not 0.0 <= roughness <= 1.0:
        raise ValueError("roughness %g is outside [0, 1]" % roughness)
    return roughness


def split_sun(scene):
    """Moves the world's compact sun into a Sun lamp: the sun's pixels take the median of the ring
    around them, and the lamp gets the irradiance they held above it (∑ (L - fill) dω, per
    channel), their luminance-weighted mean direction (through the world's Mapping rotation) and
    the angular diameter of a disc of their solid angle. Returns a description, or None."""
    tree = scene.world.node_tree
    env = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeTexEnvironment")
    mapping = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeMapping")
    w, h = env.image.size
    px = np.empty(w * h * 4, np.float32)
    env.image.pixels.foreach_get(px)
    px = px.reshape(h, w, 4).copy()
    lum = image_error.luminance(px)
    for threshold in SUN_THRESHOLDS:
        sun = lum > threshold * lum.max()
        if sun.sum() <= SUN_MAX_PIXELS:
            break
    else:
        return None
    # Equirectangular texel solid angle; Blender's rows start at the bottom (the nadir).
    polar = (np.arange(h) + 0.5) / h * math.pi
    solid_angle = np.repeat(((2 * math.pi / w) * (math.pi / h) * np.sin(polar))[:, None], w, axis=1)
    ys, xs = np.nonzero(sun)
    ring = (slice(max(ys.min() - 4, 0), ys.max() + 5), slice(max(xs.min() - 4, 0), xs.max() + 5))
    fill = np.median(px[ring][..., :3][~sun[ring]], axis=0)
    irradiance = np.maximum(((px[..., :3] - fill) * (solid_angle * sun)[..., None]).sum(axis=(0, 1)), 0.0)
    weights = (lum * solid_angle)[ys, xs]
    u = float(((xs + 0.5) / w * weights).sum() / weights.sum())
    v = float(((ys + 0.5) / h * weights).sum() / weights.sum())
    elevation = (v - 0.5) * math.pi
    azimuth = (0.5 - u) * 2.0 * math.pi - mapping.inputs["Rotation"].default_value[2]  # undo the world's turn
    direction = mathutils.Vector((math.cos(elevation) * math.cos(azimuth), math.cos(elevation) * math.sin(azimuth),
                                  math.sin(elevation)))
    px[sun, :3] = fill
    image = bpy.data.images.new(env.image.name + " without sun", w, h, alpha=False, float_buffer=True)
    from ndfbake.shading import blender_compat
    image.colorspace_settings.name = blender_compat.linear_color_space()
    image.pixels.foreach_set(px.ravel())
    env.image = image
    lamp = bpy.data.lights.new("Sun", "SUN")
    strength = float(image_error.luminance(irradiance))
    lamp.energy = strength
    lamp.color = tuple(float(c) for c in irradiance / max(strength, 1e-12))
    lamp.angle = 2.0 * math.acos(1.0 - float((solid_angle * sun).sum()) / (2.0 * math.pi))
    obj = bpy.data.objects.new("Sun", lamp)
    scene.collection.objects.link(obj)
    obj.rotation_euler = direction.to_track_quat("Z", "Y").to_euler()  # the lamp shines down its -Z
    return {"pixels": int(sun.sum()), "strength": strength, "angle_degrees": math.degrees(lamp.angle),
            "elevation_degrees": math.degrees(elevation)}


def use_variant(scene, variant, max_lobes):
    """Re-bakes the scene's materials with up to `max_lobes` lobes so that Cycles draws them as
    `variant` says."""
    from ndfbake.shading import node_builders, nodes
    lobes = nodes.NARROWED if variant.startswith("narrowed") else nodes.WIDENED
    for outcome in demo_scene.bake_all(scene, max_lobes=max_lobes, cycles_lobes=lobes):
        if "error" in outcome:
            raise RuntimeError("bake of %s failed: %s" % (outcome["material"], outcome["message"]))
    if variant.endswith("-ggx"):
        for group in bpy.data.node_groups:
            if group.get(node_builders.TAG) is None:  # not the add-on's (node_builders._new_group tags its groups)
                continue
            for node in group.nodes:
                if node.bl_idname == "ShaderNodeBsdfPrincipled" and node.distribution == "MULTI_GGX":
                    node.distribution = "GGX"


@contextlib.contextmanager
def flattened(material_names, roughness=None):
    """The materials with their Normal Map nodes at Strength 0 (the surface's own normal), and with
    `roughness` every Principled BSDF's roughness set to it, restored after: the 16-spp noise that
    the material's own gloss (or a lobe `roughness` wide) costs without normals finer than a pixel."""
    trees = [bpy.data.materials[name].node_tree for name in material_names]
    changed = [(node.inputs["Strength"], 0.0) for tree in trees for node in tree.nodes
               if node.bl_idname == "ShaderNodeNormalMap"]
    if roughness is not None:
        changed += [(node.inputs["Roughness"], roughness) for tree in trees for node in tree.nodes
                    if node.bl_idname == "ShaderNodeBsdfPrincipled"]
    saved = [(socket, socket.default_value) for socket, _ in changed]
    for socket, value in changed:
        socket.default_value = value
    try:
        yield
    finally:
        for socket, value in saved:
            socket.default_value = value


def study(out, world, sun_lamp, reference_samples, converged_samples, variants, width, height, max_lobes):
    info = demo_build.build_scene(out, width, height, world=world)
    scene = bpy.context.scene
    lamp = split_sun(scene) if sun_lamp else None
    if sun_lamp:
        print("sun lamp: %s" % (lamp or "none (no compact sun in %s)" % world), flush=True)
    masks = demo_render.region_masks(scene, info["ground"], info["far_spheres"])
    path = os.path.join(out, "render.exr")
    reference = demo_render.render(scene, "CYCLES", path, reference_samples, seed=1)
    rows = []

    regions = {region: masks[region] for region in REGIONS}

    def measure(name):
        fast = {"seed %d" % s: demo_render.render(scene, "CYCLES", path, 16, seed=s) for s in SEEDS}
        converged = demo_render.render(scene, "CYCLES", path, converged_samples, seed=7)
        to_reference = image_error.compare(dict(fast, converged=converged), reference, regions)
        to_converged = image_error.compare(fast, converged, regions)
        for region in REGIONS:
            errors, noise = to_reference[region], to_converged[region]
            row = {"variant": name, "region": region,
                   "rmse16": float(np.mean([errors[f]["rmse"] for f in fast])),
                   "noise": float(np.mean([noise[f]["rmse"] for f in fast])),
                   "bias": errors["converged"]["rmse"],
                   "block": float(np.mean([errors[f]["block"] for f in fast])),
                   "block_converged": errors["converged"]["block"],
                   "mean": errors["converged"]["mean"],
                   "reference_mean": errors["reference"]["mean"]}
            row["noise_at_reference_brightness"] = row["noise"] * row["reference_mean"] / max(row["mean"], 1e-12)
            rows.append(row)
            print("%-14s %-12s rmse16 %.4f noise %.4f (at the reference's brightness %.4f) bias %.4f block %.4f "
                  "(converged %.4f) mean %.4f (reference %.4f)"
                  % (name, region, row["rmse16"], row["noise"], row["noise_at_reference_brightness"], row["bias"],
                     row["block"], row["block_converged"], row["mean"], row["reference_mean"]), flush=True)

    measure("naive")
    for variant in variants:  # the flat ones first: a bake replaces the materials' nodes
        if variant == "flat" or flat_roughness(variant) is not None:
            with flattened(info["materials"], flat_roughness(variant)):
                measure(variant)
    for variant in variants:
        if variant != "flat" and flat_roughness(variant) is None:
            use_variant(scene, variant, max_lobes)
            measure(variant)
    for row in rows:
        if row["variant"] != "naive":
            naive = next(r for r in rows if r["variant"] == "naive" and r["region"] == row["region"])
            row["ratio_rmse16"] = image_error.ratio(row["rmse16"], naive["rmse16"])
            print("%-14s %-12s rmse16 ratio to naive %.3f" % (row["variant"], row["region"], row["ratio_rmse16"]))
    with open(os.path.join(out, "study.json"), "w") as f:
        json.dump({"world": world, "sun_lamp": lamp, "reference_samples": reference_samples, "rows": rows}, f, indent=1)


def main():
    parser = argparse.ArgumentParser(prog="cycles_noise_study.py")
    parser.add_argument("--out", required=True)
    demo_build.add_world_option(parser)
    parser.add_argument("--sun-lamp", action="store_true")
    parser.add_argument("--reference-samples", type=int, default=512)
    parser.add_argument("--converged-samples", type=int, default=256)
    parser.add_argument("--variants", default=",".join(DEFAULT_VARIANTS))
    parser.add_argument("--width", type=int, default=128)
    parser.add_argument("--height", type=int, default=72)
    parser.add_argument("--max-lobes", type=int, choices=range(1, 9), default=demo_scene.MAX_LOBES,
                        help="the bakes' maximum lobes (default: the demo's)")
    parser.add_argument("--library")
    args = demo_build.script_arguments(parser)
    variants = [v for v in args.variants.split(",") if v]
    try:
        unknown = [v for v in variants if v not in VARIANTS and flat_roughness(v) is None]
    except ValueError as error:
        parser.error("variant flat-rR: %s" % error)
    if unknown:
        parser.error("unknown variants: %s" % ", ".join(unknown))
    os.makedirs(args.out, exist_ok=True)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    demo_build.import_addon(args.library)
    study(os.path.abspath(args.out), args.world, args.sun_lamp, args.reference_samples, args.converged_samples,
          variants, args.width, args.height, args.max_lobes)


if __name__ == "__main__":
    main()
