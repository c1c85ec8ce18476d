"""The OSL variant (BakeSettings.shader "OSL", addon/ndfbake/shading/osl_group.py) in a Blender whose Cycles
has OSL (the bpy module from PyPI: bpy.app.build_options.cycles_osl). Skipped (exit 0, "skipped")
where it has none.

Run: python tests/blender/test_addon_osl.py -- LIB   (the bpy module; or blender -b ... --python)

- The bake writes a MIP-mapped file per lobe slot, the group's Script node compiles (Cycles' own
  compiler, no error reported) and a Cycles render through it is finite and lit.
- One flat texel at a known level: a V-groove map (two facets of ±30°, one texel each) is the same
  two-lobe texel everywhere at level 1 and above. Seen from straight above with 4 texels in a
  pixel (level 2) under a sun of zero angle and a black world, every pixel shades that one texel
  with no noise (direct light only, every closure evaluated): the OSL variant's render matches
  the stock-node group's (its atlas at the camera's level, same lobes) within 1%, for a dielectric
  and a metal, in the sun's highlight off one facet (the plain normal map, bilinear between the
  facets, misses it). 64 times closer the OSL render resolves level 0's facets: the level is the
  renderer's.
- The tangent frame: the shader's world normal of a lobe is the Normal Map node's, on a smooth
  and a flat sphere, within 0.1 degrees.
- The panel's conditions: not offered with OSL off or on the GPU (status says why), refused for a
  material with a coat; Revert removes the Script node's group and text and restores the material.
- Not offered where Cycles' texture() ignores the wrap mode (5.2 on), checked by a lookup outside
  [0, 1] in the Blender that runs the test; there only that refusal is tested.
Renders are 16² to 32², 4 samples.
"""
import math
import os
import sys

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import test_addon_helpers as h  # noqa: E402


def osl_scene(scene):
    scene.render.engine = "CYCLES"
    scene.cycles.shading_system = True
    scene.cycles.device = "CPU"


def test_bake_compiles_renders_and_reverts():
    from ndfbake.shading import osl_group
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory, pattern="bumps", size=64, roughness=0.35, metallic=0.3)
        scene = h.sun_lit_scene(32, cycles_samples=4)
        osl_scene(scene)
        before, data_before = h.dump_material(material), h.data_counts()
        texts_before = sorted(t.name for t in bpy.data.texts)

        result = bake.bake_material(material, bake.BakeSettings(max_lobes=4, shader="OSL"))
        folder = os.path.join(directory, result.folder[2:])
        mip_files = sorted(n for n in os.listdir(folder) if n.startswith("mip_lobe"))
        h.expect(mip_files == ["mip_lobe%d.exr" % j for j in range(4)], "MIP files: %s" % mip_files)
        group = next(n for n in material.node_tree.nodes if n.bl_idname == "ShaderNodeGroup").node_tree
        script = osl_group.script_node(group)
        h.expect(script is not None and script.script is not None, "no Script node in %s" % group.name)
        ok, messages = osl_group.compile_script(script)
        h.expect(ok and not any("ERROR" in m or "WARNING" in m for m in messages),
                 "the Script node does not compile: %s" % messages)
        files = [script.inputs[osl_group.LOBE_INPUT % j].default_value for j in range(8)]
        h.expect(files == [os.path.join(folder, name) for name in mip_files] + [""] * 4,
                 "the Script node's lobe files: %s" % files)
        h.expect("OSL" in result.summary, result.summary)
        pixels = h.render_pixels(scene, os.path.join(directory, "osl.exr"))[..., :3]
        h.expect(np.all(np.isfinite(pixels)) and pixels.mean() > 0.01, "OSL render mean %g" % pixels.mean())
        print("  %s; render mean %.4f" % (result.summary.split(";")[0], pixels.mean()))

        # Re-bakes: to the stock group (the shader's text goes with the Script node) and back.
        bake.bake_material(material, bake.BakeSettings(max_lobes=2))
        h.expect(bpy.data.texts.get(osl_group.TEXT_NAME) is None, "the text outlived its Script node")
        bake.bake_material(material, bake.BakeSettings(max_lobes=3, shader="OSL"))
        group = next(n for n in material.node_tree.nodes if n.bl_idname == "ShaderNodeGroup").node_tree
        files = [osl_group.script_node(group).inputs[osl_group.LOBE_INPUT % j].default_value for j in range(8)]
        h.expect([bool(f) for f in files] == [True] * 3 + [False] * 5, "slots after re-bake: %s" % files)
        bake.revert(material)
        differences = h.differences(before, h.dump_material(material))
        h.expect(not differences, "revert left: %s" % differences)
        counts = h.data_counts()
        counts["images"] = [name for name in counts["images"] if name != "Render Result"]
        h.expect(counts == data_before, "data-blocks after revert: %s, before %s" % (counts, data_before))
        h.expect(sorted(t.name for t in bpy.data.texts) == texts_before, "texts: %s" % list(bpy.data.texts))


