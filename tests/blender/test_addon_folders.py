"""Lobe folders belong to the bakes that name them, a failed re-bake keeps the bake it replaces,
and Revert keeps what the user did after the bake.

Run: blender -b --factory-startup --python-exit-code 1 --python tests/blender/test_addon_folders.py -- LIB

- Names that safe_name maps to one folder ("Metal 01", "Metal_01") and names that differ only in
  case get folders of their own; reverting one leaves the other's files and images intact.
- A copy of a baked material (Shift+D copies the bake record): reverting the copy keeps the
  original's files; re-baking the copy gives it a folder of its own.
- A re-bake whose material changed while the library ran (MATERIAL_CHANGED) leaves the previous
  bake's files, images and nodes as they were, and no pending folder.
- A Mix Shader the user put after the group node stays after Revert (fed by the Principled again)
  and after a re-bake (fed by the new group).
- Box projection bakes level 0 for the renderer to filter, with a camera in the scene.
- Ctrl-Z after a re-bake and after a Revert gives back a material whose lobe images load; saving
  and closing deletes only the folders the file does not use (here the undone re-bake's).
- Save As into another folder keeps the lobe folder the moved .blend's images use, and Revert
  there names that folder (not one of the same name beside the new .blend).
- Folders are deleted only when the file is closed (h.close_file), and only those no save used:
  not the one the file before a Save As uses, nor one a Save Copy uses, nor the folder of a
  library a baked material was appended from; Ctrl-Z after a save finds the files.
- ndfbake.delete_unused_folders deletes the bake files of the folders beside the .blend that the
  file does not use (a saved, replaced bake's), nothing else.
- Materials named as Windows devices ("CON", "nul.001") get folders Windows can make.
- Lobe images' paths are written with '/' on every system; paths saved with '\\' (a .blend from
  Windows) still name their folder and the normal map's file on every system.
- A .blend, a material and a normal map with non-ASCII names and folders ("Zoë Projekte/材質
  scene.blend", "材質 Zoë"): the operator bakes, the lobe images load from where their paths say,
  a re-bake and reopening the file find them, and Revert restores the material.
- "Metal" and "metal" in one .blend get folders whose names differ in more than case (one folder
  on Windows and macOS), whichever is baked first, and keep their own files through re-bakes and a
  Revert of the other.
"""
import os
import re
import shutil
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import test_addon_helpers as h  # noqa: E402


def _lobe_files(folder):
    return sorted(n for n in os.listdir(folder) if n.endswith(".exr")) if os.path.isdir(folder) else []


def _level0_lobes(folder):
    return sum(1 for n in _lobe_files(folder) if n.startswith("level00_lobe"))


def _images_load(material):
    from ndfbake.shading import bake_record
    names = bake_record.record(material)["images"]
    for name in names:
        image = bpy.data.images[name]
        image.reload()
        h.expect(image.size[0] > 0, "image %s of %s does not load (%s)" % (name, material.name, image.filepath))
    return names


# The names Windows keeps for devices, whatever the extension: it makes no folder "CON.ndfbake",
# and "NUL.ndfbake" is the null device (what a bake writes there is gone).
WINDOWS_DEVICE = re.compile(r"(CON|PRN|AUX|NUL|COM[0-9]|LPT[0-9])$", re.IGNORECASE)


def test_windows_device_names_get_folders_windows_can_make():
    from ndfbake.core import folder_names
    from ndfbake.blender import bake
    names = ("CON", "nul", "Aux.001", "com1", "LPT9.x", "prn.", "CONSOLE")
    folders = [folder_names.folder_name(name) for name in names]
    print("  folders: %s" % folders)
    for name, folder in zip(names, folders):
        h.expect(not WINDOWS_DEVICE.match(folder.split(".")[0]), "%r: %s is a Windows device" % (name, folder))
    h.expect(len({f.casefold() for f in folders}) == len(folders), "shared folders: %s" % folders)
    h.expect(folders[-1] == "CONSOLE.ndfbake", "a name that is no device keeps its plain folder: %s" % folders[-1])
    with h.scratch_dir() as directory:
        first = h.baked_scene(directory, material_name="CON")
        second = h.normal_mapped_material("nul.001", os.path.join(directory, "normal.png"))
        h.plane_with(second, "Plane 2")
        bpy.ops.wm.save_mainfile()
        for material in (first, second):
            result = bake.bake_material(material, bake.BakeSettings(max_lobes=2))
            folder = os.path.normpath(bpy.path.abspath(result.folder))
            h.expect(os.path.basename(folder) in os.listdir(directory) and _level0_lobes(folder) == 2,
                     "%s: no lobe files in %s (%s)" % (material.name, folder, os.listdir(directory)))
            _images_load(material)


