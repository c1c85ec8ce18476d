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
  Revert); packing works; keyframes and drivers on the Principled's inputs (with their modifiers)
  move to the group node's and go again on Revert; edits on the group node survive a re-bake and
  Revert; two materials sharing an action bake and revert independently; a re-bake that no longer
  finds one of two normal-map chains reverts that one and re-bakes the other, also where the
  user renamed that one's group node; a renamed group node keeps its role key from a new one.
"""
import os
import re
import subprocess
import sys

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import test_addon_helpers as h  # noqa: E402


def _record(material):
    from ndfbake import material_scan
    return material_scan.record(material)


def _group_nodes(material):
    return [n for n in material.node_tree.nodes if n.bl_idname == "ShaderNodeGroup" and n.get("ndfbake")]


def _principled_count(tree, output="BSDF"):
    """The lobe BSDFs feeding the group's `output` ("BSDF" or nodes.EEVEE_BSDF)."""
    pattern = r"Lobe \d+ BSDF" if output == "BSDF" else r"Lobe \d+ EEVEE BSDF"
    return sum(1 for n in tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled" and re.fullmatch(pattern, n.name))


def _without_role(node_dump):
    """A dump_tree node without the role property a bake puts on the nodes its record names."""
    from ndfbake import material_scan
    kind, props = node_dump
    return kind, dict(props, custom=[k for k in props["custom"] if k != material_scan.ROLE_KEY])


def test_blender_decodes_the_map_as_the_command_line_does():
    """The add-on bakes the pixels Blender decoded, `ndfbake bake` the file through OpenImageIO:
    for the same 8-bit PNG every lobe texel of every level must agree to the last bit (EM breaks
    a symmetric NDF's ties by rounding, so a last-bit difference can change the fit)."""
    library, _ = h.arguments()
    cli = os.path.join(os.path.dirname(library), "ndfbake")
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
    from ndfbake import bake, group_node, material_scan, nodes
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
            h.expect(tagged == (material_scan.ROLE_KEY in material.node_tree.nodes[name].keys()),
                     "node %s: role %s" % (name, material.node_tree.nodes[name].get(material_scan.ROLE_KEY)))
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
        group = _group_nodes(material)[0].node_tree
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
    from ndfbake import nodes
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory)
        material.ndfbake_settings.max_lobes = 4  # the panel's settings are the user's, not the bake's
        before, data_before = h.dump_material(material), h.data_counts()
        bpy.context.view_layer.objects.active = bpy.data.objects["Plane"]
        h.expect(bpy.ops.ndfbake.bake() == {"FINISHED"}, "bake operator")
        h.expect(len(_group_nodes(material)) == 1, "one group node")
        four = _principled_count(_group_nodes(material)[0].node_tree)
        h.expect(four == 4, "4 lobes, got %d" % four)

        material.ndfbake_settings.max_lobes = 1
        h.expect(bpy.ops.ndfbake.bake(material="Bumpy") == {"FINISHED"}, "re-bake")
        groups = _group_nodes(material)
        h.expect(len(groups) == 1, "re-bake left %d group nodes" % len(groups))
        tree = groups[0].node_tree
        h.expect(_principled_count(tree) == 1, "one-lobe group expected")
        mixes = [n.name for n in tree.nodes if n.bl_idname == "ShaderNodeMixShader"
                 and n.name != nodes.EMISSION_ALPHA and not n.name.startswith(nodes.ALPHA_MIX + " ")]
        h.expect(not mixes, "a one-lobe group mixes no lobes: %s" % mixes)
        rebaked = bpy.path.abspath(_record(material)["folder"])
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
        tree = _group_nodes(material)[0].node_tree
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
    from ndfbake import nodes
    found, stack = {}, [tree.nodes["Group Output"].inputs[output].links[0].from_node]
    while stack:
        node = stack.pop()
        if node.bl_idname in ("ShaderNodeMixShader", "ShaderNodeAddShader"):
            stack += [link.from_node for socket in node.inputs if socket.type == "SHADER" for link in socket.links]
        elif node.bl_idname == "ShaderNodeBsdfPrincipled" and node.name != nodes.BASE_BSDF:
            found[node.name] = node.inputs["Roughness"].links[0].from_node.name
    return found


