"""The demo scene of examples/demo_scene.py, built from code: the add-on and library of this
checkout (import_addon), the normal maps the library synthesizes, the materials, Blender's studio
world turned so that its brightest spot lies ahead, and build_scene(), which saves it as
DIR/demo_scene.blend. demo_scene.py's docstring describes the scene and its figures.

May call: bpy, numpy, ndfbake (native, blender_compat; after import_addon). Called by
demo_scene.py, demo_render.py (eevee_engine), the other examples and
tests/blender/test_addon_image_error.py.
"""
import math
import os
import sys

sys.dont_write_bytecode = True  # no __pycache__ in examples/ or addon/

import bpy  # noqa: E402
import numpy as np  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.normpath(os.path.join(HERE, ".."))

WORLDS = bpy.utils.system_resource("DATAFILES", path="studiolights/world")  # Blender's studio worlds: <name>.exr
DEFAULT_WORLD = "interior"
BLEND_NAME = "demo_scene.blend"
MAP_SIZE = 256
CAMERA_LOCATION = (0.0, -1.0, 1.1)
CAMERA_PITCH_DOWN = 5.0          # degrees below the horizon
CAMERA_LENS = 40.0               # mm on a 36 mm sensor: 48.5 degrees across
SUN_AZIMUTH = 4.0               # degrees right of the view direction: the world's brightest spot (its sun)
GROUND = dict(name="Ground", pattern="bumps", seed=3, roughness=0.2, color=(0.82, 0.82, 0.84),
              size=(30.0, 60.0), start=-2.0, tile=1.0)
# (object, material, pattern, seed, roughness, base colour, (x, y), radius); all metallic, UV tiles 0.5 m
SPHERES = [
    ("Sphere Near", "Copper Weave", "weave", 5, 0.25, (0.95, 0.64, 0.54), (-0.5, 3.0), 0.35),
    ("Sphere Middle", "Gold Grooves", "vgroove", 6, 0.2, (1.0, 0.78, 0.34), (2.2, 8.0), 0.6),
    ("Sphere Far", "Silver Hammered", "fbm", 7, 0.15, (0.95, 0.93, 0.88), (-2.5, 18.0), 1.0),
    ("Sphere Farthest", "Steel Bumps", "bumps", 8, 0.2, (0.78, 0.79, 0.80), (-9.0, 30.0), 1.5),
]
SPHERE_TILE = 0.5
FAR_SPHERES = ("Sphere Far", "Sphere Farthest")
EXPOSURE = -1.5                  # stops, for the PNGs (Filmic); the EXRs are scene-linear


# ---- the add-on and the library -------------------------------------------------------------------

def import_addon(library=None):
    """This checkout's addon/ndfbake, with NDFBAKE_LIBRARY set to `library` (or left as it is, or
    build/native/libndfbake.so)."""
    if library:
        os.environ["NDFBAKE_LIBRARY"] = os.path.abspath(library)
    elif not os.environ.get("NDFBAKE_LIBRARY"):
        os.environ["NDFBAKE_LIBRARY"] = os.path.join(REPO, "build", "native", "libndfbake.so")
    parent = os.path.join(REPO, "addon")
    if parent not in sys.path:
        sys.path.insert(0, parent)
    import ndfbake
    return ndfbake


def eevee_engine():
    """EEVEE's engine id in this Blender (the add-on's blender_compat; import_addon first)."""
    from ndfbake.shading import blender_compat
    return blender_compat.eevee_engine()


def enable_nodes(id_with_nodes):
    """Gives a material or world its node tree in this Blender (blender_compat; import_addon first)."""
    from ndfbake.shading import blender_compat
    return blender_compat.enable_nodes(id_with_nodes)


def write_normal_map(path, pattern="bumps", size=64, seed=3):
    """A synthetic tangent-space normal map saved by the library (8-bit PNG for .png), or by
    Blender where the library writes no image files (the add-on's, in a Blender without Debian
    12's OpenImageIO: the Blender tests in the Debian 13 chroot)."""
    from ndfbake.core import native, native_abi
    with native.load().context() as ctx:
        with ctx.synthesize(pattern, size, size, seed) as normal_map:
            try:
                normal_map.save(path)
            except native.Error as e:
                if e.status != native_abi.ERROR_UNSUPPORTED_FORMAT or not path.endswith(".png"):
                    raise
                save_normals_png(normal_map.read(), path)
    return path