def test_backslashes_in_saved_paths_still_name_the_files():
    """A .blend saved on Windows may hold '//Bumpy.ndfbake\\level00_lobe0.exr' and
    '//maps\\normal.png', which Blender reads on every system: the add-on must too, or the normal
    map is missing and closing the file deletes the lobe folder it uses. A bake writes '/'."""
    from ndfbake.shading import bake_record
    from ndfbake.blender import bake, lobe_folders
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory)
        os.makedirs(os.path.join(directory, "maps"))
        shutil.move(os.path.join(directory, "normal.png"), os.path.join(directory, "maps", "normal.png"))
        material.node_tree.nodes["Normal Texture"].image.filepath = "//maps\\normal.png"
        bpy.ops.wm.save_mainfile()
        result = bake.bake_material(material, bake.BakeSettings(max_lobes=2))
        rec = bake_record.record(material)
        paths = [bpy.data.images[name].filepath for name in rec["images"]]
        h.expect(all(p.startswith(result.folder + "/") and "\\" not in p for p in paths), "lobe paths: %s" % paths)
        for name in rec["images"]:
            image = bpy.data.images[name]
            image.filepath = "//" + image.filepath[2:].replace("/", "\\")
        folder = os.path.join(directory, result.folder[2:])
        h.expect(os.path.normcase(lobe_folders.record_folder(rec)) == os.path.normcase(folder),
                 "the bake's folder: %s" % lobe_folders.record_folder(rec))
        bpy.ops.wm.save_mainfile()
        h.close_file()
        h.expect(_level0_lobes(folder) == 2, "closing the saved file deleted the folder it uses: %s"
                 % h.listing(directory))
        h.expect(lobe_folders.unused_folders() == [], "offered for deletion: %s" % lobe_folders.unused_folders())
        _images_load(material)
        result = bake.bake_material(material, bake.BakeSettings(max_lobes=1))  # the normal map is found
        h.expect(result.folder == "//Bumpy~2.ndfbake", "the re-bake went to %s" % result.folder)


def test_names_that_clash_on_disk_get_folders_of_their_own():
    from ndfbake.shading import bake_record
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        first = h.baked_scene(directory, material_name="Metal 01")
        png = os.path.join(directory, "normal.png")
        others = [h.normal_mapped_material(name, png) for name in ("Metal_01", "metal_01")]
        for k, material in enumerate(others):
            h.plane_with(material, "Plane %d" % k)
        bpy.ops.wm.save_mainfile()
        results = [bake.bake_material(m, bake.BakeSettings(max_lobes=2)) for m in [first] + others]
        folders = [r.folder for r in results]
        print("  folders: %s" % folders)
        h.expect(len({f.casefold() for f in folders}) == 3, "shared folders: %s" % folders)
        h.expect(folders[1] == "//Metal_01.ndfbake", "a safe name keeps its plain folder: %s" % folders[1])
        h.expect(folders[0].startswith("//Metal_01~") and folders[2].startswith("//metal_01~"),
                 "hashed folders: %s" % folders)
        kept = {r.material: _lobe_files(bpy.path.abspath(r.folder)) for r in results}
        reverted, kept_for = bake.revert(first)
        bpy.ops.wm.save_mainfile()
        h.close_file()
        h.expect(not os.path.exists(reverted) and not kept_for, "revert, save and close: %s left, kept for %s"
                 % (reverted, kept_for))
        for material in others:
            folder = bpy.path.abspath(bake_record.record(material)["folder"])
            h.expect(_lobe_files(folder) == kept[material.name], "%s lost files" % material.name)
            _images_load(material)


