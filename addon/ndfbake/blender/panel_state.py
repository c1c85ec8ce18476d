"""What the panel shows of a material, kept between redraws: Blender redraws a panel at every
mouse move over it, and a material's scan (material_scan.scan) walks its node tree. A scan is kept
until the data it reads may have changed: any material, node tree or image updated (the
depsgraph's update handler, which runs before the redraw that would show it), an undo or redo, a
file loaded. The handlers are installed by the add-on's register(), not at import (lobe_folders
says why a handler left behind keeps the bpy module from exiting)."""
import bpy
from bpy.app.handlers import persistent

from ..shading import material_scan
from . import app_handlers

# material.as_pointer() -> (the material's name, its scan); the name guards against a new material
# allocated where a deleted one was.
_scans = {}


def scan(material):
    """material_scan.scan(material), from the cache where the material has not changed since."""
    key = material.as_pointer() if material is not None else 0
    name = material.name if material is not None else None
    cached = _scans.get(key)
    if cached is None or cached[0] != name:
        cached = _scans[key] = (name, material_scan.scan(material))
    return cached[1]


def forget():
    _scans.clear()


@persistent
def _on_depsgraph_update(_scene, depsgraph):
    scanned = (bpy.types.Material, bpy.types.NodeTree, bpy.types.Image)  # what a scan reads
    if any(isinstance(update.id, scanned) for update in depsgraph.updates):
        forget()


@persistent
def _on_data_replaced(*_args):
    forget()


_HANDLERS = (("depsgraph_update_post", _on_depsgraph_update), ("undo_post", _on_data_replaced),
             ("redo_post", _on_data_replaced), ("load_post", _on_data_replaced))


def install_handlers():
    forget()
    app_handlers.install(__name__, _HANDLERS)


def remove_handlers():
    """Also those of an earlier load of this module (a reloaded add-on)."""
    forget()
    app_handlers.remove(__name__, _HANDLERS)
