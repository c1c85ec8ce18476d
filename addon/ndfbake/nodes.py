"""Shader node groups that shade a normal-mapped Principled BSDF through its fitted vMF lobes,
with stock nodes only, in EEVEE and Cycles alike.

Lobe textures hold R = α_j and GBA = α_j·r_j in tangent space, with |r_j| = R_j the resultant
length whose κ_j = (3R − R³)/(1 − R²). The encoding is linear: averaging texels averages
distributions. Two ways to get the texel a pixel needs:
- level of detail from the scene (AtlasLayout + scene_lod.LodPlan, the default): lobe j's MIP atlas
  (`atlas_lobej.exr`, every fitted level framed in one image) is sampled at the level the
  "NDFB Level of Detail" group computes from the view distance and angle (scene_lod.py), with one
  Linear lookup in each of the two levels around it ("NDFB Atlas UV" places it inside the
  level's frame), blended. Both engines; Cycles has no MIP levels.
- level 0 filtered by the renderer (`level00_lobej.exr`, Linear): EEVEE MIP-maps it itself;
  Cycles only averages its samples over the pixel.
Per shading point and lobe ("NDFB vMF Lobe" group):

    α_j   = R                                   (mixture weight)
    r_j   = (G, B, A) / max(α_j, 1e-6)
    R_j   = min(|r_j|, 1)                       (= 1: one direction, 1/κ = 0)
    μ_j   = normalize(r_j + 1e-5·ẑ)             (tangent space; +Z when R_j → 0)
    1/κ_j = max((1 − R²) / max(R(3 − R²), 1e-6) − 4e-4, 0)
            (no division by zero as R → 0: a uniform lobe; 4e-4 = HALF_INV_KAPPA_RESOLUTION, how
            far half-float storage may move 1/κ of a single direction off 0)
    a     = roughness²                          (Blender's GGX α)
    a'    = sqrt(min(a² + 1.5/κ_j, 1))          (brdf.h: kGgxVmfWidening = 1.5, α' ≤ 1)
    roughness'_j = sqrt(a')

μ_j goes to a tangent-space Normal Map node (same UV map and Strength as the original one) as the
colour μ·0.5 + 0.5, so the tangent frame is Blender's own in both engines. Lobe j is a copy of the
original Principled BSDF with that normal and roughness'_j, every other input as the original's
but the emission, which the group draws once (_emission).
The library's rule also has an amplitude ∫D_α / ∫D_α' (brdf.h: it keeps the NDF's mass over the
sphere, which is what its error measure compares); the shader leaves it out: every fine normal's
BSDF is normalized about its own normal, and so must the lobe that stands for them be. Measured in
a white furnace (Cycles, bumps map, roughness 0.15, view from above): 0.885 of the reference with
the amplitude, 1.002 without (tests/blender/test_addon_render.py checks the furnace). The lobes
use Multiscatter GGX where the original uses GGX and does not transmit (see _lobe_bsdf). Lobes
are summed with weights α_j (each a Mix Shader of factor α_j, then Add Shader nodes; see
_weighted_sum for why not a chain of mixes). Every other Principled input (linked or not) is
carried over through the group's inputs; the emission is drawn once beside the lobes
(_emission). A material whose fit needs one lobe gets a one-lobe group (nothing to sum): the
group is built for the lobe slots the bake wrote.

The group has two shader outputs: BSDF, the lobes above (Cycles, and both engines where the
material's graph is the user's), and EEVEE BSDF, the same lobes narrowed toward grazing views
(grazing_roughness_group), which EEVEE draws through a Material Output of target EEVEE that the
bake adds beside the user's (add_eevee_output) and Revert removes. With cycles_lobes NARROWED
the group is built with the narrowed lobes only and both outputs draw them: closer to the
filtered reference in a converged Cycles render, noisier at low sample counts where a small
bright light (an HDR's sun) glints in them (README, "Open problems": image error in Cycles).

OSL: where Cycles runs OSL on the CPU, a bake may draw Cycles' lobes through one Script node
instead (osl_group.py); `osl_status()` says where. The stock-node group works in both engines.
"""
from dataclasses import dataclass, field

import bpy

from . import blender_compat, id_names, material_scan, node_animation, scene_lod, specular_split
from .node_builders import (COLOR, FLOAT, GROUP_VERSION, TAG, VECTOR, _add_socket, _find_group, _group_with_io,
                            _link, _math, _mix, _new_group, _vmath)

LOBE_GROUP = "NDFB vMF Lobe v%d" % GROUP_VERSION
GRAZING_GROUP = "NDFB Grazing Roughness v%d" % GROUP_VERSION
LOD_GROUP = "NDFB Level of Detail v%d" % GROUP_VERSION
ATLAS_UV_GROUP = "NDFB Atlas UV v%d" % GROUP_VERSION
# Shared groups of earlier versions of this add-on (version 2), removed with the last bake using them.
RETIRED_GROUPS = tuple("NDFB %s v2" % name for name in ("vMF Lobe", "Grazing Roughness", "Level of Detail",
                                                         "Atlas Taps", "Bilinear"))
LOD_INPUTS = ("Texels per Unit", "Pixel Angle", "Pixel Size")
EEVEE_BSDF = "EEVEE BSDF"             # the group's second shader output (narrowed lobes)
# BakeSettings.cycles_lobes: what the group's BSDF output (Cycles' view) draws.
WIDENED, NARROWED = "WIDENED", "NARROWED"
ATLAS_LOOKUP = "Atlas Level %d"       # the material group's atlas-table nodes (0: low, 1: high level)
# An atlas table's name until bake._take_names names it after its group (atlas_table_name); no
# "NDFB " name, so that it holds no name a group or table of the bake is to take.
PROVISIONAL_TABLE_NAME = "ndfbake atlas table"
GGX_VMF_WIDENING = 1.5                # native/src/math/brdf.h kGgxVmfWidening
HALF_INV_KAPPA_RESOLUTION = 4e-4      # native/src/io/lobe_exr.h kHalfInvKappaResolution (the add-on
                                      # writes half floats)