def test_a_copy_shares_the_folder_until_it_is_baked_itself():
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        original = h.baked_scene(directory)
        bake.bake_material(original, bake.BakeSettings(max_lobes=2))
        folder = os.path.join(directory, "Bumpy.ndfbake")
        files = _lobe_files(folder)
        copy = original.copy()
        h.expect(copy.name == "Bumpy.001" and bake.is_baked(copy), "the copy has the bake record")
        reverted, kept_for = bake.revert(copy)
        h.expect(kept_for == ["Bumpy"], "revert of the copy: kept for %s" % kept_for)
        bpy.ops.wm.save_mainfile()
        h.close_file()
        h.expect(_lobe_files(folder) == files and bake.is_baked(original), "the original lost its bake")
        _images_load(original)

        copy = original.copy()
        result = bake.bake_material(copy, bake.BakeSettings(max_lobes=1))
        h.expect(result.folder == "//%s.ndfbake" % copy.name, "the copy's re-bake went to %s" % result.folder)
        h.expect(_lobe_files(folder) == files, "re-baking the copy changed the original's files")
        _images_load(original)
        _images_load(copy)
        reverted, kept_for = bake.revert(original)
        h.expect(not kept_for, "revert of the original: kept for %s" % kept_for)
        bpy.ops.wm.save_mainfile()
        h.close_file()
        h.expect(os.path.isdir(folder), "the original's folder, which a save used, was deleted")
        _images_load(copy)


def test_a_rebake_that_fails_keeps_the_previous_bake():
    from ndfbake.blender import bake, lobe_folders
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory)
        bake.bake_material(material, bake.BakeSettings(max_lobes=3))
        baked, listing = h.dump_material(material), h.listing(directory)
        job = bake.prepare(material, bake.BakeSettings(max_lobes=1))
        job.run()
        material.node_tree.nodes["Normal Map"].name = "Renamed"
        e = h.raised(bake.BakeError, lambda: bake.finish(job), "finish() accepted a material whose nodes changed")
        h.expect(e.code == "MATERIAL_CHANGED", "%s: %s" % (e.code, e.message))
        lobe_folders.discard_pending(job)
        material.node_tree.nodes["Renamed"].name = "Normal Map"
        h.expect(h.listing(directory) == listing, "files changed: %s" % h.listing(directory))
        h.expect(h.dump_material(material) == baked, "the baked material changed")
        h.expect(len(_images_load(material)) == 3, "the previous bake's images")


def test_revert_and_rebake_keep_a_mix_shader_added_after_the_bake():
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory)
        bake.bake_material(material, bake.BakeSettings(max_lobes=2))
        tree = material.node_tree
        group, output = tree.nodes["ndfbake"], tree.nodes["Material Output"]
        mix = tree.nodes.new("ShaderNodeMixShader")
        mix.name = "User Mix"
        tree.links.new(group.outputs["BSDF"], mix.inputs[1])
        tree.links.new(mix.outputs[0], output.inputs["Surface"])

        def feeds_mix():
            socket = tree.nodes["User Mix"].inputs[1]
            return socket.links[0].from_node.name if socket.is_linked else None
        bake.bake_material(material, bake.BakeSettings(max_lobes=1))
        h.expect(feeds_mix() == "ndfbake", "after re-bake the mix is fed by %s" % feeds_mix())
        h.expect(output.inputs["Surface"].links[0].from_node.name == "User Mix", "the output lost the mix")
        bake.revert(material)
        h.expect(feeds_mix() == "Principled BSDF", "after revert the mix is fed by %s" % feeds_mix())
        h.expect(output.inputs["Surface"].links[0].from_node.name == "User Mix", "the output lost the mix")
        h.expect(not [n for n in tree.nodes if n.get("ndfbake") is not None], "ndfbake nodes left")


def test_box_projection_leaves_filtering_to_the_renderer():
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory)
        bpy.ops.object.camera_add(location=(0.0, 0.0, 5.0))
        bpy.context.scene.camera = bpy.context.active_object
        tree = material.node_tree
        texture = tree.nodes["Normal Texture"]
        texture.projection = "BOX"
        coords = tree.nodes.new("ShaderNodeTexCoord")
        tree.links.new(coords.outputs["Object"], texture.inputs["Vector"])
        bpy.ops.wm.save_mainfile()
        result = bake.bake_material(material, bake.BakeSettings(max_lobes=2))
        h.expect("level 0 filtered by the renderer" in result.summary, result.summary)
        inner = tree.nodes["ndfbake"].node_tree
        projections = {n.projection for n in inner.nodes if n.bl_idname == "ShaderNodeTexImage"}
        h.expect(projections == {"BOX"}, "lobe textures sampled with %s" % projections)
        h.expect(not any(n.startswith("atlas") for n in os.listdir(os.path.join(directory, "Bumpy.ndfbake"))),
                 "atlases written for a box-projected texture")


