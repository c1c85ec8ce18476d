"""Keyframes and drivers of node inputs, moved with the values when a bake puts the Principled
BSDF's inputs on the ndfbake group node and when Revert puts them back.

A material's node tree is animated by its active action, by the actions of its NLA strips, and by
its drivers; a driver's variables may read other node inputs of the same material. All of them
follow: curves are copied within each action, drivers are copied, and driver variables of the
tree's and the material's drivers that read a moved input read it where it now lives (paths by
socket index or by socket name; drivers on other IDs are not visited). An action other node trees
share (Material.copy() shares them) is theirs too: where another tree has a node of the target's
name, a curve already at the target path is kept, and the source's curves stay.

An action linked from a library cannot keep new curves (they are not saved); material_scan refuses
such a material (LINKED_ANIMATION) before anything is changed.
"""
import bpy

from . import blender_compat
from .blender_compat import action_fcurves

TEMPORARY_ACTION = "ndfbake temporary"


def node_prefix(node_name):
    return 'nodes["%s"]' % bpy.utils.escape_identifier(node_name)


def _socket_paths(node, index):
    """The data paths that name input `index` of `node`: by index (as Blender writes them), by
    socket name in double quotes and, where no escaping is needed, in single quotes."""
    name = node.inputs[index].name
    nodes = [node_prefix(node.name)]
    sockets = ["inputs[%d]" % index, 'inputs["%s"]' % bpy.utils.escape_identifier(name)]
    if "'" not in node.name and "\\" not in node.name:
        nodes.append("nodes['%s']" % node.name)
    if "'" not in name and "\\" not in name:
        sockets.append("inputs['%s']" % name)
    return [(n, s) for n in nodes for s in sockets]


def _input_paths(source, target, index_pairs):
    """{data path of a source input: the same form of path for its target input} for each
    (source index, target index), in every form _socket_paths knows."""
    paths = {}
    for i, j in index_pairs:
        for (n, s), (tn, ts) in zip(_socket_paths(source, i), _socket_paths(target, j)):
            paths["%s.%s.default_value" % (n, s)] = "%s.%s.default_value" % (tn, ts)
    return paths


def tree_actions(material_tree):
    """The (action, slot) pairs animating the tree, each once: the active action and those of its
    NLA strips (meta strips opened), with the slot they animate it through
    (blender_compat.animation_slot)."""
    animation = material_tree.animation_data
    if animation is None:
        return []
    actions = []

    def add(holder):
        pair = (holder.action, blender_compat.animation_slot(holder))
        if holder.action is not None and pair not in actions:
            actions.append(pair)

    def visit(strips):
        for strip in strips:
            add(strip)
            visit(strip.strips)
    add(animation)
    for track in animation.nla_tracks:
        visit(track.strips)
    return actions


def input_animated(material_tree, node, index):
    """Whether a keyframe curve (active action or NLA strip) or a driver of the tree or its
    material sets input `index` of `node`."""
    paths = set(_input_paths(node, node, [(index, index)]))
    if any(curve.data_path in paths for action, slot in tree_actions(material_tree)
           for curve in action_fcurves(action, slot)):
        return True
    sets, _ = _driver_sets(material_tree)
    return any(driver.data_path[len(prefix):] in paths for animation, prefix in sets
               for driver in animation.drivers if driver.data_path.startswith(prefix))


def animates_elsewhere(action, material_tree, node_name):
    """Whether another node tree that the action animates has a node of that name."""
    for user in bpy.data.user_map(subset=[action]).get(action, ()):
        tree = user if isinstance(user, bpy.types.NodeTree) else getattr(user, "node_tree", None)
        if isinstance(tree, bpy.types.NodeTree) and tree != material_tree and node_name in tree.nodes:
            return True
    return False


def _copy_properties(source, target, skip=()):
    """Every writable plain property of `source` onto `target`. Twice, since some take values only
    after others (a Generator's coefficients after its order)."""
    for _ in range(2):
        for prop in source.bl_rna.properties:
            if prop.is_readonly or prop.identifier in skip or prop.type in ("POINTER", "COLLECTION"):
                continue
            try:
                setattr(target, prop.identifier, getattr(source, prop.identifier))
            except (AttributeError, TypeError, ValueError):
                pass


