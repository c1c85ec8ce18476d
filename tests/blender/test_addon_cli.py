"""The scripted bake (addon/ndfbake/blender/command_line.py) through examples/bake_blend.py: a .blend baked from the command line.

Run: blender -b --factory-startup --python-exit-code 1 --python tests/blender/test_addon_cli.py -- LIB

A .blend with two rendered materials, "Good" (a PNG normal map) and "Bad" (its normal map's Color
Space is sRGB), and an unrendered "Hidden" one. The script runs in a separate `blender -b`:
- baking everything the scene needs exits 1, prints the baked material's report and the other's
  specific failure, saves the file: Good is baked, Bad and Hidden are exactly as they were;
- naming Good alone exits 0 (a new folder; the replaced one stays, the first run's saved file used
  it); --revert restores Good exactly (the folders stay for the same reason);
- an unknown material and --max-lobes 0 exit 2, changing nothing;
- a bake whose .blend cannot be saved exits 1 with a FAILED line, and its lobe folder, which no
  saved file uses, goes;
- --delete-unused deletes the earlier runs' folders the file does not use (not with --no-save);
- --revert in a file that links a baked material from a library reverts the file's own baked
  materials, leaves the linked one alone (the summary says so) and exits 0.
"""
import json
import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import test_addon_helpers as h  # noqa: E402



def reopen(blend):
    bpy.ops.wm.open_mainfile(filepath=blend)
    return {name: h.dump_material(bpy.data.materials[name]) for name in ("Good", "Bad", "Hidden")}


def test_command_line_bake_and_revert():
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        h.reset_scene()
        png = h.write_normal_map(os.path.join(directory, "normal.png"), "weave", 64)
        good = h.normal_mapped_material("Good", png)
        h.plane_with(good, "A")
        bad_png = h.write_normal_map(os.path.join(directory, "srgb.png"), "bumps", 32)
        h.plane_with(h.normal_mapped_material("Bad", bad_png, colorspace="sRGB"), "B")
        h.plane_with(h.normal_mapped_material("Hidden", png), "C").hide_render = True
        blend = os.path.join(directory, "scene.blend")
        bpy.ops.wm.save_as_mainfile(filepath=blend)
        original = reopen(blend)

        code, out = h.run_bake_blend(blend, "--max-lobes", "2", "--refine")
        h.expect(code == 1, "one failure must exit 1, got %d:\n%s" % (code, out))
        h.expect("baked Good into //Good.ndfbake: 2 lobes" in out, out)
        h.expect("FAILED Bad [COLOR_SPACE]: image 'srgb.png' has Color Space 'sRGB'" in out, out)
        h.expect("baked 1 of 2 materials" in out, out)
        after = reopen(blend)
        h.expect(bake.is_baked(bpy.data.materials["Good"]), "Good not baked in the saved file")
        with open(os.path.join(directory, "Good.ndfbake", "report.json")) as f:
            h.expect(json.load(f)["settings"]["refined_for_brdf"] is True, "--refine did not reach the library")
        h.expect(after["Bad"] == original["Bad"] and after["Hidden"] == original["Hidden"],
                 "a material that was not baked changed")
        h.expect(sorted(os.listdir(directory)) == ["Good.ndfbake", "normal.png", "scene.blend", "scene.blend1",
                                                   "srgb.png"], sorted(os.listdir(directory)))

        code, out = h.run_bake_blend(blend, "--material", "Good", "--max-lobes", "1", "--cycles-lobes", "widened")
        h.expect(code == 0, "re-bake of Good: exit %d\n%s" % (code, out))
        h.expect("baked Good into //Good~2.ndfbake: 1 lobe," in out, out)
        h.expect("Cycles draws the lobes widened only" in out, "--cycles-lobes widened not said:\n" + out)
        reopen(blend)
        h.expect(json.loads(bpy.data.materials["Good"][bake.RECORD_KEY])["settings"]["cycles_lobes"] == "WIDENED",
                 "--cycles-lobes widened did not reach the bake")
        h.expect(os.path.isdir(os.path.join(directory, "Good.ndfbake")),
                 "the replaced folder, which the file saved by the first run used, was deleted")

        code, out = h.run_bake_blend(blend, "--revert")
        h.expect(code == 0, "revert: exit %d\n%s" % (code, out))
        h.expect("reverted Good" in out, out)
        h.expect(reopen(blend) == original, "the reverted file differs from the original")
        h.expect(sorted(f for f in os.listdir(directory) if f.endswith(".ndfbake")) == ["Good.ndfbake", "Good~2.ndfbake"],
                 "lobe folders after revert: %s (saved files used both: they stay)" % os.listdir(directory))

        mtime = os.path.getmtime(blend)
        code, out = h.run_bake_blend(blend, "--material", "Nope")
        h.expect(code == 2 and "no material named 'Nope'" in out, "unknown material: exit %d\n%s" % (code, out))
        code, out = h.run_bake_blend(blend, "--max-lobes", "0")
        h.expect(code == 2 and "max_lobes must be in 1..8, got 0" in out, "--max-lobes 0: exit %d\n%s" % (code, out))
        code, out = h.run_bake_blend(blend, "--cycles-lobes", "sharp")
        h.expect(code == 2 and "invalid choice: 'sharp'" in out, "--cycles-lobes sharp: exit %d\n%s" % (code, out))
        h.expect(os.path.getmtime(blend) == mtime, "the .blend was saved after a usage error")

        # Blender writes "<file>@" and renames it over the file: a folder of that name makes the
        # save fail (for root too, unlike permissions).
        os.mkdir(blend + "@")
        code, out = h.run_bake_blend(blend, "--material", "Good")
        h.expect(code == 1 and "FAILED saving %s" % blend in out, "a failed save: exit %d\n%s" % (code, out))
        h.expect(os.path.getmtime(blend) == mtime, "the .blend changed although its save failed")
        h.expect(sorted(f for f in os.listdir(directory) if ".ndfbake" in f) == ["Good.ndfbake", "Good~2.ndfbake"],
                 "the unsaved bake's folder was left: %s" % os.listdir(directory))

        # The folders of earlier runs go only when asked; never together with --no-save.
        os.rmdir(blend + "@")
        code, out = h.run_bake_blend(blend, "--delete-unused", "--no-save")
        h.expect(code == 2, "--delete-unused with --no-save: exit %d\n%s" % (code, out))
        code, out = h.run_bake_blend(blend, "--revert", "--delete-unused")
        h.expect(code == 0 and "deleted 2 unused lobe folders: Good.ndfbake, Good~2.ndfbake" in out,
                 "--delete-unused: exit %d\n%s" % (code, out))
        h.expect(not [f for f in os.listdir(directory) if ".ndfbake" in f], "left: %s" % os.listdir(directory))