def _undoable(operator, what):
    """Runs an ndfbake operator on Bumpy and pushes the undo step a window pushes after an operator
    with the UNDO flag (`blender -b` pushes none by itself)."""
    h.expect(operator(material="Bumpy") == {"FINISHED"}, what)
    bpy.ops.ed.undo_push(message=what)


def _baked_with_undo(directory):
    """baked_scene, then a bake of Bumpy through the operator with the undo steps a window pushes.
    Returns the bake's folder ('//…')."""
    from ndfbake.shading import bake_record
    h.baked_scene(directory)
    bpy.ops.ed.undo_push(message="ndfbake test scene")
    _undoable(bpy.ops.ndfbake.bake, "bake")
    return bake_record.record(bpy.data.materials["Bumpy"])["folder"]


def test_undo_after_rebake_and_revert_finds_the_files():
    from ndfbake.shading import bake_record
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        first = _baked_with_undo(directory)
        bpy.data.materials["Bumpy"].ndfbake_settings.max_lobes = 1
        _undoable(bpy.ops.ndfbake.bake, "re-bake")
        second = bake_record.record(bpy.data.materials["Bumpy"])["folder"]
        h.expect(first != second, "the re-bake wrote into the first bake's folder %s" % first)

        h.expect(bpy.ops.ed.undo() == {"FINISHED"}, "Ctrl-Z after the re-bake")
        material = bpy.data.materials["Bumpy"]
        rec = bake_record.record(material)
        h.expect(rec and rec["folder"] == first and rec["lobes"] == 4, "Ctrl-Z did not bring back the first bake")
        h.expect(len(_images_load(material)) == 4, "the first bake's images")

        _undoable(bpy.ops.ndfbake.revert, "revert")
        h.expect(bpy.ops.ed.undo() == {"FINISHED"}, "Ctrl-Z after the revert")
        material = bpy.data.materials["Bumpy"]
        h.expect(bake.is_baked(material) and len(_images_load(material)) == 4, "Ctrl-Z after the revert")

        bpy.ops.wm.save_mainfile()
        h.close_file()
        folders = sorted(f for f in os.listdir(directory) if f.endswith(".ndfbake"))
        h.expect(folders == [first[2:]], "after save and close: %s (the file uses only %s)" % (folders, first))


def test_save_as_elsewhere_keeps_the_textures():
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory)
        bake.bake_material(material, bake.BakeSettings(max_lobes=2))
        os.makedirs(os.path.join(directory, "moved"))
        bpy.ops.wm.save_as_mainfile(filepath=os.path.join(directory, "moved", "scene.blend"))
        folder = os.path.join(directory, "Bumpy.ndfbake")
        h.expect(os.path.isdir(folder), "Save As deleted the folder the moved .blend's images use")
        material = bpy.data.materials["Bumpy"]
        _images_load(material)
        # A re-bake here must not take '//Bumpy.ndfbake' (moved/Bumpy.ndfbake): Ctrl-Z brings back
        # the image paths from before Save As remapped them, which name it relative to the .blend.
        result = bake.bake_material(material, bake.BakeSettings(max_lobes=1))
        h.expect(result.folder == "//Bumpy~2.ndfbake", "the re-bake after Save As went to %s" % result.folder)
        reverted, _ = bake.revert(material)
        h.expect(os.path.normpath(reverted) == os.path.join(directory, "moved", "Bumpy~2.ndfbake"),
                 "revert released %s" % reverted)
        bpy.ops.wm.save_mainfile()
        h.close_file()
        h.expect(os.path.isdir(folder), "the folder the first save of moved/scene.blend used is gone")


