"""A material's node group: a normal-mapped Principled BSDF shaded through its fitted vMF lobes,
with stock nodes only, in EEVEE and Cycles alike. Assembles lobe_nodes' decoding, lod_nodes'
lookups and specular_split's layers into one group per bake; group_node.py puts it into the
material.

Per lobe j, μ_j goes to a tangent-space Normal Map node (same UV map and Strength as the original
one) as the colour μ·0.5 + 0.5, so the tangent frame is Blender's own in both engines. Where the
material allows (specular_split.may_split: Principled v2 without coat, sheen or transmission), a
lobe draws only the specular reflection and one base Principled draws the diffuse once at the
texel's mean normal; elsewhere lobe j is a whole copy of the original Principled BSDF with that
normal and roughness. The lobes use Multiscatter GGX where the original uses GGX and does not
transmit (see lobe_bsdfs.lobe_bsdf). Lobes are summed with weights α_j (each a Mix Shader of factor α_j,
then Add Shader nodes; see _weighted_sum for why not a chain of mixes). Every other Principled
input (linked or not) is carried over through the group's inputs; the emission is drawn once
beside the lobes (lobe_bsdfs.emission). A material whose fit needs one lobe gets a one-lobe group (nothing to
sum): the group is built for the lobe slots the bake wrote.

The group has two shader outputs, each with its own lobes: BSDF (Cycles, and both engines where
the material's graph is the user's) and EEVEE BSDF, which EEVEE draws through a Material Output of
target EEVEE that the bake adds beside the user's (group_node.add_eevee_output) and Revert
removes. Each output's lobes are narrowed toward grazing views with its engine's constant
(default_grazing_narrowing; lobe_nodes.grazing_roughness_group) where it has one, Cycles' unless
cycles_lobes is WIDENED. Both outputs' lobes read the same lookups, decodes and Normal Map nodes,
except with an atlas where EEVEE never draws BSDF: then BSDF's lobes have their own, with one
Linear lookup a level instead of EEVEE's four Closest ones (lod_nodes).

OSL: where Cycles runs OSL on the CPU, a bake may draw Cycles' lobes through one Script node
instead (osl_group.py); `osl_group.status()` says where. The stock-node group works in both engines.
"""
import bpy

from . import blender_compat, lobe_bsdfs, lobe_nodes, lod_nodes, material_scan, specular_split
from .node_builders import TAG, _add_socket, _new_group, socket_value

# Shared groups of earlier versions of this add-on, removed with the last bake using them: version
# 2's, and the specular split's groups that drew Karis's fit of the layer's albedo and then Cycles'
# estimate for both engines (until 2026-11-28).
RETIRED_GROUPS = tuple("NDFB %s v2" % name for name in ("vMF Lobe", "Grazing Roughness", "Level of Detail",
                                                         "Atlas Taps", "Bilinear")) \
    + ("NDFB Specular Split v3", "NDFB Specular Layer v3", "NDFB Specular Layers v3")
EEVEE_BSDF = "EEVEE BSDF"             # the group's second shader output (EEVEE's own lobes)
# BakeSettings.cycles_lobes: what the group's BSDF output (Cycles' view) draws.
WIDENED, NARROWED = "WIDENED", "NARROWED"
# How an output's lobes read an atlas (build_material_group): lod_nodes' taps, or one Linear lookup a
# level; the decode node of lobe j in each.
TAPS, LINEAR = "taps", "linear"
DECODE = {TAPS: "Decode %d", LINEAR: "Decode %d Linear"}
# C of lobe_nodes.grazing_roughness_group, per group output (the engine that draws it); 0: the
# lobes are drawn widened, not narrowed. Cycles' fitted offline against the normal map's own
# response (docs/grazing-fit.md; brdf.h kGrazingNarrowing, which ndfbake.glsl uses too). EEVEE's
# measured on the demo scene under Blender's 8 studio worlds (studies/world_sweep.py;
# docs/rendering.md, "Grazing views"): EEVEE Legacy (3.x) 32, against its own supersampled render
# of the fine normals; EEVEE Next (4.2+) none, against the Cycles reference, which it comes closer
# to widened under every world (EEVEE Next's own supersampled render of the fine normals loses
# what they reflect: docs/rendering.md, "EEVEE Next's reference").
CYCLES_GRAZING_NARROWING = 4.0
EEVEE_LEGACY_GRAZING_NARROWING = 32.0


def default_grazing_narrowing():
    """C per group output in this Blender (a function: importing the add-on asks Blender nothing)."""
    return {"BSDF": CYCLES_GRAZING_NARROWING,
            EEVEE_BSDF: 0.0 if blender_compat.eevee_next() else EEVEE_LEGACY_GRAZING_NARROWING}


