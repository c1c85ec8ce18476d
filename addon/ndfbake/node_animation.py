"""Keyframes and drivers of node inputs, moved with the values when a bake puts the Principled
BSDF's inputs on the ndfbake group node and when Revert puts them back.

A material's node tree is animated by its active action, by the actions of its NLA strips, and by
its drivers; a driver's variables may read other node inputs of the same material. All of them
follow: curves are copied within each action, drivers are copied, and driver variables that read a
moved input read it where it now lives. An action other materials share (Material.copy() shares
them) keeps a node's curves while another of its materials has a node of that name: they are
that node's curves too.
"""
import re

import bpy

TEMPORARY_ACTION = "ndfbake temporary"


def input_path(node, index):
    return 'nodes["%s"].inputs[%d].default_value' % (bpy.utils.escape_identifier(node.name), index)


def node_prefix(node_name):
    return 'nodes["%s"]' % bpy.utils.escape_identifier(node_name)


def tree_actions(material_tree):
    """The actions animating the tree, each once: the active one and those of its NLA strips
    (meta strips opened)."""
    animation = material_tree.animation_data
    if animation is None:
        return []
    actions = [animation.action] if animation.action is not None else []

    def visit(strips):
        for strip in strips:
            if strip.action is not None and strip.action not in actions:
                actions.append(strip.action)
            visit(strip.strips)
    for track in animation.nla_tracks:
        visit(track.strips)
    return actions


def animates_elsewhere(action, material_tree, node_name):
    """Whether the action animates a node of that name in another ID than the tree's material (an
    ID that is no material counts as one that does)."""
    for user in bpy.data.user_map(subset=[action]).get(action, ()):
        if not isinstance(user, bpy.types.Material):
            return True
        if user.node_tree is not None and user.node_tree != material_tree and node_name in user.node_tree.nodes:
            return True
    return False


def copy_fcurve(action, source, data_path):
    """A copy of `source` at `data_path` in `action`, replacing any curve there: its keys, their
    handles and easing, its extrapolation and its modifiers (every writable setting)."""
    existing = action.fcurves.find(data_path, index=source.array_index)
    if existing is not None:
        action.fcurves.remove(existing)
    copy = action.fcurves.new(data_path, index=source.array_index,
                              action_group=source.group.name if source.group else "")
    copy.extrapolation = source.extrapolation
    copy.keyframe_points.add(len(source.keyframe_points))
    for key, original in zip(copy.keyframe_points, source.keyframe_points):
        for attribute in ("co", "handle_left", "handle_right", "handle_left_type", "handle_right_type",
                          "interpolation", "easing", "amplitude", "back", "period"):
            setattr(key, attribute, getattr(original, attribute))
    for modifier in source.modifiers:
        new = copy.modifiers.new(modifier.type)
        for prop in modifier.bl_rna.properties:
            if not prop.is_readonly and prop.identifier not in ("type", "active"):
                try:
                    setattr(new, prop.identifier, getattr(modifier, prop.identifier))
                except (AttributeError, TypeError, ValueError):
                    pass  # a collection (envelope points): left at its default
    copy.update()


def _retarget(data_path, paths):
    """`data_path` with a key of `paths` (or that key and an array index after it) replaced by its
    value; None where it reads none of them."""
    match = re.fullmatch(r"(.*?\.default_value)(\[\d+\])?", data_path)
    if match is None or match.group(1) not in paths:
        return None
    return paths[match.group(1)] + (match.group(2) or "")


def _retarget_variables(material_tree, paths, skip_prefix):
    """Driver variables of the tree's drivers (but those on inputs under `skip_prefix`) that read
    an input of `paths`, through the tree or through its material, read the new path instead."""
    material = next((m for m in bpy.data.materials if m.node_tree == material_tree), None)
    for fcurve in material_tree.animation_data.drivers:
        if fcurve.data_path.startswith(skip_prefix):
            continue
        for variable in fcurve.driver.variables:
            for target in variable.targets:
                through_material = target.id_type == "MATERIAL" and material is not None and target.id == material
                if through_material and target.data_path.startswith("node_tree."):
                    new = _retarget(target.data_path[len("node_tree."):], paths)
                    if new is not None:
                        target.data_path = "node_tree." + new
                elif target.id_type == "NODETREE" and target.id == material_tree:
                    new = _retarget(target.data_path, paths)
                    if new is not None:
                        target.data_path = new


def copy_input_animation(material_tree, paths, source_node, move):
    """Copies the keyframes (in every action of the tree) and drivers at each source data path of
    `paths` to its target path, and makes driver variables that read a source read its target
    (except the drivers of the source node's inputs, which stay as they are). With `move`, the
    sources' drivers go, and their keyframes but where the action animates the source node
    elsewhere."""
    animation = material_tree.animation_data
    if animation is None:
        return
    for action in tree_actions(material_tree):
        keep_sources = not move or animates_elsewhere(action, material_tree, source_node)
        for source in [f for f in action.fcurves if f.data_path in paths]:
            copy_fcurve(action, source, paths[source.data_path])
            if not keep_sources:
                action.fcurves.remove(source)
    for source in [f for f in animation.drivers if f.data_path in paths]:
        existing = animation.drivers.find(paths[source.data_path], index=source.array_index)
        if existing is not None:
            animation.drivers.remove(existing)
        animation.drivers.from_existing(src_driver=source).data_path = paths[source.data_path]
        if move:
            animation.drivers.remove(source)
    _retarget_variables(material_tree, paths, node_prefix(source_node))


def remove_node_animation(material_tree, node_name):
    """Drops the drivers and keyframes of the named node's inputs (but the keyframes of an action
    that animates that node elsewhere); and the tree's animation data when nothing is left in it."""
    animation = material_tree.animation_data
    if animation is None:
        return
    prefix = node_prefix(node_name)
    for fcurve in [f for f in animation.drivers if f.data_path.startswith(prefix)]:
        animation.drivers.remove(fcurve)
    for action in tree_actions(material_tree):
        if not animates_elsewhere(action, material_tree, node_name):
            for fcurve in [f for f in action.fcurves if f.data_path.startswith(prefix)]:
                action.fcurves.remove(fcurve)
    if not animation.drivers and animation.action is None and not animation.nla_tracks:
        material_tree.animation_data_clear()


def remove_node(material_tree, node):
    """Removes `node`. Blender drops a removed node's curves from every action of the tree, also
    from an action that animates a node of that name in another material: there they are put back."""
    prefix = node_prefix(node.name)
    kept = []
    try:
        for action in tree_actions(material_tree):
            curves = [f for f in action.fcurves if f.data_path.startswith(prefix)]
            if curves and animates_elsewhere(action, material_tree, node.name):
                holder = bpy.data.actions.new(TEMPORARY_ACTION)
                kept.append((action, holder))
                for fcurve in curves:
                    copy_fcurve(holder, fcurve, fcurve.data_path)
        material_tree.nodes.remove(node)
    finally:
        for action, holder in kept:
            for fcurve in holder.fcurves:
                copy_fcurve(action, fcurve, fcurve.data_path)
            bpy.data.actions.remove(holder)