def test_cycles_lobes_narrowed_or_widened():
    """Cycles Lobes: Narrowed (the default) gives Cycles' lobes (the user's output) a grazing
    narrowing of their own (nodes.GRAZING_NARROWING["BSDF"]) beside EEVEE's (its own output:
    EEVEE Legacy's narrowing, or in EEVEE Next the widened lobes); a
    re-bake with Widened gives Cycles the widened lobes only; bad values are refused."""
    from ndfbake import bake, lobe_nodes, nodes
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory)
        before = h.dump_material(material)
        result = bake.bake_material(material, bake.BakeSettings(max_lobes=4, cycles_lobes=nodes.NARROWED))
        h.expect("widened only" not in result.summary, result.summary)
        h.expect(_record(material)["settings"]["cycles_lobes"] == nodes.NARROWED, "record: %s" % _record(material))
        baked_node = material.node_tree.nodes["ndfbake"]
        tree = baked_node.node_tree
        cycles, eevee = (_lobe_roughness_sources(tree, output) for output in ("BSDF", nodes.EEVEE_BSDF))
        h.expect(len(cycles) == len(eevee) == result.lobes == _principled_count(tree)
                 == _principled_count(tree, nodes.EEVEE_BSDF) and not set(cycles.values()) & set(eevee.values()),
                 "Cycles' lobes %s, EEVEE's %s, %d lobes" % (cycles, eevee, result.lobes))
        for output, sources in (("BSDF", cycles), (nodes.EEVEE_BSDF, eevee)):
            if not nodes.GRAZING_NARROWING[output]:  # EEVEE Next: its lobes are drawn widened
                h.expect(all(source.startswith("Decode") for source in sources.values()),
                         "%s: a lobe does not take the decoded (widened) roughness: %s" % (output, sources))
                continue
            narrowing = {tree.nodes[source].inputs["Narrowing"].default_value for source in sources.values()}
            h.expect(all(tree.nodes[source].node_tree == lobe_nodes.grazing_roughness_group() for source in sources.values())
                     and narrowing == {nodes.GRAZING_NARROWING[output]},
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
        h.expect(_record(material)["settings"]["cycles_lobes"] == nodes.WIDENED, "record after the re-bake")

        bake.revert(material)
        h.expect(h.dump_material(material) == before, "material differs after revert")
        e = h.raised(bake.BakeError, lambda: bake.bake_material(material, bake.BakeSettings(cycles_lobes="SHARP")),
                     "an unknown Cycles Lobes value must be refused")
        h.expect(e.code == "BAD_SETTINGS" and "SHARP" in e.message, "%s: %s" % (e.code, e.message))
        h.expect(h.dump_material(material) == before, "a refused bake changed the material")


def test_save_reopen_then_revert():
    from ndfbake import bake
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
        bake.revert(material)
        h.expect(h.dump_material(material) == before, "material differs after revert in the reopened file")
        h.expect(not any(i.name.startswith("Bumpy lobe") for i in bpy.data.images), "lobe images left")
        bpy.ops.wm.save_mainfile()
        h.close_file()
        # A saved .blend (and its .blend1 backup) used the folder: it is not deleted automatically.
        h.expect(os.path.isdir(os.path.join(directory, "Bumpy.ndfbake")), "the folder a saved file used was deleted")


def test_bake_all_bakes_what_the_scene_renders():
    from ndfbake import bake
    with h.scratch_dir() as directory:
        h.reset_scene()
        png = h.write_normal_map(os.path.join(directory, "normal.png"), "fbm", 32)
        seen = h.normal_mapped_material("Seen", png)
        hidden = h.normal_mapped_material("Hidden", png)
        plain = bpy.data.materials.new("Plain")
        plain.use_nodes = True
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
    from ndfbake import bake, blender_compat, nodes
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
        h.expect(clearcoat.name not in [s.name for s in nodes.carried_inputs(principled)],
                 "a muted Clearcoat Normal link is carried (is_linked: %s)" % clearcoat.is_linked)
        bpy.ops.wm.save_mainfile()
        before = h.dump_material(material)

        bake.bake_material(material, bake.BakeSettings(max_lobes=2))
        baked_node = _group_nodes(material)[0]
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
    from ndfbake import bake, group_node, nodes
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
        baked_node = _group_nodes(material)[0]
        h.expect(group_node.EEVEE_OUTPUT not in tree.nodes, "an EEVEE output was added behind the user's mix")
        h.expect([l.to_node for l in baked_node.outputs["BSDF"].links] == [mix], "the group does not feed the mix")
        h.expect(not baked_node.outputs[nodes.EEVEE_BSDF].is_linked, "the EEVEE BSDF is wired somewhere")
        h.expect(tree.get_output_node("EEVEE") == output, "EEVEE no longer draws the user's output")
        bake.revert(material)
        h.expect(h.dump_material(material) == before, "material differs after revert: %s"
                 % h.differences(before, h.dump_material(material)))


def material_record(material):
    from ndfbake import material_scan
    return material_scan.record(material)


def test_pack_option():
    from ndfbake import bake
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory)
        data_before = h.data_counts()
        bake.bake_material(material, bake.BakeSettings(max_lobes=1, pack=True))
        image = bpy.data.images["Bumpy lobe 0"]
        h.expect(image.packed_file is not None, "not packed")
        bake.revert(material)
        h.expect(h.data_counts() == data_before, "packed image left after revert")


def _bake_with_a_bug_in(material, function, **settings):
    """Bakes with <function> of the node modules (nodes, group_node, lod_nodes) raising, and returns
    the BakeError the bake must end with."""
    from ndfbake import bake, group_node, lod_nodes, nodes
    module = next(m for m in (nodes, group_node, lod_nodes) if hasattr(m, function))
    original = getattr(module, function)

    def broken(*args, **kwargs):
        raise RuntimeError("simulated bug")
    setattr(module, function, broken)
    try:
        return h.raised(bake.BakeError, lambda: bake.bake_material(material, bake.BakeSettings(**settings)),
                        "the simulated bug in %s.%s did not surface" % (module.__name__, function))
    finally:
        setattr(module, function, original)