# cos θ is floored here (θ ≈ 89.9°) so that tan²θ stays finite where a lobe faces away.
GRAZING_MIN_COSINE = 1e-3
EEVEE_OUTPUT = "ndfbake EEVEE Output"   # the Material Output (target EEVEE) a bake may add
GROUP_NODE_OFFSET = 250               # the group node sits this far above its Principled BSDF
# The Principled BSDF's settings that are no sockets: kept in the bake record, for Revert to make
# a deleted Principled again.
PRINCIPLED_SETTINGS = ("distribution", "subsurface_method")

# Principled inputs the lobe group computes itself rather than passing through.
COMPUTED_INPUTS = {"Normal", "Roughness"}
# Principled inputs the group draws once, beside the lobes, rather than in every lobe (_emission).
EMISSION_COLOR = blender_compat.principled_input("Emission")
EMISSION_INPUTS = {EMISSION_COLOR, "Emission Strength"}
EMISSION_ALPHA = "Emission Alpha"    # the group's Mix Shader that weights the emission by Alpha
# The specular split (specular_split.py): its node, the base BSDF and the Mix Shader weighting it by Alpha.
SPECULAR_SPLIT, BASE_BSDF, BASE_ALPHA = "Specular Split", "Base BSDF", "Base Alpha"
# What a specular-only lobe takes from the group, by kind; the rest of its Principled stays at the
# default (coat, sheen, subsurface and transmission off).
_SHARED_LOBE_INPUTS = {"Alpha", "Anisotropic", "Anisotropic Rotation", "Tangent", "Specular Tint"}
SPECULAR_LOBE_INPUTS = {specular_split.CONDUCTOR: _SHARED_LOBE_INPUTS | {"Base Color"},
                        specular_split.DIELECTRIC: _SHARED_LOBE_INPUTS | {"IOR", "Specular IOR Level"}}
# What the base sets itself rather than take from the group.
BASE_SET_INPUTS = {"Base Color", "Metallic", "Specular IOR Level", "Alpha"}


def osl_status(scene=None):
    """(available, message) for the OSL Script variant of the group (osl_group.py): in this build,
    or with `scene` also with its Cycles settings."""
    from . import osl_group  # imports this module
    return osl_group.status(scene) if scene is not None else osl_group.build_status()


# ---- shared helper groups ------------------------------------------------------------------------

def lobe_group():
    """Decodes one lobe texel: inputs Lobe (RGB), Lobe Z (A), Roughness; outputs Weight, Normal
    (tangent-space colour for a Normal Map node), Roughness (widened) and Moment (α_j·r_j: the
    lobes' moments sum to the texel's mean normal times its length)."""
    tree = _find_group(LOBE_GROUP)
    if tree is not None:
        return tree
    tree, gin, gout = _group_with_io(
        LOBE_GROUP, [(COLOR, "Lobe"), (FLOAT, "Lobe Z"), ("NodeSocketFloatFactor", "Roughness")],
        [(FLOAT, "Weight"), (COLOR, "Normal"), (FLOAT, "Roughness"), (VECTOR, "Moment")], (-1400, 1300))

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
    big_r = _math(tree, "MINIMUM", length, 1.0, location=(-400, 250))
    mu = _vmath(tree, "NORMALIZE", _vmath(tree, "ADD", r, (0.0, 0.0, 1e-5), location=(-550, -100)),
                location=(-400, -100))
    color = _vmath(tree, "MULTIPLY_ADD", mu, (0.5, 0.5, 0.5), (0.5, 0.5, 0.5), location=(-250, -100))

    r2 = _math(tree, "MULTIPLY", big_r, big_r, location=(-250, 250))
    numerator = _math(tree, "SUBTRACT", 1.0, r2, location=(-100, 350))
    denominator = _math(tree, "MAXIMUM", _math(tree, "MULTIPLY", big_r, _math(tree, "SUBTRACT", 3.0, r2,
                                                                               location=(-100, 200)),
                                               location=(50, 200)), 1e-6, location=(200, 200))
    inv_kappa = _math(tree, "MAXIMUM", _math(tree, "SUBTRACT", _math(tree, "DIVIDE", numerator, denominator,
                                                                      location=(350, 300)),
                                             HALF_INV_KAPPA_RESOLUTION, location=(350, 450)), 0.0,
                      location=(350, 600))

    rough = gin.outputs["Roughness"]
    alpha = _math(tree, "MULTIPLY", rough, rough, location=(-1000, -300))
    alpha2 = _math(tree, "MULTIPLY", alpha, alpha, location=(-850, -300))
    widened2 = _math(tree, "MINIMUM", _math(tree, "MULTIPLY_ADD", inv_kappa, GGX_VMF_WIDENING, alpha2,
                                            location=(500, 300)), 1.0, location=(650, 300))
    roughness_out = _math(tree, "SQRT", _math(tree, "SQRT", widened2, location=(800, 300)), location=(950, 300))
    tree.links.new(weight, gout.inputs["Weight"])
    tree.links.new(color, gout.inputs["Normal"])
    tree.links.new(roughness_out, gout.inputs["Roughness"])
    tree.links.new(comb.outputs[0], gout.inputs["Moment"])
    return tree


