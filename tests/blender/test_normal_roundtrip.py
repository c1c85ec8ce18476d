"""Round trip of an object-space normal map through ndfbake's tangent-space conversion and
Blender's Normal Map node, checked with Cycles bakes inside `blender -b`.

Run: blender -b --factory-startup --python-exit-code 1 --python tests/blender/test_normal_roundtrip.py -- LIB

1. A mirrored Suzanne (triangulated, copy's UVs mirrored beside the original's) gets a bumpy
   material; Cycles bakes its shading normals in OBJECT space: the object-space map O.
2. ndfb_object_to_tangent converts O to a tangent-space map T (frames computed by ndfbake, with
   the frame normal this Blender's Cycles uses: as interpolated up to 5.0, normalized from 5.1).
3. A second material renders T through an Image Texture and the Normal Map node (tangent space,
   Cycles computing its own MikkTSpace tangents); Cycles bakes its shading normals in OBJECT
   space again: O'.
4. O' must reproduce O: per texel angle, away from island borders (where a texel centre can fall
   outside every triangle) under 1 degree. Also checks that ndfb_tangent_to_object(T) == O, and
   that T made with the other frame normal misses by at least 3 degrees (the negative control).
"""
import os
import sys

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from ndfb_mesh import library_from_argv, MeshArrays, FRAME_NORMAL_INTERPOLATED, FRAME_NORMAL_UNIT  # noqa: E402
from test_addon_helpers import exit_now  # noqa: E402
from test_tangents import mirrored_suzanne  # noqa: E402
from ndfbake.shading import blender_compat  # noqa: E402  (ndfb_mesh put addon/ on the path)

SIZE = 128
LIMIT_DEGREES = 1.0
# The other frame normal must miss by at least this much, or the test could not tell them apart.
CONTROL_DEGREES = 3.0
RULE_NAMES = {FRAME_NORMAL_INTERPOLATED: "as interpolated", FRAME_NORMAL_UNIT: "normalized"}
BUMP_FREQUENCY = 12.0  # radians per object unit: a few bumps across Suzanne's features
BUMP_DISTANCE = 0.05   # height scale: normals bent by tens of degrees
# A bumped normal this far from the unmapped one is at the horizon or past it: 3.4's Bump node
# bends such normals back to the horizon, 4.2+'s leaves a few past it (up to ~150 degrees), and no
# tangent-space map renders a normal below the surface. Those texels are left out of the comparison.
HORIZON_DEGREES = 80.0


def bake_object_normals(obj, material, image):
    """Cycles NORMAL bake in object space into `image` (float), returned as rows top to bottom,
    unit vectors, plus the mask of baked texels."""
    obj.data.materials.clear()
    obj.data.materials.append(material)
    nodes = material.node_tree.nodes
    target = nodes.new("ShaderNodeTexImage")
    target.image = image
    nodes.active = target
    image.generated_color = (0.0, 0.0, 0.0, 0.0)
    image.pixels.foreach_set(np.zeros(SIZE * SIZE * 4, dtype=np.float32))
    bpy.ops.object.bake(type="NORMAL", normal_space="OBJECT", margin=0, use_clear=False)
    px = np.empty(SIZE * SIZE * 4, dtype=np.float32)
    image.pixels.foreach_get(px)
    px = px.reshape(SIZE, SIZE, 4)[::-1]  # Blender stores rows bottom to top
    normals = px[..., :3] * 2.0 - 1.0
    baked = px[..., 3] > 0.5  # the bake writes alpha 1 where it wrote a normal
    normals /= np.maximum(np.linalg.norm(normals, axis=-1, keepdims=True), 1e-12)
    nodes.remove(target)
    return normals, baked


def float_image(name):
    image = bpy.data.images.new(name, SIZE, SIZE, alpha=True, float_buffer=True)
    image.colorspace_settings.name = "Non-Color"
    return image


def diffuse_material(name):
    """A new material drawing one Diffuse BSDF: (material, that node)."""
    m = bpy.data.materials.new(name)
    blender_compat.enable_nodes(m)
    nodes = m.node_tree.nodes
    nodes.remove(nodes["Principled BSDF"])
    bsdf = nodes.new("ShaderNodeBsdfDiffuse")
    m.node_tree.links.new(bsdf.outputs["BSDF"], nodes["Material Output"].inputs["Surface"])
    return m, bsdf


