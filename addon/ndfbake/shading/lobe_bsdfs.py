"""The BSDFs of a material's group (nodes.build_material_group assembles them): each lobe's
Principled BSDF (a whole copy, or specular only over a base where specular_split says so), the
base that draws the diffuse beneath specular-only lobes, the emission drawn once, and which of the
Principled's inputs each takes from the group."""
from . import blender_compat, material_scan, specular_split
from .node_builders import _vmath


# Principled inputs the lobe group computes itself rather than passing through.
COMPUTED_INPUTS = {"Normal", "Roughness"}


EMISSION_ALPHA = "Emission Alpha"    # the group's Mix Shader that weights the emission by Alpha
# The specular split (specular_split.py): its node, the base BSDFs and the Mix Shaders of the Alpha
# (one of each per output: "<BASE_BSDF> BSDF", "<BASE_BSDF> EEVEE BSDF"...).
SPECULAR_SPLIT, BASE_BSDF, ALPHA_MIX = "Specular Split", "Base BSDF", "Alpha"
# What a specular-only lobe takes from the group, by kind; the rest of its Principled stays at the
# default (coat, sheen, subsurface and transmission off).
_SHARED_LOBE_INPUTS = {"Anisotropic", "Anisotropic Rotation", "Tangent", "Specular Tint", "Thin Film Thickness",
                       "Thin Film IOR"}
SPECULAR_LOBE_INPUTS = {specular_split.CONDUCTOR: _SHARED_LOBE_INPUTS | {"Base Color"},
                        specular_split.DIELECTRIC: _SHARED_LOBE_INPUTS | {"IOR", "Specular IOR Level"}}
# What the base sets itself rather than take from the group.
BASE_SET_INPUTS = {"Base Color", "Metallic", "Specular IOR Level", "Alpha"}
# Principled inputs at the value that leaves a closure out of EEVEE's shader (Metallic 1: the
# diffuse, subsurface and refraction; coat, sheen, subsurface, transmission 0; Alpha 1: the
# transparency). EEVEE (Legacy and Next) reads the value only of an unlinked socket and compiles
# every closure a linked one may turn on, so a whole-copy lobe linked to the group's inputs cost
# what a plain Principled with all of them on costs: in 3.4's EEVEE Legacy the metal demo at 4
# lobes took 2.2x a plain frame, 1.6-1.8x with these unlinked, the image the same to the bit
# (docs/speed.md, "EEVEE Legacy"). Cycles folds such constants itself. Principled v1's names and
# v2's (4.0+) side by side: a Principled has one of each.
CLOSURE_OFF_VALUES = {"Metallic": 1.0, "Alpha": 1.0, "Clearcoat": 0.0, "Coat Weight": 0.0, "Sheen": 0.0,
                      "Sheen Weight": 0.0, "Subsurface": 0.0, "Subsurface Weight": 0.0, "Transmission": 0.0,
                      "Transmission Weight": 0.0}


def emission_inputs():
    """Principled inputs the group draws once, beside the lobes, rather than in every lobe
    (emission): the emission colour (blender_compat.principled_input) and strength."""
    return {blender_compat.principled_input("Emission"), "Emission Strength"}


def carried_inputs(principled, current=None):
    """Principled inputs passed through the group: every enabled input except Normal; the
    implicit-default vectors (Clearcoat Normal, Tangent) only when linked (not muted: a muted link
    renders as that default), since a group input cannot reproduce their "use the geometry"
    default. `current`: see held_input."""
    carried = []
    for socket in principled.inputs:
        if not socket.enabled or socket.name == "Normal":
            continue
        if socket.hide_value and material_scan.live_link(held_input(socket, current, socket.name)) is None:
            continue
        carried.append(socket)
    return carried


def closure_off_inputs(holder):
    """{input name: value} of the CLOSURE_OFF_VALUES that `holder` (the Principled, or the group
    node of the bake a re-bake replaces) holds at that value with nothing to change it (no live
    link, no animation): a whole-copy lobe takes these as constants, not from the group's inputs.
    Like the specular split (specular_split.lobe_kind), read when the group is built: a coat or a
    transmission set on the group node after the bake shows once the material is baked again."""
    return {name: value for name, value in CLOSURE_OFF_VALUES.items()
            if material_scan.constant_input(holder, name) == value}


