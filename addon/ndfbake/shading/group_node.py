"""The group node in the user's material: inserting a bake's group in place of the Principled BSDF
and Normal Map it shades through, replacing a bake's group with a re-bake's (undoable until
committed), the EEVEE output a bake adds, and removing all of it again (Revert) with the user's
edits carried back. Works on the user's node tree only; the group's inside is nodes.py's.
"""
from dataclasses import dataclass, field

from ..core import id_names
from . import bake_record, material_scan, node_animation
from .node_builders import GROUP_VERSION, TAG, socket_value
from .lobe_bsdfs import held_input
from .nodes import EEVEE_BSDF, lobe_count

EEVEE_OUTPUT = "ndfbake EEVEE Output"   # the Material Output (target EEVEE) a bake may add
GROUP_NODE_OFFSET = 250               # the group node sits this far above its Principled BSDF
# The Principled BSDF's settings that are no sockets: kept in the bake record, for Revert to make
# a deleted Principled again.
PRINCIPLED_SETTINGS = ("distribution", "subsurface_method")
GROUP_NODE_NAME = "ndfbake"  # a bake's group node's name (made free: group_node_name)
# A re-bake's group node's name until the one it replaces goes (then it is named as a first bake's):
# a name no other node tree uses, since renaming a node renames the animation paths naming it in
# every ID.
REBAKE_NAME = "ndfbake re-bake"


def _shared_inputs(node, principled, normal_map=None):
    """[(principled, {its input index: group node input index}), (normal_map, {...})] for the inputs
    the group node carries: the Principled's of the same name, the Normal Map's Strength as Normal
    Strength (left out without normal_map)."""
    shared = [(principled, {i: node.inputs.find(s.name) for i, s in enumerate(principled.inputs)
                            if s.name in node.inputs})]
    if normal_map is not None and "Normal Strength" in node.inputs:
        shared.append((normal_map, {normal_map.inputs.find("Strength"): node.inputs.find("Normal Strength")}))
    return shared


def carry_animation(material_tree, principled, node, normal_map, skip=()):
    """Copies the keyframes and drivers of the Principled's and the Normal Map's carried inputs with
    no live link (a muted link is no link) to the group node's inputs that hold those values after
    the bake (_shared_inputs): an animated colour, emission or bump strength goes on animating, and
    drivers that read those inputs read the node's. Not to the group node's inputs (indices) in
    `skip`: a re-bake's, whose animation comes from the node it replaces."""
    for source, pairs in _shared_inputs(node, principled, normal_map):
        unlinked = [(i, j) for i, j in pairs.items()
                    if j not in skip and material_scan.live_link(source.inputs[i]) is None]
        node_animation.copy_input_animation(material_tree, source, node, unlinked, move=False)


def _copy_input(links, source, target):
    """Makes input socket `target` take what `source` takes: the same link (muted or not), or, with
    none, its value; under a muted link, its value too (what renders). Touches nothing that already
    matches. Links, not is_linked: Blender's tree updates clear is_linked where the link is muted."""
    if source.links:
        link = source.links[0]
        current = target.links[0] if target.links else None
        if not (current is not None and current.from_socket == link.from_socket
                and current.is_muted == link.is_muted):
            links.new(link.from_socket, target).is_muted = link.is_muted
        if not link.is_muted:
            return  # the link decides what renders
    else:
        for link in list(target.links):
            links.remove(link)
    if socket_value(target) != socket_value(source):
        target.default_value = source.default_value


def write_back_inputs(material_tree, node, principled, normal_map=None):
    """The group node's inputs as the user left them (values, links, keyframes, drivers) go back to
    the Principled BSDF, and Normal Strength to the Normal Map's Strength, before the node goes, so
    that Revert keeps the user's edits on the node and a re-bake starts from them. Unedited, the
    Principled and the Normal Map are left exactly as they were."""
    for target, pairs in _shared_inputs(node, principled, normal_map):
        for i, j in pairs.items():
            _copy_input(material_tree.links, node.inputs[j], target.inputs[i])
        unlinked = [(j, i) for i, j in pairs.items() if material_scan.live_link(node.inputs[j]) is None]
        node_animation.copy_input_animation(material_tree, node, target, unlinked, move=True)


