"""One lobe texel decoded in shader nodes ("NDFB vMF Lobe"), and its roughness narrowed toward
grazing views ("NDFB Grazing Roughness"). Shared groups, built once per file; they know lobes,
not materials. nodes.py assembles them into a material's group.

Lobe textures hold R = α_j and GBA = α_j·r_j in tangent space, with |r_j| = R_j the resultant
length whose κ_j = (3R − R³)/(1 − R²). The encoding is linear: averaging texels averages
distributions. Per shading point and lobe:

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

The library's rule also has an amplitude ∫D_α / ∫D_α' (brdf.h: it keeps the NDF's mass over the
sphere, which is what its error measure compares); the shader leaves it out: every fine normal's
BSDF is normalized about its own normal, and so must the lobe that stands for them be. Measured in
a white furnace (Cycles, bumps map, roughness 0.15, view from above): 0.885 of the reference with
the amplitude, 1.002 without (tests/blender/test_addon_render.py checks the furnace).
"""
from .node_builders import COLOR, FLOAT, GROUP_VERSION, VECTOR, _find_group, _group_with_io, _math, _vmath

LOBE_GROUP = "NDFB vMF Lobe v%d" % GROUP_VERSION
GRAZING_GROUP = "NDFB Grazing Roughness v%d" % GROUP_VERSION
GGX_VMF_WIDENING = 1.5                # native/src/math/brdf.h kGgxVmfWidening
HALF_INV_KAPPA_RESOLUTION = 4e-4      # native/src/io/lobe_exr.h kHalfInvKappaResolution (the add-on
# cos θ is floored here (θ ≈ 89.9°) so that tan²θ stays finite where a lobe faces away.
GRAZING_MIN_COSINE = 1e-3


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
    """A widened lobe's roughness narrowed toward grazing views: inputs Roughness (widened, α′ =
    Roughness²), Base Roughness (the original's, α), Normal (the lobe's, world space) and
    Narrowing (C, nodes.default_grazing_narrowing by output); output Roughness with

        α″² = max(α′² / (1 + C·α′² tan²θ), α²),   θ between the view and the lobe's normal.

    Why: a microfacet lobe weights its facets by their area seen from the view, (h·v)/(μ·v)·G, and
    loses those turned away; the normal map it stands for has no masking between its fine normals,
    and each fine normal's own 1/(n·v) cancels its projected area. So at grazing views a widened
    lobe reflects light from higher above the horizon than the map does (Cycles' far ground 1.57×
    the reference's brightness under Blender's city world, 0.64× under courtyard). The narrowing
    grows with α′ tan θ, the quantity GGX's masking grows with, and stops at the original
    roughness, so a flat map (κ → ∞, α′ = α) is left exactly as it is. C was fitted offline
    against the normal map's own response (docs/grazing-fit.md: 4 for Cycles' GGX) and measured
    on the demo scene under the 8 studio worlds (studies/world_sweep.py; docs/rendering.md,
    "Grazing views"). The first form (C = 1, EEVEE only, 2026-11-25) was chosen on EEVEE's
    sunset ground, which widened lobes rendered 25% too dark.
    """
    tree = _find_group(GRAZING_GROUP)
    if tree is not None:
        return tree
    tree, gin, gout = _group_with_io(
        GRAZING_GROUP, [("NodeSocketFloatFactor", "Roughness"), ("NodeSocketFloatFactor", "Base Roughness"),
                        (VECTOR, "Normal"), (FLOAT, "Narrowing")], [(FLOAT, "Roughness")], (-1000, 900))
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
    stretch = _math(tree, "MULTIPLY_ADD", _math(tree, "MULTIPLY", widened2, gin.outputs["Narrowing"],
                                                location=(-50, 100)), tan2, 1.0, location=(100, 100))
    narrowed2 = _math(tree, "MAXIMUM", _math(tree, "DIVIDE", widened2, stretch, location=(250, 150)), base2,
                      location=(400, 100))
    tree.links.new(_math(tree, "SQRT", _math(tree, "SQRT", narrowed2, location=(550, 100)), location=(700, 100)),
                   gout.inputs["Roughness"])
    return tree
