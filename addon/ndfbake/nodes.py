"""Shader node groups that shade a normal-mapped Principled BSDF through its fitted vMF lobes,
with stock nodes only, in EEVEE and Cycles alike.

Lobe texture j (level 0, `level00_lobej.exr`) holds R = α_j and GBA = α_j·r_j in tangent space,
with |r_j| = R_j the resultant length whose κ_j = (3R − R³)/(1 − R²). The encoding is linear, so
the texture filtering EEVEE does by itself (bilinear + MIP levels built from level 0) averages
distributions, which is what filtering needs; Cycles samples level 0 and averages over the pixel.
Per shading point and lobe ("NDFB vMF Lobe" group):

    α_j   = R                                   (mixture weight)
    r_j   = (G, B, A) / max(α_j, 1e-6)
    R_j   = min(|r_j|, 0.9999)
    μ_j   = normalize(r_j + 1e-5·ẑ)             (tangent space; +Z when R_j → 0)
    1/κ_j = (1 − R²) / max(R(3 − R²), 1e-6)     (no division by zero as R → 0: a uniform lobe)
    a     = roughness²                          (Blender's GGX α)
    a'    = sqrt(min(a² + 1.5/κ_j, 1))          (brdf.h: kGgxVmfWidening = 1.5, α' ≤ 1)
    roughness'_j = sqrt(a')
    amplitude_j  = I(a) / I(a'),  I(x) = 1 + x²·artanh(k)/k, k = sqrt(1 − x²), I(1) = 2
                   (artanh(k) is evaluated as ln((1 + k)/x), exact for k = sqrt(1 − x²) and stable
                   as x → 0; k is kept ≥ 1e-4 so that I → 2 as x → 1)

μ_j goes to a tangent-space Normal Map node (same UV map and Strength as the original one) as the
colour μ·0.5 + 0.5, so the tangent frame is Blender's own in both engines. Lobe j is a copy of the
original Principled BSDF with that normal, roughness'_j, and its specular scaled by amplitude_j:
Specular × amplitude (the dielectric F0) and Base Color × (1 + Metallic·(amplitude − 1)) (the
metallic F0; exact for pure metals and pure dielectrics, a blend in between). The diffuse part is
not scaled: a Lambert lobe keeps its shape under a narrow vMF lobe. Lobes are summed with weights
α_j by a chain of Mix Shader nodes, factor α_k / (α_0 + … + α_k), which also renormalizes the
weights where filtering leaves Σα ≠ 1. Every other Principled input (linked or not) is carried
over through the group's inputs. A material whose fit needs one lobe gets a one-lobe group (no
mix chain): the group is built for the lobe slots the bake wrote.

OSL: Debian's Blender is built without OSL (bpy.app.build_options.cycles_osl is False), so no OSL
Script variant is offered; `osl_status()` says so. The stock-node group works in both engines.
"""
import bpy

GROUP_VERSION = 1
TAG = "ndfbake"                       # ID/custom property marking what this add-on created
LOBE_GROUP = "NDFB vMF Lobe v%d" % GROUP_VERSION
INTEGRAL_GROUP = "NDFB GGX Sphere Integral v%d" % GROUP_VERSION
GGX_VMF_WIDENING = 1.5                # native/src/math/brdf.h kGgxVmfWidening
E = 2.718281828459045

# Principled inputs the lobe group computes itself rather than passing through.
COMPUTED_INPUTS = {"Normal", "Roughness", "Specular", "Base Color"}


def osl_status():
    """(available, message) for the OSL Script variant of the group."""
    if getattr(bpy.app.build_options, "cycles_osl", False):
        return True, "OSL is available in this Blender build, but ndfbake emits the stock-node group only"
    return False, "this Blender build has no OSL (bpy.app.build_options.cycles_osl is False): stock-node group"


# ---- small builders ------------------------------------------------------------------------------

def _new_group(name):
    tree = bpy.data.node_groups.new(name, "ShaderNodeTree")
    tree[TAG] = GROUP_VERSION
    return tree