def grazing_roughness_group():
    """EEVEE's roughness for a widened lobe: inputs Roughness (widened, α′ = Roughness²), Base
    Roughness (the original's, α) and Normal (the lobe's, world space); output Roughness with

        α″² = max(α′² / (1 + α′² tan²θ), α²),   θ between the view and the lobe's normal.

    Why: a widened GGX lobe loses far more of its light at grazing views in EEVEE than the fine
    normals' narrow lobes do (the far ground of the demo scene under sunset rendered 25% darker
    than its supersampled reference). The narrowing grows with α′ tan θ, the quantity GGX's
    masking grows with, and stops at the original roughness; for α′ tan θ ≫ 1, α″ → 1/tan θ,
    which keeps the lobe's facets out of the foreshortening a microfacet lobe applies at grazing
    views and a normal map does not (README, Open problems: bias at grazing views). Measured
    (EEVEE block error against the supersampled reference, ratio to the naive map's; far ground /
    far spheres; sunset, 4 lobes; demo 320×180 and test 128×72): no narrowing 1.11 / 0.49 and
    1.18 / 0.31; α′²(1 + α′² tan²θ)^(−p) with p = 1/3 0.40 / 0.48 and 0.55 / 0.34, p = 1/2
    0.31 / 0.47 and 0.40 / 0.34, p = 1 (this) 0.25 / 0.44 and 0.29 / 0.33, with the far ground's
    mean luminance 2.11 against the reference's 2.16 (p = 2 overshoots it: 2.21). Cycles draws the
    widened lobes unless the bake's cycles_lobes is NARROWED: there narrowed sun glints at grazing
    views come out as fireflies at 16 samples per pixel, though converged they are closer (README,
    open problems)."""
    tree = _find_group(GRAZING_GROUP)
    if tree is not None:
        return tree
    tree, gin, gout = _group_with_io(
        GRAZING_GROUP, [("NodeSocketFloatFactor", "Roughness"), ("NodeSocketFloatFactor", "Base Roughness"),
                        (VECTOR, "Normal")], [(FLOAT, "Roughness")], (-1000, 900))
    geometry = tree.nodes.new("ShaderNodeNewGeometry")
    geometry.location = (-1000, -300)
    cosine = _math(tree, "MAXIMUM", _vmath(tree, "DOT_PRODUCT", geometry.outputs["Incoming"], gin.outputs["Normal"],
                                           location=(-800, -300), output=1),
                   GRAZING_MIN_COSINE, location=(-650, -300))
    cos2 = _math(tree, "MULTIPLY", cosine, cosine, location=(-500, -300))
    tan2 = _math(tree, "DIVIDE", _math(tree, "SUBTRACT", 1.0, cos2, location=(-350, -200)), cos2,
                 location=(-200, -300))

    def alpha2(roughness, y):  # α² = roughness⁴
        r2 = _math(tree, "MULTIPLY", roughness, roughness, location=(-800, y))
        return _math(tree, "MULTIPLY", r2, r2, location=(-650, y))

    widened2 = alpha2(gin.outputs["Roughness"], 200)
    base2 = alpha2(gin.outputs["Base Roughness"], 0)
    stretch = _math(tree, "MULTIPLY_ADD", widened2, tan2, 1.0, location=(100, 100))
    narrowed2 = _math(tree, "MAXIMUM", _math(tree, "DIVIDE", widened2, stretch, location=(250, 150)), base2,
                      location=(400, 100))
    tree.links.new(_math(tree, "SQRT", _math(tree, "SQRT", narrowed2, location=(550, 100)), location=(700, 100)),
                   gout.inputs["Roughness"])
    return tree


def level_of_detail_group():
    """Level = clamp(log2(footprint), 0, Max Level) with the footprint of scene_lod.py, from the
    distance to the camera and the angle of view at the shading point."""
    tree = _find_group(LOD_GROUP)
    if tree is not None:
        return tree
    tree, gin, gout = _group_with_io(
        LOD_GROUP, [(FLOAT, name) for name in LOD_INPUTS + ("Max Level",)], [(FLOAT, "Level")])
    camera = tree.nodes.new("ShaderNodeCameraData")
    camera.location = (-900, 300)
    geometry = tree.nodes.new("ShaderNodeNewGeometry")
    geometry.location = (-900, -300)
    distance = camera.outputs["View Distance"]
    facing = _math(tree, "ABSOLUTE", _vmath(tree, "DOT_PRODUCT", geometry.outputs["Incoming"],
                                            geometry.outputs["True Normal"], location=(-700, -300), output=1),
                   location=(-550, -300))
    stretch = _math(tree, "POWER", _math(tree, "MAXIMUM", facing, scene_lod.MIN_FACING, location=(-400, -300)),
                    scene_lod.STRETCH, location=(-250, -300))
    world = _math(tree, "MULTIPLY_ADD", distance, gin.outputs["Pixel Angle"], gin.outputs["Pixel Size"],
                  location=(-550, 200))
    texels = _math(tree, "DIVIDE", _math(tree, "MULTIPLY", world, gin.outputs["Texels per Unit"],
                                         location=(-400, 200)), stretch, location=(-100, 100))
    level = _math(tree, "LOGARITHM", _math(tree, "MAXIMUM", texels, 1e-6, location=(50, 100)), 2.0,
                  location=(200, 100))
    level = _math(tree, "MINIMUM", _math(tree, "MAXIMUM", level, 0.0, location=(350, 100)),
                  gin.outputs["Max Level"], location=(500, 100))
    tree.links.new(level, gout.inputs["Level"])
    return tree