def test_failure_while_building_nodes_rolls_back():
    """An error while the nodes are built (a bug) leaves the material as it was before that bake:
    unbaked after a failed first bake; after a failed re-bake, with the previous bake in place
    (its group node with the user's edit on it, node groups, images, drivers, record), so that
    bake_materials' promise holds. Only the failed bake's files go."""
    from ndfbake import bake
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory)
        bpy.ops.object.camera_add(location=(0.0, 0.0, 4.0))  # level of detail: drivers on the node
        bpy.context.scene.camera = bpy.context.active_object
        bpy.ops.wm.save_mainfile()
        before, data_before, files_before = h.dump_material(material), h.data_counts(), h.listing(directory)
        error = _bake_with_a_bug_in(material, "_wire_group_node", max_lobes=2)
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
        baked, data_baked, record = h.dump_material(material), h.data_counts(), _record(material)
        files_baked = [f for f in h.listing(directory) if f != "scene.blend1"]
        for function in ("build_material_group", "_wire_group_node", "drive_lod_inputs"):
            error = _bake_with_a_bug_in(material, function, max_lobes=3)
            h.expect(error.code == "INTERNAL" and "simulated bug" in error.message
                     and "as it was before this bake" in error.message, error.message)
            h.expect(h.dump_material(material) == baked, "a re-bake failing in %s changed the material: %s"
                     % (function, h.differences(baked, h.dump_material(material))))
            h.expect(h.data_counts() == data_baked, "a re-bake failing in %s: data-blocks %s, before %s"
                     % (function, h.data_counts(), data_baked))
            h.expect(_record(material) == record, "a re-bake failing in %s changed the record" % function)
        h.expect(tuple(tree.nodes["ndfbake"].inputs["Base Color"].default_value) == (0.0, 0.0, 1.0, 1.0),
                 "the edit on the group node went")
        bpy.ops.wm.save_mainfile()
        h.close_file()  # the failed bakes' folders, which no saved file uses, go
        h.expect([f for f in h.listing(directory) if f != "scene.blend1"] == files_baked,
                 "files after the save: %s, after the bake: %s" % (h.listing(directory), files_baked))
        h.expect(files_baked != files_before, "the bake wrote no files")


def _ramped_scene(directory):
    """baked_scene, with the Principled's Emission Strength keyed 0 at frame 1 and 10 at frame 11
    (about 5 at frame 6). Returns the material and that input."""
    material = h.baked_scene(directory)
    strength = material.node_tree.nodes["Principled BSDF"].inputs["Emission Strength"]
    for frame, value in ((1, 0.0), (11, 10.0)):
        strength.default_value = value
        strength.keyframe_insert("default_value", frame=frame)
    return material, strength


def test_animated_inputs_keep_animating():
    from ndfbake import bake
    with h.scratch_dir() as directory:
        material, strength = _ramped_scene(directory)
        tree = material.node_tree
        principled = tree.nodes["Principled BSDF"]
        curve = h.tree_fcurves(tree)[0]
        curve.modifiers.new("CYCLES")  # repeats the 1..11 ramp
        driver = principled.inputs["Metallic"].driver_add("default_value").driver
        driver.type = "SCRIPTED"
        driver.expression = "0.25"
        paths_before = sorted(f.data_path for f in h.tree_fcurves(tree))
        drivers_before = sorted(f.data_path for f in tree.animation_data.drivers)
        bpy.ops.wm.save_mainfile()
        bake.bake_material(material, bake.BakeSettings(max_lobes=2))
        group = tree.nodes["ndfbake"]
        scene = bpy.context.scene
        for frame, expected in ((1, 0.0), (6, 5.0), (11, 10.0), (16, 5.0)):
            scene.frame_set(frame)
            value = group.inputs["Emission Strength"].default_value
            h.expect(abs(value - expected) < 0.6, "Emission Strength at frame %d: %g, expected about %g (the Cycles "
                     "modifier repeats the ramp)" % (frame, value, expected))
        h.expect(abs(group.inputs["Metallic"].default_value - 0.25) < 1e-6, "the driver on Metallic was not carried")
        bake.revert(material)
        h.expect(sorted(f.data_path for f in h.tree_fcurves(tree)) == paths_before,
                 "keyframes after revert: %s" % [f.data_path for f in h.tree_fcurves(tree)])
        h.expect(sorted(f.data_path for f in tree.animation_data.drivers) == drivers_before, "drivers after revert")


def test_edits_on_the_group_node_survive_rebake_and_revert():
    """After a bake the group node holds the material's inputs: a colour set and keyframed there
    is what a re-bake starts from and what Revert leaves on the Principled BSDF."""
    from ndfbake import bake
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory)
        bake.bake_material(material, bake.BakeSettings(max_lobes=2))
        tree = material.node_tree
        color = tree.nodes["ndfbake"].inputs["Base Color"]
        for frame, green in ((1, 0.5), (11, 1.0)):
            color.default_value = (0.0, green, 0.0, 1.0)
            color.keyframe_insert("default_value", frame=frame)
        bake.bake_material(material, bake.BakeSettings(max_lobes=1))
        scene = bpy.context.scene
        scene.frame_set(11)
        h.expect(tuple(round(c, 3) for c in tree.nodes["ndfbake"].inputs["Base Color"].default_value)
                 == (0.0, 1.0, 0.0, 1.0), "the re-bake lost the colour keyframed on the node")
        bake.revert(material)
        scene.frame_set(1)
        principled = tree.nodes["Principled BSDF"].inputs["Base Color"]
        h.expect(tuple(round(c, 3) for c in principled.default_value) == (0.0, 0.5, 0.0, 1.0),
                 "Revert did not keep the node's keyframed colour: %s" % (tuple(principled.default_value),))


