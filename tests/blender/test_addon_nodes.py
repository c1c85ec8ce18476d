"""The lobe node group computes what native/src/math/brdf.h says, in Cycles and in EEVEE, and the
grazing-roughness group (EEVEE's narrowed lobes) what lobe_nodes.py's formula says.

Run: blender -b --factory-startup --python-exit-code 1 --python tests/blender/test_addon_nodes.py -- LIB

A 32² normal map is baked; for every lobe slot j and levels 0 and 2 a plane shows, as emission,
the decode group's outputs read from levelLL_lobej.exr (Closest interpolation, whole texels per
pixel under an orthographic camera): (widened roughness, 0, weight) on one row of planes and the
tangent-space normal colour on the other. The renders (Cycles and EEVEE, Standard view transform,
no pixel filter) must match a NumPy evaluation of the rule written from brdf.h, independently of
lobe_nodes.py:  α'² = min(α² + 1.5/κ, 1), α = roughness², κ = (3R − R³)/(1 − R²), R ≤ 1, with 1/κ
lowered by the half-float resolution 4e-4 (io/lobe_exr.h) and kept ≥ 0. (brdf.h's amplitude is not
part of the shading: see lobe_nodes.py.)

The lobe BSDFs keep GGX, rather than Multiscatter GGX, where the material transmits, and take the
inputs that leave a closure off as constants where the material holds them there (structure).
"""
import os
import sys

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import test_addon_helpers as h  # noqa: E402

SIZE = 32
ROUGHNESS = 0.3


def reference(rgba, roughness, widening=1.5, resolution=4e-4):
    """weight, normal colour and widened roughness per texel, from brdf.h's rule."""
    alpha_j = rgba[..., 0].astype(np.float64)
    v = rgba[..., 1:4].astype(np.float64)
    r = v / np.maximum(alpha_j, 1e-6)[..., None]
    big_r = np.minimum(np.linalg.norm(r, axis=-1), 1.0)
    mu = r + np.array([0, 0, 1e-5])
    mu /= np.linalg.norm(mu, axis=-1, keepdims=True)
    with np.errstate(divide="ignore"):
        kappa = (3 * big_r - big_r ** 3) / (1 - big_r ** 2)
        inv_kappa = np.where(kappa > 0, np.maximum(1.0 / kappa - resolution, 0.0), 1e6)
    a = roughness ** 2
    widened = np.sqrt(np.minimum(a * a + widening * inv_kappa, 1.0))
    return alpha_j, mu * 0.5 + 0.5, np.sqrt(widened)


def image_rgba(image):
    px = np.empty(image.size[0] * image.size[1] * 4, dtype=np.float32)
    image.pixels.foreach_get(px)
    return px.reshape(image.size[1], image.size[0], 4)  # rows bottom to top, as the render's


def probe_material(name, image, output):
    """Emission of the decode group's outputs for lobe image `image`."""
    from ndfbake.shading import lobe_nodes
    material = bpy.data.materials.new(name)
    h.enable_nodes(material)
    tree = material.node_tree
    tree.nodes.remove(tree.nodes["Principled BSDF"])
    tex = tree.nodes.new("ShaderNodeTexImage")
    tex.image = image
    tex.interpolation = "Closest"
    dec = tree.nodes.new("ShaderNodeGroup")
    dec.node_tree = lobe_nodes.lobe_group()
    dec.inputs["Roughness"].default_value = ROUGHNESS
    tree.links.new(tex.outputs["Color"], dec.inputs["Lobe"])
    tree.links.new(tex.outputs["Alpha"], dec.inputs["Lobe Z"])
    emission = tree.nodes.new("ShaderNodeEmission")
    if output == "normal":
        tree.links.new(dec.outputs["Normal"], emission.inputs["Color"])
    else:
        combine = tree.nodes.new("ShaderNodeCombineXYZ")
        tree.links.new(dec.outputs["Roughness"], combine.inputs["X"])
        tree.links.new(dec.outputs["Weight"], combine.inputs["Z"])
        tree.links.new(combine.outputs[0], emission.inputs["Color"])
    tree.links.new(emission.outputs[0], tree.nodes["Material Output"].inputs["Surface"])
    return material


