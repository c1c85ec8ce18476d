"""Where a baked material's Cycles frame time goes: the demo scene's dielectric bake (4 lobes)
rendered with parts of its groups changed, measured in one run.

    python studies/cycles_cost_parts.py -- --out DIR [--rounds R] [--lobes N]   (the bpy module)
    blender -b --factory-startup --python studies/cycles_cost_parts.py -- --out DIR ...

A diagnostic: only the times mean something. Variants (every material's group, same scene,
320x180, 16 samples):
- plain: the materials as the artist made them (Metallic 0); baked: the bake as it ships;
- made constant, so that Cycles folds the part away (each of these also changes the image, and
  with it the light paths, so its saving is not the part's cost alone):
  constant table (each atlas table's outputs, a level's frame in the atlas), constant level (the
  level of detail: 2; the tables and the blend of two levels fold away with it), no atlas
  sampling (the lobes' texels a smooth function of the UV: what is left is the decode, the Normal
  Map nodes and the closures);
- four taps a level: Cycles' lobes read EEVEE's four Closest lookups a level, bilinear in nodes,
  instead of their one Linear lookup (what a group draws where EEVEE shares its BSDF output;
  addon/ndfbake/shading/lod_nodes.py): the same image;
- done twice, the second result mixed in with weight 1e-6 and its inputs nudged by a relative
  1e-6 (Cycles merges nodes of equal inputs): the same image and light paths, so the added time
  is the part's cost. lookups twice (lookup addresses, lookups and blends of every lobe),
  all sampling twice (the level of detail and the atlas tables too).
Each variant is rendered once to warm up and once timed per round, the rounds interleaved; the
fastest round counts. Prints seconds and the ratio to plain.
"""
import argparse
import os
import sys
import time

import bpy

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "examples"))  # the demo
import demo_build  # noqa: E402
import demo_render  # noqa: E402
import demo_scene  # noqa: E402

SAMPLES = 16
CONSTANT_LEVEL = 2.0


def _groups():
    """The material groups that sample MIP atlases."""
    from ndfbake.shading import lod_nodes
    return [g for g in bpy.data.node_groups if lod_nodes.atlas_table(g) is not None]


def _set_input(tree, socket, value):
    for link in list(socket.links):
        tree.links.remove(link)
    socket.default_value = value


def _unlink_to_constant(tree, output, value):
    for socket in [link.to_socket for link in output.links]:
        _set_input(tree, socket, value)


