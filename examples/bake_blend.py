"""Bake the normal-mapped materials of a .blend from the command line, with the add-on's own code:
its scripted bake (addon/ndfbake/blender/command_line.py, the same code the Bake button runs),
which Blender 4.2+ also runs as `blender -c ndfbake FILE.blend [OPTIONS]`.

    blender -b scene.blend --python examples/bake_blend.py -- [--material NAME ...]
            [--max-lobes N] [--tolerance T] [--refine] [--level-of-detail scene|renderer]
            [--cycles-lobes widened|narrowed] [--pack] [--revert] [--no-save | --delete-unused]

What it does, and its exit status (0 all baked, 1 a failure, 2 bad usage): command_line.py.

The add-on is the enabled or installed ndfbake if there is one (from Blender 4.2 on an extension,
module `bl_ext.<repository>.ndfbake`; before, a legacy add-on), else this repository's addon/
folder; the native library is the one inside the add-on folder, or $NDFBAKE_LIBRARY, or
build/native/libndfbake.so of this checkout (see addon/ndfbake/core/native.py).
"""
import importlib
import os
import sys

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


if __name__ == "__main__":
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    try:
        command_line = importlib.import_module(_import_addon().__name__ + ".blender.command_line")
        status = command_line.run(argv, prog="blender -b FILE.blend --python examples/bake_blend.py --")
    except Exception:  # a bug: Blender would print it and still exit 0
        import traceback
        traceback.print_exc()
        status = 1
    sys.exit(status)
