"""The add-on turned on and off (the package's register() and unregister() call these): the
panel's and operators' classes, the per-material settings, the lobe folders' and panel's
handlers, and `blender -c ndfbake` (command_line.command) where Blender has commands (4.2+)."""
import atexit

import bpy

from ..core import native
from . import command_line, lobe_folders, operators, panel_state, ui

_cli_command = None  # register_cli_command's handle (Blender 4.2+: `blender -c ndfbake`)


def register():
    global _cli_command
    lobe_folders.install_handlers()
    panel_state.install_handlers()
    ui.NDFBakeSettings.__annotations__["max_lobes"] = ui.max_lobes_property(native.status()[0])
    for cls in ui.classes + operators.classes:
        bpy.utils.register_class(cls)
    bpy.types.Material.ndfbake_settings = bpy.props.PointerProperty(type=ui.NDFBakeSettings)
    if hasattr(bpy.utils, "register_cli_command") and _cli_command is None:
        _cli_command = bpy.utils.register_cli_command("ndfbake", command_line.command)
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
    global _cli_command
    atexit.unregister(_unregister_at_exit)
    if not hasattr(bpy.types.Material, "ndfbake_settings"):  # registered last by register()
        return
    if _cli_command is not None:
        bpy.utils.unregister_cli_command(_cli_command)
        _cli_command = None
    operators.stop_running_bakes(bpy.context)
    lobe_folders.remove_handlers()  # and nothing of this session is deleted any more
    panel_state.remove_handlers()
    del bpy.types.Material.ndfbake_settings
    for cls in reversed(ui.classes + operators.classes):
        bpy.utils.unregister_class(cls)