def _add_socket(tree, in_out, socket_type, name):
    if hasattr(tree, "interface"):  # Blender 4.x
        return tree.interface.new_socket(name, in_out=in_out, socket_type=socket_type)
    return (tree.inputs if in_out == "INPUT" else tree.outputs).new(socket_type, name)


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


# ---- shared helper groups ------------------------------------------------------------------------

def sphere_integral_group():
    """I(x) = ∫ D_GGX(x) dω = 1 + x²·artanh(k)/k, k = √(1 − x²); I(1) = 2 (brdf.h ggx_sphere_integral)."""
    tree = _find_group(INTEGRAL_GROUP)
    if tree is not None:
        return tree
    tree = _new_group(INTEGRAL_GROUP)
    _add_socket(tree, "INPUT", "NodeSocketFloat", "Alpha")
    _add_socket(tree, "OUTPUT", "NodeSocketFloat", "Integral")
    gin = tree.nodes.new("NodeGroupInput")
    gin.location = (-900, 0)
    gout = tree.nodes.new("NodeGroupOutput")
    gout.location = (600, 0)
    x = _math(tree, "MAXIMUM", gin.outputs["Alpha"], 1e-4, location=(-700, 0))
    x2 = _math(tree, "MULTIPLY", x, x, location=(-550, 0))
    k = _math(tree, "SQRT", _math(tree, "SUBTRACT", 1.0, x2, location=(-400, -150)), location=(-250, -150))
    k = _math(tree, "MAXIMUM", k, 1e-4, location=(-100, -150))
    artanh = _math(tree, "LOGARITHM", _math(tree, "DIVIDE", _math(tree, "ADD", 1.0, k, location=(50, -150)), x,
                                            location=(200, -150)), E, location=(350, -150))
    ratio = _math(tree, "DIVIDE", artanh, k, location=(350, 50))
    tree.links.new(_math(tree, "MULTIPLY_ADD", x2, ratio, 1.0, location=(450, 0)), gout.inputs["Integral"])
    return tree