def render(scene, engine, path, width, height):
    scene.render.engine = engine
    h.configure_render(scene, width, height, cycles_samples=1, eevee_samples=1)
    scene.render.filter_size = 0.0
    scene.render.image_settings.color_depth = "32"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    scene.cycles.filter_width = 0.01
    scene.world = None
    return h.render_pixels(scene, path)


def test_decode_group_matches_the_rule_in_both_engines():
    from ndfbake.shading import blender_compat
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory, pattern="scratches", size=SIZE, roughness=ROUGHNESS)
        bake.bake_material(material, bake.BakeSettings(max_lobes=4))
        # Level 0 (one fine normal per texel: κ huge) and level 2 (8x8 texels of 16 normals each:
        # the widening regime), every lobe slot.
        folder = bpy.path.abspath("//%s.ndfbake" % material.name)
        images = {}
        for level in (0, 2):
            for j in range(4):
                images[level, j] = bpy.data.images.load(os.path.join(folder, "level%02d_lobe%d.exr" % (level, j)))
                images[level, j].colorspace_settings.name = "Non-Color"
                images[level, j].alpha_mode = "CHANNEL_PACKED"
        scene = bpy.context.scene
        for obj in list(scene.objects):
            bpy.data.objects.remove(obj)
        # Planes of side 2 at x = 2j (lobe j); rows from the top: level 0 scalars, level 0 normal
        # colour, level 2 scalars, level 2 normal colour.
        rows = [(0, "scalars"), (0, "normal"), (2, "scalars"), (2, "normal")]
        for j in range(4):
            for row, (level, output) in enumerate(rows):
                bpy.ops.mesh.primitive_plane_add(size=2.0, location=(2.0 * j, -2.0 * row, 0.0))
                bpy.context.active_object.data.materials.append(
                    probe_material("probe L%d %d %s" % (level, j, output), images[level, j], output))
        bpy.ops.object.camera_add(location=(3.0, -3.0, 5.0), rotation=(0.0, 0.0, 0.0))
        camera = bpy.context.active_object
        camera.data.type = "ORTHO"
        camera.data.ortho_scale = 8.0
        scene.camera = camera
        width, height = 4 * SIZE, 4 * SIZE

        expected = {}
        for (level, j), image in images.items():
            rgba = image_rgba(image)
            h.expect(np.isfinite(rgba).all(), "level %d lobe %d has non-finite texels" % (level, j))
            h.expect(np.all(np.linalg.norm(rgba[..., 1:], axis=-1) <= rgba[..., 0] * 1.001 + 1e-3),
                     "level %d lobe %d: |alpha r| > alpha: the alpha channel is not read raw" % (level, j))
            weight, normal, rough = reference(rgba, ROUGHNESS)
            scale = SIZE // rgba.shape[0]  # texels of level 2 cover scale x scale pixels
            up = lambda a: np.repeat(np.repeat(a, scale, axis=0), scale, axis=1)  # noqa: E731
            expected[level, j] = (up(np.stack([rough, np.zeros_like(rough), weight], axis=-1)), up(normal))
            # The comparison must be able to tell the rule from its neighbours (2/κ, Filament's).
            occupied = weight > 1e-3
            other = reference(rgba, ROUGHNESS, widening=2.0)[2]
            sensitivity = float(np.abs(other - rough)[occupied].max()) if occupied.any() else 0.0
            print("level %d lobe %d: %d occupied texels, roughness' %.3f..%.3f, 1.5/κ vs 2/κ differ by up to %.3f"
                  % (level, j, int(occupied.sum()), float(rough[occupied].min(initial=1)),
                     float(rough[occupied].max(initial=0)), sensitivity))
            if level == 2 and j == 0:
                h.expect(sensitivity > 0.02, "level 2 does not exercise the widening rule")

        for engine in ("CYCLES", blender_compat.eevee_engine()):
            got = render(scene, engine, os.path.join(directory, engine + ".exr"), width, height)
            got = got[::-1]  # rows top to bottom
            for j in range(4):
                x = slice(j * SIZE, (j + 1) * SIZE)
                for row, (level, output) in enumerate(rows):
                    want_scalars, want_normal = expected[level, j]
                    occupied = want_scalars[..., 2] > 1e-3
                    # Rendered rows are top to bottom; Blender's image rows bottom to top.
                    block = got[row * SIZE:(row + 1) * SIZE, x, :3][::-1]
                    # Half-float textures and float32 nodes: 2e-3 absolute is plenty.
                    if output == "scalars":
                        err = np.abs(block - want_scalars)
                        for c, what in enumerate(("roughness", "(unused)", "weight")):
                            mask = occupied if c < 2 else np.ones_like(occupied)
                            worst = float(err[..., c][mask].max()) if mask.any() else 0.0
                            h.expect(worst < 2e-3, "%s level %d lobe %d %s: max error %.4g" % (
                                engine, level, j, what, worst))
                    else:
                        worst = float(np.abs(block - want_normal)[occupied].max()) if occupied.any() else 0.0
                        h.expect(worst < 2e-3, "%s level %d lobe %d normal: max error %.4g" % (
                            engine, level, j, worst))
            print("%s: decode group matches the rule on levels 0 and 2, 4 lobes" % engine)


