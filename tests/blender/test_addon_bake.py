"""Scripted bakes of a normal-mapped material, and Revert, inside `blender -b`.

Run: blender -b --factory-startup --python-exit-code 1 --python tests/blender/test_addon_bake.py -- LIB

The scene: a plane whose material reads a 64² PNG normal map written by the library
(ndfb_synthesize + ndfb_normal_map_save) through Image Texture -> Normal Map -> Principled BSDF,
saved as a .blend in a temporary folder.
- A bake adds exactly one node (the group) and rewires only the Principled BSDF's output; the
  lobe textures land in //<material>.ndfbake/ with relative paths.
- Revert restores every node, link, socket value and property exactly (full dump compared) and
  the data-blocks as they were; the files and the folder go when the saved file is closed.
- An error while the nodes are built leaves the material exactly as it was before that bake: a
  failed re-bake keeps the previous bake (group node and its edits, node groups, images, record).
- Ctrl-Z after a re-bake and after a Revert gives back a material whose lobe images load
  (test_addon_folders.py).
- The operators work in the background; re-baking with fewer lobes emits a one-lobe group and
  drops the surplus textures; bake + save + reopen keeps working and reverts; bake_all bakes only
  what the scene renders; linked Principled inputs are carried over (muted links muted, and kept on
  Revert); packing works.
Animated inputs: test_addon_animation.py; re-bakes of edited materials: test_addon_rebake.py.
"""
import os
import re
import subprocess
import sys

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import test_addon_helpers as h  # noqa: E402