def atlas_uv_group():
    """Where one level of a MIP atlas (native bake/lobe_atlas.h; tests/native/test_lobe_atlas.cpp
    checks this addressing) puts a texture coordinate: inputs UV, the level's frame X, Y (top-left,
    rows counted from the top) and size W, H, the atlas size, and Repeat (1: the texture tiles, 0:
    it clamps); output the atlas coordinate

        u = (X + 1 + w_u·W) / Atlas Width,   v = (Atlas Height − 1 − Y − H + w_v·H) / Atlas Height,

    w the coordinate wrapped (fract) or clamped to [0, 1]. A renderer's bilinear (Linear) lookup there
    reads texel centres x + 0.5 of the level exactly as a lookup of the level's own file would, and
    the frame's one-texel border (the wrapped or clamped edge) keeps it inside the level."""
    tree = _find_group(ATLAS_UV_GROUP)
    if tree is not None:
        return tree
    tree, gin, gout = _group_with_io(
        ATLAS_UV_GROUP,
        [(VECTOR, "UV")] + [(FLOAT, n) for n in ("X", "Y", "W", "H", "Atlas Width", "Atlas Height", "Repeat")],
        [(VECTOR, "Atlas UV")], (-1000, 700))
    sep = tree.nodes.new("ShaderNodeSeparateXYZ")
    sep.location = (-800, 200)
    tree.links.new(gin.outputs["UV"], sep.inputs[0])

    def wrapped(value, y):
        clamped = _math(tree, "MINIMUM", _math(tree, "MAXIMUM", value, 0.0, location=(-650, y)), 1.0,
                        location=(-500, y))
        return _mix(tree, "FLOAT", gin.outputs["Repeat"], clamped, _math(tree, "FRACT", value, location=(-500, y - 100)),
                    (-350, y))

    column = _math(tree, "MULTIPLY_ADD", wrapped(sep.outputs["X"], 300), gin.outputs["W"],
                   _math(tree, "ADD", gin.outputs["X"], 1.0, location=(-350, 450)), location=(-150, 350))
    row_base = _math(tree, "SUBTRACT", _math(tree, "SUBTRACT", _math(
        tree, "SUBTRACT", gin.outputs["Atlas Height"], 1.0, location=(-500, -350)), gin.outputs["Y"],
        location=(-350, -350)), gin.outputs["H"], location=(-200, -350))
    row = _math(tree, "MULTIPLY_ADD", wrapped(sep.outputs["Y"], -100), gin.outputs["H"], row_base,
                location=(-50, -150))
    comb = tree.nodes.new("ShaderNodeCombineXYZ")
    comb.location = (300, 0)
    tree.links.new(_math(tree, "DIVIDE", column, gin.outputs["Atlas Width"], location=(100, 300)), comb.inputs["X"])
    tree.links.new(_math(tree, "DIVIDE", row, gin.outputs["Atlas Height"], location=(150, -150)), comb.inputs["Y"])
    tree.links.new(comb.outputs[0], gout.inputs["Atlas UV"])
    return tree


def material_group_name(material_name):
    """The name a bake gives a material's group: "NDFB <material>" (cut to fit, .001… where taken)."""
    return "NDFB " + material_name


def lobe_image_name(material_name, j):
    """(body, tail) of the name of the image of a material's lobe slot j (id_names): "<material> lobe j"."""
    return material_name, " lobe %d" % j


def atlas_table_name(group_name):
    """(body, tail) of the name of a group's atlas table (id_names): "<group> atlas", the group's
    ".NNN" kept before " atlas", its body cut to fit."""
    body, number = id_names.numbered(group_name)
    return body, number + " atlas"


def atlas_table(group_tree):
    """The atlas table (atlas_table_group) a material group looks its levels up in, or None (level
    0): found through the group's lookup nodes, not by name (the material's name may be long)."""
    lookup = group_tree.nodes.get(ATLAS_LOOKUP % 0)
    return lookup.node_tree if lookup is not None and lookup.bl_idname == "ShaderNodeGroup" else None


def atlas_table_group(name, atlas):
    """Level → the level's frame X, Y and size W, H in the atlas: a step sum over the levels,
    Σ_k [Level ≥ k]·(v_k − v_(k−1)), exact for integer levels."""
    keys = ("X", "Y", "W", "H")
    tree, gin, gout = _group_with_io(name, [(FLOAT, "Level")], [(FLOAT, key) for key in keys],
                                     (-400, 300 + 150 * len(atlas.levels)))
    totals = {key: 0.0 for key in keys}
    previous = {key: 0.0 for key in keys}
    for k, place in enumerate(atlas.levels):
        values = dict(zip(keys, (place["x"], place["y"], place["width"], place["height"])))
        reached = _math(tree, "GREATER_THAN", gin.outputs["Level"], k - 0.5, location=(-200 + 150 * k, 300))
        for i, key in enumerate(keys):
            step = float(values[key] - previous[key])
            if step != 0.0:
                totals[key] = _math(tree, "MULTIPLY_ADD", reached, step, totals[key],
                                    location=(-200 + 150 * k, 150 - 150 * i))
        previous = values
    for key in keys:
        _link(tree, totals[key], gout.inputs[key])
    return tree


# ---- the per-material group --------------------------------------------------------------------

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


def held_input(socket, current, name):
    """The socket that holds `socket` (a Principled input, or the Normal Map's Strength) as the
    user edits it now: `current`'s input `name` where `current`, the group node of the bake a
    re-bake replaces, has one; else `socket` itself."""
    if current is not None and name in current.inputs:
        return current.inputs[name]
    return socket


def _value(socket):
    value = socket.default_value
    return tuple(value) if hasattr(value, "__len__") else value


@dataclass
class AtlasLayout:
    """Where the levels sit in a lobe's MIP atlas (native write option `atlas`): report.json's
    "atlas"."""
    width: int
    height: int
    levels: list                 # per level {"x", "y", "width", "height"}




def _uv_source(tree, gin, has_vector, location):
    if has_vector:
        return gin.outputs["Vector"]
    coordinates = tree.nodes.new("ShaderNodeTexCoord")
    coordinates.location = location
    return coordinates.outputs["UV"]