GRAZING_ROUGHNESS = (0.3, 0.5, 0.7, 0.9)       # widened roughness, one column each
GRAZING_TILT_DEG = (0.0, 45.0, 75.0, 89.0)      # the lobe normal's angle from the view, one row each
GRAZING_BASE = 0.25
GRAZING_C = 2.5                                  # the Narrowing input


def grazing_reference(roughness, tilt_deg, base, narrowing):
    """α″² = max(α′² / (1 + C·α′² tan²θ), α²), from lobe_nodes.grazing_roughness_group's docstring."""
    widened2, base2 = roughness ** 4, base ** 4
    c = max(np.cos(np.radians(tilt_deg)), 1e-3)
    tan2 = (1.0 - c * c) / (c * c)
    return max(widened2 / (1.0 + narrowing * widened2 * tan2), base2) ** 0.25


def test_grazing_group_matches_its_formula_in_both_engines():
    """A grid of planes under an orthographic camera looking down (the view direction is +Z at
    every pixel), each showing as emission the group's output for one widened roughness and one
    constant lobe normal tilted from the view."""
    from ndfbake.shading import blender_compat, lobe_nodes
    with h.scratch_dir() as directory:
        h.reset_scene()
        scene = bpy.context.scene
        for column, roughness in enumerate(GRAZING_ROUGHNESS):
            for row, tilt in enumerate(GRAZING_TILT_DEG):
                material = bpy.data.materials.new("grazing %d %d" % (column, row))
                h.enable_nodes(material)
                tree = material.node_tree
                tree.nodes.remove(tree.nodes["Principled BSDF"])
                group = tree.nodes.new("ShaderNodeGroup")
                group.node_tree = lobe_nodes.grazing_roughness_group()
                group.inputs["Roughness"].default_value = roughness
                group.inputs["Base Roughness"].default_value = GRAZING_BASE
                group.inputs["Narrowing"].default_value = GRAZING_C
                group.inputs["Normal"].default_value = (np.sin(np.radians(tilt)), 0.0, np.cos(np.radians(tilt)))
                emission = tree.nodes.new("ShaderNodeEmission")
                tree.links.new(group.outputs["Roughness"], emission.inputs["Strength"])
                tree.links.new(emission.outputs[0], tree.nodes["Material Output"].inputs["Surface"])
                bpy.ops.mesh.primitive_plane_add(size=2.0, location=(2.0 * column, -2.0 * row, 0.0))
                bpy.context.active_object.data.materials.append(material)
        bpy.ops.object.camera_add(location=(3.0, -3.0, 5.0), rotation=(0.0, 0.0, 0.0))
        scene.camera = bpy.context.active_object
        scene.camera.data.type = "ORTHO"
        scene.camera.data.ortho_scale = 8.0
        want = np.array([[grazing_reference(r, t, GRAZING_BASE, GRAZING_C) for r in GRAZING_ROUGHNESS]
                         for t in GRAZING_TILT_DEG])
        h.expect(float(np.abs(want - np.array(GRAZING_ROUGHNESS)[None, :]).max()) > 0.3,
                 "the grid does not exercise the narrowing")
        for engine in ("CYCLES", blender_compat.eevee_engine()):
            got = render(scene, engine, os.path.join(directory, engine + ".exr"), 64, 64)[::-1]  # rows from the top
            centres = got[8::16, 8::16, 0]  # each plane covers 16 x 16 pixels
            worst = float(np.abs(centres - want).max())
            h.expect(worst < 2e-3, "%s: grazing roughness off by %.4g\n%s\n%s" % (engine, worst, centres, want))
            print("%s: grazing roughness matches its formula (max error %.1e)" % (engine, worst))


