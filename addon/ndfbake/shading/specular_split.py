"""The Principled BSDF taken apart so that a bake draws the material's diffuse once and only its
specular reflection per lobe, where Principled v2 (Blender 4.0+) allows it exactly enough.

What the lobes change is the specular reflection: its normals and its roughness. A lobe drawn as a
whole copy of the Principled BSDF also draws the diffuse (and subsurface) under its specular, once
per lobe, though the diffuse of the fine normals is the diffuse of their mean normal to the
accuracy a Lambertian term has (it is smooth in the normal). So where it may, a bake builds:

- one "base" Principled BSDF per engine at the texel's mean normal (Σ_j α_j·r_j, the first
  moment of the lobes) with the original roughness, Metallic 0, Specular IOR Level 0 (no specular
  layer of its own), and Base Color = c·(1 − m)·(1 − max over R, G, B of E_s), c the Base Color,
  m Metallic: the diffuse (and subsurface) a Principled v2 draws under its dielectric specular layer, which
  takes the layer's directional albedo E_s out of it as Cycles estimates it
  (bsdf_microfacet_estimate_albedo, closure_layering_weight): E_s = mix(F0·t, 1, s)·M, t the
  Specular Tint, F0 the dielectric's after Specular IOR Level, s where the lobe-averaged Fresnel
  lies between F0 and 1, M = E + F_ms·(1 − E) for Multiscatter GGX (1 for GGX). s, E and F_ms are
  read from one table image (tools/specular_albedo.py computes them; specular_albedo_table.py
  holds them), two lookups per material. That is Cycles' base; EEVEE Next's (the group's EEVEE
  output) is darkened by EEVEE's own estimate, its split sum F0·t·A + F90·B, read from the same
  image by a lookup that only EEVEE's output draws (four Closest texels weighted in nodes:
  _table_lookup_taps). No base at all where Metallic is a
  constant 1: it would draw nothing.
- per lobe, the Principled BSDF's specular only: where Metallic is a constant 1 a conductor
  (Metallic 1: the original's metal lobe), where it is a constant 0 the dielectric layer over a
  black base (no diffuse closure), else both, mixed by Metallic as the Principled mixes them.
  Each keeps the original's Fresnel (F82 tint; IOR and Specular IOR Level) exactly.

Not where Coat, Sheen or Transmission may matter (linked, animated or non-zero): those layers sit
over or beside the specular and darken it by their own albedo, which a separate base cannot do;
there a lobe stays a whole copy of the Principled BSDF. Nor in Principled v1 (Blender 3.x).
Checked by tests/blender/test_addon_render.py's furnace at view angles down to 2° (metal and
dielectric).
"""
import bpy

from . import lod_nodes, material_scan
from . import specular_albedo_table as table
from .node_builders import COLOR, FLOAT, GROUP_VERSION, VECTOR, _find_group, _group_with_io, _link, _math, _vmath

SPLIT_GROUP = "NDFB Specular Albedo v%d" % GROUP_VERSION
SPLIT_INPUTS = ("Base Color", "Metallic", "IOR", "Specular IOR Level", "Specular Tint", "Roughness")
# Layers that keep a lobe a whole Principled BSDF (Principled v2 names).
LAYERED_INPUTS = ("Coat Weight", "Sheen Weight", "Transmission Weight")
# The group's outputs: the base's Base Color as Cycles darkens it, and as EEVEE Next does.
CYCLES_DIFFUSE, EEVEE_DIFFUSE = "Diffuse Color", "EEVEE Diffuse Color"
TABLE_IMAGE = "NDFB Specular Layer Table"
TABLE_KEY = "ndfbake specular layer table"   # the image's ID property: what remove_unused_table removes


def may_split(principled, holder):
    """Whether the bake of `principled` (whose inputs `holder` holds now: itself, or the group node
    of the bake a re-bake replaces) draws specular-only lobes over one base: Principled v2, and no
    coat, sheen or transmission that may matter."""
    if "Specular IOR Level" not in principled.inputs:
        return False
    return not any(material_scan.input_may_matter(holder, name) for name in LAYERED_INPUTS)


CONDUCTOR, DIELECTRIC, BOTH = "CONDUCTOR", "DIELECTRIC", "BOTH"