def copy_fcurve(fcurves, source, data_path):
    """A copy of `source` at `data_path` in `fcurves` (an action's, action_fcurves), replacing any curve
    there: its settings (extrapolation, mute, lock, hide, colour…), its keys with their handles,
    easing and types, and its modifiers with their settings and envelope points."""
    existing = fcurves.find(data_path, index=source.array_index)
    if existing is not None:
        fcurves.remove(existing)
    copy = blender_compat.new_fcurve(fcurves, data_path, source.array_index,
                                     source.group.name if source.group else "")
    _copy_properties(source, copy, skip=("data_path", "array_index", "select"))
    copy.keyframe_points.add(len(source.keyframe_points))
    for key, original in zip(copy.keyframe_points, source.keyframe_points):
        _copy_properties(original, key, skip=("select_control_point", "select_left_handle", "select_right_handle"))
    for modifier in source.modifiers:
        new = copy.modifiers.new(modifier.type)
        _copy_properties(modifier, new, skip=("type", "active"))
        if modifier.type == "ENVELOPE":
            _copy_envelope_points(modifier.control_points, new.control_points)
    copy.update()


def _copy_envelope_points(source, target):
    """An Envelope's control points, with their bounds. The bounds are written with foreach_set:
    assigning a point's min or max runs Blender's F-Modifier update on the point, which reads an
    F-Modifier's fields past the point's memory (to 5.0 at least) and crashes now and then."""
    count = len(source)
    frames, lows, highs = ([0.0] * count for _ in range(3))
    source.foreach_get("frame", frames)
    source.foreach_get("min", lows)
    source.foreach_get("max", highs)
    for frame in frames:
        target.add(frame)
    bounds = dict(zip(frames, zip(lows, highs)))
    added = [0.0] * count
    target.foreach_get("frame", added)  # add() keeps the points in frame order
    target.foreach_set("min", [bounds[frame][0] for frame in added])
    target.foreach_set("max", [bounds[frame][1] for frame in added])


def _driver_sets(material_tree):
    """The drivers of the tree and of its material (the ID that owns it)."""
    material = next((m for m in bpy.data.materials if m.node_tree == material_tree), None)
    sets = [(material_tree.animation_data, "")]
    if material is not None and material.animation_data is not None:
        sets.append((material.animation_data, "node_tree."))
    return [(animation, prefix) for animation, prefix in sets if animation is not None], material


def _retarget(data_path, paths):
    """`data_path` with its input path (a key of `paths`, maybe followed by an array index)
    replaced; None where it reads no input of `paths`."""
    head, bracket, index = data_path.rpartition("[")
    if bracket and index.endswith("]") and index[:-1].isdigit() and head in paths:
        return paths[head] + "[" + index
    return paths.get(data_path)


def retarget_variables(material_tree, source, target, index_pairs):
    """Driver variables of the tree's and the material's drivers (but the drivers on `source`'s
    inputs) that read input i of `source`, through the tree or through the material, read input j
    of `target` instead, for each (i, j)."""
    _retarget_variables(material_tree, _input_paths(source, target, index_pairs), source.name)


def _retarget_variables(material_tree, paths, source_node):
    sets, material = _driver_sets(material_tree)
    for animation, prefix in sets:
        skip = prefix + node_prefix(source_node)
        for fcurve in animation.drivers:
            if fcurve.data_path.startswith(skip):
                continue
            for variable in fcurve.driver.variables:
                for target in variable.targets:
                    if target.id_type == "MATERIAL" and material is not None and target.id == material \
                            and target.data_path.startswith("node_tree."):
                        new = _retarget(target.data_path[len("node_tree."):], paths)
                        if new is not None:
                            target.data_path = "node_tree." + new
                    elif target.id_type == "NODETREE" and target.id == material_tree:
                        new = _retarget(target.data_path, paths)
                        if new is not None:
                            target.data_path = new


