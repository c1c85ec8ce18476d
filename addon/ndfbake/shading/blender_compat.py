"""Where Blender 3.4, 4.2 LTS, 4.5 LTS and 5.x differ in what the add-on uses: each difference in
one function here, so that the rest of the add-on (and its tests) names no version."""
import re

import bpy

# Principled BSDF v1 (Blender 3.x) input names that v2 (4.0+) renamed; None: v2 has no such input.
_PRINCIPLED_V2_NAMES = {
    "Emission": "Emission Color",
    "Specular": "Specular IOR Level",
    "Transmission": "Transmission Weight",
    "Transmission Roughness": None,
    "Subsurface": "Subsurface Weight",
    "Sheen": "Sheen Weight",
    "Clearcoat": "Coat Weight",
    "Clearcoat Roughness": "Coat Roughness",
    "Clearcoat Normal": "Coat Normal",
}
# The socket types NodeTreeInterface.new_socket (4.0+) takes; a subtype's idname starts with one.
_BASE_SOCKET_TYPES = ("NodeSocketFloat", "NodeSocketInt", "NodeSocketBool", "NodeSocketVector",
                      "NodeSocketColor", "NodeSocketShader")


def principled_input(name):
    """The current name of the Principled BSDF input called `name` in Blender 3.x (Principled v1):
    4.0+ (Principled v2) renamed several (Emission -> Emission Color...) and dropped some (None)."""
    if bpy.app.version < (4, 0, 0):
        return name
    return _PRINCIPLED_V2_NAMES.get(name, name)


def new_interface_socket(tree, in_out, socket_type, name):
    """A new group input or output (in_out INPUT/OUTPUT) of socket idname `socket_type`: 3.x takes
    any idname in tree.inputs/outputs.new; 4.0+ tree.interface.new_socket takes only the base
    types, the rest (NodeSocketFloatFactor...) set as the interface socket's subtype, with the
    0..1 range 3.x gives a factor."""
    if not hasattr(tree, "interface"):
        return (tree.inputs if in_out == "INPUT" else tree.outputs).new(socket_type, name)
    base = next((t for t in _BASE_SOCKET_TYPES if socket_type.startswith(t)), socket_type)
    socket = tree.interface.new_socket(name, in_out=in_out, socket_type=base)
    suffix = socket_type[len(base):]
    if suffix:
        # FloatFactor: FACTOR, FloatTimeAbsolute: TIME_ABSOLUTE, VectorXYZ: XYZ
        socket.subtype = re.sub(r"(?<=[a-z])(?=[A-Z])", "_", suffix).upper()
        if socket.subtype == "FACTOR":
            socket.min_value, socket.max_value = 0.0, 1.0
    return socket


def _node_trees_always_used():
    # 5.0 gives every material and world a node tree and deprecates use_nodes (removal: 6.0).
    return bpy.app.version >= (5, 0, 0)


def uses_nodes(id_with_nodes):
    """Whether a material (or world) renders from its node tree: use_nodes before 5.0; from 5.0
    always, where it has one (use_nodes is deprecated there and always True)."""
    if id_with_nodes.node_tree is None:
        return False
    return _node_trees_always_used() or id_with_nodes.use_nodes


def enable_nodes(id_with_nodes):
    """Gives a material (or world) its node tree: use_nodes = True before 5.0, where a new one has
    none; nothing from 5.0, where it always has one (and use_nodes warns)."""
    if not _node_trees_always_used():
        id_with_nodes.use_nodes = True
    return id_with_nodes.node_tree


def eevee_next():
    """True where EEVEE is EEVEE Next (4.2 on), which replaced EEVEE Legacy."""
    return bpy.app.version >= (4, 2, 0)


def eevee_film_darkens_with_exposure():
    """Whether EEVEE's render depends on the view Exposure: EEVEE Next's film weights each sample of
    the Combined pass by 1 / (4 + luma · s) and sets s with pow2f(exposure), which is exposure²
    (2^exposure was surely meant). At 0 it averages; at any other value, above or below alike, a
    pixel whose samples differ much in brightness comes out darker, a baked material's glints most
    (EEVEE Next picks one lobe a sample). Measured in 4.2, 5.0 and 5.3 (docs/rendering.md, "EEVEE
    Next's reference"); test_addon_render checks it in each Blender it runs in. EEVEE Legacy
    averages its samples."""
    return eevee_next()