def held_input(socket, current, name):
    """The socket that holds `socket` (a Principled input, or the Normal Map's Strength) as the
    user edits it now: `current`'s input `name` where `current`, the group node of the bake a
    re-bake replaces, has one; else `socket` itself."""
    if current is not None and name in current.inputs:
        return current.inputs[name]
    return socket


def normal_map_node(tree, gin, normal_map, color, location):
    """A tangent-space Normal Map node like the original's (UV map, the group's Normal Strength) of
    `color`; returns its Normal output."""
    nm = tree.nodes.new("ShaderNodeNormalMap")
    nm.space = "TANGENT"
    nm.uv_map = normal_map.uv_map
    nm.location = location
    tree.links.new(color, nm.inputs["Color"])
    tree.links.new(gin.outputs["Normal Strength"], nm.inputs["Strength"])
    return nm.outputs["Normal"]


def base_bsdfs(tree, gin, principled, carried, normal_map, moments, names, outputs, location):
    """The Principled BSDFs that draw the material's diffuse (and subsurface) beneath the lobes
    (specular_split), one per group output in `outputs` ({output: the specular split's diffuse it
    takes}), each darkened as its engine darkens a Principled's diffuse under its specular
    (Cycles' for BSDF, EEVEE Next's for EEVEE BSDF): at the
    texel's mean normal, normalize(Σ_j α_j·r_j + 1e-5·ẑ) (+Z where the moments cancel), the original
    roughness, no specular of their own, opaque (the group mixes the Alpha in once: _alpha_over).
    Returns {output: its base's BSDF}."""
    total = moments[0]
    for k, moment in enumerate(moments[1:], 1):
        total = _vmath(tree, "ADD", total, moment, location=(location[0] - 1200 + 100 * k, location[1] + 300))
    mean = _vmath(tree, "NORMALIZE", _vmath(tree, "ADD", total, (0.0, 0.0, 1e-5), location=(location[0] - 600,
                                                                                             location[1] + 300)),
                  location=(location[0] - 450, location[1] + 300))
    color = _vmath(tree, "MULTIPLY_ADD", mean, (0.5, 0.5, 0.5), (0.5, 0.5, 0.5),
                   location=(location[0] - 300, location[1] + 300))
    normal = normal_map_node(tree, gin, normal_map, color, (location[0] - 150, location[1] + 300))
    split = tree.nodes.new("ShaderNodeGroup")
    split.node_tree = specular_split.specular_split_group()
    split.name = split.label = SPECULAR_SPLIT
    split.location = (location[0] - 150, location[1] - 300)
    for key in specular_split.SPLIT_INPUTS:
        if key in names:
            tree.links.new(gin.outputs[key], split.inputs[key])
    tree.links.new(normal, split.inputs["Normal"])
    split.inputs["Multiscatter"].default_value = specular_split.multiscatter(principled)

    bases = {}
    skipped = COMPUTED_INPUTS | emission_inputs() | BASE_SET_INPUTS
    for k, (output, diffuse) in enumerate(outputs.items()):
        bsdf = tree.nodes.new("ShaderNodeBsdfPrincipled")
        bsdf.name = bsdf.label = "%s %s" % (BASE_BSDF, output)
        bsdf.distribution = principled.distribution
        bsdf.subsurface_method = principled.subsurface_method
        bsdf.location = (location[0], location[1] + 700 * k)
        for socket in carried:
            if socket.name in skipped:
                continue
            tree.links.new(gin.outputs[socket.name], bsdf.inputs[socket.identifier])
        tree.links.new(split.outputs[diffuse], bsdf.inputs["Base Color"])
        bsdf.inputs["Metallic"].default_value = 0.0
        bsdf.inputs["Specular IOR Level"].default_value = 0.0
        bsdf.inputs["Emission Strength"].default_value = 0.0
        tree.links.new(normal, bsdf.inputs["Normal"])
        if "Roughness" in gin.outputs:
            tree.links.new(gin.outputs["Roughness"], bsdf.inputs["Roughness"])
        bases[output] = bsdf.outputs["BSDF"]
    return bases