def _atlas_levels(tree, gin, atlas, repeat, uv):
    """The two levels the footprint falls between: per level the atlas coordinate (atlas_uv_group),
    and the blend factor. Computed once for every lobe: the lobes' atlases share one layout."""
    lod = tree.nodes.new("ShaderNodeGroup")
    lod.node_tree = level_of_detail_group()
    lod.location = (-2000, 400)
    for key in LOD_INPUTS:
        tree.links.new(gin.outputs[key], lod.inputs[key])
    lod.inputs["Max Level"].default_value = float(len(atlas.levels) - 1)
    level = lod.outputs["Level"]
    low = _math(tree, "FLOOR", level, location=(-1850, 400))
    high = _math(tree, "MINIMUM", _math(tree, "ADD", low, 1.0, location=(-1700, 500)), float(len(atlas.levels) - 1),
                 location=(-1550, 500))
    blend = _math(tree, "SUBTRACT", level, low, location=(-1700, 300))
    table = atlas_table_group(PROVISIONAL_TABLE_NAME, atlas)  # Blender numbers it where taken
    coordinates = []
    for k, index in enumerate((low, high)):
        lookup = tree.nodes.new("ShaderNodeGroup")
        lookup.name = lookup.label = ATLAS_LOOKUP % k
        lookup.node_tree = table
        lookup.location = (-1550, 300 - 250 * k)
        tree.links.new(index, lookup.inputs["Level"])
        place = tree.nodes.new("ShaderNodeGroup")
        place.node_tree = atlas_uv_group()
        place.location = (-1350, 300 - 250 * k)
        tree.links.new(uv, place.inputs["UV"])
        for key in ("X", "Y", "W", "H"):
            tree.links.new(lookup.outputs[key], place.inputs[key])
        place.inputs["Atlas Width"].default_value = float(atlas.width)
        place.inputs["Atlas Height"].default_value = float(atlas.height)
        place.inputs["Repeat"].default_value = 1.0 if repeat else 0.0
        coordinates.append(place.outputs["Atlas UV"])
    return coordinates, blend


def _sample_atlas(tree, image, coordinates, blend, j, y):
    """Lobe j's RGBA at the shading point: the renderer's bilinear lookup in each of the two levels
    (one Linear lookup a level, at atlas_uv_group's coordinate), blended. Measured against four
    Closest lookups and bilinear weights in nodes (what this group did before): the same
    image in Cycles, whose Linear lookup is plain bilinear; see README for EEVEE, which MIP-maps
    Linear images."""
    colors, alphas = [], []
    for k, coordinate in enumerate(coordinates):
        tex = tree.nodes.new("ShaderNodeTexImage")
        tex.name = tex.label = "Lobe %d level %s" % (j, "low" if k == 0 else "high")
        tex.image = image
        tex.interpolation = "Linear"
        tex.extension = "EXTEND"  # the frames hold the wrap; never read past the atlas
        tex.location = (-1150, y - 200 * k)
        tree.links.new(coordinate, tex.inputs["Vector"])
        colors.append(tex.outputs["Color"])
        alphas.append(tex.outputs["Alpha"])
    return (_mix(tree, "VECTOR", blend, colors[0], colors[1], (-950, y)),
            _mix(tree, "FLOAT", blend, alphas[0], alphas[1], (-950, y - 150)))


def _sample_level0(tree, gin, image, image_texture, has_vector, j, y):
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
    return tex.outputs["Color"], tex.outputs["Alpha"]