def lobe_group():
    """Decodes one lobe texel: inputs Lobe (RGB), Lobe Z (A), Roughness; outputs Weight, Normal
    (tangent-space colour for a Normal Map node), Roughness (widened) and Amplitude."""
    tree = _find_group(LOBE_GROUP)
    if tree is not None:
        return tree
    integral = sphere_integral_group()
    tree = _new_group(LOBE_GROUP)
    _add_socket(tree, "INPUT", "NodeSocketColor", "Lobe")
    _add_socket(tree, "INPUT", "NodeSocketFloat", "Lobe Z")
    _add_socket(tree, "INPUT", "NodeSocketFloatFactor", "Roughness")
    for name, kind in (("Weight", "NodeSocketFloat"), ("Normal", "NodeSocketColor"),
                       ("Roughness", "NodeSocketFloat"), ("Amplitude", "NodeSocketFloat")):
        _add_socket(tree, "OUTPUT", kind, name)
    gin = tree.nodes.new("NodeGroupInput")
    gin.location = (-1400, 0)
    gout = tree.nodes.new("NodeGroupOutput")
    gout.location = (1300, 0)

    sep = tree.nodes.new("ShaderNodeSeparateXYZ")  # colour -> (R, G, B)
    sep.location = (-1200, 100)
    tree.links.new(gin.outputs["Lobe"], sep.inputs[0])
    weight = sep.outputs["X"]
    comb = tree.nodes.new("ShaderNodeCombineXYZ")
    comb.location = (-1000, 0)
    tree.links.new(sep.outputs["Y"], comb.inputs["X"])
    tree.links.new(sep.outputs["Z"], comb.inputs["Y"])
    tree.links.new(gin.outputs["Lobe Z"], comb.inputs["Z"])

    inv_weight = _math(tree, "DIVIDE", 1.0, _math(tree, "MAXIMUM", weight, 1e-6, location=(-1000, 250)),
                       location=(-850, 250))
    r = _vmath(tree, "SCALE", comb.outputs[0], scale=inv_weight, location=(-700, 100))
    length = _vmath(tree, "LENGTH", r, location=(-550, 250), output=1)
    big_r = _math(tree, "MINIMUM", length, 0.9999, location=(-400, 250))
    mu = _vmath(tree, "NORMALIZE", _vmath(tree, "ADD", r, (0.0, 0.0, 1e-5), location=(-550, -100)),
                location=(-400, -100))
    color = _vmath(tree, "MULTIPLY_ADD", mu, (0.5, 0.5, 0.5), (0.5, 0.5, 0.5), location=(-250, -100))

    r2 = _math(tree, "MULTIPLY", big_r, big_r, location=(-250, 250))
    numerator = _math(tree, "SUBTRACT", 1.0, r2, location=(-100, 350))
    denominator = _math(tree, "MAXIMUM", _math(tree, "MULTIPLY", big_r, _math(tree, "SUBTRACT", 3.0, r2,
                                                                               location=(-100, 200)),
                                               location=(50, 200)), 1e-6, location=(200, 200))
    inv_kappa = _math(tree, "DIVIDE", numerator, denominator, location=(350, 300))

    rough = gin.outputs["Roughness"]
    alpha = _math(tree, "MULTIPLY", rough, rough, location=(-1000, -300))
    alpha2 = _math(tree, "MULTIPLY", alpha, alpha, location=(-850, -300))
    widened2 = _math(tree, "MINIMUM", _math(tree, "MULTIPLY_ADD", inv_kappa, GGX_VMF_WIDENING, alpha2,
                                            location=(500, 300)), 1.0, location=(650, 300))
    widened = _math(tree, "SQRT", widened2, location=(800, 300))
    roughness_out = _math(tree, "SQRT", widened, location=(950, 300))

    def integral_of(socket, location):
        node = tree.nodes.new("ShaderNodeGroup")
        node.node_tree = integral
        node.location = location
        tree.links.new(socket, node.inputs["Alpha"])
        return node.outputs["Integral"]

    amplitude = _math(tree, "DIVIDE", integral_of(alpha, (800, -300)), integral_of(widened, (950, 100)),
                      location=(1100, -100))
    tree.links.new(weight, gout.inputs["Weight"])
    tree.links.new(color, gout.inputs["Normal"])
    tree.links.new(roughness_out, gout.inputs["Roughness"])
    tree.links.new(amplitude, gout.inputs["Amplitude"])
    return tree


# ---- the per-material group --------------------------------------------------------------------

def carried_inputs(principled):
    """Principled inputs passed through the group: every enabled input except Normal; the
    implicit-default vectors (Clearcoat Normal, Tangent) only when linked, since a group input
    cannot reproduce their "use the geometry" default."""
    carried = []
    for socket in principled.inputs:
        if not socket.enabled or socket.name == "Normal":
            continue
        if socket.hide_value and not socket.is_linked:
            continue
        carried.append(socket)
    return carried


def _value(socket):
    value = socket.default_value
    return tuple(value) if hasattr(value, "__len__") else value


