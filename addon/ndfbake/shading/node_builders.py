"""Small builders of shader node trees: tagged groups with their sockets, math nodes linked in one
call. Plain helpers with no knowledge of lobes; nodes.py and the groups beside it build with them.
Blender's own API only (bpy); version differences go through blender_compat."""
import bpy

from . import blender_compat

GROUP_VERSION = 3  # in every shared group's name: a group whose inputs or outputs change gets a new one
TAG = "ndfbake"                       # ID/custom property marking what this add-on created
FLOAT, COLOR, VECTOR = "NodeSocketFloat", "NodeSocketColor", "NodeSocketVector"


def _new_group(name):
    tree = bpy.data.node_groups.new(name, "ShaderNodeTree")
    tree[TAG] = GROUP_VERSION
    return tree


def _group_with_io(name, inputs, outputs, span=(-900, 700)):
    """A new tagged group with (socket type, name) inputs and outputs; returns the tree and its
    Group Input and Group Output nodes (placed at x = span)."""
    tree = _new_group(name)
    for socket_type, socket_name in inputs:
        _add_socket(tree, "INPUT", socket_type, socket_name)
    for socket_type, socket_name in outputs:
        _add_socket(tree, "OUTPUT", socket_type, socket_name)
    gin = tree.nodes.new("NodeGroupInput")
    gin.location = (span[0], 0)
    gout = tree.nodes.new("NodeGroupOutput")
    gout.location = (span[1], 0)
    return tree, gin, gout


def _add_socket(tree, in_out, socket_type, name):
    return blender_compat.new_interface_socket(tree, in_out, socket_type, name)


def _link(tree, source, target):
    """Link an output socket to `target`, or set target's value when source is a number."""
    if isinstance(source, (int, float)):
        target.default_value = source
    elif isinstance(source, tuple):
        target.default_value = source
    else:
        tree.links.new(source, target)


def _math(tree, operation, a, b=None, c=None, location=(0, 0), clamp=False):
    node = tree.nodes.new("ShaderNodeMath")
    node.operation = operation
    node.use_clamp = clamp
    node.location = location
    for socket, value in zip(node.inputs, (a, b, c)):
        if value is not None:
            _link(tree, value, socket)
    return node.outputs[0]


def _vmath(tree, operation, a, b=None, c=None, scale=None, location=(0, 0), output=0):
    node = tree.nodes.new("ShaderNodeVectorMath")
    node.operation = operation
    node.location = location
    for socket, value in zip(node.inputs, (a, b, c)):
        if value is not None:
            _link(tree, value, socket)
    if scale is not None:
        _link(tree, scale, node.inputs["Scale"])
    return node.outputs[output]


def _find_group(name):
    tree = bpy.data.node_groups.get(name)
    if tree is not None and tree.get(TAG) == GROUP_VERSION and tree.bl_idname == "ShaderNodeTree":
        return tree
    return None


def _mix(tree, data_type, factor, a, b, location):
    """ShaderNodeMix: (1 − factor)·a + factor·b, for FLOAT or VECTOR data."""
    node = tree.nodes.new("ShaderNodeMix")
    node.data_type = data_type
    node.clamp_factor = False
    node.location = location
    first = {"FLOAT": 2, "VECTOR": 4}[data_type]
    _link(tree, factor, node.inputs[0])
    _link(tree, a, node.inputs[first])
    _link(tree, b, node.inputs[first + 1])
    return node.outputs[{"FLOAT": 0, "VECTOR": 1}[data_type]]


def socket_value(socket):
    """A socket's default value, as a tuple where it has several components (comparable, storable)."""
    value = socket.default_value
    return tuple(value) if hasattr(value, "__len__") else value
