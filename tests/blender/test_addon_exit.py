"""A script on the bpy module that imports, registers or bakes with the add-on ends on its own,
with status 0, by Python's normal exit (no os._exit), and a background session's unsaved lobe
folders are gone after it.

Run: <bpy venv>/bin/python tests/blender/test_addon_exit.py -- LIB

Each case is a new Python process (this one's, which has bpy) given 120 s. Before the fix, a
function of the add-on left in bpy.app.handlers or a class left registered kept bpy alive past
Python's finalization: PyPI's 4.5 hung in its own exit and 4.2 crashed (status 139), on a bare
`import ndfbake`. The bpy module only: Blender's binary turns add-ons off at its own exit.
"""
import os
import subprocess
import sys
import textwrap

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import test_addon_helpers as h  # noqa: E402

EXIT_SECONDS = 120

# The start of every baking case: the add-on imported (registered or not), a saved .blend with one
# normal-mapped material.
_SCENE = """
import os, sys
import bpy
sys.path.insert(0, %(here)r)
import test_addon_helpers as h
directory = %(directory)r
h.import_addon(register=%(register)s)
material = h.baked_scene(directory)
"""


def _run_child(code, directory, name):
    """Runs `code` in a new bpy Python; returns its output. Fails on a timeout or a status not 0."""
    script = os.path.join(directory, name + ".py")
    with open(script, "w") as f:
        f.write(textwrap.dedent(code))
    library, _ = h.arguments()
    env = dict(os.environ, NDFBAKE_LIBRARY=library)
    try:
        done = subprocess.run([sys.executable, script, "--", library], capture_output=True, text=True,
                              timeout=EXIT_SECONDS, env=env)
    except subprocess.TimeoutExpired as e:
        raise AssertionError("%s: the process had not ended after %d s (it printed: %s)"
                             % (name, EXIT_SECONDS, (e.stdout or b"")[-800:])) from None
    output = done.stdout + done.stderr
    h.expect(done.returncode == 0, "%s: exit status %d: %s" % (name, done.returncode, output[-1500:]))
    h.expect("CHILD DONE" in done.stdout, "%s: the script did not run to its end: %s" % (name, output[-1500:]))
    return output


def _lobe_folders(directory):
    return sorted(name for name in os.listdir(directory) if name.endswith(".ndfbake"))


def test_importing_every_module_leaves_nothing_running():
    """import bpy, then the package and every module in its subpackages; the script ends at once."""
    with h.scratch_dir() as directory:
        _run_child("""
            import importlib, os, pkgutil, sys
            import bpy
            sys.path.insert(0, %r)
            import ndfbake
            names = [m.name for m in pkgutil.walk_packages(ndfbake.__path__, "ndfbake.")]
            for name in names:
                importlib.import_module(name)
            assert len(names) > 25 and "ndfbake.blender.ui" in sys.modules, names
            print("CHILD DONE", flush=True)
        """ % h.ADDON_PARENT, directory, "import_only")


def test_registered_and_baked_session_ends_and_deletes_its_unsaved_folder():
    """Registered, baked (a background session: a lobe folder beside the saved .blend, not saved
    again), never unregistered: the script ends, and its unsaved folder is deleted at exit."""
    with h.scratch_dir() as directory:
        _run_child(_SCENE % {"here": h.HERE, "directory": directory, "register": True} + textwrap.dedent("""
            from ndfbake.blender import bake
            bake.bake_material(material, bake.BakeSettings(max_lobes=2))
            assert [n for n in os.listdir(directory) if n.endswith(".ndfbake")], "no lobe folder"
            print("CHILD DONE", flush=True)
        """), directory, "registered")
        h.expect(_lobe_folders(directory) == [], "the unsaved folders stayed: %s" % _lobe_folders(directory))


def test_unregistered_bake_ends_and_keeps_the_saved_folder():
    """Baked through bake.py without registering, then saved: the script ends, and the folder the
    saved .blend uses stays."""
    with h.scratch_dir() as directory:
        _run_child(_SCENE % {"here": h.HERE, "directory": directory, "register": False} + textwrap.dedent("""
            from ndfbake.blender import bake
            bake.bake_material(material, bake.BakeSettings(max_lobes=2))
            bpy.ops.wm.save_mainfile()
            print("CHILD DONE", flush=True)
        """), directory, "unregistered")
        h.expect(len(_lobe_folders(directory)) == 1, "the saved folder: %s" % _lobe_folders(directory))


if __name__ == "__main__":
    if bpy.app.binary_path:
        print("SKIP test_addon_exit: Blender's binary turns add-ons off at its own exit; this is the bpy "
              "module's test")
    else:
        h.import_addon(register=False)
        h.run([test_importing_every_module_leaves_nothing_running,
               test_registered_and_baked_session_ends_and_deletes_its_unsaved_folder,
               test_unregistered_bake_ends_and_keeps_the_saved_folder])