def test_the_normal_maps_strength_is_carried_like_the_principleds_inputs():
    """Normal Strength on the group node stands for the Normal Map's Strength: its keyframes go on
    animating after a bake, an edit on the node survives a re-bake, and Revert leaves the node's
    value and keyframes on the Normal Map."""
    from ndfbake import bake
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory)
        tree = material.node_tree
        strength = tree.nodes["Normal Map"].inputs["Strength"]
        for frame, value in ((1, 0.0), (11, 1.0)):
            strength.default_value = value
            strength.keyframe_insert("default_value", frame=frame)
        bake.bake_material(material, bake.BakeSettings(max_lobes=1))
        scene = bpy.context.scene
        scene.frame_set(6)
        h.expect(abs(tree.nodes["ndfbake"].inputs["Normal Strength"].default_value - 0.5) < 0.05,
                 "Normal Strength at frame 6: %g, the Normal Map's keyframes give 0.5"
                 % tree.nodes["ndfbake"].inputs["Normal Strength"].default_value)
        for frame, value in ((1, 0.2), (11, 0.4)):  # the user re-keys it on the node
            node_strength = tree.nodes["ndfbake"].inputs["Normal Strength"]
            node_strength.default_value = value
            node_strength.keyframe_insert("default_value", frame=frame)
        bake.bake_material(material, bake.BakeSettings(max_lobes=2))
        scene.frame_set(11)
        h.expect(abs(tree.nodes["ndfbake"].inputs["Normal Strength"].default_value - 0.4) < 1e-4,
                 "the re-bake lost Normal Strength keyed on the node: %g"
                 % tree.nodes["ndfbake"].inputs["Normal Strength"].default_value)
        bake.revert(material)
        scene.frame_set(1)
        strength = tree.nodes["Normal Map"].inputs["Strength"]
        h.expect(abs(strength.default_value - 0.2) < 1e-4, "Revert left the Normal Map's Strength at %g, not "
                 "the node's 0.2" % strength.default_value)
        paths = sorted(f.data_path for f in h.tree_fcurves(tree))
        h.expect(paths == ['nodes["Normal Map"].inputs[0].default_value'], "keyframes after revert: %s" % paths)


def test_a_keyed_strength_behind_a_muted_link_is_carried():
    """A muted link is no link: the Normal Map's Strength keyframed behind a muted link (its value
    is what renders) animates Normal Strength on the group node (the link carried muted), through a
    re-bake and a failed one, and Revert gives the Normal Map back its link and keyframes exactly."""
    from ndfbake import bake
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory)
        tree = material.node_tree
        strength = tree.nodes["Normal Map"].inputs["Strength"]
        value = tree.nodes.new("ShaderNodeValue")
        value.outputs[0].default_value = 5.0
        tree.links.new(value.outputs[0], strength).is_muted = True
        for frame, key in ((1, 0.2), (11, 1.0)):
            strength.default_value = key
            strength.keyframe_insert("default_value", frame=frame)
        scene = bpy.context.scene
        scene.frame_set(1)
        bpy.ops.wm.save_mainfile()
        before = h.dump_material(material)
        curves_before = [_curve_state(f) for f in h.tree_fcurves(tree)]

        def check(when):
            node = tree.nodes["ndfbake"]
            socket = node.inputs["Normal Strength"]
            h.expect([(l.from_node, l.is_muted) for l in socket.links] == [(value, True)],
                     "%s: the muted Strength link is not carried muted: %s"
                     % (when, [(l.from_node.name, l.is_muted) for l in socket.links]))
            path = 'nodes["ndfbake"].inputs[%d].default_value' % node.inputs.find("Normal Strength")
            curves = [_curve_state(f)[1:] for f in h.tree_fcurves(tree) if f.data_path == path]
            h.expect(curves == [c[1:] for c in curves_before], "%s: Normal Strength's keyframes %s, the Normal "
                     "Map's %s" % (when, curves, curves_before))
            for frame, expected in ((6, 0.6), (11, 1.0)):
                scene.frame_set(frame)
                h.expect(abs(socket.default_value - expected) < 0.05, "%s: Normal Strength at frame %d: %g, the "
                         "keyframes give %g" % (when, frame, socket.default_value, expected))
            scene.frame_set(1)

        bake.bake_material(material, bake.BakeSettings(max_lobes=1))
        check("after the bake")
        baked = h.dump_material(material)
        _bake_with_a_bug_in(material, "_wire_group_node", max_lobes=2)
        h.expect(h.dump_material(material) == baked, "the failed re-bake changed the material: %s"
                 % h.differences(baked, h.dump_material(material)))
        check("after a failed re-bake")
        bake.bake_material(material, bake.BakeSettings(max_lobes=2))
        check("after the re-bake")
        bake.revert(material)
        scene.frame_set(1)
        h.expect(h.dump_material(material) == before, "material differs after revert: %s"
                 % h.differences(before, h.dump_material(material)))
        curves = [_curve_state(f) for f in h.tree_fcurves(tree)]
        h.expect(curves == curves_before, "keyframes after revert: %s, before the bake: %s" % (curves, curves_before))

        bake.bake_material(material, bake.BakeSettings(max_lobes=1))  # a key the user moves on the node
        path = 'nodes["ndfbake"].inputs[%d].default_value' % tree.nodes["ndfbake"].inputs.find("Normal Strength")
        h.tree_fcurves(tree).find(path).keyframe_points[1].co.y = 0.6
        bake.revert(material)
        scene.frame_set(11)
        h.expect(abs(strength.default_value - 0.6) < 1e-4, "Revert did not keep the key moved on the node: the "
                 "Normal Map's Strength at frame 11 is %g" % strength.default_value)
        h.expect([l.is_muted for l in strength.links] == [True], "the Strength link after Revert")