def _principled_count(tree, output="BSDF"):
    """The lobe BSDFs feeding the group's `output` ("BSDF" or nodes.EEVEE_BSDF)."""
    pattern = r"Lobe \d+ BSDF" if output == "BSDF" else r"Lobe \d+ EEVEE BSDF"
    return sum(1 for n in tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled" and re.fullmatch(pattern, n.name))


def _without_role(node_dump):
    """A dump_tree node without the role property a bake puts on the nodes its record names."""
    from ndfbake.shading import bake_record
    kind, props = node_dump
    return kind, dict(props, custom=[k for k in props["custom"] if k != bake_record.ROLE_KEY])


def test_blender_decodes_the_map_as_the_command_line_does():
    """The add-on bakes the pixels Blender decoded, `ndfbake bake` the file through OpenImageIO:
    for the same 8-bit PNG every lobe texel of every level must agree to the last bit (EM breaks
    a symmetric NDF's ties by rounding, so a last-bit difference can change the fit)."""
    library, _ = h.arguments()
    cli = os.path.join(os.path.dirname(library), "ndfbake.exe" if sys.platform == "win32" else "ndfbake")
    h.expect(os.path.isfile(cli), "no command line beside the library: %s" % cli)
    with h.scratch_dir() as directory:
        png = h.write_normal_map(os.path.join(directory, "bumps.png"), "bumps", 64)
        addon_out, cli_out = os.path.join(directory, "addon"), os.path.join(directory, "cli")
        h.bake_image_file(png, addon_out, max_lobes=4, roughness=0.5)
        subprocess.run([cli, "bake", png, "--out", cli_out, "--max-lobes", "4", "--brdf", "ggx:0.5", "--quiet"],
                       check=True)
        files = sorted(f for f in os.listdir(cli_out) if f.startswith("level") and f.endswith(".exr"))
        h.expect(files and files == sorted(f for f in os.listdir(addon_out) if f.startswith("level")
                                           and f.endswith(".exr")), "different lobe files: %s" % files)
        for name in files:
            pixels = []
            for folder in (addon_out, cli_out):
                image = bpy.data.images.load(os.path.join(folder, name))
                pixels.append(np.array(image.pixels[:], dtype=np.float32))
                bpy.data.images.remove(image)
            h.expect(np.array_equal(pixels[0], pixels[1]), "%s differs: largest difference %g"
                     % (name, float(np.abs(pixels[0] - pixels[1]).max())))
        print("  %d lobe files identical" % len(files))


def test_bake_adds_only_the_group_and_bypass():
    from ndfbake.shading import bake_record
    from ndfbake.shading import group_node, nodes
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory)
        before, data_before, files_before = h.dump_material(material), h.data_counts(), h.listing(directory)
        result = bake.bake_material(material, bake.BakeSettings(max_lobes=4))
        print("bake:", result.summary)
        h.expect(result.summary.endswith("level 0 filtered by the renderer (the scene has no active camera)"),
                 "the summary does not say why the level of detail is the renderer's: %s" % result.summary)
        after = h.dump_material(material)

        added = set(after["nodes"]) - set(before["nodes"])
        h.expect(added == {"ndfbake", group_node.EEVEE_OUTPUT}, "added nodes: %s" % added)
        h.expect(set(before["nodes"]) <= set(after["nodes"]), "a node went away")
        # The nodes the record names carry their role in it (found again when renamed), and
        # nothing else of any node changes; the Principled's output is bypassed (links, below).
        for name, node in before["nodes"].items():
            tagged = name in ("Principled BSDF", "Normal Map")
            h.expect((_without_role(after["nodes"][name]) if tagged else after["nodes"][name]) == node,
                     "node %s changed" % name)
            h.expect(tagged == (bake_record.ROLE_KEY in material.node_tree.nodes[name].keys()),
                     "node %s: role %s" % (name, material.node_tree.nodes[name].get(bake_record.ROLE_KEY)))
        removed_links = set(before["links"]) - set(after["links"])
        added_links = set(after["links"]) - set(before["links"])
        h.expect(removed_links == {("Principled BSDF", "BSDF", "Material Output", "Surface", False, True)},
                 "removed links: %s" % removed_links)
        h.expect(all("ndfbake" in (l[0], l[2]) or l[2] == group_node.EEVEE_OUTPUT for l in added_links),
                 "added links not at the group or its EEVEE output: %s" % added_links)
        baked_node = material.node_tree.nodes["ndfbake"]
        h.expect([l.to_node.name for l in baked_node.outputs["BSDF"].links] == ["Material Output"],
                 "group not at the output")
        h.expect([l.to_node.name for l in baked_node.outputs[nodes.EEVEE_BSDF].links] == [group_node.EEVEE_OUTPUT],
                 "the group's EEVEE BSDF does not reach the EEVEE output")
        eevee_output = material.node_tree.nodes[group_node.EEVEE_OUTPUT]
        h.expect(eevee_output.target == "EEVEE" and material.node_tree.nodes["Material Output"].target == "ALL",
                 "output targets: %s, %s" % (eevee_output.target, material.node_tree.nodes["Material Output"].target))
        h.expect(material.node_tree.get_output_node("EEVEE") == eevee_output
                 and material.node_tree.get_output_node("CYCLES") == material.node_tree.nodes["Material Output"],
                 "EEVEE must draw the EEVEE output, Cycles the user's")

        folder = os.path.join(directory, "Bumpy.ndfbake")
        files = sorted(os.listdir(folder))
        h.expect("report.json" in files and "level00_lobe0.exr" in files, "files: %s" % files)
        h.expect(not any(f.startswith(".") for f in files), "staging left behind: %s" % files)
        h.expect(result.lobes == len([f for f in files if f.startswith("level00_lobe")]), "lobe count")
        group = h.bake_group_nodes(material)[0].node_tree
        h.expect(_principled_count(group) == result.lobes == _principled_count(group, nodes.EEVEE_BSDF),
                 "one BSDF per lobe and output")
        for j in range(result.lobes):
            image = bpy.data.images["Bumpy lobe %d" % j]
            h.expect(image.filepath == "//Bumpy.ndfbake/level00_lobe%d.exr" % j, "path %s" % image.filepath)
            h.expect(image.colorspace_settings.name == "Non-Color", "colour space")
            h.expect(image.alpha_mode == "CHANNEL_PACKED", "alpha mode")
            h.expect(image.has_data or image.size[0] > 0, "image %d did not load" % j)

        reverted_folder, kept_for = bake.revert(material)
        h.expect(reverted_folder == folder and not kept_for, "revert: %s, kept for %s" % (reverted_folder, kept_for))
        h.expect(sorted(os.listdir(folder)) == files, "revert deleted files before the save")
        bpy.ops.wm.save_mainfile()
        h.expect(os.path.isdir(folder), "the save deleted the reverted folder (Ctrl-Z could still need it)")
        h.close_file()
        h.expect(not os.path.exists(folder), "closing the saved file left the reverted folder: %s"
                 % h.listing(directory))
        restored = h.dump_material(material)
        for name in set(before["nodes"]) | set(restored["nodes"]):
            h.expect(before["nodes"].get(name) == restored["nodes"].get(name), "node %s differs after revert:\n%s\n%s"
                     % (name, before["nodes"].get(name), restored["nodes"].get(name)))
        h.expect(restored == before, "material differs after revert")
        h.expect(h.data_counts() == data_before, "data-blocks differ after revert: %s vs %s"
                 % (h.data_counts(), data_before))
        h.expect([f for f in h.listing(directory) if f != "scene.blend1"] == files_before,
                 "files after revert and save: %s" % h.listing(directory))