def multiscatter(principled):
    """The group's Multiscatter input for `principled`: 1 where it draws Multiscatter GGX. What its
    specular takes out of its diffuse follows its own distribution, not the lobes'."""
    return 1 if principled.distribution == "MULTI_GGX" else 0


def lobe_kind(holder):
    """What a lobe's specular is: CONDUCTOR where Metallic is a constant 1 (no link, no animation;
    the base would draw nothing and is left out), DIELECTRIC where it is a constant 0, else BOTH
    (mixed by Metallic, as the Principled BSDF mixes them)."""
    metallic = material_scan.constant_input(holder, "Metallic")
    if metallic == 1.0:
        return CONDUCTOR
    if metallic == 0.0:
        return DIELECTRIC
    return BOTH


# Each slice of the image is MU_SIZE columns with a copy of its first and last column on either
# side: EEVEE's Linear lookup at the last column's centre still reads 2.5% of the texel beside it
# (measured in 5.0: s 0.0249 where Cycles reads 0.0002), which without the copy was the next
# slice's grazing column (EEVEE's dielectric furnace 2.2% dark at normal incidence).
SLICE_WIDTH = table.MU_SIZE + 2
EEVEE_SLICE = table.Z_SIZE   # the slice after the z slices: EEVEE's split sum
SLICES = table.Z_SIZE + 1


def table_pixels():
    """The table image's RGBA floats, rows bottom up: row i is roughness i/15; slice j < Z_SIZE
    (columns j·SLICE_WIDTH to j·SLICE_WIDTH + MU_SIZE + 1) holds (s(r, z_j, √μ_k), E(r, √μ_k),
    F_ms(r, z_j), 1) at column j·SLICE_WIDTH + 1 + k, its edge columns repeated beside it, and
    slice EEVEE_SLICE likewise (A(r, √μ_k), B(r, √μ_k), 0, 1), EEVEE's split sum."""
    r_size, z_size, mu_size = table.ROUGHNESS_SIZE, table.Z_SIZE, table.MU_SIZE
    columns = [0] + list(range(mu_size)) + [mu_size - 1]
    pixels = []
    for i in range(r_size):
        for j in range(z_size):
            for k in columns:
                pixels += (table.FRESNEL_SHAPE[(i * z_size + j) * mu_size + k], table.GGX_ALBEDO[i * mu_size + k],
                           table.MULTISCATTER_FRESNEL[i * z_size + j], 1.0)
        for k in columns:
            pixels += (table.EEVEE_SPLIT_SCALE[i * mu_size + k], table.EEVEE_SPLIT_BIAS[i * mu_size + k], 0.0, 1.0)
    return pixels


def table_image():
    """A new packed float image of table_pixels(), Non-Color."""
    width, height = SLICE_WIDTH * SLICES, table.ROUGHNESS_SIZE
    image = bpy.data.images.new(TABLE_IMAGE, width, height, alpha=True, float_buffer=True)
    image.colorspace_settings.name = "Non-Color"
    image.alpha_mode = "CHANNEL_PACKED"
    image.pixels.foreach_set(table_pixels())
    image.pack()
    image[TABLE_KEY] = GROUP_VERSION
    return image


def remove_unused_table():
    """Removes the table images no group uses any more (after the last split group is removed)."""
    for image in [image for image in bpy.data.images if image.get(TABLE_KEY) is not None and image.users == 0]:
        bpy.data.images.remove(image)


def _table_lookup(tree, image, column, v, slice_index, location):
    """The table's RGB at slice `slice_index`, √μ column `column` (texel units from the slice's first
    data column's left edge), row coordinate v."""
    u = _math(tree, "DIVIDE", _math(tree, "MULTIPLY_ADD", slice_index, float(SLICE_WIDTH), column,
                                    location=location), float(SLICE_WIDTH * SLICES),
              location=(location[0] + 150, location[1]))
    uv = tree.nodes.new("ShaderNodeCombineXYZ")
    uv.location = (location[0] + 300, location[1])
    tree.links.new(u, uv.inputs["X"])
    _link(tree, v, uv.inputs["Y"])
    tex = tree.nodes.new("ShaderNodeTexImage")
    tex.image = image
    # Bilinear in √μ and roughness; the slices are mixed in nodes. Where √μ changes fast across a
    # pixel (silhouettes) EEVEE's MIP-mapping may blend neighbouring texels too: a smooth table.
    tex.interpolation = "Linear"
    tex.extension = "EXTEND"
    tex.location = (location[0] + 450, location[1])
    tree.links.new(uv.outputs["Vector"], tex.inputs["Vector"])
    rgb = tree.nodes.new("ShaderNodeSeparateXYZ")
    rgb.location = (location[0] + 750, location[1])
    tree.links.new(tex.outputs["Color"], rgb.inputs["Vector"])
    return rgb.outputs


