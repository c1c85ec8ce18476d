"""A bake's Transparent Shadows setting (addon/ndfbake/shading/transparent_shadow.py), inside `blender -b`.

Run: blender -b --factory-startup --python-exit-code 1 --python tests/blender/test_addon_transparent_shadow.py -- LIB

The bake wires Alpha through its group, so EEVEE Next (4.2+) takes any baked material for a
transparent one and, with Transparent Shadows on, draws its shadow maps through the whole group
(docs/speed.md, "EEVEE Next frame time in 4.2/4.3"). A bake of an opaque material turns the
setting off and Revert puts it back; a material with an Alpha below 1, linked or animated keeps
it; a re-bake follows the Alpha the group node has then; a setting the user had off stays off.
Blender 3.4 has no such setting: its bakes record nothing.
"""
import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import test_addon_helpers as h  # noqa: E402

HAS_SETTING = "use_transparent_shadow" in bpy.types.Material.bl_rna.properties


def _principled(material):
    return next(n for n in material.node_tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")


def _setting(material):
    return material.use_transparent_shadow if HAS_SETTING else None


def test_an_opaque_material_bakes_without_transparent_shadows():
    """Off after the bake, recorded as on; Revert restores the material exactly."""
    from ndfbake.shading import transparent_shadow
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory)
        if HAS_SETTING:
            material.use_transparent_shadow = True
        before = h.dump_material(material)
        bake.bake_material(material, bake.BakeSettings(max_lobes=2))
        rec = h.bake_record(material)
        if not HAS_SETTING:
            h.expect(transparent_shadow.RECORD_FIELD not in rec, "3.4 recorded a setting it has not: %s" % rec)
            return
        h.expect(not material.use_transparent_shadow, "the opaque baked material kept Transparent Shadows")
        h.expect(rec.get(transparent_shadow.RECORD_FIELD, {}).get("use_transparent_shadow") is True,
                 "the record lacks the setting: %s" % rec)
        bake.revert(material)
        h.expect(material.use_transparent_shadow, "Revert did not turn Transparent Shadows back on")
        after = h.dump_material(material)
        h.expect(after == before, "Revert left differences: %s" % h.differences(before, after))


def test_a_transparent_material_keeps_them():
    """An Alpha below 1, linked, or animated at 1: the bake leaves the setting alone."""
    from ndfbake.shading import transparent_shadow
    from ndfbake.blender import bake
    if not HAS_SETTING:
        return

    def below_one(material):
        _principled(material).inputs["Alpha"].default_value = 0.5

    def linked(material):
        tree = material.node_tree
        value = tree.nodes.new("ShaderNodeValue")
        value.outputs[0].default_value = 1.0
        tree.links.new(value.outputs[0], _principled(material).inputs["Alpha"])

    def animated(material):
        _principled(material).inputs["Alpha"].keyframe_insert("default_value", frame=1)

    def transparent_bsdf(material):
        material.node_tree.nodes.new("ShaderNodeBsdfTransparent")

    for change in (below_one, linked, animated, transparent_bsdf):
        with h.scratch_dir() as directory:
            material = h.baked_scene(directory)
            material.use_transparent_shadow = True
            change(material)
            bake.bake_material(material, bake.BakeSettings(max_lobes=2))
            h.expect(material.use_transparent_shadow, "%s: the bake turned Transparent Shadows off" % change.__name__)
            h.expect(transparent_shadow.RECORD_FIELD not in h.bake_record(material),
                     "%s: recorded %s" % (change.__name__, h.bake_record(material)))


def test_a_rebake_follows_the_group_nodes_alpha():
    """Alpha lowered on the group node: the re-bake puts the setting back; raised to 1 again, the
    next re-bake turns it off again and still records the user's setting, which Revert restores.
    A setting the user had off stays off and is not recorded."""
    from ndfbake.shading import transparent_shadow
    from ndfbake.blender import bake
    if not HAS_SETTING:
        return
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory)
        material.use_transparent_shadow = True
        bake.bake_material(material, bake.BakeSettings(max_lobes=2))
        h.expect(not material.use_transparent_shadow, "the first bake left Transparent Shadows on")
        group = h.bake_group_nodes(material)[0]
        group.inputs["Alpha"].default_value = 0.5
        bake.bake_material(material, bake.BakeSettings(max_lobes=2))
        h.expect(material.use_transparent_shadow, "the re-bake of a transparent material left them off")
        h.expect(transparent_shadow.RECORD_FIELD not in h.bake_record(material), str(h.bake_record(material)))
        h.bake_group_nodes(material)[0].inputs["Alpha"].default_value = 1.0
        bake.bake_material(material, bake.BakeSettings(max_lobes=2))
        h.expect(not material.use_transparent_shadow, "the re-bake of an opaque material left them on")
        bake.bake_material(material, bake.BakeSettings(max_lobes=1))
        recorded = h.bake_record(material).get(transparent_shadow.RECORD_FIELD, {})
        h.expect(recorded.get("use_transparent_shadow") is True, str(h.bake_record(material)))
        bake.revert(material)
        h.expect(material.use_transparent_shadow, "Revert after re-bakes did not turn them back on")

    with h.scratch_dir() as directory:
        material = h.baked_scene(directory)
        material.use_transparent_shadow = False
        bake.bake_material(material, bake.BakeSettings(max_lobes=2))
        h.expect(not material.use_transparent_shadow, "the bake turned Transparent Shadows on")
        h.expect(transparent_shadow.RECORD_FIELD not in h.bake_record(material), str(h.bake_record(material)))
        bake.revert(material)
        h.expect(not material.use_transparent_shadow, "Revert turned Transparent Shadows on")


if __name__ == "__main__":
    h.import_addon()
    h.run([test_an_opaque_material_bakes_without_transparent_shadows, test_a_transparent_material_keeps_them,
           test_a_rebake_follows_the_group_nodes_alpha])