def test_two_materials_sharing_an_action_bake_and_revert():
    from ndfbake import bake
    with h.scratch_dir() as directory:
        first, _ = _ramped_scene(directory)
        second = first.copy()
        h.plane_with(second, "Second")
        bpy.ops.wm.save_mainfile()
        shared = first.node_tree.animation_data.action == second.node_tree.animation_data.action
        print("  the copy shares the action: %s" % shared)
        for material in (first, second):
            bake.bake_material(material, bake.BakeSettings(max_lobes=1))
        bake.revert(first)
        bpy.context.scene.frame_set(6)
        value = second.node_tree.nodes["ndfbake"].inputs["Emission Strength"].default_value
        h.expect(abs(value - 5.0) < 0.6, "reverting the first material stopped the second's animation (%g)" % value)


def test_nla_strips_and_driver_variables_follow_the_inputs():
    """Keyframes in an NLA strip's action (shared with a copy of the material) and a driver
    elsewhere in the tree that reads a Principled input follow the inputs to the group node and
    back: the strip animates the node, the driver reads the node's value, Revert restores the
    paths, and the copy's strip keeps its curves."""
    from ndfbake import bake, blender_compat
    with h.scratch_dir() as directory:
        first, strength = _ramped_scene(directory)
        tree = first.node_tree
        principled = tree.nodes["Principled BSDF"]
        animation = tree.animation_data
        action = animation.action
        strip = animation.nla_tracks.new().strips.new("ramp", 1, action)
        animation.action = None

        def strip_paths():
            slot = blender_compat.animation_slot(strip)
            return sorted(f.data_path for f in blender_compat.action_fcurves(action, slot))
        reader = tree.nodes.new("ShaderNodeValue")
        reader.name = "Reads Metallic"
        driver = reader.outputs[0].driver_add("default_value").driver
        driver.type = "AVERAGE"
        variable = driver.variables.new()
        variable.targets[0].id_type = "MATERIAL"
        variable.targets[0].id = first
        metallic_path = 'node_tree.nodes["Principled BSDF"].inputs[%d].default_value' % principled.inputs.find("Metallic")
        variable.targets[0].data_path = metallic_path
        second = first.copy()
        h.plane_with(second, "Second")
        bpy.ops.wm.save_mainfile()
        h.expect(second.node_tree.animation_data.nla_tracks[0].strips[0].action == action, "the copy shares no strip")
        curves_before = strip_paths()
        for material in (first, second):
            bake.bake_material(material, bake.BakeSettings(max_lobes=1))
        scene = bpy.context.scene
        group = tree.nodes["ndfbake"]
        group.inputs["Metallic"].default_value = 0.75
        scene.frame_set(6)
        for material in (first, second):
            value = material.node_tree.nodes["ndfbake"].inputs["Emission Strength"].default_value
            h.expect(abs(value - 5.0) < 0.6, "%s: the NLA strip does not animate the node (%g)" % (material.name, value))
        h.expect(abs(reader.outputs[0].default_value - 0.75) < 1e-6,
                 "the driver reads %g, not the node's Metallic 0.75" % reader.outputs[0].default_value)
        bake.revert(first)
        scene.frame_set(6)
        h.expect(variable.targets[0].data_path == metallic_path, "Revert left the variable at %s"
                 % variable.targets[0].data_path)
        h.expect(abs(strength.default_value - 5.0) < 0.6, "after Revert the strip does not animate the Principled")
        value = second.node_tree.nodes["ndfbake"].inputs["Emission Strength"].default_value
        h.expect(abs(value - 5.0) < 0.6, "reverting the first material stopped the copy's strip (%g)" % value)
        bake.revert(second)
        h.expect(strip_paths() == curves_before, "the strip's curves after both Reverts: %s" % strip_paths())
        h.expect(not [a for a in bpy.data.actions if a.name.startswith("ndfbake")], "a temporary action was left")


def _curve_state(fcurve):
    return (fcurve.data_path, fcurve.mute, fcurve.lock, fcurve.hide, fcurve.extrapolation,
            [(tuple(k.co), k.type, k.interpolation) for k in fcurve.keyframe_points],
            [(m.type, len(getattr(m, "control_points", ()))) for m in fcurve.modifiers])


