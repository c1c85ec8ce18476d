"""What a scene needs of a baked material: the MIP levels its cameras reach, and the constants from
which the node group picks a level per shading point.

Cycles has no MIP levels and shader nodes see no screen derivatives (DESIGN.md), but they see the
distance to the camera and the angle of view. The node group ("NDFB Level of Detail") computes

    footprint = (d·pixel_angle + pixel_size) · texels_per_unit / max(|cos θ|, MIN_FACING)^STRETCH
    level     = clamp(log2(footprint), 0, levels − 1)

the side, in texels of the normal map, of the square a pixel covers on the surface: d is the
distance to the camera; pixel_angle the angle a pixel's long side subtends (a perspective camera)
and pixel_size its length (an orthographic one; the pixel aspect makes pixels non-square);
texels_per_unit the UV texel density from the library's tangent module (ndfb_texel_density,
world space, times the map's size); θ the angle between the view ray and the surface, which
stretches the footprint by 1/cos θ along one axis.
STRETCH = 1 takes that long axis: the texel then holds every normal the pixel sees, so a few
samples per pixel (Cycles) see one distribution instead of glints from texel to texel, at the
price of a wider distribution across the short axis, which for the statistically uniform
normal maps of materials is the same distribution. (STRETCH = 0.5, the geometric mean of the
axes, gave the same image errors on the demo scene at 128×72, under sunset with 4 lobes.)

The same formula over the vertices of every object that renders the material, seen from every
camera in the scene, gives the levels the bake must fit: up to the ceiling of the largest level
plus one for the blend between two levels.

A Mapping node between the UV map and the texture (tiling) scales texels_per_unit by how often
the texture repeats per unit of UV, measured on the UV map the texture reads (texture_uv). Where
the texture coordinates come from anything else (Generated, Object, math nodes) the density is
unknown, and the bake leaves the level of detail to the renderer.
"""
from __future__ import annotations  # np.ndarray in annotations: registering needs no NumPy

import math
from dataclasses import dataclass

import bpy

try:
    import numpy as np
except ImportError:  # native.status() says so in the panel; nothing here runs without the library
    np = None

from ..core import native
from . import material_scan

# Grazing views stretch the footprint without bound; past 1/64 (an 89° view) the stretch is
# capped (at 64×, six levels, with STRETCH = 1) so that silhouettes keep some detail.
MIN_FACING = 1.0 / 64.0
STRETCH = 1.0


@dataclass
class CameraFootprint:
    location: tuple              # world position of the camera
    pixel_angle: float           # radians per pixel (perspective), 0 for orthographic
    pixel_size: float            # world units per pixel (orthographic), 0 for perspective
    clip_end: float


@dataclass
class LodPlan:
    """A material's level of detail for a bake: the levels to fit, and the footprint constants
    of its node group."""
    levels: int
    texels_per_unit: float
    pixel_angle: float
    pixel_size: float
    footprint_max: float


@dataclass
class MaterialLod:
    texels_per_unit: float       # map texels per world unit on the material's surfaces
    levels: int                  # levels the scene's cameras reach (0: no camera sees it)
    footprint_max: float         # largest footprint in texels over the material's vertices


def _sensor_fit(cam):
    """(sensor property, the side it spans: "larger", "width" or "height"). AUTO spans the sensor
    width (and the orthographic scale) over the larger side."""
    if cam.sensor_fit == "AUTO":
        return "sensor_width", "larger"
    if cam.sensor_fit == "HORIZONTAL":
        return "sensor_width", "width"
    return "sensor_height", "height"


