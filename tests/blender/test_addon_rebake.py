"""Re-bakes of materials the user changed after a bake, inside `blender -b`.

Run: blender -b --factory-startup --python-exit-code 1 --python tests/blender/test_addon_rebake.py -- LIB

The scene is test_addon_bake.py's (test_addon_helpers.baked_scene). A material changed while its
bake runs is not baked; renamed nodes are found again (a renamed group node keeps its role key
from a new one); a deleted Principled BSDF is made again on Revert; a re-bake that no longer finds
one of two normal-map chains reverts that one and re-bakes the other, also where the user renamed
that one's group node; a deleted group node beside a renamed one is baked again. A re-bake while
another program holds one of the previous bake's files open either succeeds (Linux replaces open
files) or fails cleanly, naming the file and changing no file and no node; once it is closed, the
re-bake succeeds.
"""
import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import test_addon_helpers as h  # noqa: E402


def test_a_material_changed_during_the_bake_is_not_baked():
    """What the worker fitted must be what the material shows: a normal map swapped or set to
    object space while the bake ran refuses it (MATERIAL_CHANGED, nothing changed, no folder); a
    renamed material still gets its bake."""
    from ndfbake.blender import bake, lobe_folders
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory)
        tree = material.node_tree
        texture = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeTexImage")
        normal_map = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeNormalMap")
        other = bpy.data.images.load(h.write_normal_map(os.path.join(directory, "other.png"), "weave", 64))
        other.colorspace_settings.name = "Non-Color"
        before, original_image = h.dump_material(material), texture.image
        changes = [(lambda: setattr(texture, "image", other), lambda: setattr(texture, "image", original_image)),
                   (lambda: setattr(normal_map, "space", "OBJECT"), lambda: setattr(normal_map, "space", "TANGENT"))]
        for change, undo in changes:
            job = bake.prepare(material, bake.BakeSettings(max_lobes=1))
            job.run()
            change()
            e = h.raised(bake.BakeError, lambda: bake.finish(job), "a bake of a changed material was applied")
            h.expect(e.code == "MATERIAL_CHANGED", "%s: %s" % (e.code, e.message))
            lobe_folders.discard_pending(job)
            undo()
            h.expect(h.dump_material(material) == before, "the refused bake changed the material")
            h.expect(not [f for f in os.listdir(directory) if ".ndfbake" in f], "files left: %s" % os.listdir(directory))
        job = bake.prepare(material, bake.BakeSettings(max_lobes=1))
        job.run()
        material.name = "Renamed"
        bake.finish(job)
        h.expect(bake.is_baked(bpy.data.materials["Renamed"]), "the renamed material did not get its bake")


def test_renamed_nodes_are_found_again():
    """Renamed after the bake, the Principled BSDF, the Normal Map, the group node and the EEVEE
    output are still the record's: a re-bake fits the Roughness set on the group node, and
    Revert restores the material exactly (names aside)."""
    from ndfbake.shading import bake_record
    from ndfbake.shading import group_node, node_builders
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory)
        tree = material.node_tree
        before = h.dump_material(material)
        bake.bake_material(material, bake.BakeSettings(max_lobes=2))
        for old, new in (("Principled BSDF", "Skin"), ("Normal Map", "NM"), ("ndfbake", "Filtered"),
                         (group_node.EEVEE_OUTPUT, "EO")):
            tree.nodes[old].name = new
        tree.nodes["Filtered"].inputs["Roughness"].default_value = 0.9
        bake.bake_material(material, bake.BakeSettings(max_lobes=1))
        settings = bake_record.record(material)["settings"]
        h.expect(abs(settings["roughness"] - 0.9) < 1e-6, "the re-bake fitted roughness %g, not the group "
                 "node's 0.9" % settings["roughness"])
        tree.nodes["ndfbake"].name = "Filtered again"
        bake.revert(material)
        h.expect(not [n.name for n in tree.nodes if bake_record.ROLE_KEY in n.keys() or n.get(node_builders.TAG)],
                 "nodes of the bake left: %s" % [n.name for n in tree.nodes])
        skin = tree.nodes["Skin"]
        h.expect([l.to_node.name for l in skin.outputs["BSDF"].links] == ["Material Output"], "Skin not at the output")
        h.expect(abs(skin.inputs["Roughness"].default_value - 0.9) < 1e-6, "the node's Roughness did not go back")
        skin.name, tree.nodes["NM"].name = "Principled BSDF", "Normal Map"
        skin.inputs["Roughness"].default_value = 0.35
        h.expect(h.dump_material(material) == before, "material differs after revert: %s"
                 % h.differences(before, h.dump_material(material)))