def build_material_group(name, principled, normal_map, image_texture, lobe_images, atlas=None, lod=None,
                         current=None, cycles_lobes=WIDENED):
    """A group with the carried Principled inputs (+ Normal Strength, + Vector if the original
    texture's has a live (unmuted) link, + the level-of-detail constants with an atlas) and the
    BSDF and EEVEE BSDF outputs, shading through len(lobe_images) lobes: level-0 textures that
    the renderer filters itself (atlas None), or MIP atlases (AtlasLayout) sampled at the level
    of detail the scene gives (lod: a scene_lod.LodPlan, required with an atlas). BSDF draws the
    widened lobes, or with cycles_lobes NARROWED the narrowed ones EEVEE BSDF draws. For a
    re-bake, `current` is the group node of the bake it replaces, which holds the Principled's
    inputs (held_input)."""
    tree = _new_group(name)
    decode = lobe_group()
    carried = carried_inputs(principled, current)
    # Not where the material transmits: Blender's Principled BSDF with Multiscatter GGX has no
    # Transmission Roughness (Cycles' multiscatter glass takes Roughness), so rough glass would
    # turn sharp; the lobes keep the original GGX there.
    multiscatter = principled.distribution == "GGX" and not transmits(principled if current is None else current)
    for socket in carried:
        iface = _add_socket(tree, "INPUT", socket.bl_idname, socket.name)
        try:
            iface.default_value = _value(held_input(socket, current, socket.name))
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
        for key, value in zip(LOD_INPUTS, (lod.texels_per_unit, lod.pixel_angle, lod.pixel_size)):
            _add_socket(tree, "INPUT", "NodeSocketFloat", key).default_value = value
    _add_socket(tree, "OUTPUT", "NodeSocketShader", "BSDF")
    _add_socket(tree, "OUTPUT", "NodeSocketShader", EEVEE_BSDF)

    gin = tree.nodes.new("NodeGroupInput")
    gin.location = (-2300, 0)
    gout = tree.nodes.new("NodeGroupOutput")
    count = len(lobe_images)
    gout.location = (1400 + 200 * count, 0)
    names = {s.name for s in carried}
    if atlas is not None:
        uv = _uv_source(tree, gin, has_vector, (-2000, 100))
        coordinates, blend = _atlas_levels(tree, gin, atlas, image_texture.extension == "REPEAT", uv)

    holder = principled if current is None else current
    # Specular-only lobes over one base (specular_split), or whole copies (kind None).
    kind = specular_split.lobe_kind(holder) if specular_split.may_split(principled, holder) else None

    # The outputs whose lobe BSDFs the group builds: (y offset of a lobe's BSDF, y of the sum).
    layout = ({"BSDF": (0, -200)} if cycles_lobes == WIDENED else {}) | {EEVEE_BSDF: (-450, -500)}
    shaders, weights, moments = {output: [] for output in layout}, [], []
    for j, image in enumerate(lobe_images):
        y = -900 * j
        if atlas is not None:
            color, alpha = _sample_atlas(tree, image, coordinates, blend, j, y)
        else:
            color, alpha = _sample_level0(tree, gin, image, image_texture, has_vector, j, y)

        dec = tree.nodes.new("ShaderNodeGroup")
        dec.node_tree = decode
        dec.name = dec.label = "Decode %d" % j
        dec.location = (-800, y)
        tree.links.new(color, dec.inputs["Lobe"])
        tree.links.new(alpha, dec.inputs["Lobe Z"])
        if "Roughness" in names:
            tree.links.new(gin.outputs["Roughness"], dec.inputs["Roughness"])
        moments.append(dec.outputs["Moment"])

        nm = _normal_map(tree, gin, normal_map, dec.outputs["Normal"], (-550, y - 150))
        grazing = tree.nodes.new("ShaderNodeGroup")
        grazing.node_tree = grazing_roughness_group()
        grazing.name = grazing.label = "Grazing %d" % j
        grazing.location = (-300, y - 450)
        tree.links.new(dec.outputs["Roughness"], grazing.inputs["Roughness"])
        if "Roughness" in names:
            tree.links.new(gin.outputs["Roughness"], grazing.inputs["Base Roughness"])
        else:
            grazing.inputs["Base Roughness"].default_value = dec.inputs["Roughness"].default_value
        tree.links.new(nm, grazing.inputs["Normal"])

        roughness = {"BSDF": dec.outputs["Roughness"], EEVEE_BSDF: grazing.outputs["Roughness"]}
        for output, (dy, _) in layout.items():
            shaders[output].append(_lobe_bsdf(tree, gin, principled, carried, roughness[output], nm,
                                              "Lobe %d %s" % (j, output), (0, y + dy), multiscatter, kind))
        weights.append(dec.outputs["Weight"])

    x_end = 1000 + 200 * count
    drawn_once = [_emission(tree, gin, (x_end, -900))]
    if kind in (specular_split.DIELECTRIC, specular_split.BOTH):
        drawn_once.append(_base_bsdf(tree, gin, principled, carried, normal_map, moments, names, (x_end, 600)))
    sums = {}
    for output, lobes in shaders.items():
        total = _weighted_sum(tree, lobes, weights, layout[output][1])
        for k, shader in enumerate(drawn_once):
            add = tree.nodes.new("ShaderNodeAddShader")
            add.location = (x_end + 200 * (k + 1), layout[output][1])
            tree.links.new(total, add.inputs[0])
            tree.links.new(shader, add.inputs[1])
            total = add.outputs["Shader"]
        sums[output] = total
    tree.links.new(sums[EEVEE_BSDF], gout.inputs[EEVEE_BSDF])
    tree.links.new(sums.get("BSDF", sums[EEVEE_BSDF]), gout.inputs["BSDF"])  # NARROWED: EEVEE's lobes
    return tree


def _normal_map(tree, gin, normal_map, color, location):
    """A tangent-space Normal Map node like the original's (UV map, the group's Normal Strength) of
    `color`; returns its Normal output."""
    nm = tree.nodes.new("ShaderNodeNormalMap")
    nm.space = "TANGENT"
    nm.uv_map = normal_map.uv_map
    nm.location = location
    tree.links.new(color, nm.inputs["Color"])
    tree.links.new(gin.outputs["Normal Strength"], nm.inputs["Strength"])
    return nm.outputs["Normal"]


def _base_bsdf(tree, gin, principled, carried, normal_map, moments, names, location):
    """The one Principled BSDF that draws the material's diffuse (and subsurface) beneath the lobes
    (specular_split): at the texel's mean normal, normalize(Σ_j α_j·r_j + 1e-5·ẑ) (+Z where the
    moments cancel), the original roughness, no specular of its own; weighted by Alpha, whose
    transparent remainder the lobes draw (each carries the Alpha)."""
    total = moments[0]
    for k, moment in enumerate(moments[1:], 1):
        total = _vmath(tree, "ADD", total, moment, location=(location[0] - 1200 + 100 * k, location[1] + 300))
    mean = _vmath(tree, "NORMALIZE", _vmath(tree, "ADD", total, (0.0, 0.0, 1e-5), location=(location[0] - 600,
                                                                                             location[1] + 300)),
                  location=(location[0] - 450, location[1] + 300))
    color = _vmath(tree, "MULTIPLY_ADD", mean, (0.5, 0.5, 0.5), (0.5, 0.5, 0.5),
                   location=(location[0] - 300, location[1] + 300))
    normal = _normal_map(tree, gin, normal_map, color, (location[0] - 150, location[1] + 300))
    split = tree.nodes.new("ShaderNodeGroup")
    split.node_tree = specular_split.specular_split_group()
    split.name = split.label = SPECULAR_SPLIT
    split.location = (location[0] - 150, location[1] - 300)
    for key in specular_split.SPLIT_INPUTS:
        if key in names:
            tree.links.new(gin.outputs[key], split.inputs[key])
    tree.links.new(normal, split.inputs["Normal"])

    bsdf = tree.nodes.new("ShaderNodeBsdfPrincipled")
    bsdf.name = bsdf.label = BASE_BSDF
    bsdf.distribution = principled.distribution
    bsdf.subsurface_method = principled.subsurface_method
    bsdf.location = location
    for socket in carried:
        if socket.name in COMPUTED_INPUTS or socket.name in EMISSION_INPUTS or socket.name in BASE_SET_INPUTS:
            continue
        tree.links.new(gin.outputs[socket.name], bsdf.inputs[socket.identifier])
    tree.links.new(split.outputs["Diffuse Color"], bsdf.inputs["Base Color"])
    bsdf.inputs["Metallic"].default_value = 0.0
    bsdf.inputs["Specular IOR Level"].default_value = 0.0
    bsdf.inputs["Emission Strength"].default_value = 0.0
    tree.links.new(normal, bsdf.inputs["Normal"])
    if "Roughness" in gin.outputs:
        tree.links.new(gin.outputs["Roughness"], bsdf.inputs["Roughness"])
    weighted = tree.nodes.new("ShaderNodeMixShader")
    weighted.name = weighted.label = BASE_ALPHA
    weighted.location = (location[0] + 200, location[1])
    tree.links.new(gin.outputs["Alpha"], weighted.inputs["Fac"])
    tree.links.new(bsdf.outputs["BSDF"], weighted.inputs[2])
    return weighted.outputs["Shader"]