def bumpy_material():
    """Diffuse with a Bump node over height sin(ax) sin(ay) sin(az) of the object coordinates: math
    nodes, which every Blender evaluates alike (the Noise texture's output changed in 4.0)."""
    m, bsdf = diffuse_material("bumpy")
    nodes, links = m.node_tree.nodes, m.node_tree.links
    coord = nodes.new("ShaderNodeTexCoord")
    xyz = nodes.new("ShaderNodeSeparateXYZ")
    links.new(coord.outputs["Object"], xyz.inputs["Vector"])
    height = None
    for axis in "XYZ":
        scaled = nodes.new("ShaderNodeMath")
        scaled.operation = "MULTIPLY"
        scaled.inputs[1].default_value = BUMP_FREQUENCY
        links.new(xyz.outputs[axis], scaled.inputs[0])
        wave = nodes.new("ShaderNodeMath")
        wave.operation = "SINE"
        links.new(scaled.outputs["Value"], wave.inputs[0])
        if height is None:
            height = wave
        else:
            product = nodes.new("ShaderNodeMath")
            product.operation = "MULTIPLY"
            links.new(height.outputs["Value"], product.inputs[0])
            links.new(wave.outputs["Value"], product.inputs[1])
            height = product
    bump = nodes.new("ShaderNodeBump")
    bump.inputs["Strength"].default_value = 1.0
    bump.inputs["Distance"].default_value = BUMP_DISTANCE
    links.new(height.outputs["Value"], bump.inputs["Height"])
    links.new(bump.outputs["Normal"], bsdf.inputs["Normal"])
    return m


def normal_map_material(image, uv_name):
    """Diffuse like bumpy_material: the NORMAL bake averages its closures' normals, and Principled's
    specular closures bend theirs where the mirror direction would leave the surface (Cycles'
    ensure_valid_specular_reflection; in 4.2+ it moves some texels here by up to 19 degrees), which
    is no part of the tangent-space round trip."""
    m, bsdf = diffuse_material("normal_mapped")
    nodes, links = m.node_tree.nodes, m.node_tree.links
    tex = nodes.new("ShaderNodeTexImage")
    tex.image = image
    tex.interpolation = "Closest"
    nmap = nodes.new("ShaderNodeNormalMap")
    nmap.space = "TANGENT"
    nmap.uv_map = uv_name
    links.new(tex.outputs["Color"], nmap.inputs["Color"])
    links.new(nmap.outputs["Normal"], bsdf.inputs["Normal"])
    return m


def cycles_frame_normal():
    """The frame normal of Cycles' Normal Map node (tangent space) in this Blender: the barycentric
    interpolation of the corner normals, as is, up to 5.0; normalized first from 5.1 on (up to 14.5
    degrees apart on Suzanne's curved low-poly ears)."""
    return FRAME_NORMAL_UNIT if blender_compat.normal_map_normalizes_normal() else FRAME_NORMAL_INTERPOLATED


def round_trip(lib, obj, arrays, original, rule):
    """O -> T by ndfbake (frame normal `rule`), T rendered through the Normal Map node and baked back
    to object space: (rendered, its bake mask, ndfbake's coverage, ndfb_tangent_to_object(T))."""
    tangent_map, coverage = lib.convert(arrays, original, SIZE, SIZE, to_tangent=True, padding=4, frame_normal=rule)
    back, _ = lib.convert(arrays, tangent_map, SIZE, SIZE, to_tangent=False, padding=0, frame_normal=rule)
    tangent_image = float_image("tangent_space")
    rgba = np.ones((SIZE, SIZE, 4), dtype=np.float32)
    rgba[..., :3] = tangent_map * 0.5 + 0.5
    tangent_image.pixels.foreach_set(rgba[::-1].reshape(-1))
    rendered, baked_again = bake_object_normals(obj, normal_map_material(tangent_image, obj.data.uv_layers.active.name),
                                                float_image("object_space_again"))
    return rendered, baked_again, coverage, back


def interior(mask, radius):
    """Texels whose (2 radius + 1)^2 neighbourhood is entirely inside `mask`."""
    out = mask.copy()
    for dy in range(-radius, radius + 1):
        for dx in range(-radius, radius + 1):
            shifted = np.zeros_like(mask)
            ys = slice(max(dy, 0), SIZE + min(dy, 0))
            yd = slice(max(-dy, 0), SIZE + min(-dy, 0))
            xs = slice(max(dx, 0), SIZE + min(dx, 0))
            xd = slice(max(-dx, 0), SIZE + min(-dx, 0))
            shifted[yd, xd] = mask[ys, xs]
            out &= shifted
    return out