def test_revert_leaves_linked_materials_alone():
    """--revert reverts this file's baked materials; one linked from a library (baked in its own
    file) is left alone and counted in the summary, and the run succeeds."""
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        shared = h.baked_scene(directory, material_name="Shared")
        local = h.normal_mapped_material("Local", os.path.join(directory, "normal.png"))
        h.plane_with(local, "P2")
        bpy.ops.wm.save_mainfile()
        for material in (shared, local):
            bake.bake_material(material, bake.BakeSettings(max_lobes=1, level_of_detail="RENDERER"))
        bpy.ops.wm.save_mainfile()
        library_mtime = os.path.getmtime(os.path.join(directory, "scene.blend"))
        shot = os.path.join(directory, "shot.blend")
        h.shot_with_material_from(directory, "Shared", link=True)
        with bpy.data.libraries.load(os.path.join(directory, "scene.blend"), link=False) as (source, target):
            target.materials = ["Local"]
        h.plane_with(bpy.data.materials["Local"], "P2")
        bpy.ops.wm.save_mainfile()

        code, out = h.run_bake_blend(shot, "--revert")
        h.expect(code == 0, "revert with a linked baked material: exit %d\n%s" % (code, out))
        h.expect("reverted Local" in out and "FAILED" not in out, out)
        h.expect("reverted 1 of 1 materials" in out and "left 1 baked material linked from a library alone "
                 "(revert it in its own file): Shared" in out, out)
        bpy.ops.wm.open_mainfile(filepath=shot)
        h.expect(not bake.is_baked(bpy.data.materials["Local"]), "Local is still baked")
        h.expect(bake.is_baked(bpy.data.materials["Shared"]), "the linked material lost its bake")
        h.expect(os.path.getmtime(os.path.join(directory, "scene.blend")) == library_mtime, "the library changed")

        code, out = h.run_bake_blend(shot, "--revert")  # only the linked one is baked now
        h.expect(code == 0 and "nothing to revert in %s; left 1 baked material linked" % shot in out,
                 "nothing local to revert: exit %d\n%s" % (code, out))


if __name__ == "__main__":
    h.import_addon()
    h.run([test_command_line_bake_and_revert, test_revert_leaves_linked_materials_alone])
