"""Level of detail in shader nodes: which texel of which MIP level a pixel reads. Shared groups
("NDFB Level of Detail", "NDFB Atlas Taps", "NDFB Atlas Point", "NDFB Bilinear"), a material's
atlas table, the lookups a material's group makes, and the drivers that keep the footprint's
camera terms live. The footprint itself is scene_lod.py's; nodes.py calls these while it
assembles a group.

Two ways to get the texel a pixel needs:
- level of detail from the scene (AtlasLayout + scene_lod.LodPlan, the default): lobe j's MIP atlas
  (`atlas_lobej.exr`, every fitted level framed in one image) is sampled at the level the
  "NDFB Level of Detail" group computes from the view distance and angle (scene_lod.py), in each
  of the two levels around it, blended. Two ways to filter inside a level, the same texels:
  - four Closest lookups ("NDFB Atlas Taps") weighted in nodes ("NDFB Bilinear"), which both
    engines draw alike. EEVEE needs these: it MIP-maps Linear images by their screen derivatives,
    which jump where a tiled texture wraps (fract), so at every tile seam one Linear lookup read
    the atlas's coarsest levels, blends of unrelated frames: dark lines on the demo's ground, dots
    on its spheres (Blender 5.0, 2026-11-28).
  - one Linear lookup ("NDFB Atlas Point"), which the level's one-texel frame makes exact; for
    Cycles alone (no MIP levels of its own), where EEVEE draws an output of its own
    (nodes.build_material_group's cycles_only). Three lookups fewer a level, a lobe.
- level 0 filtered by the renderer (`level00_lobej.exr`, Linear): EEVEE MIP-maps it itself;
  Cycles only averages its samples over the pixel.
"""
from dataclasses import dataclass

from ..core import id_names
from . import scene_lod
from .node_builders import COLOR, FLOAT, GROUP_VERSION, VECTOR, _find_group, _group_with_io, _link, _math, _mix, _vmath

LOD_GROUP = "NDFB Level of Detail v%d" % GROUP_VERSION
TAPS_GROUP = "NDFB Atlas Taps v%d" % GROUP_VERSION
POINT_GROUP = "NDFB Atlas Point v%d" % GROUP_VERSION
BILINEAR_GROUP = "NDFB Bilinear v%d" % GROUP_VERSION
TAP_CORNERS = ("00", "10", "01", "11")  # x then y offset of a bilinear tap
LOD_INPUTS = ("Texels per Unit", "Pixel Angle", "Pixel Size")
ATLAS_LOOKUP = "Atlas Level %d"       # the material group's atlas-table nodes (0: low, 1: high level)
# An atlas table's name until bake._take_names names it after its group (atlas_table_name); no
# "NDFB " name, so that it holds no name a group or table of the bake is to take.
PROVISIONAL_TABLE_NAME = "ndfbake atlas table"


@dataclass
class AtlasLayout:
    """Where the levels sit in a lobe's MIP atlas (native write option `atlas`): report.json's
    "atlas"."""
    width: int
    height: int
    levels: list                 # per level {"x", "y", "width", "height"}


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


# Inputs of the groups that address one level of an atlas: the UV, the level's frame X, Y (top-left,
# rows counted from the top) and size W, H (atlas_table_group), the atlas size, and Repeat (1: the
# texture tiles, 0: it clamps).
LEVEL_ADDRESS_INPUTS = [(VECTOR, "UV")] + [(FLOAT, n) for n in ("X", "Y", "W", "H", "Atlas Width", "Atlas Height",
                                                                "Repeat")]


def _level_texel(tree, gin, value, size, y):
    """The position in texels, from the level's first texel, of texture coordinate `value` along
    an axis of `size` texels: wrapped into the level (fract) or clamped to it, as Repeat says."""
    wrapped = _mix(tree, "FLOAT", gin.outputs["Repeat"], _math(tree, "MINIMUM", _math(
        tree, "MAXIMUM", value, 0.0, location=(-850, y)), 1.0, location=(-700, y)),
        _math(tree, "FRACT", value, location=(-700, y - 100)), location=(-550, y))
    return _math(tree, "MULTIPLY", wrapped, size, location=(-400, y))


def _level_origin(tree, gin):
    """Where the level's texels start in the atlas, in texels from its left and bottom edges:
    column X + 1, row Atlas Height − 1 − Y − H (the frame's border is one texel)."""
    column = _math(tree, "ADD", gin.outputs["X"], 1.0, location=(-100, 400))
    row = _math(tree, "SUBTRACT", _math(tree, "SUBTRACT", _math(tree, "SUBTRACT", gin.outputs["Atlas Height"], 1.0,
                                                                location=(-250, -300)),
                                        gin.outputs["Y"], location=(-100, -300)),
                gin.outputs["H"], location=(50, -300))
    return column, row