def save_normals_png(normals, path):
    """Unit normals ((height, width, 3), rows top to bottom) as an 8-bit PNG written by Blender: for
    a library that writes no image files (the add-on's)."""
    height, width, _ = normals.shape
    image = bpy.data.images.new("ndfb-normals", width, height, alpha=False)
    rgba = np.ones((height, width, 4), dtype=np.float32)
    rgba[..., :3] = normals[::-1] * 0.5 + 0.5  # Blender's rows run bottom to top
    image.pixels.foreach_set(rgba.ravel())
    image.filepath_raw = path
    image.file_format = "PNG"
    image.save()
    bpy.data.images.remove(image)
    return path


# ---- the scene ------------------------------------------------------------------------------------

def normal_mapped_material(name, image_path, roughness, color, metallic=1.0):
    """Image Texture (Non-Color, Linear) -> Normal Map (tangent) -> Principled BSDF -> Material Output."""
    material = bpy.data.materials.new(name)
    enable_nodes(material)
    tree = material.node_tree
    principled = tree.nodes["Principled BSDF"]
    principled.inputs["Base Color"].default_value = tuple(color) + (1.0,)
    principled.inputs["Metallic"].default_value = metallic
    principled.inputs["Roughness"].default_value = roughness
    texture = tree.nodes.new("ShaderNodeTexImage")
    texture.name = texture.label = "Normal Texture"
    texture.location = (-700, -300)
    image = bpy.data.images.load(image_path, check_existing=True)
    image.colorspace_settings.name = "Non-Color"
    texture.image = image
    texture.interpolation = "Linear"
    normal_map = tree.nodes.new("ShaderNodeNormalMap")
    normal_map.location = (-400, -300)
    normal_map.space = "TANGENT"
    tree.links.new(texture.outputs["Color"], normal_map.inputs["Color"])
    tree.links.new(normal_map.outputs["Normal"], principled.inputs["Normal"])
    return material


def _scale_uvs(mesh, su, sv):
    uv = mesh.uv_layers.active.data
    coords = np.empty(len(uv) * 2, dtype=np.float32)
    uv.foreach_get("uv", coords)
    coords[0::2] *= su
    coords[1::2] *= sv
    uv.foreach_set("uv", coords)


def _sun_longitude(image):
    """u of the brightest pixel of an equirectangular image (Blender's pixel rows start at the bottom)."""
    w, h = image.size
    px = np.empty(w * h * 4, dtype=np.float32)
    image.pixels.foreach_get(px)
    lum = px.reshape(h, w, 4)[..., :3] @ np.array([0.2126, 0.7152, 0.0722], dtype=np.float32)
    _, x = np.unravel_index(int(np.argmax(lum)), lum.shape)
    return (x + 0.5) / w


def world_names():
    return sorted(name[:-4] for name in os.listdir(WORLDS) if name.endswith(".exr"))


def add_world_option(parser, **kwargs):
    """--world: one of Blender's studio worlds (world_names()), DEFAULT_WORLD unless given."""
    parser.add_argument("--world", default=DEFAULT_WORLD, choices=world_names(), **kwargs)


def script_arguments(parser):
    """`parser`'s arguments from what follows "--" on the command line (`blender -b --python
    script.py -- ...` or `python script.py -- ...`); none without "--"."""
    return parser.parse_args(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else [])


def studio_world(scene, name):
    world = bpy.data.worlds.new(name.capitalize())
    enable_nodes(world)
    tree = world.node_tree
    background = tree.nodes["Background"]
    coords = tree.nodes.new("ShaderNodeTexCoord")
    mapping = tree.nodes.new("ShaderNodeMapping")
    env = tree.nodes.new("ShaderNodeTexEnvironment")
    env.image = bpy.data.images.load(os.path.join(WORLDS, name + ".exr"), check_existing=True)
    # Blender's equirectangular lookup: u = 0.5 - atan2(y, x) / 2pi. Rotate the world about Z so
    # that the sun (the brightest spot: interior's is a ceiling light) lies SUN_AZIMUTH degrees
    # right of the camera's +Y view direction.
    sun_u = _sun_longitude(env.image)
    want = math.radians(90.0 - SUN_AZIMUTH)          # atan2(y, x) of the wanted direction
    have = (0.5 - sun_u) * 2.0 * math.pi             # atan2(y, x) the image puts the sun at
    mapping.inputs["Rotation"].default_value = (0.0, 0.0, have - want)
    tree.links.new(coords.outputs["Generated"], mapping.inputs["Vector"])
    tree.links.new(mapping.outputs["Vector"], env.inputs["Vector"])
    tree.links.new(env.outputs["Color"], background.inputs["Color"])
    scene.world = world
    return world