def insert_group_node(material_tree, group_tree, principled, normal_map, image_texture):
    """Adds the group node beside `principled`, feeds it the Principled's inputs, and bypasses the
    Principled BSDF: every link leaving its BSDF output now leaves the group's BSDF output. Where
    the Principled fed the material's only output (target All) directly, a Material Output with
    target EEVEE gets the group's EEVEE BSDF (see add_eevee_output). Returns the node, the bypassed
    links as (to_node, to_socket identifier, muted), and the added output's name ("" if none), for
    revert."""
    node = material_tree.nodes.new("ShaderNodeGroup")
    moved = []
    try:
        _wire_group_node(material_tree, node, group_tree, principled, normal_map, image_texture, moved)
        carry_animation(material_tree, principled, node, normal_map)
        return node, _bsdf_links(moved), add_eevee_output(material_tree, node, _bsdf_links(moved))
    except Exception:
        remove_group_node(material_tree, node.name, principled.name, _bsdf_links(moved), keep_edits=False,
                          normal_map_name=normal_map.name)
        raise


def _bsdf_links(moved):
    """The moved links (_wire_group_node) that leave the BSDF output, as (to_node name, to_socket
    identifier, muted): the links a bake bypasses, as its record keeps them."""
    return [(to_node, identifier, muted) for name, to_node, identifier, muted in moved if name == "BSDF"]


@dataclass
class Replacement:
    """A re-bake's group node, not yet in place of the one it replaces (replace_group_node)."""
    node: str                     # the new group node's name (REBAKE_NAME, made unique)
    old: str                      # the name of the group node it replaces
    principled: str
    normal_map: str
    roles: dict                   # {node name: its ROLE_KEY value before (None: none)}
    had_animation: bool           # whether the tree had animation data before
    eevee_output: str             # old's EEVEE output (add_eevee_output), which the new node takes over; ""
    # The links moved off old's shader outputs: (output name, to_node name, to_socket identifier, muted).
    moved: list = field(default_factory=list)

    @property
    def bypassed(self):
        return _bsdf_links(self.moved)


def replace_group_node(material_tree, group_tree, principled, normal_map, image_texture, old, eevee_output=None):
    """For a re-bake: adds the new group node in the place of `old`, the group node of the bake it
    replaces, with old's inputs (the Principled's inputs as the user edits them now: held_input),
    and moves onto it the links leaving old's shader outputs (the EEVEE output's too). Old stays
    in the tree, untouched otherwise, until commit_replacement; undo_replacement puts the material
    back exactly as it was (as on any error here). Keyframes and drivers of old's inputs, which go
    by node name, move at the commit, and so does the role of `eevee_output`, old's EEVEE output
    node (bake_record.recorded_targets finds it), or None. Returns a Replacement."""
    replacement = Replacement(node="", old=old.name, principled=principled.name, normal_map=normal_map.name,
                              roles={n.name: n.get(bake_record.ROLE_KEY) for n in (principled, normal_map)},
                              had_animation=material_tree.animation_data is not None,
                              eevee_output=eevee_output.name if eevee_output is not None else "")
    node = material_tree.nodes.new("ShaderNodeGroup")
    node.name = REBAKE_NAME
    replacement.node = node.name
    try:
        _wire_group_node(material_tree, node, group_tree, principled, normal_map, image_texture,
                         replacement.moved, replacing=old)
    except Exception:
        undo_replacement(material_tree, replacement)
        raise
    return replacement


def undo_replacement(material_tree, replacement):
    """Takes a re-bake's group node away again: the links it took go back to the old node, the
    roles back to the Principled and Normal Map nodes, its drivers (level of detail) go, and so
    does the node. The material is then as it was before replace_group_node."""
    nodes = material_tree.nodes
    node, old = nodes.get(replacement.node), nodes.get(replacement.old)
    for name, to_node, identifier, muted in reversed(replacement.moved):
        target = nodes.get(to_node)
        socket = _socket_by_identifier(target.inputs, identifier) if target is not None else None
        if socket is None or old is None:
            continue
        for link in list(socket.links):
            material_tree.links.remove(link)
        material_tree.links.new(old.outputs[name], socket).is_muted = muted
    for name, role in replacement.roles.items():
        marked = nodes.get(name)
        if marked is None:
            continue
        if role is not None:
            marked[bake_record.ROLE_KEY] = role
        elif bake_record.ROLE_KEY in marked.keys():
            del marked[bake_record.ROLE_KEY]
    if node is not None:
        node_animation.remove_node_animation(material_tree, node.name, clear_empty=not replacement.had_animation)
        nodes.remove(node)