def angles_degrees(a, b):
    """Angle between unit vectors, in float64 via atan2: arccos of a float32 dot product cannot
    resolve angles below ~0.02 degrees."""
    a, b = a.astype(np.float64), b.astype(np.float64)
    return np.degrees(np.arctan2(np.linalg.norm(np.cross(a, b), axis=-1), np.sum(a * b, axis=-1)))


def main():
    lib, _ = library_from_argv()
    me = mirrored_suzanne(True)
    obj = bpy.context.object
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = 1
    scene.cycles.use_denoising = False  # Debian's Blender has no OpenImageDenoise: baking would fail
    obj.select_set(True)
    bpy.context.view_layer.objects.active = obj

    original, baked = bake_object_normals(obj, bumpy_material(), float_image("object_space"))

    blender_compat.ensure_loop_normals(me)
    arrays = MeshArrays.from_blender(me)
    rule = cycles_frame_normal()
    other_rule = FRAME_NORMAL_INTERPOLATED if rule == FRAME_NORMAL_UNIT else FRAME_NORMAL_UNIT
    rendered, baked_again, coverage, back = round_trip(lib, obj, arrays, original, rule)
    rendered_other, _, _, _ = round_trip(lib, obj, arrays, original, other_rule)

    # How much the map itself bends the normals: the round trip must do much better than that.
    plain = bpy.data.materials.new("plain")
    blender_compat.enable_nodes(plain)
    surface, _ = bake_object_normals(obj, plain, float_image("plain_normals"))
    detail = angles_degrees(original, surface)
    below_horizon = detail >= HORIZON_DEGREES
    inside = (coverage == 1) & baked & baked_again
    inner = interior(inside, 1)
    away = inner & ~below_horizon
    error = angles_degrees(original, rendered)
    error_other = angles_degrees(original, rendered_other)
    inverse = angles_degrees(original, back / np.maximum(np.linalg.norm(back, axis=-1, keepdims=True), 1e-12))
    print("texels: %d baked, %d rasterized by ndfbake, %d away from island borders" % (
        int(baked.sum()), int((coverage == 1).sum()), int(away.sum())))
    print("normal map detail (angle to the unmapped normal): mean %.2f deg, max %.2f deg; %d texels at or past "
          "the horizon (>= %.0f deg) left out" % (float(detail[away].mean()), float(detail[away].max()),
                                                 int((inner & below_horizon).sum()), HORIZON_DEGREES))
    print("ndfb_tangent_to_object(ndfb_object_to_tangent(O)) vs O: max %.2e deg" % float(inverse[coverage == 1].max()))
    border = inside & ~inner & ~below_horizon
    print("round trip through Blender's Normal Map node (Cycles), frame normal %s: %d texels away from island "
          "borders: max %.3f deg, mean %.4f deg; %d border texels: median %.3f deg, %d over 1 deg (texel centres near "
          "an edge that the two rasterizers give to different triangles, or UVs that overlap)" % (
              RULE_NAMES[rule], int(away.sum()), float(error[away].max()), float(error[away].mean()),
              int(border.sum()), float(np.median(error[border])), int((error[border] > 1.0).sum())))
    print("the other frame normal (%s), the negative control: max %.3f deg, mean %.4f deg" % (
        RULE_NAMES[other_rule], float(error_other[away].max()), float(error_other[away].mean())))
    failures = []
    if away.sum() < 0.3 * (coverage == 1).sum():
        failures.append("too few texels compared")
    if detail[away].mean() < 5.0:
        failures.append("the test map has too little detail to tell anything")
    if float(inverse[coverage == 1].max()) > 1e-3:
        failures.append("ndfb_tangent_to_object is not the inverse of ndfb_object_to_tangent")
    if float(error[away].max()) >= LIMIT_DEGREES:
        failures.append("round trip error %.3f deg >= %.1f deg" % (float(error[away].max()), LIMIT_DEGREES))
    if float(error_other[away].max()) < CONTROL_DEGREES:
        failures.append("the other frame normal renders within %.1f deg too (max %.3f): the mesh no longer tells the "
                        "two rules apart" % (CONTROL_DEGREES, float(error_other[away].max())))
    if failures:
        print("FAILURES:\n  " + "\n  ".join(failures))
        exit_now(1)
    print("round trip passed")


if __name__ == "__main__":
    main()
    exit_now(0)