def _table_lookup_taps(tree, image, column, v, slice_index, location):
    """_table_lookup from four Closest lookups weighted in nodes, for what EEVEE alone draws (its
    split-sum slice): EEVEE 5.3 reads 0 from a Linear lookup whose coordinates have no screen
    derivatives (a flat surface under an orthographic camera: the furnace drew the diffuse base
    black), where Closest lookups are read as they are. Cycles keeps the one Linear lookup."""
    x, y = location
    width, height = float(SLICE_WIDTH * SLICES), float(table.ROUGHNESS_SIZE)
    # Texel positions measured from texel centres: the lower tap and the fraction past it, per axis.
    across = _math(tree, "SUBTRACT", _math(tree, "MULTIPLY_ADD", slice_index, float(SLICE_WIDTH), column,
                                           location=(x, y)), 0.5, location=(x + 100, y))
    down = _math(tree, "MULTIPLY_ADD", v, height, -0.5, location=(x, y - 100))
    taps = []
    for position, size, yy in ((across, width, y), (down, height, y - 100)):
        first = _math(tree, "FLOOR", position, location=(x + 200, yy))
        low = _math(tree, "DIVIDE", _math(tree, "ADD", first, 0.5, location=(x + 300, yy)), size,
                    location=(x + 400, yy))
        high = _math(tree, "ADD", low, 1.0 / size, location=(x + 500, yy))
        taps.append((low, high, _math(tree, "SUBTRACT", position, first, location=(x + 300, yy - 50))))
    (u0, u1, fx), (v0, v1, fy) = taps
    corner_uvs = []
    for i, (u, row) in enumerate(((u0, v0), (u1, v0), (u0, v1), (u1, v1))):  # lod_nodes.TAP_CORNERS' order
        uv = tree.nodes.new("ShaderNodeCombineXYZ")
        uv.location = (x + 600, y - 60 * i)
        uv.hide = True
        tree.links.new(u, uv.inputs["X"])
        tree.links.new(row, uv.inputs["Y"])
        corner_uvs.append(uv.outputs["Vector"])
    bilinear = lod_nodes.bilinear_closest(tree, image, corner_uvs, fx, fy, (x + 1000, y), alpha=False)
    rgb = tree.nodes.new("ShaderNodeSeparateXYZ")
    rgb.location = (x + 1150, y)
    tree.links.new(bilinear.outputs["Color"], rgb.inputs["Vector"])
    return rgb.outputs