def test_offered_only_where_cycles_runs_osl_on_the_cpu():
    from ndfbake.shading import osl_group
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory, pattern="bumps", size=16)
        scene = bpy.context.scene
        osl_scene(scene)
        h.expect(osl_group.status(scene)[0], osl_group.status(scene)[1])
        scene.cycles.shading_system = False
        available, why = osl_group.status(scene)
        h.expect(not available and "Open Shading Language" in why, why)
        error = h.raised(bake.BakeError, lambda: bake.bake_material(material, bake.BakeSettings(shader="OSL")),
                         "an OSL bake with OSL off")
        h.expect(error.code == "OSL_UNAVAILABLE", error.code)
        osl_scene(scene)
        scene.cycles.device = "GPU"
        available, why = osl_group.status(scene)
        h.expect(not available and "OptiX" in why, why)
        osl_scene(scene)
        material.node_tree.nodes["Principled BSDF"].inputs["Coat Weight"].default_value = 0.5
        error = h.raised(bake.BakeError, lambda: bake.bake_material(material, bake.BakeSettings(shader="OSL")),
                         "an OSL bake of a coated material")
        h.expect(error.code == "OSL_UNSUPPORTED" and "Coat Weight" in error.message, error.message)
        h.expect(not bake.is_baked(material), "a refused bake left a record")


WRAP_PROBE = """
shader wrap_probe(string File = "", output closure color BSDF = 0, output color Outside = 0)
{
  Outside = texture(File, u * 0.5 + 2.25, v * 0.5 - 1.75, "wrap", "periodic");
}
"""


def test_offered_only_where_texture_lookups_wrap():
    """The OSL variant reads its tiling lobe files with texture(..., "wrap", "periodic"); Cycles
    from 5.2 on ignores the wrap mode (black outside [0, 1]). A Script node samples a red image at
    s in [2.25, 2.75], t in [-1.75, -1.25]: where that is red, blender_compat.osl_texture_wraps must
    say so and the variant is offered; where black, the variant is refused by name and a bake asked
    for it leaves the material as it was."""
    from ndfbake.shading import blender_compat, osl_group
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        h.reset_scene()
        red = bpy.data.images.new("red", 4, 4, float_buffer=True)
        red.pixels.foreach_set(np.tile(np.float32([0.8, 0.1, 0.05, 1.0]), 16))
        red.filepath_raw = os.path.join(directory, "red.exr")
        red.file_format = "OPEN_EXR"
        red.save()
        material = bpy.data.materials.new("Wrap Probe")
        tree = h.enable_nodes(material)
        script = tree.nodes.new("ShaderNodeScript")
        script.mode = "INTERNAL"
        script.script = bpy.data.texts.new("wrap_probe.osl")
        script.script.write(WRAP_PROBE)
        ok, messages = osl_group.compile_script(script)
        h.expect(ok and "Outside" in script.outputs, "the probe does not compile: %s" % messages)
        script.inputs["File"].default_value = red.filepath_raw
        emission = tree.nodes.new("ShaderNodeEmission")
        tree.links.new(script.outputs["Outside"], emission.inputs["Color"])
        output = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial")
        tree.links.new(emission.outputs[0], output.inputs["Surface"])
        h.plane_with(material)
        scene = bpy.context.scene
        bpy.ops.object.camera_add(location=(0.0, 0.0, 3.0))
        scene.camera = bpy.context.active_object
        scene.camera.data.type = "ORTHO"
        scene.camera.data.ortho_scale = 1.0
        h.configure_render(scene, 8, 8, cycles_samples=1)
        osl_scene(scene)
        centre = h.render_pixels(scene, os.path.join(directory, "probe.exr"))[4, 4, :3]
        wraps = bool(centre[0] > 0.4)
        print("  a periodic lookup outside [0, 1] reads %s: the wrap mode is %s" % (
            np.round(centre, 3), "honoured" if wraps else "ignored"))
        h.expect(wraps == blender_compat.osl_texture_wraps(),
                 "blender_compat.osl_texture_wraps() is %s, but Cycles %s the wrap mode here" % (
                     blender_compat.osl_texture_wraps(), "honours" if wraps else "ignores"))
        if wraps:
            return
        available, why = osl_group.build_status()
        h.expect(not available and "wrap mode" in why and "Stock Nodes" in why, why)
        material = h.baked_scene(directory, pattern="bumps", size=16)
        osl_scene(bpy.context.scene)
        before = h.dump_material(material)
        error = h.raised(bake.BakeError, lambda: bake.bake_material(material, bake.BakeSettings(shader="OSL")),
                         "an OSL bake where texture() does not wrap")
        h.expect(error.code == "OSL_UNAVAILABLE" and "wrap mode" in error.message, error.message)
        h.expect(not h.differences(before, h.dump_material(material)), "the refused bake changed the material")
        h.expect(not bake.is_baked(material), "a refused bake left a record")