def build_material_group(name, principled, normal_map, image_texture, lobe_images):
    """A group with the carried Principled inputs (+ Normal Strength, + Vector if the original
    texture's was linked) and one BSDF output, shading through len(lobe_images) lobes."""
    tree = _new_group(name)
    decode = lobe_group()
    carried = carried_inputs(principled)
    for socket in carried:
        iface = _add_socket(tree, "INPUT", socket.bl_idname, socket.name)
        try:
            iface.default_value = _value(socket)
        except (AttributeError, TypeError):
            pass
    strength = _add_socket(tree, "INPUT", "NodeSocketFloat", "Normal Strength")
    strength.default_value = 1.0
    strength.min_value = 0.0
    has_vector = image_texture.inputs["Vector"].is_linked
    if has_vector:
        vector = _add_socket(tree, "INPUT", "NodeSocketVector", "Vector")
        vector.hide_value = True
    _add_socket(tree, "OUTPUT", "NodeSocketShader", "BSDF")

    gin = tree.nodes.new("NodeGroupInput")
    gin.location = (-1400, 0)
    gout = tree.nodes.new("NodeGroupOutput")
    count = len(lobe_images)
    gout.location = (1400 + 200 * count, 0)
    names = {s.name for s in carried}

    bsdfs, weights = [], []
    for j, image in enumerate(lobe_images):
        y = -900 * j
        tex = tree.nodes.new("ShaderNodeTexImage")
        tex.name = tex.label = "Lobe %d" % j
        tex.image = image
        # Linear, whatever the original uses: EEVEE filters (and MIP-maps) linear textures only,
        # and the filtered look is the point. Extension and projection follow the original.
        tex.interpolation = "Linear"
        tex.extension = image_texture.extension
        tex.projection = image_texture.projection
        tex.projection_blend = image_texture.projection_blend
        tex.location = (-1100, y)
        if has_vector:
            tree.links.new(gin.outputs["Vector"], tex.inputs["Vector"])

        dec = tree.nodes.new("ShaderNodeGroup")
        dec.node_tree = decode
        dec.name = dec.label = "Decode %d" % j
        dec.location = (-800, y)
        tree.links.new(tex.outputs["Color"], dec.inputs["Lobe"])
        tree.links.new(tex.outputs["Alpha"], dec.inputs["Lobe Z"])
        if "Roughness" in names:
            tree.links.new(gin.outputs["Roughness"], dec.inputs["Roughness"])

        nm = tree.nodes.new("ShaderNodeNormalMap")
        nm.space = "TANGENT"
        nm.uv_map = normal_map.uv_map
        nm.location = (-550, y - 150)
        tree.links.new(dec.outputs["Normal"], nm.inputs["Color"])
        tree.links.new(gin.outputs["Normal Strength"], nm.inputs["Strength"])

        amplitude = dec.outputs["Amplitude"]
        bsdf = tree.nodes.new("ShaderNodeBsdfPrincipled")
        bsdf.name = bsdf.label = "Lobe %d BSDF" % j
        bsdf.distribution = principled.distribution
        bsdf.subsurface_method = principled.subsurface_method
        bsdf.location = (0, y)
        for socket in carried:
            if socket.name in COMPUTED_INPUTS:
                continue
            tree.links.new(gin.outputs[socket.name], bsdf.inputs[socket.identifier])
        tree.links.new(dec.outputs["Roughness"], bsdf.inputs["Roughness"])
        tree.links.new(nm.outputs["Normal"], bsdf.inputs["Normal"])
        tree.links.new(_math(tree, "MULTIPLY", gin.outputs["Specular"], amplitude, location=(-300, y + 100)),
                       bsdf.inputs["Specular"])
        metal_scale = _math(tree, "MULTIPLY_ADD", _math(tree, "SUBTRACT", amplitude, 1.0, location=(-550, y + 250)),
                            gin.outputs["Metallic"], 1.0, location=(-400, y + 250))
        tree.links.new(_vmath(tree, "SCALE", gin.outputs["Base Color"], scale=metal_scale,
                              location=(-250, y + 250)), bsdf.inputs["Base Color"])
        bsdfs.append(bsdf.outputs["BSDF"])
        weights.append(dec.outputs["Weight"])

    # Σ_j α_j·BSDF_j / Σ_j α_j as a chain of mixes: factor α_k / (α_0 + … + α_k).
    shader, total = bsdfs[0], weights[0]
    for k in range(1, count):
        x = 400 + 200 * k
        total = _math(tree, "ADD", total, weights[k], location=(x, 300))
        mix = tree.nodes.new("ShaderNodeMixShader")
        mix.location = (x, -200)
        tree.links.new(_math(tree, "DIVIDE", weights[k], total, location=(x, 150)), mix.inputs["Fac"])
        tree.links.new(shader, mix.inputs[1])
        tree.links.new(bsdfs[k], mix.inputs[2])
        shader = mix.outputs["Shader"]
    tree.links.new(shader, gout.inputs["BSDF"])
    return tree