def specular_split_group():
    """Inputs SPLIT_INPUTS, Multiscatter (1 where the Principled draws Multiscatter GGX, else 0) and
    Normal (the base's, world space); outputs CYCLES_DIFFUSE and EEVEE_DIFFUSE."""
    tree = _find_group(SPLIT_GROUP)
    if tree is not None:
        return tree
    tree, gin, gout = _group_with_io(
        SPLIT_GROUP, [(COLOR, "Base Color"), (FLOAT, "Metallic"), (FLOAT, "IOR"), (FLOAT, "Specular IOR Level"),
                      (COLOR, "Specular Tint"), (FLOAT, "Roughness"), (FLOAT, "Multiscatter"), (VECTOR, "Normal")],
        [(COLOR, CYCLES_DIFFUSE), (COLOR, EEVEE_DIFFUSE)], (-1400, 1500))
    metallic = _math(tree, "MINIMUM", _math(tree, "MAXIMUM", gin.outputs["Metallic"], 0.0, location=(-1200, 500)),
                     1.0, location=(-1050, 500))
    dielectric = _math(tree, "SUBTRACT", 1.0, metallic, location=(-900, 500))

    # F0 = 2·level·((η − 1)/(η + 1))² in [0, 1] (Cycles moves η to match a level other than 0.5).
    eta = gin.outputs["IOR"]
    ratio = _math(tree, "DIVIDE", _math(tree, "SUBTRACT", eta, 1.0, location=(-1200, 200)),
                  _math(tree, "MAXIMUM", _math(tree, "ADD", eta, 1.0, location=(-1200, 100)), 1e-6,
                        location=(-1050, 100)), location=(-900, 200))
    f0 = _math(tree, "MULTIPLY", _math(tree, "MULTIPLY", ratio, ratio, location=(-750, 200)),
               _math(tree, "MULTIPLY", gin.outputs["Specular IOR Level"], 2.0, location=(-750, 50)),
               location=(-600, 200), clamp=True)

    # The table's coordinates: √μ (μ = max(view · normal, 0)) and roughness in texels' centres,
    # z = F0^(1/4) between two slices.
    geometry = tree.nodes.new("ShaderNodeNewGeometry")
    geometry.location = (-1200, -400)
    mu = _math(tree, "MAXIMUM", _vmath(tree, "DOT_PRODUCT", geometry.outputs["Incoming"], gin.outputs["Normal"],
                                       location=(-1050, -400), output=1), 0.0, location=(-900, -400))
    last = float(table.MU_SIZE - 1)
    column = _math(tree, "MULTIPLY_ADD", _math(tree, "SQRT", mu, location=(-750, -400)), last, 1.5,
                   location=(-600, -400))  # past the slice's copy of its first column
    rough = _math(tree, "MULTIPLY", gin.outputs["Roughness"], 1.0, location=(-900, -600), clamp=True)
    v = _math(tree, "DIVIDE", _math(tree, "MULTIPLY_ADD", rough, float(table.ROUGHNESS_SIZE - 1), 0.5,
                                    location=(-750, -600)), float(table.ROUGHNESS_SIZE), location=(-600, -600))
    z = _math(tree, "MULTIPLY", _math(tree, "POWER", f0, 0.25, location=(-450, 200)), float(table.Z_SIZE - 1),
              location=(-300, 200))
    lower = _math(tree, "MINIMUM", _math(tree, "FLOOR", z, location=(-150, 200)), float(table.Z_SIZE - 2),
                  location=(0, 200))
    between = _math(tree, "SUBTRACT", z, lower, location=(150, 200))
    image = table_image()
    low = _table_lookup(tree, image, column, v, lower, (-450, -900))
    high = _table_lookup(tree, image, column, v, _math(tree, "ADD", lower, 1.0, location=(-600, -1200)),
                         (-450, -1200))

    def between_slices(channel, y):
        return _math(tree, "MULTIPLY_ADD", _math(tree, "SUBTRACT", high[channel], low[channel], location=(450, y)),
                     between, low[channel], location=(600, y))
    shape = between_slices("X", -900)
    albedo = low["Y"]
    # M = E + F_ms·(1 − E) with Multiscatter GGX, 1 with GGX
    compensated = _math(tree, "MULTIPLY_ADD", between_slices("Z", -1050),
                        _math(tree, "SUBTRACT", 1.0, albedo, location=(600, -1200)), albedo, location=(750, -1050))
    scale = _math(tree, "MULTIPLY_ADD", _math(tree, "SUBTRACT", compensated, 1.0, location=(900, -1050)),
                  gin.outputs["Multiscatter"], 1.0, location=(1050, -1050))
    # E_s = mix(F0·t, 1, s)·M per channel = (F0·(1 − s)·t + s)·M
    tinted = _vmath(tree, "SCALE", gin.outputs["Specular Tint"],
                    scale=_math(tree, "MULTIPLY", f0, _math(tree, "SUBTRACT", 1.0, shape, location=(750, -800)),
                                location=(900, -800)), location=(1050, -700))
    # (a float linked to a vector socket is read as (s, s, s))
    layer = _vmath(tree, "SCALE", _vmath(tree, "ADD", tinted, shape, location=(1200, -700)), scale=scale,
                   location=(1350, -700))
    _diffuse_under(tree, gin, _largest_channel(tree, layer, (1500, -700)), dielectric, gout.inputs[CYCLES_DIFFUSE],
                   (1950, -700))
    split_sum = _table_lookup_taps(tree, image, column, v, float(EEVEE_SLICE), (-450, -1600))
    eevee = _eevee_layer_albedo(tree, gin, f0, split_sum["X"], split_sum["Y"], (600, -1600))
    _diffuse_under(tree, gin, eevee, dielectric, gout.inputs[EEVEE_DIFFUSE], (1950, -1600))
    return tree