def test_operators_rebake_fewer_lobes_and_revert():
    from ndfbake.shading import lobe_bsdfs
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory)
        material.ndfbake_settings.max_lobes = 4  # the panel's settings are the user's, not the bake's
        before, data_before = h.dump_material(material), h.data_counts()
        bpy.context.view_layer.objects.active = bpy.data.objects["Plane"]
        h.expect(bpy.ops.ndfbake.bake() == {"FINISHED"}, "bake operator")
        h.expect(len(h.bake_group_nodes(material)) == 1, "one group node")
        four = _principled_count(h.bake_group_nodes(material)[0].node_tree)
        h.expect(four == 4, "4 lobes, got %d" % four)

        material.ndfbake_settings.max_lobes = 1
        h.expect(bpy.ops.ndfbake.bake(material="Bumpy") == {"FINISHED"}, "re-bake")
        groups = h.bake_group_nodes(material)
        h.expect(len(groups) == 1, "re-bake left %d group nodes" % len(groups))
        tree = groups[0].node_tree
        h.expect(_principled_count(tree) == 1, "one-lobe group expected")
        mixes = [n.name for n in tree.nodes if n.bl_idname == "ShaderNodeMixShader"
                 and n.name != lobe_bsdfs.EMISSION_ALPHA and not n.name.startswith(lobe_bsdfs.ALPHA_MIX + " ")]
        h.expect(not mixes, "a one-lobe group mixes no lobes: %s" % mixes)
        rebaked = bpy.path.abspath(h.bake_record(material)["folder"])
        h.expect(os.path.basename(rebaked) == "Bumpy~2.ndfbake", "re-baked into %s" % rebaked)
        files = sorted(os.listdir(rebaked))
        h.expect("level00_lobe1.exr" not in files, "surplus lobe files in the new folder: %s" % files)
        h.expect(os.path.isdir(os.path.join(directory, "Bumpy.ndfbake")), "the previous bake's folder went before a save")
        h.expect("Bumpy lobe 1" not in bpy.data.images, "surplus lobe image kept")
        h.expect(len([g for g in bpy.data.node_groups if g.name.startswith("NDFB Bumpy")]) == 1,
                 "old material groups kept: %s" % [g.name for g in bpy.data.node_groups])

        # Four lobes allowed, but a tolerance that one lobe meets everywhere: the cheapest group.
        material.ndfbake_settings.max_lobes = 4
        material.ndfbake_settings.tolerance = 1.0
        h.expect(bpy.ops.ndfbake.bake(material="Bumpy") == {"FINISHED"}, "re-bake with a tolerance")
        tree = h.bake_group_nodes(material)[0].node_tree
        h.expect(_principled_count(tree) == 1, "a tolerance one lobe meets: %d lobes" % _principled_count(tree))

        h.expect(bpy.ops.ndfbake.revert(material="Bumpy") == {"FINISHED"}, "revert operator")
        h.expect(h.dump_material(material) == before, "material differs after revert")
        h.expect(h.data_counts() == data_before, "data-blocks differ after revert")
        bpy.ops.wm.save_mainfile()
        h.close_file()
        h.expect(not [f for f in os.listdir(directory) if f.endswith(".ndfbake")],
                 "lobe folders left after the save and close: %s" % os.listdir(directory))
        e = h.raised(RuntimeError, lambda: bpy.ops.ndfbake.revert(material="Bumpy"),
                     "reverting an unbaked material must fail")
        h.expect("has no ndfbake bake" in str(e), str(e))


