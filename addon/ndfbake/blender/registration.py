"""The add-on turned on and off (the package's register() and unregister() call these): the
panel's and operators' classes, the per-material settings, the lobe folders' and panel's
handlers."""
import atexit

import bpy

from . import lobe_folders, operators, panel_state, ui


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