def test_a_damaged_record_on_another_material_stops_no_bake():
    """A record someone else's script damaged (wrong types) names no folder; the other materials
    bake and Delete Unused lists as before."""
    from ndfbake.blender import bake, lobe_folders
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory)
        other = bpy.data.materials.new("Other")
        other["ndfbake_bake"] = '{"version": 1, "folder": null, "images": null, "targets": []}'
        result = bake.bake_material(material, bake.BakeSettings(max_lobes=1))
        h.expect(result.folder == "//Bumpy.ndfbake", result.folder)
        h.expect(lobe_folders.unused_folders() == [], "unused: %s" % lobe_folders.unused_folders())


def test_folders_other_blend_files_use_are_kept():
    """A folder stays while any .blend saved with it exists: the file before a Save As, a Save
    Copy, the library a material was appended from; and Ctrl-Z after a save finds its files."""
    from ndfbake.shading import bake_record
    from ndfbake.blender import bake, lobe_folders
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory)
        bake.bake_material(material, bake.BakeSettings(max_lobes=2))
        bpy.ops.wm.save_mainfile()
        first = os.path.join(directory, "Bumpy.ndfbake")
        bpy.ops.wm.save_as_mainfile(filepath=os.path.join(directory, "scene_v2.blend"))
        bake.bake_material(bpy.data.materials["Bumpy"], bake.BakeSettings(max_lobes=1))
        bpy.ops.wm.save_mainfile()
        h.close_file()
        h.expect(os.path.isdir(first), "closing scene_v2.blend deleted the folder scene.blend uses")
        second = lobe_folders.record_folder(bake_record.record(bpy.data.materials["Bumpy"]))

        bpy.ops.wm.save_as_mainfile(filepath=os.path.join(directory, "backup.blend"), copy=True)
        bake.revert(bpy.data.materials["Bumpy"])
        bpy.ops.wm.save_mainfile()
        h.close_file()
        h.expect(os.path.isdir(second), "closing deleted the folder a Save Copy (backup.blend) uses")

        # The library: a baked material appended into a new file, then reverted there.
        appended = h.shot_with_material_from(directory, "Bumpy", link=False)
        _images_load(appended)
        bake.revert(appended)
        bpy.ops.wm.save_mainfile()
        h.close_file()
        h.expect(os.path.isdir(first), "closing shot.blend deleted the folder of the library it appended from")


def test_undo_after_a_save_finds_the_files():
    from ndfbake.shading import bake_record
    with h.scratch_dir() as directory:
        first = _baked_with_undo(directory)
        bpy.ops.wm.save_mainfile()
        bpy.data.materials["Bumpy"].ndfbake_settings.max_lobes = 1
        _undoable(bpy.ops.ndfbake.bake, "re-bake")
        bpy.ops.wm.save_mainfile()
        h.expect(bpy.ops.ed.undo() == {"FINISHED"}, "Ctrl-Z after the save")
        material = bpy.data.materials["Bumpy"]
        h.expect(bake_record.record(material)["folder"] == first, "Ctrl-Z did not bring back the first bake")
        h.expect(len(_images_load(material)) == 4, "the first bake's images after a save and Ctrl-Z")


def test_delete_unused_folders_keeps_what_ctrl_z_brings_back():
    from ndfbake.blender import bake, lobe_folders
    with h.scratch_dir() as directory:
        folder = _baked_with_undo(directory)
        bpy.ops.wm.save_mainfile()  # a save used the folder: closing the file keeps it
        _undoable(bpy.ops.ndfbake.revert, "revert")
        bpy.ops.wm.save_mainfile()  # neither the file nor its saved copy uses it now; Ctrl-Z does
        offered = [os.path.basename(f) for f in lobe_folders.unused_folders()]
        h.expect(offered == [], "offered while Ctrl-Z can bring the bake back: %s" % offered)
        h.expect(bpy.ops.ndfbake.delete_unused_folders() in ({"FINISHED"}, {"CANCELLED"}), "the operator did not run")
        h.expect(bpy.ops.ed.undo() == {"FINISHED"}, "Ctrl-Z after the revert")
        material = bpy.data.materials["Bumpy"]
        h.expect(bake.is_baked(material) and len(_images_load(material)) == 4,
                 "Ctrl-Z brought back a bake whose files in %s were deleted" % folder)
        _undoable(bpy.ops.ndfbake.revert, "revert again")
        bpy.ops.wm.save_mainfile()
        h.close_file()  # the undo steps went with the file: now the folder is offered
        offered = [os.path.basename(f) for f in lobe_folders.unused_folders()]
        h.expect(offered == [folder[2:]], "offered after the file was closed: %s" % offered)