def commit_replacement(material_tree, replacement):
    """Puts a re-bake's group node in the place of the old one for good: the keyframes and drivers
    of old's inputs move to it (and the Principled's or the Normal Map's, as a first bake copies
    them, for inputs old did not carry), old goes, and the new node takes the name a bake gives
    its node (group_node_name), the roles' key with it (Blender renames the animation paths and
    driver variables that name it), old's EEVEE output's too. Returns the node."""
    nodes = material_tree.nodes
    node, old = nodes[replacement.node], nodes[replacement.old]
    principled, normal_map = nodes[replacement.principled], nodes[replacement.normal_map]
    old_key = bake_record.role_key(old)
    carried_by_old, pairs = set(), []
    for _, shared in _shared_inputs(node, principled, normal_map):
        for j in shared.values():
            k = old.inputs.find(node.inputs[j].name)
            if k >= 0:
                carried_by_old.add(j)
                if material_scan.live_link(old.inputs[k]) is None:
                    pairs.append((k, j))
    carry_animation(material_tree, principled, node, normal_map, skip=carried_by_old)  # the rest: as a first bake
    node_animation.copy_input_animation(material_tree, old, node, pairs, move=True)
    node_animation.remove_node_animation(material_tree, old.name)
    node_animation.remove_node(material_tree, old)
    new_key = node.name
    node.name = group_node_name(material_tree, node, keys=(new_key, old_key))
    bake_record.rekey_roles(material_tree, (new_key, old_key), node.name)
    # Rekeyed above where it carries old's role; a record older than roles found it by name alone.
    # "" where the bake added no EEVEE output, or it is gone or ambiguous (recorded_node).
    if replacement.eevee_output:
        nodes[replacement.eevee_output][bake_record.ROLE_KEY] = bake_record.node_role("eevee_output", node.name)
    return node


def add_eevee_output(material_tree, node, bypassed):
    """EEVEE draws the group's EEVEE BSDF (its lobes, nodes.default_grazing_narrowing) through a Material
    Output of target EEVEE, which Blender prefers to a target-All output for EEVEE and its viewport;
    Cycles goes on drawing the All output, fed by the group's BSDF. Added only where that output is
    the Principled's one destination, it is the active one, and the material has no EEVEE output
    yet: elsewhere (shader mixes, outputs per engine the user made) the graph downstream is the
    user's, and both engines draw the group's BSDF. Returns the new
    node's name, or ""; on an error, removes what it added."""
    nodes = material_tree.nodes
    output = _eevee_output_beside(material_tree, bypassed)
    if output is None:
        return ""
    eevee = nodes.new("ShaderNodeOutputMaterial")
    try:
        eevee.name = eevee.label = EEVEE_OUTPUT
        eevee[TAG] = GROUP_VERSION
        eevee[bake_record.ROLE_KEY] = bake_record.node_role("eevee_output", node.name)
        eevee.target = "EEVEE"
        eevee.parent = output.parent
        eevee.location = (output.location.x, output.location.y - 220)
        new = material_tree.links.new(node.outputs[EEVEE_BSDF], eevee.inputs["Surface"])
        new.is_muted = bypassed[0][2]
        for socket in output.inputs:  # Volume and Displacement go on as the user wired them
            if socket.identifier != "Surface" and socket.is_linked:
                link = socket.links[0]
                material_tree.links.new(link.from_socket, eevee.inputs[socket.identifier]).is_muted = link.is_muted
    except Exception:
        nodes.remove(eevee)
        raise
    return eevee.name


