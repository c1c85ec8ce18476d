"""Material > Settings > Transparent Shadows (Blender 4.2+) of a baked material that is opaque.

A bake wires the Principled BSDF's Alpha through the group (each lobe's, the emission's, a
Transparent BSDF mixed over the lobes: nodes.py), so EEVEE's shader compiler marks the baked
material transparent even where Alpha is 1 and the plain material was opaque. With Transparent
Shadows on (a new material's default since 4.2), EEVEE Next in 4.2-4.5 then renders its shadow
maps with the whole surface node tree, every lobe's atlas lookups included, where the plain
material used the opaque shadow shader: on llvmpipe a frame of the demo scene took 25x the plain
one in 4.3 (docs/speed.md, "EEVEE Next frame time in 4.2/4.3"). An opaque material's shadows
are the same either way (an Alpha of 1 discards nothing), so a bake turns the setting off where
the material is opaque, records what it was, and Revert (or a re-bake of a material that is no
longer opaque) puts it back (with 4.2-4.x's deprecated Shadow Mode, which follows it). Blender 3.4's EEVEE Legacy has no such setting (its Shadow Mode
stays as the user set it).

May call: bpy, node_animation, node_builders (TAG). Called by: bake, bake_revert.
"""
import bpy

from . import node_animation
from .node_builders import TAG

RECORD_FIELD = "transparent_shadow"  # in the bake record: the settings before the first bake turned it off
SETTINGS = ("use_transparent_shadow", "shadow_method")
OPAQUE_ALPHA = 1.0 - 1e-5            # what EEVEE's Principled BSDF counts as an Alpha of 1


def _opaque_alpha(tree, node, top):
    socket = node.inputs.get("Alpha")
    if socket is None:
        return True
    if socket.is_linked or socket.default_value < OPAQUE_ALPHA:
        return False
    index = list(node.inputs).index(socket)
    return not (top and node_animation.input_animated(tree, node, index))


def _opaque_tree(tree, top, seen):
    """Whether nothing in `tree` makes EEVEE draw it transparent: no Transparent BSDF, and every
    Principled BSDF and ndfbake group node with an Alpha of 1, unlinked and not animated (in a
    user's node group, any animation of the group counts as a changing Alpha)."""
    if tree is None or tree.as_pointer() in seen:
        return True
    seen.add(tree.as_pointer())
    if not top and tree.animation_data is not None and (tree.animation_data.action is not None
                                                      or len(tree.animation_data.drivers)):
        return False
    for node in tree.nodes:
        if node.mute:
            continue
        if node.bl_idname == "ShaderNodeBsdfTransparent":
            return False
        if node.bl_idname == "ShaderNodeBsdfPrincipled" and not _opaque_alpha(tree, node, top):
            return False
        if node.bl_idname == "ShaderNodeGroup" and node.node_tree is not None:
            if node.node_tree.get(TAG) is not None:  # a bake's group: its Alpha is the Principled's
                if not _opaque_alpha(tree, node, top):
                    return False
            elif not _opaque_tree(node.node_tree, False, seen):
                return False
    return True


def opaque(material):
    """Whether the material, as baked, is opaque whatever EEVEE's compiler decides."""
    return _opaque_tree(material.node_tree, True, set())


def _settings(material):
    """The settings a bake may change: Transparent Shadows, and in 4.2-4.x the deprecated Shadow
    Mode too, which Blender sets to Hashed whenever Transparent Shadows is turned on."""
    return {name: getattr(material, name) for name in SETTINGS if hasattr(material, name)}


def settle(material, old_record):
    """Called as a bake finishes: turns Transparent Shadows off on an opaque material; returns the
    settings to record (as they were before the first of this material's bakes turned it off), or
    None where the bake left the setting as the user had it (and then puts back what an earlier
    bake turned off)."""
    if not hasattr(material, "use_transparent_shadow"):
        return None
    before = old_record.get(RECORD_FIELD)
    if not isinstance(before, dict):
        before = _settings(material)
    if before.get("use_transparent_shadow") and opaque(material):
        material.use_transparent_shadow = False
        return before
    if RECORD_FIELD in old_record:
        restore(material, old_record)
    return None


def restore(material, record):
    """Revert: the settings as they were before the bake."""
    settings = record.get(RECORD_FIELD)
    if not isinstance(settings, dict):
        return
    for name in SETTINGS:  # Transparent Shadows first: turning it on sets Shadow Mode
        if name in settings and hasattr(material, name):
            setattr(material, name, settings[name])