def _lobe_roughness_sources(tree, output):
    """The node each lobe BSDF feeding the group's `output` takes its Roughness from, by lobe."""
    from ndfbake.shading import lobe_bsdfs
    found, stack = {}, [tree.nodes["Group Output"].inputs[output].links[0].from_node]
    while stack:
        node = stack.pop()
        if node.bl_idname in ("ShaderNodeMixShader", "ShaderNodeAddShader"):
            stack += [link.from_node for socket in node.inputs if socket.type == "SHADER" for link in socket.links]
        elif node.bl_idname == "ShaderNodeBsdfPrincipled" and not node.name.startswith(lobe_bsdfs.BASE_BSDF):
            found[node.name] = node.inputs["Roughness"].links[0].from_node.name
    return found


def test_cycles_lobes_narrowed_or_widened():
    """Cycles Lobes: Narrowed (the default) gives Cycles' lobes (the user's output) a grazing
    narrowing of their own (nodes.CYCLES_GRAZING_NARROWING) beside EEVEE's (its own output:
    EEVEE Legacy's narrowing, or in EEVEE Next the widened lobes); a
    re-bake with Widened gives Cycles the widened lobes only; bad values are refused."""
    from ndfbake.shading import lobe_nodes, nodes
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory)
        before = h.dump_material(material)
        result = bake.bake_material(material, bake.BakeSettings(max_lobes=4, cycles_lobes=nodes.NARROWED))
        h.expect("widened only" not in result.summary, result.summary)
        h.expect(h.bake_record(material)["settings"]["cycles_lobes"] == nodes.NARROWED, "record: %s" % h.bake_record(material))
        baked_node = material.node_tree.nodes["ndfbake"]
        tree = baked_node.node_tree
        cycles, eevee = (_lobe_roughness_sources(tree, output) for output in ("BSDF", nodes.EEVEE_BSDF))
        h.expect(len(cycles) == len(eevee) == result.lobes == _principled_count(tree)
                 == _principled_count(tree, nodes.EEVEE_BSDF) and not set(cycles.values()) & set(eevee.values()),
                 "Cycles' lobes %s, EEVEE's %s, %d lobes" % (cycles, eevee, result.lobes))
        for output, sources in (("BSDF", cycles), (nodes.EEVEE_BSDF, eevee)):
            if not nodes.default_grazing_narrowing()[output]:  # EEVEE Next: its lobes are drawn widened
                h.expect(all(source.startswith("Decode") for source in sources.values()),
                         "%s: a lobe does not take the decoded (widened) roughness: %s" % (output, sources))
                continue
            narrowing = {tree.nodes[source].inputs["Narrowing"].default_value for source in sources.values()}
            h.expect(all(tree.nodes[source].node_tree == lobe_nodes.grazing_roughness_group() for source in sources.values())
                     and narrowing == {nodes.default_grazing_narrowing()[output]},
                     "%s: a lobe's roughness is not the grazing group's at its constant: %s, %s"
                     % (output, sources, narrowing))
        h.expect(material.node_tree.get_output_node("CYCLES").inputs["Surface"].links[0].from_node == baked_node,
                 "Cycles does not draw the group")

        result = bake.bake_material(material, bake.BakeSettings(max_lobes=4, cycles_lobes=nodes.WIDENED))
        h.expect("Cycles draws the lobes widened only" in result.summary, result.summary)
        tree = material.node_tree.nodes["ndfbake"].node_tree
        cycles, eevee = (_lobe_roughness_sources(tree, output) for output in ("BSDF", nodes.EEVEE_BSDF))
        h.expect(len(cycles) == len(eevee) == _principled_count(tree) and not set(cycles) & set(eevee),
                 "after a Widened re-bake: Cycles' lobes %s, EEVEE's %s" % (cycles, eevee))
        h.expect(all(source.startswith("Decode") for source in cycles.values()),
                 "Cycles' lobes do not take the decoded (widened) roughness: %s" % cycles)
        h.expect(h.bake_record(material)["settings"]["cycles_lobes"] == nodes.WIDENED, "record after the re-bake")

        bake.revert(material)
        h.expect(h.dump_material(material) == before, "material differs after revert")
        e = h.raised(bake.BakeError, lambda: bake.bake_material(material, bake.BakeSettings(cycles_lobes="SHARP")),
                     "an unknown Cycles Lobes value must be refused")
        h.expect(e.code == "BAD_SETTINGS" and "SHARP" in e.message, "%s: %s" % (e.code, e.message))
        h.expect(h.dump_material(material) == before, "a refused bake changed the material")