def material_group_name(material_name):
    """The name a bake gives a material's group: "NDFB <material>" (cut to fit, .001… where taken)."""
    return "NDFB " + material_name


def lobe_image_name(material_name, j):
    """(body, tail) of the name of the image of a material's lobe slot j (id_names): "<material> lobe j"."""
    return material_name, " lobe %d" % j


def build_material_group(name, principled, normal_map, image_texture, lobe_images, atlas=None, lod=None,
                         current=None, cycles_lobes=NARROWED, cycles_only=False, narrowing=None):
    """A group with the carried Principled inputs (+ Normal Strength, + Vector if the original
    texture's has a live (unmuted) link, + the level-of-detail constants with an atlas) and the
    BSDF and EEVEE BSDF outputs, shading through len(lobe_images) lobes: level-0 textures that
    the renderer filters itself (atlas None), or MIP atlases (AtlasLayout) sampled at the level
    of detail the scene gives (lod: a scene_lod.LodPlan, required with an atlas). Each output's
    lobes are narrowed toward grazing views with its constant (`narrowing`, by output, else
    default_grazing_narrowing()) where it is not 0, BSDF's not with cycles_lobes WIDENED; with cycles_lobes None the BSDF output is left
    unlinked for the caller (osl_group draws Cycles' lobes itself). cycles_only: EEVEE draws the
    EEVEE BSDF output, never BSDF (group_node.has_eevee_output), so BSDF's lobes may read an atlas
    with one Linear lookup a level. For a re-bake, `current` is the group node of the bake it
    replaces, which holds the Principled's inputs (held_input)."""
    tree = _new_group(name)
    decode = lobe_nodes.lobe_group()
    carried = lobe_bsdfs.carried_inputs(principled, current)
    # Not where the material transmits: Blender's Principled BSDF with Multiscatter GGX has no
    # Transmission Roughness (Cycles' multiscatter glass takes Roughness), so rough glass would
    # turn sharp; the lobes keep the original GGX there.
    multiscatter = principled.distribution == "GGX" and not lobe_bsdfs.transmits(principled if current is None else current)
    for socket in carried:
        iface = _add_socket(tree, "INPUT", socket.bl_idname, socket.name)
        try:
            iface.default_value = socket_value(lobe_bsdfs.held_input(socket, current, socket.name))
        except (AttributeError, TypeError):
            pass
    strength = _add_socket(tree, "INPUT", "NodeSocketFloat", "Normal Strength")
    strength.default_value = 1.0
    strength.min_value = 0.0
    # A muted link is no link: the texture then reads its default UVs, and so must the group.
    has_vector = material_scan.live_link(image_texture.inputs["Vector"]) is not None
    if has_vector:
        vector = _add_socket(tree, "INPUT", "NodeSocketVector", "Vector")
        vector.hide_value = True
    if atlas is not None:
        for key, value in zip(lod_nodes.LOD_INPUTS, (lod.texels_per_unit, lod.pixel_angle, lod.pixel_size)):
            _add_socket(tree, "INPUT", "NodeSocketFloat", key).default_value = value
    _add_socket(tree, "OUTPUT", "NodeSocketShader", "BSDF")
    _add_socket(tree, "OUTPUT", "NodeSocketShader", EEVEE_BSDF)

    gin = tree.nodes.new("NodeGroupInput")
    gin.location = (-2300, 0)
    gout = tree.nodes.new("NodeGroupOutput")
    count = len(lobe_images)
    gout.location = (1400 + 200 * count, 0)
    names = {s.name for s in carried}

    holder = principled if current is None else current
    # Specular-only lobes over one base (specular_split), or whole copies (kind None).
    kind = specular_split.lobe_kind(holder) if specular_split.may_split(principled, holder) else None
    constants = lobe_bsdfs.closure_off_inputs(holder) if kind is None else {}

    # The outputs whose lobe BSDFs the group builds: (y offset of a lobe's BSDF, y of the sum).
    layout = ({"BSDF": (0, -200)} if cycles_lobes is not None else {}) | {EEVEE_BSDF: (-450, -500)}
    # The lookups each output reads: one set for both, or with an atlas where Cycles alone draws
    # BSDF, one Linear lookup a level for it (lod_nodes' docstring) and the taps for EEVEE BSDF.
    reads = {output: LINEAR if atlas is not None and cycles_only and output == "BSDF" else TAPS for output in layout}
    if atlas is not None:
        uv = lod_nodes.uv_source(tree, gin, has_vector, (-2000, 100))
        levels, blend = lod_nodes.atlas_levels(tree, gin, atlas)
        repeat = image_texture.extension == "REPEAT"
        addressing = {TAPS: lod_nodes.address_levels(tree, lod_nodes.atlas_taps_group(), levels, atlas, repeat,
                                                     uv, 300)}
        if LINEAR in reads.values():
            addressing[LINEAR] = lod_nodes.address_levels(tree, lod_nodes.atlas_point_group(), levels, atlas,
                                                          repeat, uv, -300)

    shaders = {output: [] for output in layout}
    weights = {read: [] for read in reads.values()}
    moments = {read: [] for read in reads.values()}
    for j, image in enumerate(lobe_images):
        y = -900 * j
        lobes = {}  # per set of lookups: (decode node, the lobe's normal)
        for read in dict.fromkeys(reads.values()):
            dy = 0 if read == TAPS else -450
            if atlas is None:
                color, alpha = lod_nodes.sample_level0(tree, gin, image, image_texture, has_vector, j, y)
            elif read == TAPS:
                color, alpha = lod_nodes.sample_atlas(tree, image, addressing[read], blend, j, y)
            else:
                color, alpha = lod_nodes.sample_atlas_linear(tree, image, addressing[read], blend, j, y + dy)
            dec = tree.nodes.new("ShaderNodeGroup")
            dec.node_tree = decode
            dec.name = dec.label = DECODE[read] % j
            dec.location = (-800, y + dy)
            tree.links.new(color, dec.inputs["Lobe"])
            tree.links.new(alpha, dec.inputs["Lobe Z"])
            if "Roughness" in names:
                tree.links.new(gin.outputs["Roughness"], dec.inputs["Roughness"])
            moments[read].append(dec.outputs["Moment"])
            weights[read].append(dec.outputs["Weight"])
            lobes[read] = dec, lobe_bsdfs.normal_map_node(tree, gin, normal_map, dec.outputs["Normal"], (-550, y + dy - 150))

        for output, (dy, _) in layout.items():
            dec, nm = lobes[reads[output]]
            roughness = dec.outputs["Roughness"]
            constant = grazing_narrowing(output, cycles_lobes, narrowing)
            if constant:
                roughness = _grazing_roughness(tree, gin, dec, nm, names, "Grazing %d %s" % (j, output),
                                               constant, (-300, y + dy - 150))
            shaders[output].append(lobe_bsdfs.lobe_bsdf(tree, gin, principled, carried, roughness, nm,
                                              "Lobe %d %s" % (j, output), (0, y + dy), multiscatter, kind,
                                              constants))

    x_end = 1000 + 200 * count
    emission = lobe_bsdfs.emission(tree, gin, (x_end, -900))
    bases = {}
    if kind in (specular_split.DIELECTRIC, specular_split.BOTH):
        for k, read in enumerate(dict.fromkeys(reads.values())):
            diffuse = {output: specular_split.EEVEE_DIFFUSE if output == EEVEE_BSDF else specular_split.CYCLES_DIFFUSE
                       for output in layout if reads[output] == read}
            bases |= lobe_bsdfs.base_bsdfs(tree, gin, principled, carried, normal_map, moments[read], names, diffuse,
                                           (x_end, 600 + 1400 * k))
    sums = {}
    for output, lobes in shaders.items():
        y = layout[output][1]
        total = _weighted_sum(tree, lobes, weights[reads[output]], y)
        if output in bases:
            total = _add_shader(tree, total, bases[output], (x_end + 200, y))
        if kind is not None:  # split lobes carry no Alpha: the group mixes the transparency in once
            total = _alpha_over(tree, gin, total, "%s %s" % (lobe_bsdfs.ALPHA_MIX, output), (x_end + 400, y))
        sums[output] = _add_shader(tree, total, emission, (x_end + 600, y))
    tree.links.new(sums[EEVEE_BSDF], gout.inputs[EEVEE_BSDF])
    if "BSDF" in sums:
        tree.links.new(sums["BSDF"], gout.inputs["BSDF"])
    return tree