def _atlas_uv(tree, column, row, gin, location):
    """The atlas UV of a position (column, row) in texels."""
    comb = tree.nodes.new("ShaderNodeCombineXYZ")
    comb.location = location
    tree.links.new(_math(tree, "DIVIDE", column, gin.outputs["Atlas Width"], location=(location[0] - 200, location[1])),
                   comb.inputs["X"])
    tree.links.new(_math(tree, "DIVIDE", row, gin.outputs["Atlas Height"],
                         location=(location[0] - 200, location[1] - 100)), comb.inputs["Y"])
    return comb.outputs[0]


def atlas_taps_group():
    """The four point lookups of bilinear filtering inside one level of a MIP atlas (native
    bake/lobe_atlas.h; tests/native/test_lobe_atlas.cpp checks this addressing): inputs
    LEVEL_ADDRESS_INPUTS; outputs the texel centres UV 00/10/01/11 and the fractions Fx, Fy."""
    tree = _find_group(TAPS_GROUP)
    if tree is not None:
        return tree
    tree, gin, gout = _group_with_io(
        TAPS_GROUP, LEVEL_ADDRESS_INPUTS,
        [(VECTOR, "UV " + c) for c in TAP_CORNERS] + [(FLOAT, "Fx"), (FLOAT, "Fy")], (-1200, 900))
    sep = tree.nodes.new("ShaderNodeSeparateXYZ")
    sep.location = (-1000, 200)
    tree.links.new(gin.outputs["UV"], sep.inputs[0])
    column, row = _level_origin(tree, gin)
    centres, fractions = [], []
    for axis, size, origin, y in (("X", "W", column, 300), ("Y", "H", row, -100)):
        # The texel whose centre is at or left of (below) the point, and the point's fraction past it.
        texel = _math(tree, "SUBTRACT", _level_texel(tree, gin, sep.outputs[axis], gin.outputs[size], y), 0.5,
                      location=(-300, y))
        first = _math(tree, "FLOOR", texel, location=(-200, y))
        fractions.append(_math(tree, "SUBTRACT", texel, first, location=(-100, y - 100)))
        low = _math(tree, "ADD", _math(tree, "ADD", origin, first, location=(150, y)), 0.5, location=(250, y))
        centres.append((low, _math(tree, "ADD", low, 1.0, location=(350, y - 100))))
    (u0, u1), (v0, v1) = centres
    for name, (u, v), y in (("UV 00", (u0, v0), 300), ("UV 10", (u1, v0), 150), ("UV 01", (u0, v1), 0),
                            ("UV 11", (u1, v1), -150)):
        tree.links.new(_atlas_uv(tree, u, v, gin, (700, y)), gout.inputs[name])
    tree.links.new(fractions[0], gout.inputs["Fx"])
    tree.links.new(fractions[1], gout.inputs["Fy"])
    return tree


def atlas_point_group():
    """The atlas UV of the point itself inside one level (inputs LEVEL_ADDRESS_INPUTS; output UV),
    for one Linear lookup: the level's one-texel frame holds the texels its wrap mode puts beside
    its edges, so the renderer's bilinear filtering there is the taps' (atlas_taps_group)."""
    tree = _find_group(POINT_GROUP)
    if tree is not None:
        return tree
    tree, gin, gout = _group_with_io(POINT_GROUP, LEVEL_ADDRESS_INPUTS, [(VECTOR, "UV")], (-1200, 600))
    sep = tree.nodes.new("ShaderNodeSeparateXYZ")
    sep.location = (-1000, 200)
    tree.links.new(gin.outputs["UV"], sep.inputs[0])
    column, row = _level_origin(tree, gin)
    u = _math(tree, "ADD", column, _level_texel(tree, gin, sep.outputs["X"], gin.outputs["W"], 300),
              location=(150, 300))
    v = _math(tree, "ADD", row, _level_texel(tree, gin, sep.outputs["Y"], gin.outputs["H"], -100),
              location=(150, -100))
    tree.links.new(_atlas_uv(tree, u, v, gin, (500, 0)), gout.inputs["UV"])
    return tree


def bilinear_group():
    """(1 − Fy)·((1 − Fx)·00 + Fx·10) + Fy·((1 − Fx)·01 + Fx·11) of four RGBA lookups."""
    tree = _find_group(BILINEAR_GROUP)
    if tree is not None:
        return tree
    tree, gin, gout = _group_with_io(
        BILINEAR_GROUP,
        [io for c in TAP_CORNERS for io in ((COLOR, "Color " + c), (FLOAT, "Alpha " + c))]
        + [(FLOAT, "Fx"), (FLOAT, "Fy")],
        [(COLOR, "Color"), (FLOAT, "Alpha")], (-600, 400))
    fx, fy = gin.outputs["Fx"], gin.outputs["Fy"]
    for kind, data_type, y in (("Color", "VECTOR", 200), ("Alpha", "FLOAT", -200)):
        bottom = _mix(tree, data_type, fx, gin.outputs[kind + " 00"], gin.outputs[kind + " 10"], (-300, y + 100))
        top = _mix(tree, data_type, fx, gin.outputs[kind + " 01"], gin.outputs[kind + " 11"], (-300, y - 100))
        tree.links.new(_mix(tree, data_type, fy, bottom, top, (0, y)), gout.inputs[kind])
    return tree


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