def test_grazing_narrowing_is_a_bake_parameter():
    """A study's other narrowing constants (BakeSettings.grazing_narrowing) reach each output's
    grazing nodes; a C of 0 draws that output widened; a missing output or a negative C is refused."""
    from ndfbake.shading import nodes
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory)
        before = h.dump_material(material)
        bake.bake_material(material, bake.BakeSettings(max_lobes=2, grazing_narrowing={"BSDF": 2.5,
                                                                                       nodes.EEVEE_BSDF: 0.0}))
        tree = material.node_tree.nodes["ndfbake"].node_tree
        cycles, eevee = (_lobe_roughness_sources(tree, output) for output in ("BSDF", nodes.EEVEE_BSDF))
        h.expect({tree.nodes[source].inputs["Narrowing"].default_value for source in cycles.values()} == {2.5},
                 "Cycles' lobes: %s" % cycles)
        h.expect(all(source.startswith("Decode") for source in eevee.values()), "EEVEE's lobes: %s" % eevee)
        bake.revert(material)
        for bad in ({"BSDF": 2.5}, {"BSDF": -1.0, nodes.EEVEE_BSDF: 0.0}, {"BSDF": float("nan"), nodes.EEVEE_BSDF: 0.0}):
            e = h.raised(bake.BakeError, lambda: bake.bake_material(material, bake.BakeSettings(grazing_narrowing=bad)),
                         "grazing narrowing %r must be refused" % bad)
            h.expect(e.code == "BAD_SETTINGS" and "grazing narrowing" in e.message, "%s: %s" % (e.code, e.message))
        h.expect(h.dump_material(material) == before, "a refused bake changed the material")


def test_panel_keeps_its_scan_until_the_material_changes():
    """The panel's redraws read the material's scan once (panel_state); a change to the material's
    nodes, then the depsgraph's update (what precedes a redraw in the UI), brings a new scan, and
    the panel shows what it found."""
    from ndfbake.shading import material_scan
    from ndfbake.blender import ui
    scans = []
    original = material_scan.scan

    def counted(material):
        scans.append(material.name)
        return original(material)
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory)
        material_scan.scan = counted
        try:
            first = h.draw_panel(ui, material)
            h.expect(h.draw_panel(ui, material) == first and scans == ["Bumpy"], "scans %s" % scans)
            h.expect(any(label.startswith("Normal map: ") for label in first), "labels %s" % first)
            tree = material.node_tree
            tree.links.remove(tree.nodes["Normal Map"].outputs["Normal"].links[0])
            bpy.context.view_layer.update()
            changed = h.draw_panel(ui, material)
            h.expect(scans == ["Bumpy", "Bumpy"], "after the change: scans %s" % scans)
            h.expect(not any(label.startswith("Normal map: ") for label in changed), "labels %s" % changed)
        finally:
            material_scan.scan = original


def test_save_reopen_then_revert():
    from ndfbake.shading import specular_split
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory)
        before = h.dump_material(material)
        bake.bake_material(material, bake.BakeSettings(max_lobes=2))
        bpy.ops.wm.save_mainfile()
        bpy.ops.wm.open_mainfile(filepath=os.path.join(directory, "scene.blend"))
        material = bpy.data.materials["Bumpy"]
        h.expect(bake.is_baked(material), "bake record lost on save")
        for j in range(2):
            image = bpy.data.images["Bumpy lobe %d" % j]
            h.expect(image.filepath.startswith("//"), "absolute path saved: %s" % image.filepath)
            h.expect(image.size[0] == 64, "image %d does not load after reopening (size %s)" % (j, tuple(image.size)))
        split = bpy.app.version >= (4, 0, 0)   # Principled v2: the specular split draws the diffuse once
        tables = [i for i in bpy.data.images if i.get(specular_split.TABLE_KEY) is not None]
        size = (specular_split.SLICE_WIDTH * specular_split.SLICES, 16)
        h.expect(len(tables) == (1 if split else 0) and all(i.packed_file and tuple(i.size) == size for i in tables),
                 "the specular layer's table after reopening: %s" % [(i.name, tuple(i.size)) for i in tables])
        bake.revert(material)
        h.expect(h.dump_material(material) == before, "material differs after revert in the reopened file: %s"
                 % h.differences(before, h.dump_material(material)))
        left = [i.name for i in bpy.data.images if i.name.startswith("Bumpy lobe") or i.get(specular_split.TABLE_KEY)]
        h.expect(not left, "images left after Revert: %s" % left)
        h.expect(not any(g.get("ndfbake") for g in bpy.data.node_groups), "node groups left after Revert: %s"
                 % [g.name for g in bpy.data.node_groups])
        bpy.ops.wm.save_mainfile()
        h.close_file()
        # A saved .blend (and its .blend1 backup) used the folder: it is not deleted automatically.
        h.expect(os.path.isdir(os.path.join(directory, "Bumpy.ndfbake")), "the folder a saved file used was deleted")