def _flat_texel_scene(directory):
    h.reset_scene()
    image_path = h.write_normal_map(os.path.join(directory, "vgroove.png"), "vgroove", 64)
    materials = {"dielectric": h.normal_mapped_material("Groove Dielectric", image_path, roughness=0.3),
                 "metal": h.normal_mapped_material("Groove Metal", image_path, roughness=0.3, metallic=1.0)}
    plane = h.plane_with(materials["dielectric"], size=2.0)
    bpy.ops.wm.save_as_mainfile(filepath=os.path.join(directory, "scene.blend"))
    scene = bpy.context.scene
    bpy.ops.object.camera_add(location=(0.0, 0.0, 5.0), rotation=(0.0, 0.0, 0.0))
    camera = scene.camera = bpy.context.active_object
    camera.data.type = "ORTHO"
    camera.data.ortho_scale = 2.0  # the plane fills the frame: 64 texels over 16 pixels, 4 a pixel
    # The sun in the highlight of the +X facet (normal 30° toward +X), seen from above.
    bpy.ops.object.light_add(type="SUN", rotation=(0.0, math.radians(60.0), 0.0))
    sun = bpy.context.active_object.data
    sun.energy = 3.0
    sun.angle = 0.0
    h.uniform_world(scene, "Black", (0.0, 0.0, 0.0))
    h.configure_render(scene, 16, 16, cycles_samples=4)
    osl_scene(scene)
    return scene, plane, materials


def test_flat_texel_matches_the_stock_group():
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        scene, plane, materials = _flat_texel_scene(directory)
        for kind, material in materials.items():
            plane.data.materials[0] = material
            plain = h.render_pixels(scene, os.path.join(directory, kind + "-plain.exr"))[..., :3]
            means = {}
            for shader in ("NODES", "OSL"):
                result = bake.bake_material(material, bake.BakeSettings(max_lobes=2, shader=shader))
                pixels = h.render_pixels(scene, os.path.join(directory, "%s-%s.exr" % (kind, shader)))[..., :3]
                h.expect(np.all(np.isfinite(pixels)), "%s %s: not finite" % (kind, shader))
                pixels = pixels[2:-2, 2:-2]  # the border's pixel filter reaches past the plane
                means[shader] = pixels.reshape(-1, 3).mean(axis=0)
                spread = float(np.abs(pixels - means[shader]).max() / max(means[shader].max(), 1e-9))
                h.expect(spread < 1e-3, "%s %s: the flat texel shades unevenly (%.2e)" % (kind, shader, spread))
                print("  %s, %s (%s): mean %s, largest pixel deviation %.2e" % (
                    kind, shader, result.summary.split(";")[-1].strip(), np.round(means[shader], 5), spread))
            ratio = means["OSL"] / means["NODES"]
            print("  %s: OSL / stock %s (plain normal map %s)" % (kind, np.round(ratio, 5),
                                                                  np.round(plain.reshape(-1, 3).mean(axis=0), 5)))
            h.expect(means["NODES"].max() > 0.05, "%s: the stock group's render is dark: %s" % (kind, means["NODES"]))
            h.expect(np.all(np.abs(ratio - 1.0) < 0.01), "%s: OSL / stock = %s, not within 1%%" % (kind, ratio))
        # The renderer's level: 64 times closer, a pixel is 1/16 texel and level 0 shows its two
        # facets (one lobe a texel, bilinear between them), column by column.
        camera = scene.camera
        camera.data.ortho_scale = 2.0 / 64.0
        camera.location = (0.01, 0.013, 5.0)
        row = h.render_pixels(scene, os.path.join(directory, "close.exr"))[8, :, 0]
        contrast = float((row.max() - row.min()) / max(row.max(), 1e-9))
        print("  close up (OSL, metal): a row of red %s" % np.round(row, 3))
        h.expect(contrast > 0.5, "close up, the OSL variant does not resolve level 0's facets: %s" % row)