def test_delete_unused_folders_deletes_only_what_this_file_does_not_use():
    from ndfbake.blender import bake, lobe_folders
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory)
        bake.bake_material(material, bake.BakeSettings(max_lobes=2))
        bpy.ops.wm.save_mainfile()
        bake.bake_material(material, bake.BakeSettings(max_lobes=1))  # Bumpy~2; Bumpy.ndfbake was saved
        # Not saved yet: the .blend on disk still uses Bumpy.ndfbake, so it is not offered.
        offered = [os.path.basename(f) for f in lobe_folders.unused_folders()]
        h.expect(offered == [], "offered before the save: %s" % offered)
        bpy.ops.wm.save_mainfile()
        h.close_file()
        h.expect(os.path.isdir(os.path.join(directory, "Bumpy.ndfbake")), "a folder a save used went at close")
        other = os.path.join(directory, "Notes.ndfbake")  # not ours: only bake files would go
        os.makedirs(other)
        with open(os.path.join(other, "notes.txt"), "w") as f:
            f.write("mine")
        h.expect(bpy.ops.ndfbake.delete_unused_folders() == {"FINISHED"}, "the operator did not run")
        h.expect(not os.path.exists(os.path.join(directory, "Bumpy.ndfbake")), "the unused folder is left")
        h.expect(os.path.isdir(os.path.join(directory, "Bumpy~2.ndfbake")), "the folder in use was deleted")
        h.expect(os.listdir(other) == ["notes.txt"], "a file that is not a bake file was deleted")
        _images_load(bpy.data.materials["Bumpy"])


def _operator_bake(name):
    h.expect(bpy.ops.ndfbake.bake(material=name) == {"FINISHED"}, "the bake of %s did not finish" % name)


def _images_have_pixels(material):
    """The bake's lobe images: each file is where bpy.path.abspath(filepath) says and Blender
    decodes it (has_data, pixels). Returns the lobe folder (absolute)."""
    from ndfbake.shading import bake_record
    rec = bake_record.record(material)
    h.expect(rec and rec["images"], "%s has no bake record" % material.name)
    folder = os.path.normpath(bpy.path.abspath(rec["folder"]))
    for name in rec["images"]:
        image = bpy.data.images[name]
        path = os.path.normpath(bpy.path.abspath(image.filepath))
        h.expect(os.path.isfile(path) and os.path.dirname(path) == folder,
                 "image %s: %s is not a file in %s (%s)" % (name, path, folder, h.listing(os.path.dirname(folder))))
        image.reload()
        h.expect(len(image.pixels) > 0 and image.has_data and image.size[0] > 0,
                 "image %s (%s) does not load" % (name, image.filepath))
    return folder


def test_non_ascii_folder_and_material_names():
    """A .blend in 'Zoë Projekte/' named '材質 scene.blend', its material '材質 Zoë', its normal map
    under 'Texturen ü/法線 karte.png': bake, re-bake, reopen and Revert through the operators."""
    import hashlib
    from ndfbake.shading import bake_record
    name = "材質 Zoë"
    with h.scratch_dir() as scratch:
        directory = os.path.join(scratch, "Zoë Projekte")
        textures = os.path.join(directory, "Texturen ü")
        os.makedirs(textures)
        h.reset_scene()
        png = h.write_normal_map(os.path.join(textures, "法線 karte.png"), "bumps", 64)
        material = h.normal_mapped_material(name, png)
        h.plane_with(material)
        blend = os.path.join(directory, "材質 scene.blend")
        bpy.ops.wm.save_as_mainfile(filepath=blend)
        lobes = material.ndfbake_settings.max_lobes
        material.ndfbake_settings.max_lobes = lobes  # stored now, as after the re-bake's change
        before = h.dump_material(material)

        _operator_bake(name)
        expected = "_Zo_~%s.ndfbake" % hashlib.sha1(name.encode("utf-8")).hexdigest()[:8]
        rec = bake_record.record(material)
        h.expect(rec["folder"] == "//" + expected, "the bake went to %s, not //%s" % (rec["folder"], expected))
        folder = _images_have_pixels(material)
        h.expect(folder == os.path.join(directory, expected) and _level0_lobes(folder) == lobes,
                 "lobe files in %s: %s" % (folder, h.listing(directory)))

        material.ndfbake_settings.max_lobes = 2
        _operator_bake(name)
        second = _images_have_pixels(material)
        h.expect(second != folder and _level0_lobes(second) == 2, "the re-bake's files: %s" % h.listing(directory))
        h.expect(_level0_lobes(folder) == 4, "the re-bake changed the first bake's files")

        bpy.ops.wm.save_mainfile()
        bpy.ops.wm.open_mainfile(filepath=blend)
        material = bpy.data.materials[name]
        h.expect(_images_have_pixels(material) == second, "reopened, the file's bake is not in %s" % second)

        h.expect(bpy.ops.ndfbake.revert(material=name) == {"FINISHED"}, "Revert did not finish")
        material.ndfbake_settings.max_lobes = lobes
        after = h.dump_material(material)
        h.expect(after == before, "the material differs after Revert: %s" % h.differences(before, after))