def test_bake_all_bakes_what_the_scene_renders():
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        h.reset_scene()
        png = h.write_normal_map(os.path.join(directory, "normal.png"), "fbm", 32)
        seen = h.normal_mapped_material("Seen", png)
        hidden = h.normal_mapped_material("Hidden", png)
        plain = bpy.data.materials.new("Plain")
        h.enable_nodes(plain)
        h.plane_with(seen, "A")
        h.plane_with(plain, "B")
        h.plane_with(hidden, "C").hide_render = True
        # Not rendered either: objects in a render-disabled collection, or in one the view layer
        # excludes (the same material would be needed if any of these rendered).
        scene = bpy.context.scene
        for name, hide in (("Off in renders", True), ("Excluded", False)):
            collection = bpy.data.collections.new(name)
            scene.collection.children.link(collection)
            collection.hide_render = hide
            obj = h.plane_with(h.normal_mapped_material("In " + name, png), name + " plane")
            scene.collection.objects.unlink(obj)
            collection.objects.link(obj)
        bpy.context.view_layer.layer_collection.children["Excluded"].exclude = True
        bpy.ops.wm.save_as_mainfile(filepath=os.path.join(directory, "scene.blend"))
        needed = [m.name for m in bake.materials_needing_bake(bpy.context.scene)]
        h.expect(needed == ["Seen"], "needed: %s" % needed)
        plain_before, hidden_before = h.dump_material(plain), h.dump_material(hidden)
        h.expect(bpy.ops.ndfbake.bake_all() == {"FINISHED"}, "bake_all")
        h.expect(bake.is_baked(seen) and not bake.is_baked(hidden) and not bake.is_baked(plain), "baked set")
        h.expect(h.dump_material(plain) == plain_before and h.dump_material(hidden) == hidden_before,
                 "bake_all touched a material it should not")
        h.expect(sorted(os.listdir(directory)) == ["Seen.ndfbake", "normal.png", "scene.blend"],
                 "files: %s" % sorted(os.listdir(directory)))


