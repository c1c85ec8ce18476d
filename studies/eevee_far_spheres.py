"""Why EEVEE Next renders the demo scene's far spheres too dark (docs/rendering.md, "EEVEE Next's
reference"): what the view exposure does to them, how EEVEE Next renders plain rough metal spheres
against Cycles, two changes to the baked lobes that a shading cause would answer, and where on the
spheres the light is lost.

    python studies/eevee_far_spheres.py -- --out DIR [--world interior] [--extra-alpha 0.08 0.16 0.3]
    blender -b --factory-startup --python studies/eevee_far_spheres.py -- --out DIR ...

First, naive in EEVEE Next at view exposures 0, +0.5, -0.5 and the scene's: its film weights each
sample by 1 / (4 + luma * exposure_scale) with exposure_scale = exposure squared (Blender's pow2f),
so the far spheres depend on |exposure| and are unweighted at 0. Then, at exposure 0, the far
spheres with their normal maps switched off (Normal Map Strength 0) and plain Principled metal of
roughness 0.2 to 0.8 (Multiscatter GGX, as the lobes draw), EEVEE Next against Cycles at 128 spp.

Variants, each a change to the baked groups of the far spheres' materials (and, for the bent
normals, of every baked material), rendered in EEVEE Next and in Cycles at 16 spp:
- "alpha+X": the lobes widened as a specular anti-aliasing for the spheres' curvature would widen
  them (at 128x72 a pixel spans about 0.13 rad of a far sphere's normals): the group's Roughness
  input r set so that r^4 = r0^4 + X^2, i.e. GGX alpha^2 grows by X^2 before the lobes widen it;
- "bent": each lobe normal N bent, where its mirror reflection R of the view I falls below the
  shading normal's horizon (R.Ng < t, t = min(0.9 I.Ng, 0.01)), to the half vector of I and the
  direction of R lifted to R.Ng = t: what Cycles does to every glossy closure's normal and EEVEE
  Next does not.
Then the far spheres' mean luminance ring by ring from the silhouette inward (the mask eroded one
pixel at a time), naive, baked and reference.

The scene is examples/demo_build.py's at 128x72; the reference is Cycles at 512 spp, EEVEE renders
64 samples; errors as in tests/blender/test_addon_image_error.py.
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
CYCLES_SAMPLES = 16
REGIONS = ("ground_far", "spheres_far")
EXPOSURES = (0.0, 0.5, -0.5, demo_build.EXPOSURE)
ROUGHNESS = (0.2, 0.4, 0.6, 0.8)
CYCLES_CONVERGED_SAMPLES = 128


def baked_groups(materials):
    """The ndfbake group node of each material (the node whose group has a Roughness input)."""
    return [node for material in materials for node in material.node_tree.nodes
            if node.type == "GROUP" and node.node_tree.name.startswith("NDFB") and "Roughness" in node.inputs]


def bend_lobe_normals(group_tree):
    """Feeds every lobe BSDF's Normal through the bending described in the module docstring."""
    from ndfbake.shading.node_builders import _math, _vmath
    tree = group_tree
    bent = 0
    for bsdf in list(tree.nodes):
        if bsdf.type != "BSDF_PRINCIPLED" or bsdf.name.startswith("Base") or not bsdf.inputs["Normal"].is_linked:
            continue
        normal = bsdf.inputs["Normal"].links[0].from_socket
        geometry = tree.nodes.new("ShaderNodeNewGeometry")
        view, shading = geometry.outputs["Incoming"], geometry.outputs["Normal"]
        mirror = _vmath(tree, "SUBTRACT", _vmath(tree, "SCALE", normal, scale=_math(
            tree, "MULTIPLY", _vmath(tree, "DOT_PRODUCT", normal, view, output=1), 2.0)), view)
        height = _vmath(tree, "DOT_PRODUCT", mirror, shading, output=1)
        floor = _math(tree, "MINIMUM", _math(tree, "MULTIPLY", _vmath(tree, "DOT_PRODUCT", view, shading, output=1),
                                             0.9), 0.01)
        across = _vmath(tree, "NORMALIZE", _vmath(tree, "SUBTRACT", mirror,
                                                  _vmath(tree, "SCALE", shading, scale=height)))
        lifted = _vmath(tree, "ADD", _vmath(tree, "SCALE", shading, scale=floor), _vmath(
            tree, "SCALE", across, scale=_math(tree, "SQRT", _math(tree, "SUBTRACT", 1.0,
                                                                   _math(tree, "MULTIPLY", floor, floor)))))
        half = _vmath(tree, "NORMALIZE", _vmath(tree, "ADD", view, lifted))
        below = _math(tree, "LESS_THAN", height, floor)
        tree.links.new(_vmath(tree, "NORMALIZE", _vmath(tree, "ADD", normal, _vmath(
            tree, "SCALE", _vmath(tree, "SUBTRACT", half, normal), scale=below))), bsdf.inputs["Normal"])
        bent += 1
    return bent