def test_names_that_differ_in_case_get_folders_of_their_own():
    """Windows and macOS see 'Metal.ndfbake' and 'metal.ndfbake' as one folder: two materials whose
    names differ only in case must not share it, whichever is baked first."""
    from ndfbake.shading import bake_record
    for order in (("Metal", "metal"), ("metal", "Metal")):
        with h.scratch_dir() as directory:
            h.reset_scene()
            png = h.write_normal_map(os.path.join(directory, "normal.png"), "bumps", 64)
            for k, name in enumerate(order):
                h.plane_with(h.normal_mapped_material(name, png), "Plane %d" % k)
            bpy.ops.wm.save_as_mainfile(filepath=os.path.join(directory, "scene.blend"))
            folders = {}
            for name in order + order:  # bake, then re-bake each
                material = bpy.data.materials[name]
                material.ndfbake_settings.max_lobes = 2
                _operator_bake(name)
                folders.setdefault(name, []).append(bake_record.record(material)["folder"])
                _images_have_pixels(material)
            every = folders[order[0]] + folders[order[1]]
            print("  %s: folders %s" % (" then ".join(order), every))
            h.expect(len({f.casefold() for f in every}) == 4, "folders that differ only in case: %s" % every)
            on_disk = [n for n in os.listdir(directory) if n.endswith(".ndfbake")]
            h.expect(len({n.casefold() for n in on_disk}) == len(on_disk) == 4, "on disk: %s" % on_disk)
            kept = {name: _lobe_files(bpy.path.abspath(folders[name][-1])) for name in order}
            h.expect(bpy.ops.ndfbake.revert(material=order[0]) == {"FINISHED"}, "Revert did not finish")
            bpy.ops.wm.save_mainfile()
            h.close_file()
            other = bpy.data.materials[order[1]]
            h.expect(_lobe_files(bpy.path.abspath(folders[order[1]][-1])) == kept[order[1]],
                     "%s lost files when %s was reverted" % (order[1], order[0]))
            _images_have_pixels(other)


if __name__ == "__main__":
    h.import_addon()
    h.run([test_names_that_clash_on_disk_get_folders_of_their_own,
           test_windows_device_names_get_folders_windows_can_make,
           test_backslashes_in_saved_paths_still_name_the_files,
           test_a_copy_shares_the_folder_until_it_is_baked_itself,
           test_a_rebake_that_fails_keeps_the_previous_bake,
           test_revert_and_rebake_keep_a_mix_shader_added_after_the_bake,
           test_box_projection_leaves_filtering_to_the_renderer,
           test_undo_after_rebake_and_revert_finds_the_files,
           test_save_as_elsewhere_keeps_the_textures,
           test_a_damaged_record_on_another_material_stops_no_bake,
           test_folders_other_blend_files_use_are_kept,
           test_undo_after_a_save_finds_the_files,
           test_delete_unused_folders_keeps_what_ctrl_z_brings_back,
           test_delete_unused_folders_deletes_only_what_this_file_does_not_use,
           test_non_ascii_folder_and_material_names,
           test_names_that_differ_in_case_get_folders_of_their_own])
