"""Taking a bake out of a material: revert(), and the removal of a bake's nodes and images that
finish() also uses (a re-bake's previous nodes, or its own on an error). Main thread only.

Revert leads the group node's links back to the Principled BSDF(s), writes the user's edits on
the group node back (group_node.remove_group_node), removes the group node, its node groups, the
OSL text and the lobe images, puts back the material's Transparent Shadows (transparent_shadow.py)
and deletes the bake record; the lobe files stay for Ctrl-Z (when they go: lobe_folders.py).
bake.revert is this module's revert().

May call: group_node, nodes, osl_group, node_builders, material_scan, lobe_folders,
transparent_shadow, bake_job (BakeError). Called by: bake.
"""
import bpy

from ..shading import bake_record, group_node, node_builders, nodes, osl_group, transparent_shadow
from . import lobe_folders
from ..core.bake_job import BakeError


def remove_nodes(material, rec, keep_edits=True):
    """Removes a bake's nodes; with keep_edits, what the user changed on its group nodes goes back
    to the Principled BSDFs (group_node.write_back_inputs)."""
    tree = material.node_tree
    used = []
    for target in rec.get("targets", []):
        bypassed = [tuple(b) for b in target.get("bypassed", [])]
        group = group_node.remove_group_node(tree, target["group_node"], target["principled"], bypassed,
                                        target.get("eevee_output", ""), keep_edits, target.get("normal_map", ""),
                                        target.get("principled_settings"))
        if group is not None:
            used.append(group.name)
        used.append(target.get("node_group", ""))
    nodes.remove_unused_groups(used)


def remove_images(names):
    for name in names:
        image = bpy.data.images.get(name)
        if image is not None and image.get(node_builders.TAG) is not None and image.users == 0:
            bpy.data.images.remove(image)


def revert(material):
    """Restores the material as it was before the bake. Its lobe folder stays for Ctrl-Z (when it
    goes: lobe_folders.py). Returns (the folder, [names of the other materials that use it])."""
    rec = bake_record.record(material) if material is not None else None
    if rec is None:
        raise BakeError("NOT_BAKED", "material '%s' has no ndfbake bake to revert" % (
            material.name if material is not None else ""))
    if material.library is not None:
        raise BakeError("LINKED_MATERIAL", "material '%s' is linked from %s: revert it in that file"
                        % (material.name, material.library.filepath))
    folder = lobe_folders.record_folder(rec)
    remove_nodes(material, rec)
    osl_group.remove_unused_text()
    remove_images(rec.get("images", []))
    transparent_shadow.restore(material, rec)
    del material[bake_record.RECORD_KEY]
    return folder, [m.name for m in lobe_folders.folder_users(folder)] if folder else []