def grazing_narrowing(output, cycles_lobes, narrowing=None):
    """C of the grazing narrowing that `output`'s lobes are drawn with (0: widened): its engine's
    (`narrowing`, by output, else default_grazing_narrowing()), Cycles' (BSDF) only with cycles_lobes NARROWED."""
    constants = default_grazing_narrowing() if narrowing is None else narrowing
    return constants[output] if output == EEVEE_BSDF or cycles_lobes == NARROWED else 0.0


def _grazing_roughness(tree, gin, decode, normal, names, name, narrowing, location):
    """The decoded lobe's roughness narrowed toward grazing views (lobe_nodes.grazing_roughness_group)
    with constant `narrowing`, about the lobe's world normal `normal`."""
    grazing = tree.nodes.new("ShaderNodeGroup")
    grazing.node_tree = lobe_nodes.grazing_roughness_group()
    grazing.name = grazing.label = name
    grazing.location = location
    tree.links.new(decode.outputs["Roughness"], grazing.inputs["Roughness"])
    if "Roughness" in names:
        tree.links.new(gin.outputs["Roughness"], grazing.inputs["Base Roughness"])
    else:
        grazing.inputs["Base Roughness"].default_value = decode.inputs["Roughness"].default_value
    tree.links.new(normal, grazing.inputs["Normal"])
    grazing.inputs["Narrowing"].default_value = narrowing
    return grazing.outputs["Roughness"]