def _eevee_output_beside(material_tree, bypassed):
    """The Material Output that add_eevee_output puts an EEVEE output beside, for a group node that
    takes the `bypassed` links: the active target-All output, where it is their one destination
    (its Surface) and the material has no target-EEVEE output; else None."""
    if len(bypassed) != 1 or any(n.bl_idname == "ShaderNodeOutputMaterial" and n.target == "EEVEE"
                                 for n in material_tree.nodes):
        return None
    output = material_tree.nodes.get(bypassed[0][0])
    if output is None or output.bl_idname != "ShaderNodeOutputMaterial" or output.target != "ALL" \
            or not output.is_active_output or bypassed[0][1] != "Surface":
        return None
    return output


def eevee_draws_own_output(material_tree, principled, replacing=None):
    """Whether EEVEE will draw the group's EEVEE BSDF and never its BSDF output once a bake puts
    its group node in: for a first bake, where insert_group_node adds an EEVEE output for the
    links leaving `principled`; for a re-bake, where `replacing`, the group node it replaces (a
    material_scan target), has its EEVEE output and that output still draws its EEVEE BSDF."""
    if replacing is None:
        links = [(link.to_node.name, link.to_socket.identifier, bool(link.is_muted))
                 for link in principled.outputs["BSDF"].links]
        return _eevee_output_beside(material_tree, links) is not None
    eevee = replacing.eevee_output
    if eevee is None or not eevee.inputs["Surface"].is_linked:
        return False
    link = eevee.inputs["Surface"].links[0]
    return link.from_node == replacing.group_node and link.from_socket.name == EEVEE_BSDF


def group_node_name(material_tree, node, keys=()):
    """The name a bake gives its group node `node`: GROUP_NODE_NAME, with .001, .002… where another
    node has that name or carries it as its role key (bake_record.role_key), other than the
    `keys` whose roles `node` takes over. The name becomes the key of the node's roles, which must
    be no other bake's: a group node the user renamed keeps the key it was made with, and its
    nodes are still in the tree when the new ones are named (a target a re-bake drops goes after
    commit_replacement); sharing the key, each would be found for the other (recorded_node) and
    rekeyed with it."""
    taken = {n.name: n for n in material_tree.nodes}
    taken.update((bake_record.role_key(n), None) for n in material_tree.nodes
                 if n != node and bake_record.role_key(n) not in keys)
    return id_names.free(taken, GROUP_NODE_NAME, own=node)


def _wire_group_node(material_tree, node, group_tree, principled, normal_map, image_texture, moved,
                     replacing=None):
    """Sets up the group node and moves onto it the links leaving the Principled's BSDF output;
    for a re-bake, the links leaving the shader outputs of `replacing`, the group node it
    replaces, whose inputs it takes (held_input). Each link is recorded in `moved` as (output
    name, to_node name, to_socket identifier, muted) as it moves, so that a failure part way
    can put back what moved."""
    links = material_tree.links
    node.node_tree = group_tree
    if replacing is None:  # a re-bake's node is named already (replace_group_node)
        node.name = group_node_name(material_tree, node)
    node[TAG] = GROUP_VERSION
    for role, marked in (("group", node), ("principled", principled), ("normal_map", normal_map)):
        marked[bake_record.ROLE_KEY] = bake_record.node_role(role, node.name)
    node.label = "ndfbake: %d lobe%s" % (lobe_count(group_tree), "" if lobe_count(group_tree) == 1 else "s")
    placed = replacing if replacing is not None else principled
    node.location = (placed.location.x, placed.location.y + (0 if replacing is not None else GROUP_NODE_OFFSET))
    node.width = max(placed.width if replacing is not None else node.width, 220)
    node.parent = placed.parent
    for source, pairs in _shared_inputs(node, principled, normal_map):
        for i, j in pairs.items():  # a re-bake's as the node it replaces holds them (held_input)
            _copy_input(links, held_input(source.inputs[i], replacing, node.inputs[j].name), node.inputs[j])
    if "Vector" in node.inputs:  # made only where the texture's Vector has a live link
        links.new(material_scan.live_link(image_texture.inputs["Vector"]).from_socket, node.inputs["Vector"])

    sources = [("BSDF", principled.outputs["BSDF"])] if replacing is None else \
        [(output.name, output) for output in replacing.outputs if output.type == "SHADER"]
    for name, source in sources:
        for link in list(source.links):
            to_socket, muted = link.to_socket, bool(link.is_muted)
            moved.append((name, link.to_node.name, to_socket.identifier, muted))
            links.remove(link)
            links.new(node.outputs[name], to_socket).is_muted = muted