def camera_footprint(scene, camera_object):
    """The pixel footprint of a camera at the scene's render resolution: the long side of a pixel
    (non-square pixels: the pixel aspect stretches one side), as STRETCH = 1 takes the long axis."""
    render = scene.render
    scale = render.resolution_percentage / 100.0
    aspect_x, aspect_y = render.pixel_aspect_x, render.pixel_aspect_y
    # The sensor spans the chosen side in units of pixels times their aspect; a pixel's long side
    # is max(aspect) such units.
    width = render.resolution_x * scale * aspect_x
    height = render.resolution_y * scale * aspect_y
    cam = camera_object.data
    sensor, side = _sensor_fit(cam)
    units = max(1.0, {"larger": max(width, height), "width": width, "height": height}[side] / max(aspect_x, aspect_y))
    location = tuple(camera_object.matrix_world.translation)
    if cam.type == "ORTHO":
        return CameraFootprint(location, 0.0, cam.ortho_scale / units, cam.clip_end)
    if cam.type == "PANO":
        # No single focal length: the angle a pixel subtends over the camera's field of view.
        return CameraFootprint(location, 2.0 * math.pi / units, 0.0, cam.clip_end)
    return CameraFootprint(location, getattr(cam, sensor) / max(cam.lens, 1e-3) / units, 0.0, cam.clip_end)


# camera_footprint's sensor and units as a driver's simple expression: `fit` is the sensor fit's
# enum index (AUTO 0, HORIZONTAL 1, VERTICAL 2), so that changing the fit after a bake is followed.
_SENSOR_EXPRESSION = "(sh if fit == 2 else sw)"
_UNITS_EXPRESSION = ("((max(resx * ax, resy * ay) if fit == 0 else (resx * ax if fit == 1 else resy * ay))"
                     " * pct / 100 / max(ax, ay))")


def footprint_driver(camera_object):
    """How a driver recomputes camera_footprint as the camera (lens, sensor size and fit, scale)
    and the resolution (size, percentage, pixel aspect) change: (the group input it drives, a
    simple expression, [(variable, "CAMERA" or "SCENE", property path)]), or None for a panoramic
    camera."""
    cam = camera_object.data
    if cam.type not in {"PERSP", "ORTHO"}:
        return None
    variables = [("fit", "CAMERA", "sensor_fit"),
                 ("resx", "SCENE", "render.resolution_x"), ("resy", "SCENE", "render.resolution_y"),
                 ("ax", "SCENE", "render.pixel_aspect_x"), ("ay", "SCENE", "render.pixel_aspect_y"),
                 ("pct", "SCENE", "render.resolution_percentage")]
    if cam.type == "PERSP":
        return ("Pixel Angle", "%s / max(lens, 0.001) / max(1, %s)" % (_SENSOR_EXPRESSION, _UNITS_EXPRESSION),
                [("sw", "CAMERA", "sensor_width"), ("sh", "CAMERA", "sensor_height"),
                 ("lens", "CAMERA", "lens")] + variables)
    return "Pixel Size", "size / max(1, %s)" % _UNITS_EXPRESSION, [("size", "CAMERA", "ortho_scale")] + variables


def scene_cameras(scene):
    """The footprints of every camera object in the scene, the active one first."""
    cameras = [scene.camera] if scene.camera is not None and scene.camera.type == "CAMERA" else []
    cameras += [o for o in scene.objects if o.type == "CAMERA" and o is not scene.camera]
    return [camera_footprint(scene, c) for c in cameras]


RENDERED_TYPES = {"MESH", "CURVE", "SURFACE", "META", "FONT"}


def rendered_objects(scene):
    """Mesh-like objects the scene renders: in a collection of a view layer it renders, through no
    excluded or render-disabled collection, and not disabled in renders themselves."""
    found = {}

    def visit(layer_collection):
        if layer_collection.exclude or layer_collection.collection.hide_render:
            return
        for obj in layer_collection.collection.objects:
            if not obj.hide_render and obj.type in RENDERED_TYPES:
                found.setdefault(obj.as_pointer(), obj)
        for child in layer_collection.children:
            visit(child)

    for view_layer in scene.view_layers:
        if view_layer.use:
            visit(view_layer.layer_collection)
    return list(found.values())


def objects_using(scene, material):
    """Objects the scene renders (rendered_objects) that have `material` in a slot."""
    return [obj for obj in rendered_objects(scene) if any(slot.material == material for slot in obj.material_slots)]


@dataclass
class _WorldMesh:
    positions: np.ndarray        # (n, 3) world space
    normals: np.ndarray          # (n, 3) world space, unit
    density: float               # UV units per world unit (ndfb_texel_density)
    area: float                  # world area