def test_lobe_normals_are_the_normal_map_nodes():
    """The shader's tangent frame (ndfb_tangent_to_world) is the Normal Map node's, on a smooth
    and a flat UV sphere: slot 0's world normal, from a copy of the shader with it as an output,
    against the group's own Normal Map node of slot 0's decoded normal (its EEVEE path, the same
    texel: a V-groove map is one texel at every level from 1 up, here about level 2), as emission,
    one sample at each pixel's centre; within 0.1 degrees."""
    from ndfbake.shading import osl_group
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        h.reset_scene()
        image_path = h.write_normal_map(os.path.join(directory, "vgroove.png"), "vgroove", 64)
        material = h.normal_mapped_material("Groove Sphere", image_path, roughness=0.3, metallic=1.0)
        bpy.ops.mesh.primitive_uv_sphere_add(segments=32, ring_count=16, radius=1.0)
        sphere = bpy.context.active_object
        for loop in sphere.data.uv_layers.active.data:
            loop.uv = (loop.uv[0] * 8.0, loop.uv[1] * 4.0)
        sphere.data.materials.append(material)
        bpy.ops.wm.save_as_mainfile(filepath=os.path.join(directory, "scene.blend"))
        scene = bpy.context.scene
        bpy.ops.object.camera_add(location=(0.0, -5.0, 0.0), rotation=(math.pi / 2, 0.0, 0.0))
        camera = scene.camera = bpy.context.active_object
        camera.data.type = "ORTHO"
        camera.data.ortho_scale = 2.4
        h.uniform_world(scene, "Black", (0.0, 0.0, 0.0))
        h.configure_render(scene, 32, 32, cycles_samples=1)
        scene.cycles.filter_width = 0.01
        osl_scene(scene)
        bake.bake_material(material, bake.BakeSettings(max_lobes=2, shader="OSL"))
        group = next(n for n in material.node_tree.nodes if n.bl_idname == "ShaderNodeGroup").node_tree
        script = osl_group.script_node(group)
        source = osl_group.shader_source()
        source = source.replace("output closure color BSDF = 0)", "output closure color BSDF = 0, output normal N0 = 0)")
        source = source.replace("    normal n = ndfb_tangent_to_world(mu, UVMapName, NormalStrength);",
                                "    normal n = ndfb_tangent_to_world(mu, UVMapName, NormalStrength);\n"
                                "    if (j == 0)\n      N0 = n;")
        probe = bpy.data.texts.new("ndfbake probe.osl")
        probe.write(source)
        script.script = probe
        ok, messages = osl_group.compile_script(script)
        h.expect(ok and "N0" in script.outputs, "the probe does not compile: %s" % messages)
        output = next(n for n in group.nodes if n.bl_idname == "NodeGroupOutput")
        normal_map = group.nodes["Normal Map"]  # slot 0's, in the EEVEE lobes
        h.expect(normal_map.bl_idname == "ShaderNodeNormalMap", normal_map.bl_idname)
        stock = {}
        for shading in ("smooth", "flat"):
            for polygon in sphere.data.polygons:
                polygon.use_smooth = shading == "smooth"
            normals = []
            for socket in (normal_map.outputs["Normal"], script.outputs["N0"]):
                emission = group.nodes.new("ShaderNodeEmission")
                group.links.new(socket, emission.inputs["Color"])
                group.links.new(emission.outputs[0], output.inputs["BSDF"])
                normals.append(h.render_pixels(scene, os.path.join(directory, "n.exr"))[..., :3])
            a, b = normals
            stock[shading] = a
            inside = np.linalg.norm(a, axis=2) > 0.5
            cosine = (a * b).sum(axis=2) / np.maximum(np.linalg.norm(a, axis=2) * np.linalg.norm(b, axis=2), 1e-9)
            angles = np.degrees(np.arccos(np.clip(cosine[inside], -1.0, 1.0)))
            print("  %s sphere: %d pixels, the two normals %.4f degrees apart at most" % (
                shading, inside.sum(), angles.max()))
            h.expect(inside.sum() > 300 and angles.max() < 0.1, "%s: normals %.3f degrees apart" % (
                shading, angles.max()))
        apart = float(np.abs(stock["smooth"] - stock["flat"]).max())
        h.expect(apart > 0.05, "smooth and flat shading drew the same normals (%.4f apart)" % apart)


def main():
    if not getattr(bpy.app.build_options, "cycles_osl", False):
        print("skipped: this Blender has no OSL (bpy.app.build_options.cycles_osl is False)")
        return
    h.import_addon()
    from ndfbake.shading import blender_compat
    tests = [test_offered_only_where_texture_lookups_wrap]
    if blender_compat.osl_texture_wraps():
        tests += [test_bake_compiles_renders_and_reverts, test_offered_only_where_cycles_runs_osl_on_the_cpu,
                  test_flat_texel_matches_the_stock_group, test_lobe_normals_are_the_normal_map_nodes]
    else:
        print("the OSL variant is refused in this Blender (texture() does not wrap): only its refusal is tested")
    h.run(tests)


if __name__ == "__main__":
    main()