def _socket_by_identifier(sockets, identifier):
    for socket in sockets:
        if socket.identifier == identifier:
            return socket
    return None


def principled_settings(principled):
    """The Principled BSDF's settings that are no inputs, for _recreate_principled."""
    return {name: getattr(principled, name) for name in PRINCIPLED_SETTINGS}


def _recreate_principled(material_tree, node, name, settings, normal_map):
    """A Principled BSDF in place of the one the user deleted after the bake, where it was, with its
    settings and its Normal from the Normal Map node; write_back_inputs then gives it the inputs."""
    principled = material_tree.nodes.new("ShaderNodeBsdfPrincipled")
    principled.name = name
    principled.parent = node.parent
    principled.location = (node.location.x, node.location.y - GROUP_NODE_OFFSET)
    for setting, value in (settings or {}).items():
        if setting in PRINCIPLED_SETTINGS:
            setattr(principled, setting, value)
    if normal_map is not None:
        material_tree.links.new(normal_map.outputs["Normal"], principled.inputs["Normal"])
    return principled


def remove_group_node(material_tree, node_name, principled_name, bypassed, eevee_output="", keep_edits=True,
                      normal_map_name="", settings=None):
    """Undoes insert_group_node: the EEVEE output it added goes, and every link now leaving the
    group node leaves the Principled BSDF again, wherever the user has led it since the bake (a
    Mix Shader put after the group stays); where the group node is gone, the links it bypassed
    come back. With keep_edits, the node's inputs go back to the Principled (write_back_inputs;
    not when undoing a half-built insert, where only driver variables that insert pointed at the
    node read the Principled again). Then the group node goes. The nodes are found by their roles
    (bake_record.recorded_node), renamed or not; a Principled deleted since the bake is made
    again (with `settings`, principled_settings(), and its Normal from the Normal Map node).
    Returns the group tree it used (or None)."""
    nodes = material_tree.nodes
    key = node_name

    def find(name, role):
        return bake_record.recorded_node(material_tree, name, bake_record.node_role(role, key))

    added = find(eevee_output, "eevee_output") if eevee_output else None
    if added is not None and added.get(TAG) is not None:
        nodes.remove(added)
    node = find(node_name, "group")
    principled = find(principled_name, "principled")
    normal_map = find(normal_map_name, "normal_map") if normal_map_name else None
    if principled is None and node is not None and keep_edits:
        principled = _recreate_principled(material_tree, node, principled_name, settings, normal_map)
    group_tree = node.node_tree if node is not None else None
    if node is not None and principled is not None:
        if keep_edits:
            write_back_inputs(material_tree, node, principled, normal_map)
        else:
            for target, pairs in _shared_inputs(node, principled, normal_map):
                node_animation.retarget_variables(material_tree, node, target, [(j, i) for i, j in pairs.items()])
    node_animation.remove_node_animation(material_tree, node.name if node is not None else node_name)
    if node is not None:
        leaving = [link for output in node.outputs if output.type == "SHADER" for link in output.links]
        targets = [(link.to_socket, link.is_muted) for link in leaving]
        for link in leaving:
            material_tree.links.remove(link)
    else:
        targets = []
        for to_node_name, identifier, muted in bypassed:
            to_node = nodes.get(to_node_name)
            socket = _socket_by_identifier(to_node.inputs, identifier) if to_node is not None else None
            if socket is not None:
                targets.append((socket, muted))
    if principled is not None:
        for socket, muted in targets:
            for link in list(socket.links):
                material_tree.links.remove(link)
            material_tree.links.new(principled.outputs["BSDF"], socket).is_muted = muted
    if node is not None:
        node_animation.remove_node(material_tree, node)
    bake_record.clear_roles(material_tree, key)
    return group_tree
