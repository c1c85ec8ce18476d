"""Bake the normal-mapped materials of a .blend from the command line, with the add-on's own code
(bake.py, the same code the Bake button runs).

    blender -b scene.blend --python examples/bake_blend.py -- [--material NAME ...]
            [--max-lobes N] [--tolerance T] [--refine] [--level-of-detail scene|renderer]
            [--cycles-lobes widened|narrowed] [--pack] [--revert] [--no-save | --delete-unused]

Without --material it bakes every material the scene needs: those with a tangent-space normal
map (Image Texture -> Normal Map -> Principled BSDF) on objects the scene renders. Each material's
lobe textures go to //<material>.ndfbake/ beside the .blend. One line per material is printed,
then a summary; the .blend is saved afterwards (its node groups refer to the textures by relative
path), and the lobe folders this run wrote that the saved file does not use are deleted. With
--no-save nothing is saved and this run's lobe folders go when Blender exits (a dry run).
--revert undoes earlier bakes instead (nodes restored): without --material, those of the
materials of this file; baked materials linked from a library are left alone (the summary line
counts them: revert them in their own file). Folders of earlier runs stay, since other
.blend files may use them: --delete-unused also deletes, after the save, the lobe folders beside
the .blend that it does not use (as the panel's Delete Unused Lobe Folders).

Exit status: 0 when every material succeeded; 1 when any failed (a failed material and its files
are left exactly as they were; the others are still baked and saved), when the .blend could not
be saved, or on an unexpected error; 2 for bad usage (unknown option, a value out of range, a
material that does not exist, an unsaved .blend).

The add-on is the enabled or installed ndfbake if there is one (from Blender 4.2 on an extension,
module `bl_ext.<repository>.ndfbake`; before, a legacy add-on), else this repository's addon/
folder; the native library is the one inside the add-on folder, or $NDFBAKE_LIBRARY, or
build/native/libndfbake.so of this checkout (see addon/ndfbake/core/native.py).
"""
import argparse
import importlib
import os
import sys
import time

import bpy


def _is_ndfbake(module_name):
    """The legacy add-on's module, `ndfbake`, or an extension's, `bl_ext.<repository>.ndfbake`."""
    return module_name == "ndfbake" or (module_name.startswith("bl_ext.") and module_name.endswith(".ndfbake"))


def _import_addon():
    # An enabled add-on first (extension or legacy), then an installed one, then this checkout's.
    for name in bpy.context.preferences.addons.keys():
        if _is_ndfbake(name):
            return importlib.import_module(name)
    import addon_utils
    for module in addon_utils.modules(refresh=False):
        if _is_ndfbake(module.__name__):
            return importlib.import_module(module.__name__)
    here = os.path.dirname(os.path.abspath(__file__))
    sys.path.insert(0, os.path.join(here, "..", "addon"))
    import ndfbake
    return ndfbake


def _bounded(kind, low, high):
    """An argparse type: `kind` within [low, high], else a usage error (status 2)."""
    def parse(text):
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError("not a number: %r" % text) from None
        if not low <= value <= high:
            raise argparse.ArgumentTypeError("%s is not in %s..%s" % (text, low, high))
        return value
    return parse


def _arguments():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser(prog="blender -b FILE.blend --python examples/bake_blend.py --",
                                     description="Bake (or revert) ndfbake lobes for the materials of a .blend.")
    parser.add_argument("--material", action="append", default=[], metavar="NAME",
                        help="a material to bake (repeat for several); default: every material the scene needs")
    parser.add_argument("--max-lobes", type=_bounded(int, 1, 8), default=4,
                        help="vMF lobes per texel at most (1..8, default 4)")
    parser.add_argument("--tolerance", type=_bounded(float, 0.0, 1.0), default=0.0,
                        help="relative error a texel may keep, 0..1: fewer lobes where it suffices (default 0)")
    parser.add_argument("--refine", action="store_true",
                        help="refine the lobes for each material's roughness (lower error, 100-300x the fit time)")
    parser.add_argument("--level-of-detail", choices=("scene", "renderer"), default="scene",
                        help="scene (default): the node group picks a level per pixel from the scene camera and "
                             "only the levels the cameras reach are baked; renderer: level 0, filtered by the "
                             "renderer (EEVEE's own MIP levels)")
    parser.add_argument("--cycles-lobes", choices=("widened", "narrowed"), default="narrowed",
                        help="what Cycles draws: lobes narrowed toward grazing views (default: the filtered "
                             "look's brightness there), or widened only: the fewest fireflies at low sample counts")
    parser.add_argument("--pack", action="store_true", help="also pack the lobe textures into the .blend")
    parser.add_argument("--revert", action="store_true", help="undo earlier bakes instead of baking")
    saving = parser.add_mutually_exclusive_group()
    saving.add_argument("--no-save", action="store_true",
                        help="do not save the .blend afterwards (this run's lobe folders go at exit: a dry run)")
    saving.add_argument("--delete-unused", action="store_true",
                        help="after saving, delete the lobe folders beside the .blend that it does not use "
                             "(other .blend files there may still use them)")
    return parser.parse_args(argv)  # exits with status 2 on bad usage