def copy_input_animation(material_tree, source, target, index_pairs, move):
    """Gives input j of `target` the keyframes (in every action of the tree) and drivers of input
    i of `source`, for each (i, j), and makes driver variables that read a source input read its
    target (not the drivers of `source`'s own inputs, which stay as they are). With `move` (the
    target's inputs then stand for what the user left on the source), the source's curves and
    drivers go, and a target curve or driver the source no longer has goes too (the user deleted
    it). In an action that animates a node of the target's name in another tree, curves already
    at a target path and the source's curves stay (module docstring)."""
    paths = _input_paths(source, target, index_pairs)
    animation = material_tree.animation_data
    if animation is not None:
        for action, slot in tree_actions(material_tree):
            if action.library is not None:
                continue  # refused before the bake (LINKED_ANIMATION); never written
            _move_curves(action_fcurves(action, slot), paths, move,
                         keep_targets=animates_elsewhere(action, material_tree, target.name))
        _move_drivers(animation, paths, move)
    _retarget_variables(material_tree, paths, source.name)


def _move_curves(fcurves, paths, move, keep_targets):
    sources = {(f.data_path, f.array_index): f for f in fcurves if f.data_path in paths}
    if move and not keep_targets:
        targets = {path: source for source, path in paths.items()}
        for fcurve in [f for f in fcurves if f.data_path in targets]:
            if (targets[fcurve.data_path], fcurve.array_index) not in sources:
                fcurves.remove(fcurve)
    for (data_path, index), fcurve in sources.items():
        if not (keep_targets and fcurves.find(paths[data_path], index=index) is not None):
            copy_fcurve(fcurves, fcurve, paths[data_path])
        if move and not keep_targets:
            fcurves.remove(fcurve)


def _move_drivers(animation, paths, move):
    sources = {(f.data_path, f.array_index): f for f in animation.drivers if f.data_path in paths}
    if move:
        targets = {path: source for source, path in paths.items()}
        for fcurve in [f for f in animation.drivers if f.data_path in targets]:
            if (targets[fcurve.data_path], fcurve.array_index) not in sources:
                animation.drivers.remove(fcurve)
    for (data_path, index), fcurve in sources.items():
        existing = animation.drivers.find(paths[data_path], index=index)
        if existing is not None:
            animation.drivers.remove(existing)
        animation.drivers.from_existing(src_driver=fcurve).data_path = paths[data_path]
        if move:
            animation.drivers.remove(fcurve)


def remove_node_animation(material_tree, node_name, clear_empty=True):
    """Drops the drivers and keyframes of the named node's inputs (but the keyframes of an action
    that animates a node of that name in another tree); and, with clear_empty, the tree's animation
    data when nothing is left in it."""
    animation = material_tree.animation_data
    if animation is None:
        return
    prefix = node_prefix(node_name)
    for fcurve in [f for f in animation.drivers if f.data_path.startswith(prefix)]:
        animation.drivers.remove(fcurve)
    for action, slot in tree_actions(material_tree):
        if action.library is None and not animates_elsewhere(action, material_tree, node_name):
            fcurves = action_fcurves(action, slot)
            for fcurve in [f for f in fcurves if f.data_path.startswith(prefix)]:
                fcurves.remove(fcurve)
    if clear_empty and not animation.drivers and animation.action is None and not animation.nla_tracks:
        material_tree.animation_data_clear()


def remove_node(material_tree, node):
    """Removes `node`. Blender drops a removed node's curves from every action of the tree, also
    from an action that animates a node of that name in another tree: there they are put back."""
    prefix = node_prefix(node.name)
    kept = []
    try:
        for action, slot in tree_actions(material_tree):
            curves = [f for f in action_fcurves(action, slot) if f.data_path.startswith(prefix)]
            if curves and animates_elsewhere(action, material_tree, node.name):
                holder = bpy.data.actions.new(TEMPORARY_ACTION)
                held = action_fcurves(holder, blender_compat.new_action_slot(holder, "NODETREE"), create=True)
                kept.append((action, slot, holder, held))
                for fcurve in curves:
                    copy_fcurve(held, fcurve, fcurve.data_path)
        material_tree.nodes.remove(node)
    finally:
        for action, slot, holder, held in kept:
            for fcurve in held:
                copy_fcurve(action_fcurves(action, slot, create=True), fcurve, fcurve.data_path)
            bpy.data.actions.remove(holder)


def linked_curves(material_tree, node_name):
    """The names of linked (library) actions of the tree that animate the named node's inputs."""
    prefix = node_prefix(node_name)
    return [action.name for action, slot in tree_actions(material_tree)
            if action.library is not None
            and any(f.data_path.startswith(prefix) for f in action_fcurves(action, slot))]