def emission(tree, gin, location):
    """The Principled's emission, drawn once: an Emission shader of the carried Color and
    Strength, weighted by the carried Alpha (a Principled mixes a Transparent BSDF over all it
    draws, its emission too). Every lobe drawing α_j of it would sum to the same light, but in
    Cycles each lobe's Principled then grows its own emission branch, which costs about 32
    floats of the 255-float shader stack per lobe where Emission is linked (measured with
    Cycles' --debug-cycles summary: 134 at 4 lobes, 230 at 7; 8 overflowed, drawing the
    material black). The Principled always has the emission colour (blender_compat's name), Emission
    Strength and Alpha, and carried_inputs always carries them."""
    node = tree.nodes.new("ShaderNodeEmission")
    node.name = node.label = "Emission"
    node.location = location
    tree.links.new(gin.outputs[blender_compat.principled_input("Emission")], node.inputs["Color"])
    tree.links.new(gin.outputs["Emission Strength"], node.inputs["Strength"])
    alpha = tree.nodes.new("ShaderNodeMixShader")
    alpha.name = alpha.label = EMISSION_ALPHA
    alpha.location = (location[0] + 200, location[1])
    tree.links.new(gin.outputs["Alpha"], alpha.inputs["Fac"])
    tree.links.new(node.outputs["Emission"], alpha.inputs[2])
    return alpha.outputs["Shader"]


def lobe_bsdf(tree, gin, principled, carried, roughness, normal, name, location, multiscatter, kind=None,
               constants=None):
    """Lobe j's shader: a copy of the original Principled BSDF with the lobe's normal and roughness,
    emitting nothing (the group draws the emission once: emission), taking `constants` (input name:
    value, closure_off_inputs) as values rather than from the group; with a specular_split kind,
    only its specular reflection: the metal's (CONDUCTOR), the dielectric layer's over black
    (DIELECTRIC), or both mixed by Metallic (BOTH)."""
    if kind == specular_split.BOTH:
        mix = tree.nodes.new("ShaderNodeMixShader")
        mix.name = mix.label = name + " Metallic"
        mix.location = (location[0] + 200, location[1])
        tree.links.new(gin.outputs["Metallic"], mix.inputs["Fac"])
        for slot, part in ((1, specular_split.DIELECTRIC), (2, specular_split.CONDUCTOR)):
            tree.links.new(lobe_bsdf(tree, gin, principled, carried, roughness, normal,
                                      name if part == specular_split.CONDUCTOR else name + " Dielectric",
                                      (location[0], location[1] - 300 * (slot - 1)), multiscatter, part),
                           mix.inputs[slot])
        return mix.outputs["Shader"]
    bsdf = tree.nodes.new("ShaderNodeBsdfPrincipled")
    bsdf.name = bsdf.label = name
    # Multiple scattering: a widened GGX lobe loses the energy of light scattered more than
    # once between its microfacets, which the fine normals it stands for, each as narrow as
    # the original, hardly lose (white furnace, roughness 0.15: 0.81-0.86 of the reference
    # with GGX lobes, 0.88-0.98 with Multiscatter GGX). Same as GGX for narrow lobes. Not where
    # the material transmits (build_material_group).
    bsdf.distribution = "MULTI_GGX" if multiscatter else principled.distribution
    bsdf.subsurface_method = principled.subsurface_method
    bsdf.location = location
    skipped = COMPUTED_INPUTS | emission_inputs()
    for socket in carried:
        if socket.name in skipped:
            continue
        if kind is not None and socket.name not in SPECULAR_LOBE_INPUTS[kind]:
            continue
        if constants and socket.name in constants:
            bsdf.inputs[socket.identifier].default_value = constants[socket.name]
            continue
        tree.links.new(gin.outputs[socket.name], bsdf.inputs[socket.identifier])
    if kind == specular_split.CONDUCTOR:
        bsdf.inputs["Metallic"].default_value = 1.0
    elif kind == specular_split.DIELECTRIC:
        bsdf.inputs["Metallic"].default_value = 0.0
        bsdf.inputs["Base Color"].default_value = (0.0, 0.0, 0.0, 1.0)  # no diffuse: the base draws it
    bsdf.inputs["Emission Strength"].default_value = 0.0  # the group emits once (emission)
    tree.links.new(roughness, bsdf.inputs["Roughness"])
    tree.links.new(normal, bsdf.inputs["Normal"])
    return bsdf.outputs["BSDF"]


def transmits(node):
    """Whether the transmission of a Principled BSDF (or of the group node that holds its inputs
    since a bake) may matter: Transmission or Transmission Roughness linked (live), animated or
    non-zero. Read when the group is built: a transmission set on the group node after the bake
    shows once the material is baked again."""
    # Principled v2 (Blender 4.0+) has no Transmission Roughness: transmission takes Roughness.
    names = (blender_compat.principled_input(name) for name in ("Transmission", "Transmission Roughness"))
    return any(material_scan.input_may_matter(node, name) for name in names if name)