def _emission(tree, gin, location):
    """The Principled's emission, drawn once: an Emission shader of the carried Color and
    Strength, weighted by the carried Alpha (a Principled mixes a Transparent BSDF over all it
    draws, its emission too). Every lobe drawing α_j of it would sum to the same light, but in
    Cycles each lobe's Principled then grows its own emission branch, which costs about 32
    floats of the 255-float shader stack per lobe where Emission is linked (measured with
    Cycles' --debug-cycles summary: 134 at 4 lobes, 230 at 7; 8 overflowed, drawing the
    material black). The Principled always has the emission colour (EMISSION_COLOR), Emission
    Strength and Alpha, and carried_inputs always carries them."""
    node = tree.nodes.new("ShaderNodeEmission")
    node.name = node.label = "Emission"
    node.location = location
    tree.links.new(gin.outputs[EMISSION_COLOR], node.inputs["Color"])
    tree.links.new(gin.outputs["Emission Strength"], node.inputs["Strength"])
    alpha = tree.nodes.new("ShaderNodeMixShader")
    alpha.name = alpha.label = EMISSION_ALPHA
    alpha.location = (location[0] + 200, location[1])
    tree.links.new(gin.outputs["Alpha"], alpha.inputs["Fac"])
    tree.links.new(node.outputs["Emission"], alpha.inputs[2])
    return alpha.outputs["Shader"]