def _delete_unused(lobe_folders):
    """--delete-unused: the folders beside the saved .blend that it does not use. Returns 0 or 1."""
    folders = lobe_folders.unused_folders()
    _, left = lobe_folders.delete_folders(folders)
    print("deleted %d unused lobe folder%s%s" % (len(folders), "" if len(folders) == 1 else "s",
                                                  ": " + ", ".join(os.path.basename(f) for f in folders)
                                                  if folders else ""))
    for what in left:
        print("FAILED deleting %s" % what)
    return 1 if left else 0


def main():
    args = _arguments()
    addon = _import_addon()
    bake = importlib.import_module(addon.__name__ + ".blender.bake")
    lobe_folders = importlib.import_module(addon.__name__ + ".blender.lobe_folders")
    if not bpy.data.filepath:
        print("bake_blend: open a saved .blend: blender -b FILE.blend --python examples/bake_blend.py", file=sys.stderr)
        return 2
    linked = []
    if args.material:
        missing = [name for name in args.material if name not in bpy.data.materials]
        if missing:
            print("bake_blend: no material named %s in %s" % (", ".join(repr(m) for m in missing), bpy.data.filepath),
                  file=sys.stderr)
            return 2
        materials = [bpy.data.materials[name] for name in args.material]
    elif args.revert:
        baked = [m for m in bpy.data.materials if bake.is_baked(m)]
        materials = [m for m in baked if m.library is None]
        # A baked material linked from a library is reverted in its own file (bake.revert refuses
        # it), as the bake leaves it to its own file: not a failure of this one.
        linked = sorted(m.name for m in baked if m.library is not None)
    else:
        materials = bake.materials_needing_bake(bpy.context.scene)
    linked_note = ("; left %d baked material%s linked from a library alone (revert %s in %s own file): %s"
                   % (len(linked), "" if len(linked) == 1 else "s", "it" if len(linked) == 1 else "them",
                      "its" if len(linked) == 1 else "their", ", ".join(linked))) if linked else ""
    if not materials:
        print("bake_blend: nothing to %s in %s%s" % ("revert" if args.revert else "bake", bpy.data.filepath,
                                                   linked_note))
        return _delete_unused(lobe_folders) if args.delete_unused else 0

    settings = bake.BakeSettings(max_lobes=args.max_lobes, tolerance=args.tolerance, refine=args.refine,
                                 pack=args.pack, level_of_detail=args.level_of_detail.upper(),
                                 cycles_lobes=args.cycles_lobes.upper())
    start = time.perf_counter()
    failures = 0
    changed = 0
    for material in materials:
        try:
            if args.revert:
                folder, kept_for = bake.revert(material)
                print("reverted %s%s" % (material.name, "; its lobe folder stays: %s use it" % ", ".join(kept_for)
                                         if kept_for else ""))
            else:
                result = bake.bake_material(material, settings)
                print("baked %s into %s: %s" % (material.name, result.folder, result.summary))
            changed += 1
        except bake.BakeError as e:
            failures += 1
            print("FAILED %s [%s]: %s" % (material.name, e.code, e.message))
    if changed and not args.no_save:
        try:
            bpy.ops.wm.save_mainfile()
        except RuntimeError as e:
            print("FAILED saving %s: %s; nothing was saved, and the new lobe folders, which no saved "
                  ".blend uses, are deleted" % (bpy.data.filepath, str(e).strip()))
            return 1
        # What closing the file does (also at exit): the lobe folders no saved .blend uses go.
        lobe_folders.delete_unused_folders()
    if args.delete_unused and _delete_unused(lobe_folders):  # the file on disk is the one in memory
        failures += 1
    print("%s %d of %d materials in %.1f s%s%s" % ("reverted" if args.revert else "baked", changed, len(materials),
                                                 time.perf_counter() - start,
                                                 ", saved " + bpy.data.filepath if changed and not args.no_save else "",
                                                 linked_note))
    return 1 if failures else 0


if __name__ == "__main__":
    try:
        status = main()
    except Exception:  # a bug: Blender would print it and still exit 0
        import traceback
        traceback.print_exc()
        status = 1
    sys.exit(status)
