"""A bake's record on the material (RECORD_KEY: what a bake did, for a re-bake and Revert) and the
roles the nodes it names carry (ROLE_KEY), so that they are found again after the user renames
them (recorded_node)."""
import json
from typing import Any, NamedTuple

RECORD_KEY = "ndfbake_bake"
RECORD_VERSION = 1  # the record's format ("version" in it)
# Custom property on each node a bake record names: "<role>:<key>", the key being the name the
# bake gave its group node (unique in the tree when made). Roles: principled, normal_map, group,
# eevee_output.
ROLE_KEY = "ndfbake_role"


def node_role(role, key):
    return "%s:%s" % (role, key)


def role_key(node):
    """The key of the node's role (node_role): the name its bake's group node was made with; "" if none."""
    return str(node.get(ROLE_KEY, "")).partition(":")[2]


def recorded_node(tree, name, role):
    """The node a bake record calls `name`, playing `role` (node_role): by name while it carries
    the role; renamed, the one node that carries it (a copy carries it too: then none is sure);
    by name alone for a record older than roles, where no node carries any role of its bake."""
    node = tree.nodes.get(name) if name else None
    if node is not None and node.get(ROLE_KEY) == role:
        return node
    carriers = [n for n in tree.nodes if n.get(ROLE_KEY) == role]
    if len(carriers) == 1:
        return carriers[0]
    key = role.partition(":")[2]
    if not carriers and node is not None and node.get(ROLE_KEY) is None and \
            not any(role_key(n) == key for n in tree.nodes):
        return node
    return None


class RecordedTarget(NamedTuple):
    """A target of a bake record with its nodes as found now (recorded_node), None where gone."""
    target: dict                  # the record's entry
    principled: Any               # its Principled BSDF
    group_node: Any
    eevee_output: Any             # None also where the bake added none


def recorded_targets(tree, rec):
    """[RecordedTarget] for the targets of bake record `rec`, the nodes found by their roles."""
    found = []
    for target in rec.get("targets", []):
        key = target.get("group_node", "")
        eevee_output = target.get("eevee_output", "")
        found.append(RecordedTarget(
            target, recorded_node(tree, target.get("principled", ""), node_role("principled", key)),
            recorded_node(tree, key, node_role("group", key)),
            recorded_node(tree, eevee_output, node_role("eevee_output", key)) if eevee_output else None))
    return found


def clear_roles(tree, key):
    """Takes the roles of the bake whose group node was made as `key` off every node."""
    for node in tree.nodes:
        if ROLE_KEY in node.keys() and role_key(node) == key:
            del node[ROLE_KEY]


def rekey_roles(tree, keys, new_key):
    """Gives the roles of the bakes whose group node was made as one of `keys` the key `new_key`."""
    for node in tree.nodes:
        key = role_key(node)
        if key and key in keys:
            node[ROLE_KEY] = node_role(str(node[ROLE_KEY]).partition(":")[0], new_key)


def record(material):
    """The bake record stored on the material (a dict), or None."""
    raw = material.get(RECORD_KEY)
    if not raw:
        return None
    try:
        rec = json.loads(raw)
    except (TypeError, ValueError):
        return None
    return rec if isinstance(rec, dict) else None  # a property of that name someone else wrote