def test_a_deleted_principled_is_made_again():
    """The bypassed Principled BSDF deleted after the bake: a re-bake says so, and Revert makes it
    again from the group node's inputs and the recorded settings, where it was."""
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory)
        tree = material.node_tree
        tree.nodes["Principled BSDF"].distribution = "MULTI_GGX"
        before = h.dump_material(material)
        bake.bake_material(material, bake.BakeSettings(max_lobes=2))
        tree.nodes.remove(tree.nodes["Principled BSDF"])
        e = h.raised(bake.BakeError, lambda: bake.prepare(material), "a re-bake without the Principled")
        h.expect(e.code == "PRINCIPLED_GONE" and "Revert" in e.message, "%s: %s" % (e.code, e.message))
        bake.revert(material)
        h.expect(h.dump_material(material) == before, "material differs after revert: %s"
                 % h.differences(before, h.dump_material(material)))


def _two_principled_scene(directory):
    """The bumps scene with a second Principled BSDF beside the first, both taking their Normal
    from the Normal Map and mixed into the output; returns the material, the second BSDF and the
    Mix Shader (input 1: the first, input 2: the second)."""
    material = h.baked_scene(directory)
    tree = material.node_tree
    second = tree.nodes.new("ShaderNodeBsdfPrincipled")
    second.name = "Second BSDF"
    mix = tree.nodes.new("ShaderNodeMixShader")
    tree.links.new(tree.nodes["Principled BSDF"].outputs["BSDF"], mix.inputs[1])
    tree.links.new(second.outputs["BSDF"], mix.inputs[2])
    tree.links.new(mix.outputs[0], tree.nodes["Material Output"].inputs["Surface"])
    tree.links.new(tree.nodes["Normal Map"].outputs["Normal"], second.inputs["Normal"])
    return material, second, mix


def test_a_rebake_without_one_of_two_normal_maps_reverts_that_one():
    """Two Principled BSDFs baked; the Normal link of one removed: a re-bake bakes the other and
    gives the first its links back (its group node and node group go before the new bake's
    groups are named)."""
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        material, second, mix = _two_principled_scene(directory)
        tree = material.node_tree
        settings = bake.BakeSettings(max_lobes=2, level_of_detail="RENDERER")
        bake.bake_material(material, settings)
        h.expect(len(h.bake_record(material)["targets"]) == 2, "both Principled BSDFs baked")
        tree.links.remove(second.inputs["Normal"].links[0])
        bake.bake_material(material, settings)
        targets = h.bake_record(material)["targets"]
        h.expect([t["principled"] for t in targets] == ["Principled BSDF"], "re-baked: %s" % targets)
        h.expect(mix.inputs[2].links[0].from_node == second, "the second BSDF feeds the mix again")
        h.expect(len(h.bake_group_nodes(material)) == 1, "one group node: %s" % h.bake_group_nodes(material))
        h.expect(targets[0]["node_group"] in bpy.data.node_groups, "the record names the new group")