def eevee_exposure_note(scene):
    """The panel's line where `scene` renders with EEVEE at an Exposure that darkens a baked
    material's glints (eevee_film_darkens_with_exposure), else ""."""
    exposure = scene.view_settings.exposure
    if scene.render.engine != eevee_engine() or exposure == 0.0 or not eevee_film_darkens_with_exposure():
        return ""
    return ("EEVEE darkens sparkly pixels, a baked material's glints most, when the view Exposure is not 0 "
            "(%g here; Blender's film weighs them by Exposure squared): for final frames keep it at 0 and set "
            "the brightness with the lights, the world or the compositor." % exposure)


def eevee_engine():
    """The render engine id of EEVEE: BLENDER_EEVEE in 3.x and 5.0+, BLENDER_EEVEE_NEXT in 4.2-4.x."""
    return "BLENDER_EEVEE_NEXT" if eevee_next() and bpy.app.version < (5, 0, 0) else "BLENDER_EEVEE"


def normal_map_normalizes_normal():
    """Whether Cycles' Normal Map node (tangent space) normalizes the interpolated corner normal
    before it builds the frame: from 5.1 on (5.1.0, 5.2.3 and 5.3.0 checked), as is before. What a
    tangent-space map converted for this Blender must assume (ndfb_space_options.frame_normal;
    tests/blender/test_normal_roundtrip.py)."""
    return bpy.app.version >= (5, 1, 0)


def osl_texture_wraps():
    """Whether Cycles' OSL texture() honours its "wrap" option. Up to 5.1 it does; from 5.2 on
    (Cycles' own texture cache) a lookup outside [0, 1] is black whatever the wrap mode (5.2.0,
    5.2.3 and 5.3.0 checked; test_addon_osl checks it in each Blender it runs in)."""
    return bpy.app.version < (5, 2, 0)


def linear_color_space():
    """The name of the linear Rec.709 colour space: "Linear" in 3.x, "Linear Rec.709" from 4.0."""
    names = bpy.types.ColorManagedInputColorspaceSettings.bl_rna.properties["name"].enum_items.keys()
    return "Linear" if "Linear" in names else "Linear Rec.709"


def _slotted_actions():
    return "slots" in bpy.types.Action.bl_rna.properties


def animation_slot(holder):
    """The action slot through which an AnimData or an NLA strip animates its ID: 4.4+ (slotted
    actions); None before, where an action has one set of curves."""
    return getattr(holder, "action_slot", None)


def action_fcurves(action, slot, create=False):
    """The F-curves of `action` that animate through `slot` (animation_slot): Action.fcurves before
    4.4; from 4.4 the slot's channelbag in the action's first layer and strip (5.0 drops
    Action.fcurves), made with `create`, else () where the slot has none."""
    if not _slotted_actions():
        return action.fcurves
    if slot is None:
        return ()
    if create:
        layer = action.layers[0] if action.layers else action.layers.new("Layer")
        strip = layer.strips[0] if layer.strips else layer.strips.new(type="KEYFRAME")
        return strip.channelbag(slot, ensure=True).fcurves
    for layer in action.layers[:1]:
        for strip in layer.strips[:1]:
            channelbag = strip.channelbag(slot)
            if channelbag is not None:
                return channelbag.fcurves
    return ()


def new_action_slot(action, id_type):
    """Makes `action` animate an ID of type `id_type` (e.g. NODETREE): before 4.4 through
    Action.id_root (returns None); from 4.4 through a new slot, returned (5.0 drops id_root)."""
    if not _slotted_actions():
        action.id_root = id_type
        return None
    return action.slots.new(id_type=id_type, name=action.name)


def new_fcurve(fcurves, data_path, index, group_name):
    """A new F-curve in `fcurves` (action_fcurves) in the channel group `group_name` ("": none):
    Action.fcurves.new's action_group before 4.4; from 4.4 a group of the channelbag."""
    if not _slotted_actions():
        return fcurves.new(data_path, index=index, action_group=group_name)
    fcurve = fcurves.new(data_path, index=index)
    if group_name:
        channelbag = fcurves.data
        fcurve.group = channelbag.groups.get(group_name) or channelbag.groups.new(group_name)
    return fcurve


def ensure_loop_normals(mesh):
    """Makes MeshLoop.normal hold the corner normals: 3.x-4.0 need Mesh.calc_normals_split(); 4.1+
    computes them when read (and has no such method)."""
    if hasattr(mesh, "calc_normals_split"):
        mesh.calc_normals_split()