def constant_table():
    from ndfbake.shading import lod_nodes
    for tree in _groups():
        taps = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeGroup" and n.node_tree.name == lod_nodes.TAPS_GROUP)
        width, height = taps.inputs["Atlas Width"].default_value, taps.inputs["Atlas Height"].default_value
        level0 = round((width - 4) * 2 / 3)  # level 0, then level 1 beside it (native lobe_atlas.h)
        frames = ({"X": 0, "Y": 0, "W": level0, "H": height - 2},
                  {"X": level0 + 2, "Y": 0, "W": level0 // 2, "H": (height - 2) // 2})
        for k, frame in enumerate(frames):
            lookup = tree.nodes[lod_nodes.ATLAS_LOOKUP % k]
            for key, value in frame.items():
                _unlink_to_constant(tree, lookup.outputs[key], float(value))


def constant_level():
    from ndfbake.shading import lod_nodes
    for tree in _groups():
        for node in tree.nodes:
            if node.bl_idname == "ShaderNodeGroup" and node.node_tree.name == lod_nodes.LOD_GROUP:
                _unlink_to_constant(tree, node.outputs["Level"], CONSTANT_LEVEL)


def four_taps_a_level():
    """Cycles' lobes read the four Closest lookups a level that EEVEE's read (what a group draws
    where EEVEE draws its BSDF output too) instead of one Linear lookup: the same texels (the
    diffuse base's mean normal follows, through the decodes' moments)."""
    from ndfbake.shading import nodes
    for tree in _groups():
        for j in range(nodes.lobe_count(tree)):
            node, taps = (tree.nodes[nodes.DECODE[read] % j] for read in (nodes.LINEAR, nodes.TAPS))
            for output in node.outputs:
                for link in list(output.links):
                    tree.links.new(taps.outputs[output.name], link.to_socket)


def no_atlas_sampling():
    """Lobe texel (0.25, 0.05·u, 0.05·v; 0.2375): a weight of 1/4 about a mean normal that
    varies with the UV, so that nothing downstream folds to a constant."""
    from ndfbake.shading.node_builders import _math
    for tree in _groups():
        separate = tree.nodes.new("ShaderNodeSeparateXYZ")
        tree.links.new(tree.nodes.new("ShaderNodeTexCoord").outputs["UV"], separate.inputs[0])
        texel = tree.nodes.new("ShaderNodeCombineXYZ")
        texel.inputs["X"].default_value = 0.25
        for source, target in (("X", "Y"), ("Y", "Z")):
            tree.links.new(_math(tree, "MULTIPLY", separate.outputs[source], 0.05), texel.inputs[target])
        for node in tree.nodes:
            if node.name.startswith("Decode "):
                _set_input(tree, node.inputs["Lobe Z"], 0.25 * 0.95)
                for link in list(node.inputs["Lobe"].links):
                    tree.links.remove(link)
                tree.links.new(texel.outputs[0], node.inputs["Lobe"])


def _nudged(tree, socket, nudges):
    """`socket`'s value moved by a relative 1e-6: a copy that reads it is no duplicate Cycles
    merges (it merges nodes of equal inputs), and reads the same texels."""
    from ndfbake.shading.node_builders import _math, _vmath
    if socket not in nudges:
        nudges[socket] = (_vmath(tree, "ADD", socket, (1e-7, 0.0, 0.0)) if socket.type == "VECTOR"
                          else _math(tree, "MULTIPLY", socket, 1.0 + 1e-6))
    return nudges[socket]


def _copy_upstream(tree, node, shared, copies, nudges):
    """A copy of `node` and of every node it reads from, up to the `shared` ones (read nudged)."""
    from ndfbake.shading.group_node import _socket_by_identifier
    if node in copies:
        return copies[node]
    copy = tree.nodes.new(node.bl_idname)
    copies[node] = copy
    for prop in node.bl_rna.properties:
        if not prop.is_readonly and prop.identifier not in ("name", "label", "location", "parent", "select"):
            try:
                setattr(copy, prop.identifier, getattr(node, prop.identifier))
            except (AttributeError, TypeError, ValueError):
                pass
    for socket, copied in zip(node.inputs, copy.inputs):
        if hasattr(socket, "default_value") and socket.bl_idname == copied.bl_idname:
            copied.default_value = socket.default_value
        for link in socket.links:
            if link.from_node in shared:
                source = _nudged(tree, link.from_socket, nudges)
            else:
                source = _socket_by_identifier(_copy_upstream(tree, link.from_node, shared, copies, nudges).outputs,
                                               link.from_socket.identifier)
            tree.links.new(source, copied)
    return copy


def _downstream(nodes):
    """`nodes` and every node that reads from them."""
    found, stack = set(), list(nodes)
    while stack:
        node = stack.pop()
        if node not in found:
            found.add(node)
            stack.extend(link.to_node for output in node.outputs for link in output.links)
    return found


def _sampling_twice(lookups_only):
    """Every lobe's texel looked up a second time and mixed in with weight 1e-6 (the same image,
    so the same light paths): what the sampling costs. With lookups_only the second lookups have
    their own tap addresses and bilinear weights but share the level of detail and the atlas
    tables; else everything from the group's inputs and UV is computed twice."""
    from ndfbake.shading import lod_nodes
    from ndfbake.shading.group_node import _socket_by_identifier
    from ndfbake.shading.node_builders import _mix
    for tree in _groups():
        addressing = [n for n in tree.nodes if n.bl_idname == "ShaderNodeGroup"
                      and n.node_tree.name in (lod_nodes.TAPS_GROUP, lod_nodes.POINT_GROUP)]
        if lookups_only:
            shared = set(tree.nodes) - _downstream(addressing)
        else:
            shared = {n for n in tree.nodes if n.bl_idname in ("NodeGroupInput", "ShaderNodeTexCoord")}
        copies, nudges = {}, {}
        for decode in [n for n in tree.nodes if n.name.startswith("Decode ")]:
            for key, data_type in (("Lobe", "VECTOR"), ("Lobe Z", "FLOAT")):
                link = decode.inputs[key].links[0]
                twin = _copy_upstream(tree, link.from_node, shared, copies, nudges)
                second = _socket_by_identifier(twin.outputs, link.from_socket.identifier)
                tree.links.new(_mix(tree, data_type, 1e-6, link.from_socket, second, (0, 0)), decode.inputs[key])


def lookups_twice():
    _sampling_twice(lookups_only=True)


def all_sampling_twice():
    _sampling_twice(lookups_only=False)


VARIANTS = (("plain", None), ("baked", None), ("constant table", constant_table),
            ("constant level", constant_level), ("four taps a level", four_taps_a_level),
            ("no atlas sampling", no_atlas_sampling), ("lookups twice", lookups_twice),
            ("all sampling twice", all_sampling_twice))


def measure(out, rounds, lobes, log=print):
    scene_dir = os.path.join(out, "scene")
    os.makedirs(scene_dir, exist_ok=True)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    info = demo_build.build_scene(scene_dir)
    for name in info["materials"]:
        bpy.data.materials[name].node_tree.nodes["Principled BSDF"].inputs["Metallic"].default_value = 0.0
    plain_path, baked_path = os.path.join(scene_dir, "plain.blend"), os.path.join(scene_dir, "baked.blend")
    bpy.ops.wm.save_as_mainfile(filepath=plain_path, copy=True)
    failed = [b for b in demo_scene.bake_all(bpy.context.scene, max_lobes=lobes) if "error" in b]
    if failed:
        raise RuntimeError("bake failed: %s" % failed)
    bpy.ops.wm.save_as_mainfile(filepath=baked_path)
    log("cycles_cost_parts.py: Blender %s, %d lobes, %d rounds" % (bpy.app.version_string, lobes, rounds))
    frame = os.path.join(out, "frame.exr")
    seconds = {name: [] for name, _ in VARIANTS}
    for round_index in range(rounds):
        for name, change in VARIANTS:
            bpy.ops.wm.open_mainfile(filepath=plain_path if name == "plain" else baked_path)
            if change is not None:
                change()
            scene = bpy.context.scene
            demo_render.render(scene, "CYCLES", frame, SAMPLES)
            start = time.perf_counter()
            demo_render.render(scene, "CYCLES", frame, SAMPLES)
            seconds[name].append(time.perf_counter() - start)
            log("  round %d %-18s %.2f s" % (round_index + 1, name, seconds[name][-1]))
    best = {name: min(values) for name, values in seconds.items()}
    log("\n| variant | seconds a frame | ratio to plain |\n|---|---:|---:|")
    for name, _ in VARIANTS:
        log("| %s | %.2f | %.2f |" % (name, best[name], best[name] / best["plain"]))
    return best


def _arguments():
    parser = argparse.ArgumentParser(prog="studies/cycles_cost_parts.py", description=__doc__.split("\n")[0])
    parser.add_argument("--out", required=True, help="output folder")
    parser.add_argument("--rounds", type=int, default=4)
    parser.add_argument("--lobes", type=int, default=4)
    parser.add_argument("--library", help="libndfbake.so (default $NDFBAKE_LIBRARY or build/native/libndfbake.so)")
    return demo_build.script_arguments(parser)


def main():
    args = _arguments()
    demo_build.import_addon(args.library)
    measure(args.out, args.rounds, args.lobes)
    return 0


if __name__ == "__main__":
    demo_scene.run_as_script(main)