def test_a_rebake_without_a_renamed_one_of_two_normal_maps():
    """As above, but the dropped target's group node was renamed ("ndfbake" -> "bar") first: its
    nodes still carry the key "ndfbake" in their roles when the re-baked target's new node is
    named, and must not be taken for the new node's (nor it for theirs). The re-baked target keeps
    a working group node, the dropped one gets its links back, and Revert restores the material."""
    from ndfbake.shading import bake_record
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        material, second, mix = _two_principled_scene(directory)
        tree = material.node_tree
        first = tree.nodes["Principled BSDF"]
        before = h.dump_material(material)
        settings = bake.BakeSettings(max_lobes=2, level_of_detail="RENDERER")
        bake.bake_material(material, settings)
        groups = {t["principled"]: t["group_node"] for t in h.bake_record(material)["targets"]}
        h.expect(groups == {"Principled BSDF": "ndfbake", "Second BSDF": "ndfbake.001"}, "group nodes: %s" % groups)
        tree.nodes["ndfbake"].name = "bar"
        tree.links.remove(first.inputs["Normal"].links[0])
        bake.bake_material(material, settings)

        rec = h.bake_record(material)
        h.expect([t["principled"] for t in rec["targets"]] == ["Second BSDF"], "re-baked: %s" % rec["targets"])
        (target, principled, node, _), = bake_record.recorded_targets(tree, rec)
        h.expect(principled == second, "the record's Principled BSDF: %s" % principled)
        h.expect(node is not None and node.name == target["group_node"] and node in h.bake_group_nodes(material),
                 "the record's group node %r is not in the material: %s"
                 % (target["group_node"], [n.name for n in tree.nodes]))
        h.expect(node.node_tree is not None and node.node_tree.name == target["node_group"],
                 "the group node draws %s, the record names %s" % (node.node_tree, target["node_group"]))
        h.expect(mix.inputs[2].links[0].from_node == node, "the new group node does not feed the mix")
        h.expect(h.bake_group_nodes(material) == [node], "group nodes: %s" % [n.name for n in h.bake_group_nodes(material)])
        h.expect(mix.inputs[1].links[0].from_node == first, "the first BSDF does not feed the mix again")
        h.expect(bake_record.ROLE_KEY not in first.keys(), "the dropped BSDF keeps role %s"
                 % first.get(bake_record.ROLE_KEY))
        h.expect(second.get(bake_record.ROLE_KEY) == bake_record.node_role("principled", node.name),
                 "the second BSDF's role: %s" % second.get(bake_record.ROLE_KEY))

        bake.revert(material)
        tree.links.new(tree.nodes["Normal Map"].outputs["Normal"], first.inputs["Normal"])
        h.expect(h.dump_material(material) == before, "material differs after revert: %s"
                 % h.differences(before, h.dump_material(material)))


def test_a_deleted_group_node_beside_a_renamed_one_is_baked_again():
    """Two Principled BSDFs baked; the first's group node renamed ("ndfbake" -> "bar"), the
    second's deleted: the re-bake's new group node for the second must not take the first's role
    key with the name "ndfbake", or committing the first's replacement rekeys both. Both targets
    end with their group nodes, and Revert restores the material."""
    from ndfbake.shading import bake_record
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        material, _, _ = _two_principled_scene(directory)
        tree = material.node_tree
        before = h.dump_material(material)
        settings = bake.BakeSettings(max_lobes=2, level_of_detail="RENDERER")
        bake.bake_material(material, settings)
        tree.nodes["ndfbake"].name = "bar"
        tree.nodes.remove(tree.nodes["ndfbake.001"])
        bake.bake_material(material, settings)
        found = bake_record.recorded_targets(tree, h.bake_record(material))
        h.expect([(p.name if p else None, g.name if g else None) for _, p, g, _ in found]
                 == [(t["principled"], t["group_node"]) for t, _, _, _ in found]
                 and len(found) == 2 and len(h.bake_group_nodes(material)) == 2,
                 "the record's nodes: %s; roles: %s" % ([t for t, _, _, _ in found],
                                                         [(n.name, n.get(bake_record.ROLE_KEY)) for n in tree.nodes]))
        bake.revert(material)
        h.expect(h.dump_material(material) == before, "material differs after revert: %s"
                 % h.differences(before, h.dump_material(material)))