def insert_group_node(material_tree, group_tree, principled, normal_map, image_texture):
    """Adds the group node beside `principled`, feeds it the Principled's inputs, and bypasses the
    Principled BSDF: every link leaving its BSDF output now leaves the group's. Returns the node and
    the bypassed links as (to_node, to_socket identifier, muted) for revert."""
    node = material_tree.nodes.new("ShaderNodeGroup")
    bypassed = []
    try:
        return node, _wire_group_node(material_tree, node, group_tree, principled, normal_map, image_texture,
                                      bypassed)
    except Exception:
        remove_group_node(material_tree, node.name, principled.name, bypassed)
        raise


def _wire_group_node(material_tree, node, group_tree, principled, normal_map, image_texture, bypassed):
    links = material_tree.links
    node.node_tree = group_tree
    node.name = "ndfbake"
    node[TAG] = GROUP_VERSION
    node.label = "ndfbake: %d lobe%s" % (lobe_count(group_tree), "" if lobe_count(group_tree) == 1 else "s")
    node.location = (principled.location.x, principled.location.y + 250)
    node.width = max(node.width, 220)
    node.parent = principled.parent
    for socket in carried_inputs(principled):
        target = node.inputs[socket.name]
        if socket.is_linked:
            link = socket.links[0]
            new = links.new(link.from_socket, target)
            new.is_muted = link.is_muted
        else:
            target.default_value = _value(socket)
    strength = normal_map.inputs["Strength"]
    if strength.is_linked:
        links.new(strength.links[0].from_socket, node.inputs["Normal Strength"])
    else:
        node.inputs["Normal Strength"].default_value = strength.default_value
    if "Vector" in node.inputs:
        links.new(image_texture.inputs["Vector"].links[0].from_socket, node.inputs["Vector"])

    for link in list(principled.outputs["BSDF"].links):
        bypassed.append((link.to_node.name, link.to_socket.identifier, bool(link.is_muted)))
        to_socket = link.to_socket
        muted = link.is_muted
        links.remove(link)
        new = links.new(node.outputs["BSDF"], to_socket)
        new.is_muted = muted
    return bypassed


def _socket_by_identifier(sockets, identifier):
    for socket in sockets:
        if socket.identifier == identifier:
            return socket
    return None


def remove_group_node(material_tree, node_name, principled_name, bypassed):
    """Undoes insert_group_node: the bypassed links leave the Principled BSDF again, and the group
    node goes. Returns the group tree it used (or None)."""
    nodes = material_tree.nodes
    node = nodes.get(node_name)
    principled = nodes.get(principled_name)
    group_tree = node.node_tree if node is not None else None
    if node is not None and "BSDF" in node.outputs:
        for link in list(node.outputs["BSDF"].links):
            material_tree.links.remove(link)
    if principled is not None:
        for to_node_name, identifier, muted in bypassed:
            to_node = nodes.get(to_node_name)
            socket = _socket_by_identifier(to_node.inputs, identifier) if to_node is not None else None
            if socket is None:
                continue
            for link in list(socket.links):
                material_tree.links.remove(link)
            new = material_tree.links.new(principled.outputs["BSDF"], socket)
            new.is_muted = muted
    if node is not None:
        nodes.remove(node)
    return group_tree


def lobe_count(group_tree):
    return sum(1 for n in group_tree.nodes if n.bl_idname == "ShaderNodeTexImage")


def remove_unused_groups(names):
    """Removes the named node groups this add-on made once nothing uses them, then the shared
    helper groups if they are unused too."""
    for name in list(dict.fromkeys(names)) + [LOBE_GROUP, INTEGRAL_GROUP]:
        tree = bpy.data.node_groups.get(name)
        if tree is not None and tree.get(TAG) is not None and tree.users == 0:
            bpy.data.node_groups.remove(tree)
