"""The Principled BSDF taken apart so that a bake draws the material's diffuse once and only its
specular reflection per lobe, where Principled v2 (Blender 4.0+) allows it exactly enough.

What the lobes change is the specular reflection: its normals and its roughness. A lobe drawn as a
whole copy of the Principled BSDF also draws the diffuse (and subsurface) under its specular, once
per lobe, though the diffuse of the fine normals is the diffuse of their mean normal to the
accuracy a Lambertian term has (it is smooth in the normal). So where it may, a bake builds:

- one "base" Principled BSDF at the texel's mean normal (Σ_j α_j·r_j, the first moment of the
  lobes) with the original roughness, Metallic 0, Specular IOR Level 0 (no specular layer of its
  own), and Base Color = c·(1 − m)·(1 − E_s), c the Base Color, m Metallic: the diffuse (and
  subsurface) a Principled v2 draws under its dielectric specular layer, which takes the layer's
  directional albedo E_s out of it (Cycles' layering; EEVEE's split sum). E_s is approximated by
  Karis's fit of GGX's split-sum albedo (Karis 2014, "Physically Based Shading on Mobile"):
  E_s ≈ t·(F0·A(μ, r) + B(μ, r)), μ the view cosine at the mean normal, r the roughness, t the
  Specular Tint. No base at all where Metallic is a constant 1: it would draw nothing.
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
from . import material_scan, node_animation
from .node_builders import COLOR, FLOAT, GROUP_VERSION, VECTOR, _find_group, _group_with_io, _math, _vmath

SPLIT_GROUP = "NDFB Specular Split v%d" % GROUP_VERSION
SPLIT_INPUTS = ("Base Color", "Metallic", "IOR", "Specular IOR Level", "Specular Tint", "Roughness")
# Layers that keep a lobe a whole Principled BSDF (Principled v2 names).
LAYERED_INPUTS = ("Coat Weight", "Sheen Weight", "Transmission Weight")
# Karis 2014's fit of the split-sum GGX albedo: r·C0 + C1 (r the roughness), then
# a = min(x², 2^(EXP_SCALE·μ))·x + y, A = −1.04·a + z, B = 1.04·a + w.
KARIS_C0 = (-1.0, -0.0275, -0.572, 0.022)
KARIS_C1 = (1.0, 0.0425, 1.04, -0.04)
KARIS_EXP_SCALE = -9.28
KARIS_AB_SLOPE = 1.04


def may_split(principled, holder):
    """Whether the bake of `principled` (whose inputs `holder` holds now: itself, or the group node
    of the bake a re-bake replaces) draws specular-only lobes over one base: Principled v2, and no
    coat, sheen or transmission that may matter."""
    if "Specular IOR Level" not in principled.inputs:
        return False
    return not any(material_scan.input_may_matter(holder, name) for name in LAYERED_INPUTS)


CONDUCTOR, DIELECTRIC, BOTH = "CONDUCTOR", "DIELECTRIC", "BOTH"


def lobe_kind(holder):
    """What a lobe's specular is: CONDUCTOR where Metallic is a constant 1 (no link, no animation;
    the base would draw nothing and is left out), DIELECTRIC where it is a constant 0, else BOTH
    (mixed by Metallic, as the Principled BSDF mixes them)."""
    index = holder.inputs.find("Metallic")
    socket = holder.inputs[index]
    if material_scan.live_link(socket) is None and not node_animation.input_animated(holder.id_data, holder, index):
        if socket.default_value == 1.0:
            return CONDUCTOR
        if socket.default_value == 0.0:
            return DIELECTRIC
    return BOTH


def specular_split_group():
    """Inputs SPLIT_INPUTS and Normal (the base's, world space); output Diffuse Color, the base's
    Base Color."""
    tree = _find_group(SPLIT_GROUP)
    if tree is not None:
        return tree
    tree, gin, gout = _group_with_io(
        SPLIT_GROUP, [(COLOR, "Base Color"), (FLOAT, "Metallic"), (FLOAT, "IOR"), (FLOAT, "Specular IOR Level"),
                      (COLOR, "Specular Tint"), (FLOAT, "Roughness"), (VECTOR, "Normal")],
        [(COLOR, "Diffuse Color")], (-1400, 900))
    metallic = _math(tree, "MINIMUM", _math(tree, "MAXIMUM", gin.outputs["Metallic"], 0.0, location=(-1200, 500)),
                     1.0, location=(-1050, 500))
    dielectric = _math(tree, "SUBTRACT", 1.0, metallic, location=(-900, 500))

    tint = gin.outputs["Specular Tint"]
    # F0_d = 2·level·((η − 1)/(η + 1))², at most 1 (a level above 0.5 on a high IOR would pass it).
    eta = gin.outputs["IOR"]
    ratio = _math(tree, "DIVIDE", _math(tree, "SUBTRACT", eta, 1.0, location=(-1200, 200)),
                  _math(tree, "MAXIMUM", _math(tree, "ADD", eta, 1.0, location=(-1200, 100)), 1e-6,
                        location=(-1050, 100)), location=(-900, 200))
    f0 = _math(tree, "MINIMUM", _math(tree, "MULTIPLY", _math(tree, "MULTIPLY", ratio, ratio, location=(-750, 200)),
                                      _math(tree, "MULTIPLY", gin.outputs["Specular IOR Level"], 2.0,
                                            location=(-750, 50)), location=(-600, 200)), 1.0, location=(-450, 200))

    # E_s ≈ t·(F0_d·A + B) at μ = max(view · normal, 0) (Karis 2014).
    geometry = tree.nodes.new("ShaderNodeNewGeometry")
    geometry.location = (-1200, -400)
    mu = _math(tree, "MAXIMUM", _vmath(tree, "DOT_PRODUCT", geometry.outputs["Incoming"], gin.outputs["Normal"],
                                       location=(-1050, -400), output=1), 0.0, location=(-900, -400))
    rough = gin.outputs["Roughness"]
    x, y, z, w = (_math(tree, "MULTIPLY_ADD", rough, c0, c1, location=(-900, -550 - 100 * i))
                  for i, (c0, c1) in enumerate(zip(KARIS_C0, KARIS_C1)))
    falloff = _math(tree, "POWER", 2.0, _math(tree, "MULTIPLY", mu, KARIS_EXP_SCALE, location=(-750, -400)),
                    location=(-600, -400))
    a = _math(tree, "MULTIPLY_ADD", _math(tree, "MINIMUM", _math(tree, "MULTIPLY", x, x, location=(-600, -550)),
                                          falloff, location=(-450, -450)), x, y, location=(-300, -450))
    scale = _math(tree, "MULTIPLY_ADD", a, -KARIS_AB_SLOPE, z, location=(-150, -400))
    bias = _math(tree, "MULTIPLY_ADD", a, KARIS_AB_SLOPE, w, location=(-150, -550))
    albedo = _math(tree, "MINIMUM", _math(tree, "MAXIMUM", _math(tree, "MULTIPLY_ADD", f0, scale, bias,
                                                                 location=(0, -450)), 0.0, location=(150, -450)),
                   1.0, location=(300, -450))
    # Diffuse Color = c·(1 − m)·(1 − t·E_s)
    kept = _vmath(tree, "SUBTRACT", (1.0, 1.0, 1.0), _vmath(tree, "SCALE", tint, scale=albedo, location=(450, -400)),
                  location=(600, -300))
    diffuse = _vmath(tree, "SCALE", _vmath(tree, "MULTIPLY", gin.outputs["Base Color"], kept, location=(750, -200)),
                     scale=dielectric, location=(900, -100))
    tree.links.new(diffuse, gout.inputs["Diffuse Color"])
    return tree
