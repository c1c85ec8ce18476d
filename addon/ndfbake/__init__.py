"""ndfbake: normal maps that stay right at every distance (Han et al. 2007 vMF lobes).

From Blender 4.2 on, install the extension zip for your platform that the build leaves in its
folder, ndfbake-<version>-<platform>.zip (Get Extensions > Install from Disk; blender_manifest.toml
says what it is); in Blender 3.4, ndfbake-<version>.zip (Preferences > Add-ons > Install; bl_info
below), or put this folder into a scripts path's addons/. The native library (ndfbake.dll,
libndfbake.dylib or libndfbake.so: native.LIBRARY_NAME) lives beside
this file; see native.py for where else it is looked for. Registering never fails
for want of the library: the panel then shows why it cannot be used.

Modules: native (ctypes), image_pixels (the normal map as Blender decodes it), blender_compat (what
differs between Blender versions), material_scan (finds the normal map), scene_lod (what the scene's
cameras need), nodes (node groups), lobe_folders (where the textures go, and when they are
deleted), bake (the work: bake_job its native step, bake_revert its revert), operators and ui
(thin skins; panel_state keeps the panel's scans between redraws). Scripts call bake.py, or the operators bpy.ops.ndfbake.bake / bake_all / revert;
examples/bake_blend.py is a command line.
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

if "bpy" in locals():
    import importlib
    for _module in (blender_compat, id_names, native, image_pixels, node_animation, material_scan,  # noqa: F821
                    scene_lod, node_builders, specular_albedo_table, specular_split, lobe_nodes, lod_nodes,  # noqa: F821
                    nodes, group_node, osl_group, lobe_folders, bake_job, bake_revert, bake, operators,  # noqa: F821
                    panel_state, ui):  # noqa: F821
        importlib.reload(_module)

import atexit  # noqa: E402

import bpy  # noqa: E402

from . import (bake, bake_job, bake_revert, blender_compat, group_node, id_names, image_pixels,  # noqa: E402,F401
               lobe_folders, lobe_nodes, lod_nodes, material_scan, native, node_animation, node_builders, nodes,
               operators, osl_group, panel_state, scene_lod, specular_albedo_table, specular_split, ui)


def register():
    lobe_folders.install_handlers()
    panel_state.install_handlers()
    for cls in ui.classes + operators.classes:
        bpy.utils.register_class(cls)
    bpy.types.Material.ndfbake_settings = bpy.props.PointerProperty(type=ui.NDFBakeSettings)
    if not bpy.app.binary_path:  # the bpy module: see _unregister_at_exit
        atexit.register(_unregister_at_exit)


def _unregister_at_exit():
    """In the bpy module, a class left registered keeps bpy alive past Python's finalization,
    where PyPI's 4.5 hangs and 4.2 crashes (lobe_folders.exit_session), and only add-ons enabled
    through addon_utils are turned off at its exit, after this: a script that called register()
    itself would not end. The unsaved folders go first, as at any exit."""
    lobe_folders.exit_session()
    unregister()


def unregister():
    """Also after _unregister_at_exit, when the bpy module's exit turns the add-on off again."""
    atexit.unregister(_unregister_at_exit)
    if not hasattr(bpy.types.Material, "ndfbake_settings"):  # registered last by register()
        return
    operators.stop_running_bakes(bpy.context)
    lobe_folders.remove_handlers()  # and nothing of this session is deleted any more
    panel_state.remove_handlers()
    del bpy.types.Material.ndfbake_settings
    for cls in reversed(ui.classes + operators.classes):
        bpy.utils.unregister_class(cls)