def test_linked_inputs_are_carried_and_restored():
    from ndfbake.shading import lobe_bsdfs
    from ndfbake.shading import blender_compat
    from ndfbake.blender import bake
    specular = blender_compat.principled_input("Specular")
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory, metallic=1.0)
        tree = material.node_tree
        principled = tree.nodes["Principled BSDF"]
        rgb = tree.nodes.new("ShaderNodeRGB")
        rgb.outputs[0].default_value = (0.9, 0.5, 0.2, 1.0)
        value = tree.nodes.new("ShaderNodeValue")
        value.outputs[0].default_value = 0.42
        tree.links.new(rgb.outputs[0], principled.inputs["Base Color"])
        tree.links.new(value.outputs[0], principled.inputs["Roughness"])
        tree.nodes["Normal Map"].inputs["Strength"].default_value = 0.8
        tree.nodes["Normal Map"].uv_map = "UVMap"
        mapping = tree.nodes.new("ShaderNodeMapping")
        coords = tree.nodes.new("ShaderNodeTexCoord")
        tree.links.new(coords.outputs["UV"], mapping.inputs["Vector"])
        tree.links.new(mapping.outputs["Vector"], tree.nodes["Normal Texture"].inputs["Vector"])
        principled.inputs[specular].default_value = 0.7
        # A muted link renders as the input's value, and stays muted on the group node and after Revert.
        glow = tree.nodes.new("ShaderNodeValue")
        glow.outputs[0].default_value = 5.0
        principled.inputs["Emission Strength"].default_value = 0.25
        tree.links.new(glow.outputs[0], principled.inputs["Emission Strength"]).is_muted = True
        # Muted, a Clearcoat Normal link renders as the geometry's normal, which a group input
        # cannot give: not carried (Blender still says is_linked here, before a tree update).
        clearcoat = principled.inputs[blender_compat.principled_input("Clearcoat Normal")]
        tree.links.new(tree.nodes["Normal Map"].outputs["Normal"], clearcoat).is_muted = True
        h.expect(clearcoat.name not in [s.name for s in lobe_bsdfs.carried_inputs(principled)],
                 "a muted Clearcoat Normal link is carried (is_linked: %s)" % clearcoat.is_linked)
        bpy.ops.wm.save_mainfile()
        before = h.dump_material(material)

        bake.bake_material(material, bake.BakeSettings(max_lobes=2))
        baked_node = h.bake_group_nodes(material)[0]
        emission = baked_node.inputs["Emission Strength"]
        h.expect([(l.from_node, l.is_muted) for l in emission.links] == [(glow, True)],
                 "the muted Emission Strength link is not carried muted: %s" % [(l.from_node.name, l.is_muted)
                                                                             for l in emission.links])
        h.expect(abs(emission.default_value - 0.25) < 1e-6, "Emission Strength value under the muted link")
        h.expect(baked_node.inputs["Base Color"].links[0].from_node == rgb, "Base Color not carried")
        h.expect(baked_node.inputs["Roughness"].links[0].from_node == value, "Roughness not carried")
        h.expect(baked_node.inputs["Vector"].links[0].from_node == mapping, "texture coordinates not carried")
        h.expect(abs(baked_node.inputs["Normal Strength"].default_value - 0.8) < 1e-6, "strength")
        h.expect(abs(baked_node.inputs[specular].default_value - 0.7) < 1e-6, "Specular value")
        h.expect(abs(baked_node.inputs["Metallic"].default_value - 1.0) < 1e-6, "Metallic value")
        inner = baked_node.node_tree
        h.expect(all(n.uv_map == "UVMap" for n in inner.nodes if n.bl_idname == "ShaderNodeNormalMap"), "uv map")
        rec = material_record(material)
        h.expect(abs(rec["settings"]["roughness"] - 0.5) < 1e-6, "linked roughness: the fit uses 0.5")
        bake.revert(material)
        h.expect(h.dump_material(material) == before, "material differs after revert: %s"
                 % h.differences(before, h.dump_material(material)))


def test_a_user_graph_downstream_gets_no_eevee_output():
    """The Principled feeds a Mix Shader, not the output: the graph after it is the user's, so the
    bake adds no EEVEE output (both engines draw the group's BSDF through the user's mix), and a
    displacement on the output stays where it is; Revert restores everything."""
    from ndfbake.shading import group_node, nodes
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory, metallic=1.0)
        tree = material.node_tree
        output = tree.nodes["Material Output"]
        mix = tree.nodes.new("ShaderNodeMixShader")
        mix.inputs["Fac"].default_value = 0.25
        tree.links.new(tree.nodes["Principled BSDF"].outputs["BSDF"], mix.inputs[1])
        tree.links.new(tree.nodes.new("ShaderNodeBsdfDiffuse").outputs[0], mix.inputs[2])
        tree.links.new(mix.outputs[0], output.inputs["Surface"])
        tree.links.new(tree.nodes.new("ShaderNodeDisplacement").outputs[0], output.inputs["Displacement"])
        bpy.ops.wm.save_mainfile()
        before = h.dump_material(material)

        bake.bake_material(material, bake.BakeSettings(max_lobes=2))
        baked_node = h.bake_group_nodes(material)[0]
        h.expect(group_node.EEVEE_OUTPUT not in tree.nodes, "an EEVEE output was added behind the user's mix")
        h.expect([l.to_node for l in baked_node.outputs["BSDF"].links] == [mix], "the group does not feed the mix")
        h.expect(not baked_node.outputs[nodes.EEVEE_BSDF].is_linked, "the EEVEE BSDF is wired somewhere")
        h.expect(tree.get_output_node("EEVEE") == output, "EEVEE no longer draws the user's output")
        bake.revert(material)
        h.expect(h.dump_material(material) == before, "material differs after revert: %s"
                 % h.differences(before, h.dump_material(material)))