def exposure_dependence(scene, out, engine, mask):
    """Naive far spheres' mean luminance at each of EXPOSURES; leaves the scene's exposure as it was."""
    kept = scene.view_settings.exposure
    try:
        for exposure in EXPOSURES:
            scene.view_settings.exposure = exposure
            image = demo_render.render(scene, engine, os.path.join(out, "exposure%+g.exr" % exposure), EEVEE_SAMPLES)
            yield exposure, image_error.mean_luminance(image, mask)
    finally:
        scene.view_settings.exposure = kept


def plain_rough_metal(scene, out, engine, materials, mask):
    """(roughness, EEVEE Next, Cycles) mean luminance of the far spheres drawn as plain metal of
    each of ROUGHNESS, normal maps off, at exposure 0; restores the materials and the exposure."""
    kept = scene.view_settings.exposure
    principled = [next(n for n in m.node_tree.nodes if n.type == "BSDF_PRINCIPLED") for m in materials]
    normal_maps = [n for m in materials for n in m.node_tree.nodes if n.type == "NORMAL_MAP"]
    saved = ([(p.distribution, p.inputs["Roughness"].default_value) for p in principled],
             [n.inputs["Strength"].default_value for n in normal_maps])
    try:
        scene.view_settings.exposure = 0.0
        for node in normal_maps:
            node.inputs["Strength"].default_value = 0.0
        for roughness in ROUGHNESS:
            for node in principled:
                node.distribution = "MULTI_GGX"
                node.inputs["Roughness"].default_value = roughness
            path = os.path.join(out, "plain%g" % roughness)
            eevee = demo_render.render(scene, engine, path + ".exr", EEVEE_SAMPLES)
            cycles = demo_render.render(scene, "CYCLES", path + "-cycles.exr", CYCLES_CONVERGED_SAMPLES, seed=3)
            yield roughness, image_error.mean_luminance(eevee, mask), image_error.mean_luminance(cycles, mask)
    finally:
        scene.view_settings.exposure = kept
        for node, (distribution, roughness) in zip(principled, saved[0]):
            node.distribution = distribution
            node.inputs["Roughness"].default_value = roughness
        for node, strength in zip(normal_maps, saved[1]):
            node.inputs["Strength"].default_value = strength


def rings(mask):
    """The mask's pixels peeled one pixel at a time, silhouette first."""
    inner = mask.copy()
    while inner.any():
        rest = image_error.erode(inner, 1)
        yield inner & ~rest
        inner = rest