def fresh_scene(directory, width=320, height=180, world=DEFAULT_WORLD):
    """build_scene in an empty file with this checkout's add-on imported, after deleting the lobe
    folders an earlier run left in `directory` (nobody's now: left, the new bakes would go to
    '<material>~2.ndfbake'). Returns build_scene's info."""
    os.makedirs(directory, exist_ok=True)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    import_addon()
    from ndfbake.core import folder_names
    from ndfbake.blender import lobe_folders
    lobe_folders.delete_folders([os.path.join(directory, name) for name in sorted(os.listdir(directory))
                                 if name.endswith(folder_names.FOLDER_SUFFIX)])
    return build_scene(directory, width, height, world=world)


def build_scene(directory, width=320, height=180, map_size=MAP_SIZE, world=DEFAULT_WORLD):
    """Builds the demo scene in the current (empty) file, lit by Blender's studio world `world`,
    and saves it as DIR/demo_scene.blend.
    Returns {"blend", "materials" (the normal-mapped ones rendered), "far_spheres", "ground"}."""
    scene = bpy.context.scene
    maps = os.path.join(directory, "maps")
    os.makedirs(maps, exist_ok=True)

    def map_path(pattern, seed):
        return write_normal_map(os.path.join(maps, "%s-%d.png" % (pattern, seed)), pattern, map_size, seed)

    # Ground: a plane (x across, y away from the camera), its UVs tiled every GROUND["tile"] metres.
    ground_material = normal_mapped_material(GROUND["name"], map_path(GROUND["pattern"], GROUND["seed"]),
                                             GROUND["roughness"], GROUND["color"])
    bpy.ops.mesh.primitive_plane_add(size=1.0)
    ground = bpy.context.active_object
    ground.name = ground.data.name = GROUND["name"]
    sx, sy = GROUND["size"]
    for v in ground.data.vertices:
        v.co.x *= sx
        v.co.y = v.co.y * sy + GROUND["start"] + sy / 2
    _scale_uvs(ground.data, sx / GROUND["tile"], sy / GROUND["tile"])
    ground.data.materials.append(ground_material)

    materials = [ground_material]
    for obj_name, mat_name, pattern, seed, roughness, color, (x, y), radius in SPHERES:
        material = normal_mapped_material(mat_name, map_path(pattern, seed), roughness, color)
        bpy.ops.mesh.primitive_uv_sphere_add(segments=64, ring_count=32, radius=radius, location=(x, y, radius))
        obj = bpy.context.active_object
        obj.name = obj.data.name = obj_name
        bpy.ops.object.shade_smooth()
        _scale_uvs(obj.data, max(1, round(2 * math.pi * radius / SPHERE_TILE)),
                   max(1, round(math.pi * radius / SPHERE_TILE)))
        obj.data.materials.append(material)
        materials.append(material)

    # What a bake must leave alone: a plain material on a rendered object, a normal-mapped one on none.
    plain = bpy.data.materials.new("Plain Paint")
    enable_nodes(plain)
    plain.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (0.05, 0.12, 0.35, 1.0)
    plain.node_tree.nodes["Principled BSDF"].inputs["Roughness"].default_value = 0.45
    bpy.ops.mesh.primitive_cube_add(size=0.5, location=(-1.9, 5.5, 0.25), rotation=(0.0, 0.0, 0.5))
    bpy.context.active_object.name = "Marker"
    bpy.context.active_object.data.materials.append(plain)
    spare = normal_mapped_material("Spare Scratches", map_path("scratches", 9), 0.3, (0.9, 0.9, 0.9))
    spare.use_fake_user = True

    bpy.ops.object.camera_add(location=CAMERA_LOCATION, rotation=(math.radians(90.0 - CAMERA_PITCH_DOWN), 0.0, 0.0))
    camera = bpy.context.active_object
    camera.name = "Camera"
    camera.data.lens = CAMERA_LENS
    camera.data.clip_end = 500.0
    scene.camera = camera
    studio_world(scene, world)

    scene.render.resolution_x, scene.render.resolution_y = int(width), int(height)
    scene.render.resolution_percentage = 100
    scene.render.film_transparent = False
    scene.view_settings.view_transform = "Filmic"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = EXPOSURE
    scene.view_settings.gamma = 1.0
    scene.cycles.device = "CPU"
    scene.cycles.use_denoising = False          # Debian's Blender has no OpenImageDenoise
    scene.cycles.use_adaptive_sampling = False  # every pixel gets exactly the samples asked for
    scene.cycles.max_bounces = 4
    scene.frame_set(1)

    blend = os.path.join(directory, BLEND_NAME)
    bpy.ops.wm.save_as_mainfile(filepath=blend)
    return {"blend": blend, "materials": [m.name for m in materials], "far_spheres": list(FAR_SPHERES),
            "ground": GROUND["name"]}