def _material_faces(obj, material, count, attribute):
    """Which of `count` faces (polygons or loop triangles, by their material_index) use `material`
    (an index past the last slot uses the last slot, as Blender renders it)."""
    slots = obj.material_slots
    index = np.empty(count, dtype=np.int32)
    attribute.foreach_get("material_index", index)
    mine = np.array([slot.material == material for slot in slots] or [True])
    return mine[np.clip(index, 0, len(mine) - 1)]


def _uv_layer(mesh, uv_map):
    """The UV map a node naming `uv_map` reads: that one, or with no name (or a missing one) the
    one active for rendering."""
    named = mesh.uv_layers.get(uv_map) if uv_map else None
    return named or next((layer for layer in mesh.uv_layers if layer.active_render), mesh.uv_layers.active)


def _world_mesh(obj, depsgraph, uv_map, material):
    """The faces of `obj` that render with `material`, in world space, with their texel density."""
    evaluated = obj.evaluated_get(depsgraph)
    mesh = evaluated.to_mesh()
    try:
        if mesh is None or not mesh.polygons or not mesh.uv_layers:
            return None
        layer = _uv_layer(mesh, uv_map)
        nv, nl = len(mesh.vertices), len(mesh.loops)
        faces = _material_faces(obj, material, len(mesh.polygons), mesh.polygons)
        nf = len(mesh.polygons)
        co = np.empty(nv * 3, dtype=np.float32)
        mesh.vertices.foreach_get("co", co)
        vn = np.empty(nv * 3, dtype=np.float32)
        mesh.vertices.foreach_get("normal", vn)
        sizes = np.empty(nf, dtype=np.uint32)
        mesh.polygons.foreach_get("loop_total", sizes)
        starts = np.empty(nf, dtype=np.int64)
        mesh.polygons.foreach_get("loop_start", starts)
        sizes, starts = sizes[faces], starts[faces]
        if not len(sizes):
            return None
        order = np.concatenate([np.arange(s, s + t) for s, t in zip(starts, sizes)])
        corners = np.empty(nl, dtype=np.uint32)
        mesh.loops.foreach_get("vertex_index", corners)
        uvs = np.empty(nl * 2, dtype=np.float32)
        layer.data.foreach_get("uv", uvs)
        matrix = np.array(evaluated.matrix_world, dtype=np.float64)
        world = co.reshape(-1, 3) @ matrix[:3, :3].T + matrix[:3, 3]
        normal_matrix = np.linalg.inv(matrix[:3, :3]).T if abs(np.linalg.det(matrix[:3, :3])) > 1e-12 else matrix[:3, :3]
        normals = vn.reshape(-1, 3) @ normal_matrix.T
        normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-12)
        corners, uvs = corners[order], uvs.reshape(-1, 2)[order]
        with native.load().context() as ctx:
            density = ctx.texel_density(world.astype(np.float32), sizes, corners, normals.astype(np.float32), uvs)
        mesh.calc_loop_triangles()
        tris = np.empty(len(mesh.loop_triangles) * 3, dtype=np.int64)
        mesh.loop_triangles.foreach_get("vertices", tris)
        tris = tris.reshape(-1, 3)[_material_faces(obj, material, len(mesh.loop_triangles), mesh.loop_triangles)]
        tri = world[tris]
        area = 0.5 * float(np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1).sum())
        used = np.unique(corners)  # the footprints: at the vertices of these faces only
        return _WorldMesh(world[used], normals[used], density, area)
    finally:
        evaluated.to_mesh_clear()


def footprints(positions, normals, camera, texels_per_unit):
    """The footprint in texels at each vertex seen from `camera` (NaN behind the camera)."""
    offset = positions - np.asarray(camera.location)
    distance = np.minimum(np.linalg.norm(offset, axis=1), camera.clip_end)
    facing = np.abs(np.einsum("ij,ij->i", offset, normals)) / np.maximum(distance, 1e-9)
    footprint = (distance * camera.pixel_angle + camera.pixel_size) * texels_per_unit
    return footprint / np.maximum(facing, MIN_FACING) ** STRETCH