def material_record(material):
    from ndfbake.shading import bake_record
    return bake_record.record(material)


def test_pack_option():
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory)
        data_before = h.data_counts()
        bake.bake_material(material, bake.BakeSettings(max_lobes=1, pack=True))
        image = bpy.data.images["Bumpy lobe 0"]
        h.expect(image.packed_file is not None, "not packed")
        bake.revert(material)
        h.expect(h.data_counts() == data_before, "packed image left after revert")


def test_failure_while_building_nodes_rolls_back():
    """An error while the nodes are built (a bug) leaves the material as it was before that bake:
    unbaked after a failed first bake; after a failed re-bake, with the previous bake in place
    (its group node with the user's edit on it, node groups, images, drivers, record), so that
    bake_materials' promise holds. Only the failed bake's files go."""
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory)
        bpy.ops.object.camera_add(location=(0.0, 0.0, 4.0))  # level of detail: drivers on the node
        bpy.context.scene.camera = bpy.context.active_object
        bpy.ops.wm.save_mainfile()
        before, data_before, files_before = h.dump_material(material), h.data_counts(), h.listing(directory)
        error = h.bake_with_a_bug_in(material, "_wire_group_node", max_lobes=2)
        h.expect(error.code == "INTERNAL" and "simulated bug" in error.message
                 and "as it was before this bake" in error.message, error.message)
        h.expect(h.dump_material(material) == before, "a failed first bake left a half-built material: %s"
                 % h.differences(before, h.dump_material(material)))
        h.expect(h.data_counts() == data_before, "data-blocks left: %s" % h.data_counts())

        bake.bake_material(material, bake.BakeSettings(max_lobes=2))
        tree = material.node_tree
        h.expect(tree.animation_data is not None and tree.animation_data.drivers, "the bake made no drivers")
        tree.nodes["ndfbake"].inputs["Base Color"].default_value = (0.0, 0.0, 1.0, 1.0)  # the user's edit
        bpy.ops.wm.save_mainfile()
        baked, data_baked, record = h.dump_material(material), h.data_counts(), h.bake_record(material)
        files_baked = [f for f in h.listing(directory) if f != "scene.blend1"]
        for function in ("build_material_group", "_wire_group_node", "drive_lod_inputs"):
            error = h.bake_with_a_bug_in(material, function, max_lobes=3)
            h.expect(error.code == "INTERNAL" and "simulated bug" in error.message
                     and "as it was before this bake" in error.message, error.message)
            h.expect(h.dump_material(material) == baked, "a re-bake failing in %s changed the material: %s"
                     % (function, h.differences(baked, h.dump_material(material))))
            h.expect(h.data_counts() == data_baked, "a re-bake failing in %s: data-blocks %s, before %s"
                     % (function, h.data_counts(), data_baked))
            h.expect(h.bake_record(material) == record, "a re-bake failing in %s changed the record" % function)
        h.expect(tuple(tree.nodes["ndfbake"].inputs["Base Color"].default_value) == (0.0, 0.0, 1.0, 1.0),
                 "the edit on the group node went")
        bpy.ops.wm.save_mainfile()
        h.close_file()  # the failed bakes' folders, which no saved file uses, go
        h.expect([f for f in h.listing(directory) if f != "scene.blend1"] == files_baked,
                 "files after the save: %s, after the bake: %s" % (h.listing(directory), files_baked))
        h.expect(files_baked != files_before, "the bake wrote no files")


if __name__ == "__main__":
    h.import_addon()
    h.run([test_blender_decodes_the_map_as_the_command_line_does, test_bake_adds_only_the_group_and_bypass,
           test_failure_while_building_nodes_rolls_back, test_operators_rebake_fewer_lobes_and_revert,
           test_cycles_lobes_narrowed_or_widened,
           test_grazing_narrowing_is_a_bake_parameter, test_panel_keeps_its_scan_until_the_material_changes,
           test_save_reopen_then_revert,
           test_bake_all_bakes_what_the_scene_renders, test_linked_inputs_are_carried_and_restored,
           test_a_user_graph_downstream_gets_no_eevee_output, test_pack_option])