def uv_source(tree, gin, has_vector, location):
    if has_vector:
        return gin.outputs["Vector"]
    coordinates = tree.nodes.new("ShaderNodeTexCoord")
    coordinates.location = location
    return coordinates.outputs["UV"]


def atlas_levels(tree, gin, atlas):
    """The two levels the footprint falls between: per level (low, high) the atlas-table node
    whose outputs X, Y, W, H frame it, and the blend factor between them."""
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
    lookups = []
    for k, index in enumerate((low, high)):
        lookup = tree.nodes.new("ShaderNodeGroup")
        lookup.name = lookup.label = ATLAS_LOOKUP % k
        lookup.node_tree = table
        lookup.location = (-1550, 300 - 250 * k)
        tree.links.new(index, lookup.inputs["Level"])
        lookups.append(lookup)
    return lookups, blend


def address_levels(tree, group_tree, lookups, atlas, repeat, uv, y):
    """Per level (atlas_levels' lookups), a node of `group_tree` (atlas_taps_group or
    atlas_point_group) addressing `uv` in it."""
    nodes = []
    for k, lookup in enumerate(lookups):
        node = tree.nodes.new("ShaderNodeGroup")
        node.node_tree = group_tree
        node.location = (-1350, y - 250 * k)
        tree.links.new(uv, node.inputs["UV"])
        for key in ("X", "Y", "W", "H"):
            tree.links.new(lookup.outputs[key], node.inputs[key])
        node.inputs["Atlas Width"].default_value = float(atlas.width)
        node.inputs["Atlas Height"].default_value = float(atlas.height)
        node.inputs["Repeat"].default_value = 1.0 if repeat else 0.0
        nodes.append(node)
    return nodes


def bilinear_closest(tree, image, corner_uvs, fx, fy, location, alpha=True, name=None):
    """Bilinear filtering in nodes: four Closest lookups of `image` at the texel centres
    `corner_uvs` (sockets, in TAP_CORNERS order) weighted by the fractions fx, fy through
    bilinear_group. Returns that group node (outputs Color and Alpha, Alpha linked where `alpha`).
    The lookups are named "<name> <corner>" where `name` is given."""
    x, y = location
    bilinear = tree.nodes.new("ShaderNodeGroup")
    bilinear.node_tree = bilinear_group()
    bilinear.location = (x, y)
    for i, (corner, uv) in enumerate(zip(TAP_CORNERS, corner_uvs)):
        tex = tree.nodes.new("ShaderNodeTexImage")
        if name:
            tex.name = tex.label = "%s %s" % (name, corner)
        tex.image = image
        tex.interpolation = "Closest"  # the taps are texel centres; filtering is done in nodes
        tex.extension = "EXTEND"
        tex.location = (x - 250, y - 60 * i)
        tex.hide = True
        tree.links.new(uv, tex.inputs["Vector"])
        tree.links.new(tex.outputs["Color"], bilinear.inputs["Color " + corner])
        if alpha:
            tree.links.new(tex.outputs["Alpha"], bilinear.inputs["Alpha " + corner])
    tree.links.new(fx, bilinear.inputs["Fx"])
    tree.links.new(fy, bilinear.inputs["Fy"])
    return bilinear


def sample_atlas(tree, image, taps, blend, j, y):
    """Lobe j's RGBA at the shading point: bilinear in each of the two levels, blended."""
    colors, alphas = [], []
    for k, tap in enumerate(taps):
        bilinear = bilinear_closest(tree, image, [tap.outputs["UV " + c] for c in TAP_CORNERS], tap.outputs["Fx"],
                                    tap.outputs["Fy"], (-1000, y - 300 * k),
                                    name="Lobe %d level %s" % (j, "low" if k == 0 else "high"))
        colors.append(bilinear.outputs["Color"])
        alphas.append(bilinear.outputs["Alpha"])
    return (_mix(tree, "VECTOR", blend, colors[0], colors[1], (-850, y)),
            _mix(tree, "FLOAT", blend, alphas[0], alphas[1], (-850, y - 150)))


def sample_atlas_linear(tree, image, points, blend, j, y):
    """Lobe j's RGBA at the shading point from one Linear lookup in each of the two levels
    (atlas_point_group's nodes `points`), blended: for Cycles only (see the module's docstring)."""
    colors, alphas = [], []
    for k, point in enumerate(points):
        tex = tree.nodes.new("ShaderNodeTexImage")
        tex.name = tex.label = "Lobe %d level %s" % (j, "low" if k == 0 else "high")
        tex.image = image
        tex.interpolation = "Linear"
        tex.extension = "EXTEND"
        tex.location = (-1250, y - 300 * k)
        tex.hide = True
        tree.links.new(point.outputs["UV"], tex.inputs["Vector"])
        colors.append(tex.outputs["Color"])
        alphas.append(tex.outputs["Alpha"])
    return (_mix(tree, "VECTOR", blend, colors[0], colors[1], (-850, y)),
            _mix(tree, "FLOAT", blend, alphas[0], alphas[1], (-850, y - 150)))


def sample_level0(tree, gin, image, image_texture, has_vector, j, y):
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