def test_curve_settings_and_deletions_on_the_node_survive():
    """A muted, locked, hidden curve with a Breakdown key and an Envelope point is copied with all
    of that (muted on the node too), and comes back the same on Revert; a driver the user removed
    on the group node stays removed on the Principled."""
    from ndfbake import bake
    with h.scratch_dir() as directory:
        material, strength = _ramped_scene(directory)
        tree = material.node_tree
        principled = tree.nodes["Principled BSDF"]
        curve = h.tree_fcurves(tree)[0]
        curve.mute = curve.lock = curve.hide = True
        curve.keyframe_points[1].type = "BREAKDOWN"
        curve.modifiers.new("ENVELOPE").control_points.add(5)
        strength.default_value = 1.0
        principled.inputs["Metallic"].driver_add("default_value").driver.expression = "0.25"
        before = _curve_state(curve)
        bake.bake_material(material, bake.BakeSettings(max_lobes=1))
        node = tree.nodes["ndfbake"]
        bpy.context.scene.frame_set(11)
        h.expect(abs(node.inputs["Emission Strength"].default_value - 1.0) < 1e-6, "the muted curve animates the node")
        node.inputs["Metallic"].driver_remove("default_value")
        node.inputs["Metallic"].default_value = 0.3
        bake.revert(material)
        after = [_curve_state(f) for f in h.tree_fcurves(tree)]
        h.expect(after == [before], "the curve after Revert: %s, before the bake: %s" % (after, before))
        h.expect(not tree.animation_data.drivers, "the driver removed on the node came back")
        h.expect(abs(principled.inputs["Metallic"].default_value - 0.3) < 1e-6, "Metallic was not written back")


def test_a_copy_sharing_the_action_keeps_its_own_edits():
    """Two materials share an action: keys the user sets on one are not overwritten by the other's
    bake-time copies when the other is baked or reverted."""
    from ndfbake import bake
    with h.scratch_dir() as directory:
        first, _ = _ramped_scene(directory)
        second = first.copy()
        h.plane_with(second, "Second")
        bpy.ops.wm.save_mainfile()
        scene = bpy.context.scene

        def key_fifty(socket):
            socket.default_value = 50.0
            socket.keyframe_insert("default_value", frame=11)
        bake.bake_material(first, bake.BakeSettings(max_lobes=1))
        key_fifty(second.node_tree.nodes["Principled BSDF"].inputs["Emission Strength"])
        bake.revert(first)
        scene.frame_set(1)
        scene.frame_set(11)
        value = second.node_tree.nodes["Principled BSDF"].inputs["Emission Strength"].default_value
        h.expect(abs(value - 50.0) < 1e-4, "reverting the first material undid the copy's key (%g)" % value)
        bake.bake_material(second, bake.BakeSettings(max_lobes=1))
        key_fifty(second.node_tree.nodes["ndfbake"].inputs["Emission Strength"])
        bake.bake_material(first, bake.BakeSettings(max_lobes=1))
        scene.frame_set(1)
        scene.frame_set(11)
        value = second.node_tree.nodes["ndfbake"].inputs["Emission Strength"].default_value
        h.expect(abs(value - 50.0) < 1e-4, "baking the first material undid the copy's key on its node (%g)" % value)


def test_driver_variables_by_socket_name_and_on_the_material_follow():
    """A variable that names the socket and a driver on the material itself read the group node
    while baked and the Principled after Revert; a bake that fails after the node got its inputs
    leaves the variables as they were."""
    from ndfbake import bake
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory)
        tree = material.node_tree
        tree.nodes["Principled BSDF"].inputs["Metallic"].default_value = 0.25
        reader = tree.nodes.new("ShaderNodeValue")
        variables = []
        for driver in (reader.outputs[0].driver_add("default_value").driver, material.driver_add("roughness").driver):
            driver.type = "SUM"
            variable = driver.variables.new()
            variable.targets[0].id_type = "MATERIAL"
            variable.targets[0].id = material
            variable.targets[0].data_path = 'node_tree.nodes["Principled BSDF"].inputs["Metallic"].default_value'
            variables.append(variable)
        paths = [v.targets[0].data_path for v in variables]
        _bake_with_a_bug_in(material, "add_eevee_output", max_lobes=1)
        h.expect([v.targets[0].data_path for v in variables] == paths, "the failed bake left %s"
                 % [v.targets[0].data_path for v in variables])
        bake.bake_material(material, bake.BakeSettings(max_lobes=1))
        tree.nodes["ndfbake"].inputs["Metallic"].default_value = 0.75
        bpy.context.scene.frame_set(2)
        h.expect(abs(reader.outputs[0].default_value - 0.75) < 1e-6 and abs(material.roughness - 0.75) < 1e-6,
                 "the drivers read %g and %g, not the node's 0.75" % (reader.outputs[0].default_value,
                                                                    material.roughness))
        bake.revert(material)
        h.expect([v.targets[0].data_path for v in variables] == paths, "Revert left %s"
                 % [v.targets[0].data_path for v in variables])