def main():
    parser = argparse.ArgumentParser(prog="studies/eevee_far_spheres.py --")
    parser.add_argument("--out", required=True)
    parser.add_argument("--extra-alpha", type=float, nargs="*", default=[0.08, 0.16, 0.3])
    demo_build.add_world_option(parser)
    args = demo_build.script_arguments(parser)
    out = os.path.abspath(args.out)
    info, scene, masks = demo_render.study_scene(out, args.world)
    engine = demo_build.eevee_engine()

    def render_both(name):
        eevee[name] = demo_render.render(scene, engine, os.path.join(out, name + ".exr"), EEVEE_SAMPLES)
        cycles[name] = demo_render.render(scene, "CYCLES", os.path.join(out, name + "-cycles.exr"), CYCLES_SAMPLES,
                                          seed=2)

    sphere_materials = {slot.material for name in info["far_spheres"] for slot in bpy.data.objects[name].material_slots}
    print("%s, 128x72, Blender %s" % (args.world, bpy.app.version_string))
    print("  naive far spheres in EEVEE Next against the view exposure: mean luminance")
    for exposure, mean in exposure_dependence(scene, out, engine, masks["spheres_far"]):
        print("    exposure %+.1f  %.3f" % (exposure, mean))
    print("  far spheres as plain metal, exposure 0: roughness, mean luminance EEVEE Next / Cycles %d spp, ratio"
          % CYCLES_CONVERGED_SAMPLES)
    for roughness, eevee_mean, cycles_mean in plain_rough_metal(scene, out, engine, sphere_materials,
                                                                masks["spheres_far"]):
        print("    %.1f  %.3f / %.3f  %.3f" % (roughness, eevee_mean, cycles_mean, eevee_mean / cycles_mean))

    reference = demo_render.render(scene, "CYCLES", os.path.join(out, "reference.exr"), REFERENCE_SAMPLES, seed=1)
    eevee, cycles = {}, {}
    render_both("naive")
    if any("summary" not in b for b in demo_scene.bake_all(scene)):
        raise RuntimeError("a bake failed")
    render_both("ndfbake")
    roughness = [(node.inputs["Roughness"], node.inputs["Roughness"].default_value)
                 for node in baked_groups(sphere_materials)]
    if any(socket.is_linked for socket, _ in roughness):
        raise RuntimeError("a far sphere's roughness is linked; this study sets it as a value")
    for extra in args.extra_alpha:
        for socket, base in roughness:
            socket.default_value = (base ** 4 + extra ** 2) ** 0.25
        render_both("alpha+%g" % extra)
    for socket, base in roughness:
        socket.default_value = base
    trees = {node.node_tree for node in baked_groups(bpy.data.materials[m] for m in info["materials"])}
    print("bent %d lobe normals" % sum(bend_lobe_normals(tree) for tree in trees))
    render_both("bent")

    print("  baked at the scene's exposure, against Cycles %d spp: mean luminance, block error, its ratio to "
          "naive's; Cycles %d spp: mean luminance, RMSE ratio" % (REFERENCE_SAMPLES, CYCLES_SAMPLES))
    region_masks = {region: masks[region] for region in REGIONS}
    eevee_table = image_error.compare(eevee, reference, region_masks)
    cycles_table = image_error.compare(cycles, reference, region_masks)
    for region in REGIONS:
        e, c = eevee_table[region], cycles_table[region]
        print("    %s (reference %.3f)      EEVEE Next                Cycles" % (region, e["reference"]["mean"]))
        for name in eevee:
            print("      %-10s %.3f  %.4f  %.3f      %.3f  %.3f" % (
                name, e[name]["mean"], e[name]["block"], image_error.ratio(e[name]["block"], e["naive"]["block"]),
                c[name]["mean"], image_error.ratio(c[name]["rmse"], c["naive"]["rmse"])))
    print("  baked far spheres from the silhouette inward: pixels, mean luminance reference / EEVEE naive / ndfbake")
    luminance = {name: image_error.luminance(image) for name, image in
                 (("reference", reference), ("naive", eevee["naive"]), ("ndfbake", eevee["ndfbake"]))}
    for k, ring in enumerate(rings(masks["spheres_far"])):
        print("    ring %d  %3d  %.3f / %.3f / %.3f" % (k, ring.sum(), luminance["reference"][ring].mean(),
                                                        luminance["naive"][ring].mean(),
                                                        luminance["ndfbake"][ring].mean()))


if __name__ == "__main__":
    demo_scene.run_as_script(main)