def _lobe_bsdfs(material):
    """The Principled BSDFs of the bake's lobes in `material` (not the specular split's base)."""
    from ndfbake.shading import lobe_bsdfs
    group = h.bake_group_nodes(material)[0]
    return [n for n in group.node_tree.nodes
            if n.bl_idname == "ShaderNodeBsdfPrincipled" and not n.name.startswith(lobe_bsdfs.BASE_BSDF)]


def _lobe_distributions(material):
    return {n.distribution for n in _lobe_bsdfs(material)}


def _scene_with_value_node(directory, number):
    """h.baked_scene's material, its tree, its Principled BSDF and a new Value node (`number`) for
    the cases to link to the Principled's inputs."""
    material = h.baked_scene(directory)
    tree = material.node_tree
    value = tree.nodes.new("ShaderNodeValue")
    value.outputs[0].default_value = number
    return material, tree, tree.nodes["Principled BSDF"], value


def test_lobes_keep_ggx_where_the_material_transmits():
    """The lobes use Multiscatter GGX for a GGX material, except where it transmits (Transmission
    or Transmission Roughness non-zero, linked or animated): Blender's Principled BSDF with
    Multiscatter GGX has no Transmission Roughness, so rough glass would turn sharp. (Principled
    v2, Blender 4.0+, has no Transmission Roughness: the cases that set it are left out there.)"""
    from ndfbake.shading import blender_compat
    from ndfbake.blender import bake
    transmission_input = blender_compat.principled_input("Transmission")
    roughness_input = blender_compat.principled_input("Transmission Roughness")
    with h.scratch_dir() as directory:
        material, tree, principled, value = _scene_with_value_node(directory, 0.0)

        def set_up(transmission=0.0, transmission_roughness=0.0, link=None, muted=False, keyframe=False,
                   distribution="GGX"):
            for link_ in [l for l in tree.links if l.from_node == value]:
                tree.links.remove(link_)
            if tree.animation_data is not None:
                tree.animation_data_clear()
            principled.distribution = distribution
            principled.inputs[transmission_input].default_value = transmission
            if roughness_input is not None:
                principled.inputs[roughness_input].default_value = transmission_roughness
            if link:
                tree.links.new(value.outputs[0], principled.inputs[link]).is_muted = muted
            if keyframe:
                principled.inputs[transmission_input].keyframe_insert("default_value", frame=1)

        cases = [("opaque", {}, {"MULTI_GGX"}),
                 ("glass", {"transmission": 1.0, "transmission_roughness": 0.6}, {"GGX"}),
                 ("transmission only", {"transmission": 0.5}, {"GGX"}),
                 ("transmission roughness only", {"transmission_roughness": 0.3}, {"GGX"}),
                 ("transmission linked", {"link": transmission_input}, {"GGX"}),
                 ("transmission roughness linked", {"link": roughness_input}, {"GGX"}),
                 ("transmission link muted", {"link": transmission_input, "muted": True}, {"MULTI_GGX"}),
                 ("transmission animated", {"keyframe": True}, {"GGX"}),
                 ("multiscatter glass", {"transmission": 1.0, "distribution": "MULTI_GGX"}, {"MULTI_GGX"})]
        if roughness_input is None:
            cases = [case for case in cases if "roughness" not in case[0]]
        for name, setup, expected in cases:
            set_up(**setup)
            bake.bake_material(material, bake.BakeSettings(max_lobes=2, level_of_detail="RENDERER"))
            got = _lobe_distributions(material)
            print("  %s: lobes %s" % (name, ", ".join(sorted(got))))
            h.expect(got == expected, "%s: lobe distributions %s, expected %s" % (name, got, expected))
            bake.revert(material)