def test_a_driver_variable_reading_the_strength_follows_it():
    """A variable that reads the Normal Map's Strength reads Normal Strength on the group node while
    baked and the Normal Map's again after Revert, and is left as it was by a bake that fails after
    the node got its inputs, as for the Principled's inputs."""
    from ndfbake import bake
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory)
        tree = material.node_tree
        reader = tree.nodes.new("ShaderNodeValue")
        driver = reader.outputs[0].driver_add("default_value").driver
        driver.type = "SUM"
        variable = driver.variables.new()
        variable.targets[0].id_type = "MATERIAL"
        variable.targets[0].id = material
        path = 'node_tree.nodes["Normal Map"].inputs["Strength"].default_value'
        variable.targets[0].data_path = path
        _bake_with_a_bug_in(material, "add_eevee_output", max_lobes=1)
        h.expect(variable.targets[0].data_path == path, "the failed bake left %s" % variable.targets[0].data_path)
        bake.bake_material(material, bake.BakeSettings(max_lobes=1))
        tree.nodes["ndfbake"].inputs["Normal Strength"].default_value = 0.75
        bpy.context.scene.frame_set(2)
        h.expect(abs(reader.outputs[0].default_value - 0.75) < 1e-6, "the driver reads %g, not the node's Normal "
                 "Strength 0.75" % reader.outputs[0].default_value)
        bake.revert(material)
        h.expect(variable.targets[0].data_path == path, "Revert left %s" % variable.targets[0].data_path)


def test_a_linked_action_is_refused():
    """An action linked from a library cannot keep the group node's curves: LINKED_ANIMATION, and
    the material stays as it was."""
    from ndfbake import bake, blender_compat
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory)
        action = bpy.data.actions.new("Library Action")
        slot = blender_compat.new_action_slot(action, "NODETREE")
        emission = material.node_tree.nodes["Principled BSDF"].inputs.find("Emission Strength")
        path = 'nodes["Principled BSDF"].inputs[%d].default_value' % emission
        fcurves = blender_compat.action_fcurves(action, slot, create=True)
        curve = blender_compat.new_fcurve(fcurves, path, 0, "")
        curve.keyframe_points.insert(1, 0.0)
        slot_identifier = slot.identifier if slot is not None else None
        library = os.path.join(directory, "library.blend")
        bpy.data.libraries.write(library, {action}, fake_user=True)
        bpy.data.actions.remove(action)
        with bpy.data.libraries.load(library, link=True) as (source, target):
            target.actions = ["Library Action"]
        animation = material.node_tree.animation_data_create()
        animation.action = bpy.data.actions["Library Action"]
        if slot_identifier is not None:  # slotted actions (4.4+): Blender picks no slot no ID has used
            animation.action_slot = animation.action.slots[slot_identifier]
        before = h.dump_material(material)
        e = h.raised(bake.BakeError, lambda: bake.bake_material(material, bake.BakeSettings(max_lobes=1)),
                     "a material animated by a linked action was baked")
        h.expect(e.code == "LINKED_ANIMATION" and "Library Action" in e.message, "%s: %s" % (e.code, e.message))
        h.expect(h.dump_material(material) == before, "the refused bake changed the material")