def _add_shader(tree, a, b, location):
    add = tree.nodes.new("ShaderNodeAddShader")
    add.location = location
    tree.links.new(a, add.inputs[0])
    tree.links.new(b, add.inputs[1])
    return add.outputs["Shader"]


def _alpha_over(tree, gin, shader, name, location):
    """Alpha·shader + (1 − Alpha)·Transparent: what a Principled BSDF does with its Alpha."""
    transparent = tree.nodes.new("ShaderNodeBsdfTransparent")
    transparent.location = (location[0], location[1] - 150)
    mix = tree.nodes.new("ShaderNodeMixShader")
    mix.name = mix.label = name
    mix.location = location
    tree.links.new(gin.outputs["Alpha"], mix.inputs["Fac"])
    tree.links.new(transparent.outputs["BSDF"], mix.inputs[1])
    tree.links.new(shader, mix.inputs[2])
    return mix.outputs["Shader"]


def _weighted_sum(tree, shaders, weights, y):
    """Σ_j α_j·BSDF_j: lobe j through a Mix Shader of factor α_j with nothing in its other input
    (the closure weighted α_j), the lobes then added. Each weight is read in its own lobe's branch
    only: Cycles' SVM keeps every value that two closure branches share on its stack (255 floats)
    until the whole tree is done, and a chain of mixes with factors α_k / (α_0 + … + α_k) made
    each lobe's texture lookups shared; at eight lobes the stack overflowed and Cycles drew the
    material black. No renormalization is needed: the bake writes weights that sum to 1 per
    texel, and every filter between them (MIP levels, bilinear taps, the blend of two levels) is
    a convex combination, which keeps the sum."""
    if len(shaders) == 1:
        return shaders[0]
    weighted = []
    for j, (shader, weight) in enumerate(zip(shaders, weights)):
        mix = tree.nodes.new("ShaderNodeMixShader")
        mix.location = (400 + 200 * j, y)
        tree.links.new(weight, mix.inputs["Fac"])
        tree.links.new(shader, mix.inputs[2])
        weighted.append(mix.outputs["Shader"])
    total = weighted[0]
    for j, term in enumerate(weighted[1:], 1):
        add = tree.nodes.new("ShaderNodeAddShader")
        add.location = (500 + 200 * j, y - 150)
        tree.links.new(total, add.inputs[0])
        tree.links.new(term, add.inputs[1])
        total = add.outputs["Shader"]
    return total


def lobe_count(group_tree):
    return len({n.image.name for n in group_tree.nodes if n.bl_idname == "ShaderNodeTexImage" and n.image})


def remove_unused_groups(names):
    """Removes the named node groups this add-on made once nothing uses them, then the groups they
    used (a material's atlas table, the shared helpers) if nothing else uses those either, and the
    specular layer's table image once no group uses it."""
    shared = [lobe_nodes.LOBE_GROUP, lobe_nodes.GRAZING_GROUP, lod_nodes.LOD_GROUP, lod_nodes.TAPS_GROUP,
              lod_nodes.POINT_GROUP, lod_nodes.BILINEAR_GROUP, specular_split.SPLIT_GROUP, *RETIRED_GROUPS]
    pending = list(dict.fromkeys(names)) + shared
    while pending:
        tree = bpy.data.node_groups.get(pending.pop(0))
        if tree is None or tree.get(TAG) is None or tree.users != 0:
            continue
        # Found through the nodes, not by name: a long material name cuts "<group> atlas" short.
        pending += [n.node_tree.name for n in tree.nodes if n.bl_idname == "ShaderNodeGroup" and n.node_tree]
        bpy.data.node_groups.remove(tree)
    specular_split.remove_unused_table()