def test_whole_copy_lobes_leave_closures_off_as_constants():
    """A whole-copy lobe (Principled v1, or v2 with a coat) takes Metallic 1, Alpha 1 and a coat,
    sheen, subsurface or transmission of 0 as constants where the material holds them there with
    nothing to change them, and from the group's inputs where they are linked, animated or another
    value: EEVEE compiles the closures a linked socket may turn on (lobe_bsdfs.CLOSURE_OFF_VALUES).
    Checked against the material's own sockets, case by case, not against the add-on's table."""
    from ndfbake.shading import blender_compat
    from ndfbake.blender import bake
    coat = blender_compat.principled_input("Clearcoat")
    sheen = blender_compat.principled_input("Sheen")
    v2 = bpy.app.version >= (4, 0, 0)
    with h.scratch_dir() as directory:
        material, tree, principled, value = _scene_with_value_node(directory, 1.0)

        def set_up(metallic=1.0, alpha=1.0, sheen_weight=0.0, link=None, keyframe=None):
            for link_ in [l for l in tree.links if l.from_node == value]:
                tree.links.remove(link_)
            if tree.animation_data is not None:
                tree.animation_data_clear()
            principled.inputs["Metallic"].default_value = metallic
            principled.inputs["Alpha"].default_value = alpha
            principled.inputs[sheen].default_value = sheen_weight
            # Principled v2 splits lobes unless a layer may matter: a linked coat keeps whole copies.
            principled.inputs[coat].default_value = 0.0
            if v2:
                tree.links.new(value.outputs[0], principled.inputs[coat])
            if link:
                tree.links.new(value.outputs[0], principled.inputs[link])
            if keyframe:
                principled.inputs[keyframe].keyframe_insert("default_value", frame=1)

        # (case, set-up, {input: constant the lobes hold, or None where they take the group's input})
        cases = [("metal", {}, {"Metallic": 1.0, "Alpha": 1.0, sheen: 0.0}),
                 ("dielectric", {"metallic": 0.0}, {"Metallic": None, "Alpha": 1.0, sheen: 0.0}),
                 ("Metallic linked", {"link": "Metallic"}, {"Metallic": None}),
                 ("Metallic animated", {"keyframe": "Metallic"}, {"Metallic": None, "Alpha": 1.0}),
                 ("Alpha 0.5", {"alpha": 0.5}, {"Alpha": None, "Metallic": 1.0}),
                 ("sheen 0.4", {"sheen_weight": 0.4}, {sheen: None}),
                 ("sheen animated", {"keyframe": sheen}, {sheen: None})]
        if not v2:
            cases.append(("Clearcoat 0", {}, {coat: 0.0}))
        else:
            cases.append(("Coat Weight linked", {}, {coat: None}))
        for name, setup, expected in cases:
            set_up(**setup)
            bake.bake_material(material, bake.BakeSettings(max_lobes=2, level_of_detail="RENDERER"))
            lobes = _lobe_bsdfs(material)  # whole copies in every case here
            h.expect(len(lobes) >= 2, "%s: %d whole-copy lobe BSDFs" % (name, len(lobes)))
            for socket_name, constant in expected.items():
                sockets = [lobe.inputs[socket_name] for lobe in lobes]
                if constant is None:
                    ok = all(s.is_linked for s in sockets)
                else:
                    ok = all(not s.is_linked and s.default_value == constant for s in sockets)
                print("  %s: %s %s" % (name, socket_name, "from the group" if constant is None else constant))
                h.expect(ok, "%s: the lobes' %s is %s, expected %s" % (
                    name, socket_name, [s.default_value if not s.is_linked else "linked" for s in sockets],
                    "linked to the group" if constant is None else constant))
            bake.revert(material)


if __name__ == "__main__":
    h.import_addon()
    h.run([test_decode_group_matches_the_rule_in_both_engines, test_grazing_group_matches_its_formula_in_both_engines,
           test_lobes_keep_ggx_where_the_material_transmits, test_whole_copy_lobes_leave_closures_off_as_constants])
