"""ndfbake: normal maps that stay right at every distance (Han et al. 2007 vMF lobes).

From Blender 4.2 on, install the extension zip for your platform that the build leaves in its
folder, ndfbake-<version>-<platform>.zip (Get Extensions > Install from Disk; blender_manifest.toml
says what it is); in Blender 3.4, ndfbake-<version>.zip (Preferences > Add-ons > Install; bl_info
below), or put this folder into a scripts path's addons/. The native library (ndfbake.dll,
libndfbake.dylib or libndfbake.so: native.LIBRARY_NAME) lives beside
this file; see native.py for where else it is looked for. Registering never fails
for want of the library: the panel then shows why it cannot be used.

Three packages, each importing only those before it (tests/tools/test_addon_imports.py checks):
- core: the library's binding (native), the bake's native step (bake_job), folder names: no bpy,
  importable by a plain Python;
- shading: what a bake builds in Blender's data: the material scan, node groups, level of detail,
  the OSL variant;
- blender: the bake as Blender runs it (bake, bake_revert, lobe_folders), its operators, panel and
  handlers (registration).
Scripts call blender/bake.py (`from ndfbake.blender import bake`), or the operators
bpy.ops.ndfbake.bake / bake_all / revert; examples/bake_blend.py is a command line. Importing the
package asks Blender nothing and starts nothing: register() does the rest.
"""

bl_info = {
    "name": "ndfbake",
    "author": "ndfbake",
    "version": (0, 1, 0),          # = the CMake project version (tests check it against the library)
    "blender": (3, 4, 0),
    "location": "Properties > Material > ndfbake",
    "description": "Filter normal maps by their normal distribution: lobe textures and node groups "
                   "for EEVEE and Cycles",
    "category": "Material",
}


def register():
    from .blender import registration
    registration.register()


def unregister():
    from .blender import registration
    registration.unregister()


def _reload_submodules():
    """Blender's Reload Scripts reloads this module only: reload the loaded submodules too, each
    after the submodules it took names from (a name bound with `from x import name` keeps the
    object of x's earlier load otherwise)."""
    import importlib
    import sys
    import types
    loaded = {name: module for name, module in sys.modules.items() if name.startswith(__name__ + ".")}

    def dependencies(module):
        found = set()
        for value in vars(module).values():
            name = value.__name__ if isinstance(value, types.ModuleType) else getattr(value, "__module__", None)
            if name in loaded and name != module.__name__:
                found.add(name)
        return found
    done = set()

    def reload(name):
        if name in done:
            return
        done.add(name)
        for dependency in sorted(dependencies(loaded[name])):
            reload(dependency)
        importlib.reload(loaded[name])
    for name in sorted(loaded):
        reload(name)


if "_imported_once" in globals():
    _reload_submodules()
_imported_once = True