def test_a_material_changed_during_the_bake_is_not_baked():
    """What the worker fitted must be what the material shows: a normal map swapped or set to
    object space while the bake ran refuses it (MATERIAL_CHANGED, nothing changed, no folder); a
    renamed material still gets its bake."""
    from ndfbake import bake, bake_job
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
            bake_job.discard_pending(job)
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
    from ndfbake import bake, group_node, material_scan, node_builders
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
        settings = material_scan.record(material)["settings"]
        h.expect(abs(settings["roughness"] - 0.9) < 1e-6, "the re-bake fitted roughness %g, not the group "
                 "node's 0.9" % settings["roughness"])
        tree.nodes["ndfbake"].name = "Filtered again"
        bake.revert(material)
        h.expect(not [n.name for n in tree.nodes if material_scan.ROLE_KEY in n.keys() or n.get(node_builders.TAG)],
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
    from ndfbake import bake
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
    from ndfbake import bake
    with h.scratch_dir() as directory:
        material, second, mix = _two_principled_scene(directory)
        tree = material.node_tree
        settings = bake.BakeSettings(max_lobes=2, level_of_detail="RENDERER")
        bake.bake_material(material, settings)
        h.expect(len(_record(material)["targets"]) == 2, "both Principled BSDFs baked")
        tree.links.remove(second.inputs["Normal"].links[0])
        bake.bake_material(material, settings)
        targets = _record(material)["targets"]
        h.expect([t["principled"] for t in targets] == ["Principled BSDF"], "re-baked: %s" % targets)
        h.expect(mix.inputs[2].links[0].from_node == second, "the second BSDF feeds the mix again")
        h.expect(len(_group_nodes(material)) == 1, "one group node: %s" % _group_nodes(material))
        h.expect(targets[0]["node_group"] in bpy.data.node_groups, "the record names the new group")


def test_a_rebake_without_a_renamed_one_of_two_normal_maps():
    """As above, but the dropped target's group node was renamed ("ndfbake" -> "bar") first: its
    nodes still carry the key "ndfbake" in their roles when the re-baked target's new node is
    named, and must not be taken for the new node's (nor it for theirs). The re-baked target keeps
    a working group node, the dropped one gets its links back, and Revert restores the material."""
    from ndfbake import bake, material_scan
    with h.scratch_dir() as directory:
        material, second, mix = _two_principled_scene(directory)
        tree = material.node_tree
        first = tree.nodes["Principled BSDF"]
        before = h.dump_material(material)
        settings = bake.BakeSettings(max_lobes=2, level_of_detail="RENDERER")
        bake.bake_material(material, settings)
        groups = {t["principled"]: t["group_node"] for t in _record(material)["targets"]}
        h.expect(groups == {"Principled BSDF": "ndfbake", "Second BSDF": "ndfbake.001"}, "group nodes: %s" % groups)
        tree.nodes["ndfbake"].name = "bar"
        tree.links.remove(first.inputs["Normal"].links[0])
        bake.bake_material(material, settings)

        rec = _record(material)
        h.expect([t["principled"] for t in rec["targets"]] == ["Second BSDF"], "re-baked: %s" % rec["targets"])
        (target, principled, node, _), = material_scan.recorded_targets(tree, rec)
        h.expect(principled == second, "the record's Principled BSDF: %s" % principled)
        h.expect(node is not None and node.name == target["group_node"] and node in _group_nodes(material),
                 "the record's group node %r is not in the material: %s"
                 % (target["group_node"], [n.name for n in tree.nodes]))
        h.expect(node.node_tree is not None and node.node_tree.name == target["node_group"],
                 "the group node draws %s, the record names %s" % (node.node_tree, target["node_group"]))
        h.expect(mix.inputs[2].links[0].from_node == node, "the new group node does not feed the mix")
        h.expect(_group_nodes(material) == [node], "group nodes: %s" % [n.name for n in _group_nodes(material)])
        h.expect(mix.inputs[1].links[0].from_node == first, "the first BSDF does not feed the mix again")
        h.expect(material_scan.ROLE_KEY not in first.keys(), "the dropped BSDF keeps role %s"
                 % first.get(material_scan.ROLE_KEY))
        h.expect(second.get(material_scan.ROLE_KEY) == material_scan.node_role("principled", node.name),
                 "the second BSDF's role: %s" % second.get(material_scan.ROLE_KEY))

        bake.revert(material)
        tree.links.new(tree.nodes["Normal Map"].outputs["Normal"], first.inputs["Normal"])
        h.expect(h.dump_material(material) == before, "material differs after revert: %s"
                 % h.differences(before, h.dump_material(material)))


def test_a_deleted_group_node_beside_a_renamed_one_is_baked_again():
    """Two Principled BSDFs baked; the first's group node renamed ("ndfbake" -> "bar"), the
    second's deleted: the re-bake's new group node for the second must not take the first's role
    key with the name "ndfbake", or committing the first's replacement rekeys both. Both targets
    end with their group nodes, and Revert restores the material."""
    from ndfbake import bake, material_scan
    with h.scratch_dir() as directory:
        material, _, _ = _two_principled_scene(directory)
        tree = material.node_tree
        before = h.dump_material(material)
        settings = bake.BakeSettings(max_lobes=2, level_of_detail="RENDERER")
        bake.bake_material(material, settings)
        tree.nodes["ndfbake"].name = "bar"
        tree.nodes.remove(tree.nodes["ndfbake.001"])
        bake.bake_material(material, settings)
        found = material_scan.recorded_targets(tree, _record(material))
        h.expect([(p.name if p else None, g.name if g else None) for _, p, g, _ in found]
                 == [(t["principled"], t["group_node"]) for t, _, _, _ in found]
                 and len(found) == 2 and len(_group_nodes(material)) == 2,
                 "the record's nodes: %s; roles: %s" % ([t for t, _, _, _ in found],
                                                         [(n.name, n.get(material_scan.ROLE_KEY)) for n in tree.nodes]))
        bake.revert(material)
        h.expect(h.dump_material(material) == before, "material differs after revert: %s"
                 % h.differences(before, h.dump_material(material)))


if __name__ == "__main__":
    h.import_addon()
    h.run([test_blender_decodes_the_map_as_the_command_line_does, test_bake_adds_only_the_group_and_bypass, test_failure_while_building_nodes_rolls_back,
           test_operators_rebake_fewer_lobes_and_revert, test_cycles_lobes_narrowed_or_widened,
           test_save_reopen_then_revert,
           test_bake_all_bakes_what_the_scene_renders, test_linked_inputs_are_carried_and_restored,
           test_a_user_graph_downstream_gets_no_eevee_output, test_pack_option, test_animated_inputs_keep_animating,
           test_edits_on_the_group_node_survive_rebake_and_revert,
           test_the_normal_maps_strength_is_carried_like_the_principleds_inputs,
           test_a_keyed_strength_behind_a_muted_link_is_carried,
           test_two_materials_sharing_an_action_bake_and_revert,
           test_nla_strips_and_driver_variables_follow_the_inputs, test_curve_settings_and_deletions_on_the_node_survive,
           test_a_copy_sharing_the_action_keeps_its_own_edits,
           test_driver_variables_by_socket_name_and_on_the_material_follow,
           test_a_driver_variable_reading_the_strength_follows_it, test_a_linked_action_is_refused,
           test_a_material_changed_during_the_bake_is_not_baked, test_renamed_nodes_are_found_again,
           test_a_deleted_principled_is_made_again, test_a_rebake_without_one_of_two_normal_maps_reverts_that_one,
           test_a_rebake_without_a_renamed_one_of_two_normal_maps,
           test_a_deleted_group_node_beside_a_renamed_one_is_baked_again])