def _file_bytes(directory):
    """Every file under `directory`: its path relative to it and its bytes."""
    files = {}
    for root, _, names in os.walk(directory):
        for name in names:
            path = os.path.join(root, name)
            with open(path, "rb") as f:
                files[os.path.relpath(path, directory)] = f.read()
    return files


def test_a_rebake_while_a_lobe_file_is_open_elsewhere():
    """One of the previous bake's .exr files held open as another program would (on Windows,
    Python's open() shares it without FILE_SHARE_DELETE: it cannot be replaced or deleted) during
    the operator's re-bake: it succeeds, or it is cancelled with an error that names the file and
    leaves every file byte for byte and the material's nodes as they were, with no temporary files.
    Closed again, the re-bake succeeds."""
    from ndfbake.shading import bake_record
    from ndfbake.core import folder_names
    from ndfbake.blender import lobe_folders
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory)
        material.ndfbake_settings.max_lobes = 2
        h.expect(bpy.ops.ndfbake.bake(material="Bumpy") == {"FINISHED"}, "the first bake did not finish")
        first = lobe_folders.record_folder(bake_record.record(material))
        held = os.path.join(first, sorted(n for n in os.listdir(first) if n.endswith(".exr"))[0])
        files = _file_bytes(directory)
        material.ndfbake_settings.max_lobes = 1
        before = h.dump_material(material)
        with open(held, "rb"):
            try:
                outcome = bpy.ops.ndfbake.bake(material="Bumpy")
                error = None
            except RuntimeError as e:  # the operator's ERROR report, in a script
                outcome, error = {"CANCELLED"}, str(e)
        print("  re-bake with %s open: %s %s" % (os.path.basename(held), outcome, error or ""))
        if outcome == {"FINISHED"}:
            rec = bake_record.record(material)
            h.expect(rec["lobes"] == 1, "the re-bake's record: %s lobes" % rec["lobes"])
            second = lobe_folders.record_folder(rec)
            h.expect(os.path.normcase(second) != os.path.normcase(first), "the re-bake wrote into %s" % first)
            h.expect({k: v for k, v in _file_bytes(directory).items() if k in files} == files,
                     "the re-bake changed the previous bake's files")
            left = [n for n in os.listdir(second) if not folder_names.is_bake_file(n)]
            h.expect(not left, "files left in %s: %s" % (second, left))
        else:
            h.expect(outcome == {"CANCELLED"} and error, "the re-bake returned %s" % outcome)
            h.expect(os.path.basename(held) in error, "the error names no held file: %s" % error)
            h.expect(_file_bytes(directory) == files, "files changed: %s" % h.listing(directory))
            after = h.dump_material(material)
            h.expect(after == before, "the material changed: %s" % h.differences(before, after))
        h.expect(not [n for n in os.listdir(directory) if n.endswith(folder_names.PENDING_SUFFIX)],
                 "pending folders left: %s" % os.listdir(directory))

        material.ndfbake_settings.max_lobes = 3
        h.expect(bpy.ops.ndfbake.bake(material="Bumpy") == {"FINISHED"}, "the re-bake after closing the file")
        rec = bake_record.record(material)
        h.expect(rec["lobes"] == 3, "the last re-bake's record: %s lobes" % rec["lobes"])
        for name in rec["images"]:
            image = bpy.data.images[name]
            image.reload()
            h.expect(len(image.pixels) > 0, "image %s (%s) does not load" % (name, image.filepath))


if __name__ == "__main__":
    h.import_addon()
    h.run([test_a_material_changed_during_the_bake_is_not_baked, test_renamed_nodes_are_found_again,
           test_a_deleted_principled_is_made_again,
           test_a_rebake_without_one_of_two_normal_maps_reverts_that_one,
           test_a_rebake_without_a_renamed_one_of_two_normal_maps,
           test_a_deleted_group_node_beside_a_renamed_one_is_baked_again,
           test_a_rebake_while_a_lobe_file_is_open_elsewhere])
