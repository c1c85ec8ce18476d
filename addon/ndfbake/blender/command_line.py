"""The scripted bake: the normal-mapped materials of a .blend baked from the command line, with the
same code the Bake button runs (bake.py). Three ways in:

    blender -c ndfbake FILE.blend [OPTIONS]                  (Blender 4.2+, the extension enabled)
    blender -b FILE.blend --python examples/bake_blend.py -- [OPTIONS]
    run(argv) from a script, with the .blend open

OPTIONS: [--material NAME ...] [--max-lobes N] [--tolerance T] [--refine]
[--level-of-detail scene|renderer] [--cycles-lobes widened|narrowed] [--pack] [--revert]
[--no-save | --delete-unused]; --help lists them.

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
"""
import argparse
import os
import sys
import time

import bpy

from ..core import native
from . import bake, lobe_folders

PROG = "blender -c ndfbake FILE.blend"


def _lobe_help():
    """--max-lobes' help: the library's limit and default (nothing where it cannot be loaded)."""
    lib, _ = native.status()
    limits = " (1..%d, default %d)" % (lib.max_lobes, lib.default_max_lobes) if lib is not None else ""
    return "vMF lobes per texel at most" + limits


def _settings_problem(args):
    """The library's word on --max-lobes and --tolerance (None where they are fine, or where there
    is no library: each bake then says so)."""
    lib, _ = native.status()
    if lib is None:
        return None
    try:
        with lib.context() as ctx:
            ctx.fit_options(max_lobes=args.max_lobes, tolerance=args.tolerance)
    except native.Error as e:
        return e.message
    return None


def parser(prog):
    """The options of a scripted bake (argparse: a bad one exits with status 2)."""
    defaults = bake.BakeSettings()
    parser = argparse.ArgumentParser(prog=prog, description="Bake (or revert) ndfbake lobes for the materials of "
                                                            "a .blend.")
    parser.add_argument("--material", action="append", default=[], metavar="NAME",
                        help="a material to bake (repeat for several); default: every material the scene needs")
    parser.add_argument("--max-lobes", type=int, default=defaults.max_lobes, help=_lobe_help())
    parser.add_argument("--tolerance", type=float, default=defaults.tolerance,
                        help="relative error a texel may keep, 0..1: fewer lobes where it suffices (default %g)"
                             % defaults.tolerance)
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
    return parser


def _delete_unused():
    """--delete-unused: the folders beside the saved .blend that it does not use. Returns 0 or 1."""
    folders = lobe_folders.unused_folders()
    _, left = lobe_folders.delete_folders(folders)
    print("deleted %d unused lobe folder%s%s" % (len(folders), "" if len(folders) == 1 else "s",
                                                  ": " + ", ".join(os.path.basename(f) for f in folders)
                                                  if folders else ""))
    for what in left:
        print("FAILED deleting %s" % what)
    return 1 if left else 0


def run(argv, prog=PROG):
    """A scripted bake of the open .blend with the options `argv` (parser); returns the exit
    status (the module's docstring)."""
    try:
        args = parser(prog).parse_args(argv)
    except SystemExit as e:  # argparse: --help (0) or bad usage (2)
        return e.code if isinstance(e.code, int) else 2
    problem = None if args.revert else _settings_problem(args)
    if problem:
        print("ndfbake: %s (see --help)" % problem, file=sys.stderr)
        return 2
    if not bpy.data.filepath:
        print("ndfbake: open a saved .blend first", file=sys.stderr)
        return 2
    linked = []
    if args.material:
        missing = [name for name in args.material if name not in bpy.data.materials]
        if missing:
            print("ndfbake: no material named %s in %s" % (", ".join(repr(m) for m in missing), bpy.data.filepath),
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
        print("ndfbake: nothing to %s in %s%s" % ("revert" if args.revert else "bake", bpy.data.filepath,
                                                linked_note))
        return _delete_unused() if args.delete_unused else 0

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
    if args.delete_unused and _delete_unused():  # the file on disk is the one in memory
        failures += 1
    print("%s %d of %d materials in %.1f s%s%s" % ("reverted" if args.revert else "baked", changed, len(materials),
                                                 time.perf_counter() - start,
                                                 ", saved " + bpy.data.filepath if changed and not args.no_save else "",
                                                 linked_note))
    return 1 if failures else 0


def command(argv):
    """`blender -c ndfbake FILE.blend [OPTIONS]` (bpy.utils.register_cli_command, Blender 4.2+):
    opens FILE.blend, then run()."""
    if not argv or argv[0].startswith("-"):
        if "--help" in argv or "-h" in argv:
            return run(["--help"])
        print("ndfbake: name the .blend to bake first: %s [OPTIONS]" % PROG, file=sys.stderr)
        return 2
    try:
        bpy.ops.wm.open_mainfile(filepath=argv[0])
    except RuntimeError as e:
        print("ndfbake: cannot open %s: %s" % (argv[0], str(e).strip()), file=sys.stderr)
        return 2
    return run(argv[1:])