def _mapping_repeat(node):
    """How many times a Mapping node repeats the texture in the UV plane (1 when muted), or None
    where its settings do not say (linked, rotated out of the plane, Vector or Normal type)."""
    if node.mute:
        return 1.0
    rotation = node.inputs["Rotation"]
    if node.vector_type not in ("POINT", "TEXTURE") or node.inputs["Scale"].is_linked or rotation.is_linked \
            or any(abs(a) > 1e-6 for a in rotation.default_value[:2]):
        return None
    sx, sy = node.inputs["Scale"].default_value[:2]
    scale = math.sqrt(abs(sx * sy))
    if not scale > 0.0:
        return None
    return scale if node.vector_type == "POINT" else 1.0 / scale


def texture_uv(texture):
    """(repeat, UV map) of an image texture node: which UV map it reads ("" for the one active
    for rendering: Vector unlinked or Texture Coordinate's UV; a UV Map node's name) and how many
    times its image repeats per unit of that map: the geometric mean of the x and y scale of each
    Mapping node on the way (divided for a Texture-type mapping, which moves the texture instead of
    the coordinates; muted ones pass the vector through; a muted link is no link, as in renders).
    None where the nodes do not say (other coordinates, a linked scale or rotation, a rotation out
    of the UV plane, math)."""
    node, output = material_scan.upstream(texture.inputs["Vector"])  # muted link: the texture's own UV
    repeat = 1.0
    while node is not None and node.bl_idname == "ShaderNodeMapping":
        factor = _mapping_repeat(node)
        if factor is None:
            return None
        repeat *= factor
        node, output = material_scan.upstream(node.inputs["Vector"])
        if node is None:  # unlinked or muted: the Mapping maps its Vector value, not UVs
            return None
    if node is None or (node.bl_idname == "ShaderNodeTexCoord" and output.name == "UV"):
        return repeat, ""
    if node.bl_idname == "ShaderNodeUVMap":
        return repeat, node.uv_map
    return None


def level_count(width, height):
    return int(math.floor(math.log2(max(width, height, 1)))) + 1


def material_lod(scene, material, image_size, uv_map="", repeat=1.0):
    """Texel density and the levels the scene's cameras reach, for a map of image_size (w, h)
    repeating `repeat` times per unit of UV (texture_uv)."""
    depsgraph = bpy.context.evaluated_depsgraph_get()
    meshes = [m for m in (_world_mesh(obj, depsgraph, uv_map, material) for obj in objects_using(scene, material)) if m]
    side = math.sqrt(max(1, image_size[0]) * max(1, image_size[1]))
    all_levels = level_count(*image_size)
    area = sum(m.area for m in meshes)
    if not meshes or area <= 0.0:
        return MaterialLod(texels_per_unit=0.0, levels=all_levels, footprint_max=float("nan"))
    # One density per material: the node group sees no object; weight each mesh by its area.
    uv_per_unit = sum(m.density * m.area for m in meshes) / area
    texels_per_unit = uv_per_unit * side * repeat
    cameras = scene_cameras(scene)
    if not cameras:
        return MaterialLod(texels_per_unit, all_levels, float("nan"))
    largest = max(float(np.max(footprints(m.positions, m.normals, c, texels_per_unit)))
                  for m in meshes for c in cameras)
    # Levels up to ceil(log2(largest)), plus the next one for the blend between two levels.
    needed = int(math.ceil(math.log2(max(largest, 1.0)))) + 2
    return MaterialLod(texels_per_unit, max(1, min(all_levels, needed)), largest)


def plan(scene, material, image_size, uv_map="", repeat=1.0):
    """(the LodPlan of `material` for its scene's active camera, ""), or (None, why not) where the
    scene gives no level of detail."""
    if scene.camera is None or scene.camera.type != "CAMERA":
        return None, "the scene has no active camera"
    needs = material_lod(scene, material, image_size, uv_map, repeat)
    if needs.texels_per_unit <= 0.0:
        return None, "no object the scene renders has UV area where it uses the material"
    camera = camera_footprint(scene, scene.camera)
    return LodPlan(levels=needs.levels, texels_per_unit=needs.texels_per_unit, pixel_angle=camera.pixel_angle,
                   pixel_size=camera.pixel_size, footprint_max=needs.footprint_max), ""