def _lobe_bsdf(tree, gin, principled, carried, roughness, normal, name, location, multiscatter, kind=None):
    """Lobe j's shader: a copy of the original Principled BSDF with the lobe's normal and roughness,
    emitting nothing (the group draws the emission once: _emission); with a specular_split kind,
    only its specular reflection: the metal's (CONDUCTOR), the dielectric layer's over black
    (DIELECTRIC), or both mixed by Metallic (BOTH)."""
    if kind == specular_split.BOTH:
        mix = tree.nodes.new("ShaderNodeMixShader")
        mix.name = mix.label = name + " Metallic"
        mix.location = (location[0] + 200, location[1])
        tree.links.new(gin.outputs["Metallic"], mix.inputs["Fac"])
        for slot, part in ((1, specular_split.DIELECTRIC), (2, specular_split.CONDUCTOR)):
            tree.links.new(_lobe_bsdf(tree, gin, principled, carried, roughness, normal,
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
    for socket in carried:
        if socket.name in COMPUTED_INPUTS or socket.name in EMISSION_INPUTS:
            continue
        if kind is not None and socket.name not in SPECULAR_LOBE_INPUTS[kind]:
            continue
        tree.links.new(gin.outputs[socket.name], bsdf.inputs[socket.identifier])
    if kind == specular_split.CONDUCTOR:
        bsdf.inputs["Metallic"].default_value = 1.0
    elif kind == specular_split.DIELECTRIC:
        bsdf.inputs["Metallic"].default_value = 0.0
        bsdf.inputs["Base Color"].default_value = (0.0, 0.0, 0.0, 1.0)  # no diffuse: the base draws it
    bsdf.inputs["Emission Strength"].default_value = 0.0  # the group emits once (_emission)
    tree.links.new(roughness, bsdf.inputs["Roughness"])
    tree.links.new(normal, bsdf.inputs["Normal"])
    return bsdf.outputs["BSDF"]


# Principled v2 (Blender 4.0+) has no Transmission Roughness: transmission takes Roughness.
TRANSMISSION_INPUTS = tuple(name for name in map(blender_compat.principled_input,
                                                  ("Transmission", "Transmission Roughness")) if name)


def transmits(node):
    """Whether the transmission of a Principled BSDF (or of the group node that holds its inputs
    since a bake) may matter: Transmission or Transmission Roughness linked (live), animated or
    non-zero. Read when the group is built: a transmission set on the group node after the bake
    shows once the material is baked again."""
    tree = node.id_data
    for name in TRANSMISSION_INPUTS:
        index = node.inputs.find(name)
        if index < 0:
            continue
        socket = node.inputs[index]
        if material_scan.live_link(socket) is not None or socket.default_value != 0.0 \
                or node_animation.input_animated(tree, node, index):
            return True
    return False


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


def drive_lod_inputs(node, scene, camera_object):
    """Drivers that keep the group node's Pixel Angle (perspective) or Pixel Size (orthographic)
    equal to scene_lod.camera_footprint's as the camera's lens, sensor (size and fit) or the render
    resolution (size, percentage, pixel aspect) change (a 50% preview, a focal-length animation). Simple expressions only: Blender evaluates
    them without Python, so they work in files whose scripts are not trusted. Panoramic cameras
    and the texel density (a property of the meshes) keep their baked values."""
    formula = scene_lod.footprint_driver(camera_object)
    if formula is None:
        return
    socket, expression, variables = formula
    driver = node.inputs[socket].driver_add("default_value").driver
    driver.type = "SCRIPTED"
    driver.expression = expression
    owners = {"CAMERA": camera_object.data, "SCENE": scene}
    for name, id_type, path in variables:
        var = driver.variables.new()
        var.name = name
        var.type = "SINGLE_PROP"
        var.targets[0].id_type = id_type
        var.targets[0].id = owners[id_type]
        var.targets[0].data_path = path


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
    if _value(target) != _value(source):
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


GROUP_NODE_NAME = "ndfbake"  # a bake's group node's name (made free: group_node_name)
# A re-bake's group node's name until the one it replaces goes (then it is named as a first bake's):
# a name no other node tree uses, since renaming a node renames the animation paths naming it in
# every ID.
REBAKE_NAME = "ndfbake re-bake"


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
    node (material_scan.recorded_targets finds it), or None. Returns a Replacement."""
    replacement = Replacement(node="", old=old.name, principled=principled.name, normal_map=normal_map.name,
                              roles={n.name: n.get(material_scan.ROLE_KEY) for n in (principled, normal_map)},
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
            marked[material_scan.ROLE_KEY] = role
        elif material_scan.ROLE_KEY in marked.keys():
            del marked[material_scan.ROLE_KEY]
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
    old_key = material_scan.role_key(old)
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
    material_scan.rekey_roles(material_tree, (new_key, old_key), node.name)
    # Rekeyed above where it carries old's role; a record older than roles found it by name alone.
    # "" where the bake added no EEVEE output, or it is gone or ambiguous (recorded_node).
    if replacement.eevee_output:
        nodes[replacement.eevee_output][material_scan.ROLE_KEY] = material_scan.node_role("eevee_output", node.name)
    return node


def add_eevee_output(material_tree, node, bypassed):
    """EEVEE draws the group's EEVEE BSDF (lobes narrowed at grazing views) through a Material
    Output of target EEVEE, which Blender prefers to a target-All output for EEVEE and its viewport;
    Cycles goes on drawing the All output, fed by the group's BSDF. Added only where that output is
    the Principled's one destination, it is the active one, and the material has no EEVEE output
    yet: elsewhere (shader mixes, outputs per engine the user made) the graph downstream is the
    user's, and both engines draw the group's BSDF. With cycles_lobes NARROWED both outputs draw
    the same lobes and this output changes nothing that EEVEE draws; it is added all the same, so
    that a bake's nodes and a re-bake that switches the setting stay one layout. Returns the new
    node's name, or ""; on an error, removes what it added."""
    nodes = material_tree.nodes
    if len(bypassed) != 1 or any(n.bl_idname == "ShaderNodeOutputMaterial" and n.target == "EEVEE" for n in nodes):
        return ""
    output = nodes.get(bypassed[0][0])
    if output is None or output.bl_idname != "ShaderNodeOutputMaterial" or output.target != "ALL" \
            or not output.is_active_output or bypassed[0][1] != "Surface":
        return ""
    eevee = nodes.new("ShaderNodeOutputMaterial")
    try:
        eevee.name = eevee.label = EEVEE_OUTPUT
        eevee[TAG] = GROUP_VERSION
        eevee[material_scan.ROLE_KEY] = material_scan.node_role("eevee_output", node.name)
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


def group_node_name(material_tree, node, keys=()):
    """The name a bake gives its group node `node`: GROUP_NODE_NAME, with .001, .002… where another
    node has that name or carries it as its role key (material_scan.role_key), other than the
    `keys` whose roles `node` takes over. The name becomes the key of the node's roles, which must
    be no other bake's: a group node the user renamed keeps the key it was made with, and its
    nodes are still in the tree when the new ones are named (a target a re-bake drops goes after
    commit_replacement); sharing the key, each would be found for the other (recorded_node) and
    rekeyed with it."""
    taken = {n.name: n for n in material_tree.nodes}
    taken.update((material_scan.role_key(n), None) for n in material_tree.nodes
                 if n != node and material_scan.role_key(n) not in keys)
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
        marked[material_scan.ROLE_KEY] = material_scan.node_role(role, node.name)
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
    (material_scan.recorded_node), renamed or not; a Principled deleted since the bake is made
    again (with `settings`, principled_settings(), and its Normal from the Normal Map node).
    Returns the group tree it used (or None)."""
    nodes = material_tree.nodes
    key = node_name

    def find(name, role):
        return material_scan.recorded_node(material_tree, name, material_scan.node_role(role, key))

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
    material_scan.clear_roles(material_tree, key)
    return group_tree


def lobe_count(group_tree):
    return len({n.image.name for n in group_tree.nodes if n.bl_idname == "ShaderNodeTexImage" and n.image})


def remove_unused_groups(names):
    """Removes the named node groups this add-on made once nothing uses them, then the groups they
    used (a material's atlas table, the shared helpers) if nothing else uses those either."""
    pending = list(dict.fromkeys(names)) + [LOBE_GROUP, GRAZING_GROUP, LOD_GROUP, ATLAS_UV_GROUP,
                                               specular_split.SPLIT_GROUP, *RETIRED_GROUPS]
    while pending:
        tree = bpy.data.node_groups.get(pending.pop(0))
        if tree is None or tree.get(TAG) is None or tree.users != 0:
            continue
        # Found through the nodes, not by name: a long material name cuts "<group> atlas" short.
        pending += [n.node_tree.name for n in tree.nodes if n.bl_idname == "ShaderNodeGroup" and n.node_tree]
        bpy.data.node_groups.remove(tree)