def _largest_channel(tree, vector, location):
    """max(x, y, z) of `vector` (an output socket)."""
    x, y = location
    channels = tree.nodes.new("ShaderNodeSeparateXYZ")
    channels.location = location
    tree.links.new(vector, channels.inputs["Vector"])
    return _math(tree, "MAXIMUM", _math(tree, "MAXIMUM", channels.outputs["X"], channels.outputs["Y"],
                                        location=(x + 150, y + 50)), channels.outputs["Z"], location=(x + 300, y))


def _diffuse_under(tree, gin, layer_albedo, dielectric, output, location):
    """Links c·(1 − m)·clamp(1 − layer_albedo) to `output`: the diffuse under a specular layer that
    takes out `layer_albedo` (closure_layering_weight), c the Base Color, 1 − m `dielectric`."""
    x, y = location
    kept = _math(tree, "SUBTRACT", 1.0, layer_albedo, location=(x, y), clamp=True)
    diffuse = _vmath(tree, "SCALE", gin.outputs["Base Color"],
                     scale=_math(tree, "MULTIPLY", kept, dielectric, location=(x + 150, y + 200)),
                     location=(x + 300, y + 400))
    tree.links.new(diffuse, output)


def _eevee_layer_albedo(tree, gin, f0, scale, bias, location):
    """The largest channel of what EEVEE Next's Principled takes out of its diffuse for the layer
    (its bsdf_lut): R = F0·t·A + F90·B, F90 = clamp(7.06·√F0) (EEVEE fades F90 out below IOR
    1.33), and for Multiscatter GGX R / (1 − (1 − E_ss)·F_avg), F_avg = F0·t + (F90 − F0·t)/21.
    A + B stands in for EEVEE's E_ss (the reflected plus transmitted single-scatter albedo, from a
    LUT of EEVEE's own): that moves R by a factor within (A + B − E_ss)·F_avg of 1. R grows with t,
    so the largest channel is the largest t's."""
    x, y = location
    f0_tinted = _math(tree, "MULTIPLY", f0, _largest_channel(tree, gin.outputs["Specular Tint"], (x, y)),
                      location=(x + 450, y), clamp=True)
    f90 = _math(tree, "MULTIPLY", _math(tree, "SQRT", f0, location=(x + 300, y - 150)), 2.33 / 0.33,
                location=(x + 450, y - 150), clamp=True)
    # F0·t·A + F90·B
    single = _math(tree, "MULTIPLY_ADD", f0_tinted, scale,
                   _math(tree, "MULTIPLY", f90, bias, location=(x + 600, y - 150)), location=(x + 750, y - 200))
    average = _math(tree, "MULTIPLY_ADD", _math(tree, "SUBTRACT", f90, f0_tinted, location=(x + 600, y - 300)),
                    1.0 / 21.0, f0_tinted, location=(x + 750, y - 350))
    albedo = _math(tree, "ADD", scale, bias, location=(x + 600, y - 500))
    # 1 − (1 − E_ss)·F_avg ≥ E_ss ≥ 0.3 (F_avg ≤ 1; the table's least A + B is 0.31): no division by zero
    kept = _math(tree, "MULTIPLY_ADD", _math(tree, "SUBTRACT", albedo, 1.0, location=(x + 750, y - 500)), average,
                 1.0, location=(x + 900, y - 450))
    multiple = _math(tree, "DIVIDE", single, kept, location=(x + 1050, y - 300))
    return _math(tree, "MULTIPLY_ADD", _math(tree, "SUBTRACT", multiple, single, location=(x + 1200, y - 300)),
                 gin.outputs["Multiscatter"], single, location=(x + 1350, y - 200))
