"""Rendering and measuring the demo scene of examples/demo_scene.py: the plain renders (EEVEE
naive and its supersampled, point-sampled reference; Cycles reference and naive) and the baked
ones, EXR/PNG output, the regions found by casting rays through every pixel, the error tables
(examples/image_error.py) and the montage. demo_scene.py's docstring says how they are measured.

May call: bpy, numpy, image_error, demo_build (eevee_engine), ndfbake (blender_compat). Called by
demo_scene.py, the other examples and tests/blender/test_addon_image_error.py.
"""
import math
import os
import sys
import time

sys.dont_write_bytecode = True  # no __pycache__ in examples/ or addon/

import bpy  # noqa: E402
import numpy as np  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
if HERE not in sys.path:
    sys.path.insert(0, HERE)
import image_error  # noqa: E402
import demo_build  # noqa: E402
from demo_build import eevee_engine  # noqa: E402

FAR_GROUND = 8.0                 # metres from the camera: where the "far ground" region begins
# Samples of the Cycles reference's far band (converge_reference_band): at 256 spp its own noise
# was most of naive's 16-spp error on the far spheres under some worlds (city: 0.62 of 0.93), which
# holds ndfbake's ratio near 1 whatever the lobes do (docs/rendering.md, "Grazing views").
REFERENCE_BAND_SAMPLES = 4096
MAX_SUPERSAMPLED_WIDTH = 1024


# ---- rendering ------------------------------------------------------------------------------------

def read_exr(path):
    image = bpy.data.images.load(path, check_existing=False)
    try:
        w, h = image.size
        px = np.empty(w * h * 4, dtype=np.float32)
        image.pixels.foreach_get(px)
    finally:
        bpy.data.images.remove(image)
    return px.reshape(h, w, 4)[..., :3].copy()


def save_pixels(pixels, path, scene=None):
    """Linear RGB (rows bottom first, as Blender stores them) -> `path`: an .exr keeps the linear
    values (float 32), a .png goes through the scene's view transform (8-bit). Image.save_render
    does both; Image.save would write an EXR's floats sRGB-encoded even from a Linear image."""
    scene = scene or bpy.context.scene
    h, w = pixels.shape[:2]
    image = bpy.data.images.new("ndfb-demo-pixels", w, h, alpha=False, float_buffer=True)
    from ndfbake.shading import blender_compat
    image.colorspace_settings.name = blender_compat.linear_color_space()  # else saving would convert
    exr = path.lower().endswith(".exr")
    try:
        rgba = np.ones((h, w, 4), dtype=np.float32)
        rgba[..., :3] = pixels
        image.pixels.foreach_set(rgba.ravel())
        settings = scene.render.image_settings
        old = (settings.file_format, settings.color_mode, settings.color_depth)
        settings.file_format, settings.color_mode = ("OPEN_EXR" if exr else "PNG"), "RGB"
        settings.color_depth = "32" if exr else "8"
        try:
            image.save_render(path, scene=scene)
        finally:
            settings.file_format, settings.color_mode = old[0], old[1]
            settings.color_depth = old[2]
    finally:
        bpy.data.images.remove(image)
    return path


def render(scene, engine, path, samples, percentage=100, seed=0, border=None):
    """Renders the scene with `engine` into `path` (.exr, linear float) and returns its RGB pixels
    (H, W, 3), rows bottom first. border: (x0, x1, y0, y1) in [0, 1], y from the bottom (mask_border):
    only that part is rendered, the rest of the full-size image is black."""
    scene.render.engine = engine
    scene.render.resolution_percentage = percentage
    if engine == "CYCLES":
        scene.cycles.samples = samples
        scene.cycles.seed = seed
    else:
        scene.eevee.taa_render_samples = samples
    settings = scene.render.image_settings
    settings.file_format, settings.color_mode, settings.color_depth = "OPEN_EXR", "RGB", "32"
    scene.render.filepath = path
    scene.render.use_border = border is not None
    scene.render.use_crop_to_border = False
    if border is not None:
        (scene.render.border_min_x, scene.render.border_max_x,
         scene.render.border_min_y, scene.render.border_max_y) = border
    try:
        bpy.ops.render.render(write_still=True)
    finally:
        scene.render.resolution_percentage = 100
        scene.render.use_border = False
    return read_exr(path)


def mask_border(mask, margin=1):
    """The render border (x0, x1, y0, y1) around the pixels of `mask` (rows bottom first), `margin`
    pixels wider on each side: what render(border=...) takes."""
    rows, columns = np.nonzero(mask)
    height, width = mask.shape
    x0, x1 = max(columns.min() - margin, 0), min(columns.max() + 1 + margin, width)
    y0, y1 = max(rows.min() - margin, 0), min(rows.max() + 1 + margin, height)
    return (x0 / width, x1 / width, y0 / height, y1 / height)


def converge_reference_band(scene, directory, images, info, masks, regions=("ground_far", "spheres_far"),
                            samples=REFERENCE_BAND_SAMPLES, log=print):
    """Renders the band of the image that holds `regions` (mask_border) again in Cycles at `samples`
    and puts it into images["cycles_reference"] there; records the samples and the seconds in
    render_plain's `info` (format_errors' titles name them). Returns the band (render's border)."""
    band = mask_border(np.logical_or.reduce([masks[r] for r in regions]))
    start = time.perf_counter()
    pixels = render(scene, "CYCLES", os.path.join(directory, "cycles_reference_band.exr"), samples, seed=1,
                    border=band)
    width, height = scene.render.resolution_x, scene.render.resolution_y
    inside = np.zeros((height, width, 1), dtype=bool)
    inside[round(band[2] * height):round(band[3] * height), round(band[0] * width):round(band[1] * width)] = True
    images["cycles_reference"] = np.where(inside, pixels, images["cycles_reference"])
    info["seconds"]["cycles_reference_band"] = round(time.perf_counter() - start, 2)
    info["cycles_reference_band_samples"] = samples
    log("  rendered the reference's far band at %d spp in %.1f s"
        % (samples, info["seconds"]["cycles_reference_band"]))
    return band


def normal_map_textures(material):
    """The Image Texture nodes whose Color feeds a Normal Map node."""
    found = []
    for link in material.node_tree.links:
        if link.to_node.bl_idname == "ShaderNodeNormalMap" and link.from_node.bl_idname == "ShaderNodeTexImage":
            found.append(link.from_node)
    return found


def set_normal_interpolation(material_names, interpolation):
    """Sets the interpolation of the normal-map textures of the materials; `interpolation` is one
    value or a {(material, node): value} as returned (the previous values)."""
    previous = {}
    for name in material_names:
        for node in normal_map_textures(bpy.data.materials[name]):
            previous[(name, node.name)] = node.interpolation
            node.interpolation = interpolation if isinstance(interpolation, str) else interpolation[(name, node.name)]
    return previous


def supersampling_factor(width, most=8):
    """8, or less so that the supersampled render is at most MAX_SUPERSAMPLED_WIDTH pixels wide."""
    return max(1, min(most, MAX_SUPERSAMPLED_WIDTH // int(width)))


def reference_taa_samples(factor, per_pixel=1024):
    """EEVEE TAA samples of the supersampled render: about `per_pixel` point samples of the map
    per final pixel (16 at 8 x 8), at least 16."""
    return max(16, int(math.ceil(per_pixel / float(factor * factor))))


def render_eevee_reference(scene, materials, path, factor, samples):
    """EEVEE's reference: the scene at factor x factor the resolution with the materials' normal
    maps point-sampled (Closest: no MIP-mapping), box-downsampled; the big render at `path` is
    deleted again."""
    previous = set_normal_interpolation(materials, "Closest")
    try:
        big = render(scene, eevee_engine(), path, samples, percentage=100 * factor)
    finally:
        set_normal_interpolation(materials, previous)
    os.remove(path)
    return image_error.box_downsample(big, factor)


def render_plain(scene, directory, materials, reference_samples=256, samples=16, eevee_samples=64,
                 eevee_reference_samples=None, log=print):
    """The renders of the unbaked scene: {name: pixels}, and their timings and settings in `info`."""
    os.makedirs(directory, exist_ok=True)
    images, info = {}, {"seconds": {}}

    def timed(name, fn):
        start = time.perf_counter()
        images[name] = fn()
        info["seconds"][name] = round(time.perf_counter() - start, 2)
        log("  rendered %-18s %dx%d in %.1f s" % (name, images[name].shape[1], images[name].shape[0],
                                                  info["seconds"][name]))

    timed("eevee_naive", lambda: render(scene, eevee_engine(), os.path.join(directory, "eevee_naive.exr"),
                                        eevee_samples))
    factor = supersampling_factor(scene.render.resolution_x)
    eevee_reference_samples = eevee_reference_samples or reference_taa_samples(factor)
    timed("eevee_reference", lambda: render_eevee_reference(
        scene, materials, os.path.join(directory, "eevee_reference_%dx.exr" % factor), factor,
        eevee_reference_samples))  # the downsampled one is kept (written below)
    save_pixels(images["eevee_reference"], os.path.join(directory, "eevee_reference.exr"), scene)
    info["eevee_reference"] = {"factor": factor, "taa_samples": eevee_reference_samples,
                               "interpolation": "Closest"}
    timed("cycles_reference", lambda: render(scene, "CYCLES", os.path.join(directory, "cycles_reference.exr"),
                                             reference_samples, seed=1))
    timed("cycles_naive", lambda: render(scene, "CYCLES", os.path.join(directory, "cycles_naive.exr"), samples))
    info.update(eevee_samples=eevee_samples, cycles_reference_samples=reference_samples, cycles_samples=samples)
    return images, info


def render_baked(scene, directory, samples=16, eevee_samples=64, log=print):
    images, seconds = {}, {}
    for name, engine, path, n in (("eevee_ndfbake", eevee_engine(), "eevee_ndfbake.exr", eevee_samples),
                                  ("cycles_ndfbake", "CYCLES", "cycles_ndfbake.exr", samples)):
        start = time.perf_counter()
        images[name] = render(scene, engine, os.path.join(directory, path), n)
        seconds[name] = round(time.perf_counter() - start, 2)
        log("  rendered %-18s %dx%d in %.1f s" % (name, images[name].shape[1], images[name].shape[0], seconds[name]))
    return images, {"seconds": seconds}


# ---- regions --------------------------------------------------------------------------------------

def pixel_hits(scene, width, height, sub=2):
    """For every pixel (rows bottom first) and each of sub x sub rays through it: the object hit
    (index into the returned names; -1 for none) and the distance. Shapes (H, W, sub*sub)."""
    camera = scene.camera
    depsgraph = bpy.context.evaluated_depsgraph_get()
    tr, br, bl, tl = [np.array(v) for v in camera.data.view_frame(scene=scene)]
    matrix = np.array(camera.matrix_world)
    origin = matrix[:3, 3]
    offsets = (np.arange(sub) + 0.5) / sub
    u = (np.arange(width)[None, :, None, None] + offsets[None, None, None, :]) / width     # (1, W, 1, sub)
    v = (np.arange(height)[:, None, None, None] + offsets[None, None, :, None]) / height   # (H, 1, sub, 1)
    points = bl + (br - bl) * u[..., None] + (tl - bl) * v[..., None]                       # (H, W, sub, sub, 3)
    directions = points @ matrix[:3, :3].T
    directions /= np.linalg.norm(directions, axis=-1, keepdims=True)
    directions = directions.reshape(height, width, sub * sub, 3)
    names, index = [], {}
    hit = np.full((height, width, sub * sub), -1, dtype=np.int32)
    distance = np.full((height, width, sub * sub), np.inf)
    from mathutils import Vector
    o = Vector(origin)
    for y in range(height):
        for x in range(width):
            for k in range(sub * sub):
                ok, location, _, _, obj, _ = scene.ray_cast(depsgraph, o, Vector(directions[y, x, k]))
                if ok:
                    name = obj.name
                    if name not in index:
                        index[name] = len(names)
                        names.append(name)
                    hit[y, x, k] = index[name]
                    distance[y, x, k] = (location - o).length
    return names, hit, distance


def study_scene(directory, world):
    """demo_build's scene at the image-error test's 128x72 under `world`, built afresh in
    `directory`, as the EEVEE studies measure it: (its fresh_scene info, the scene, region_masks)."""
    info = demo_build.fresh_scene(directory, 128, 72, world=world)
    scene = bpy.context.scene
    return info, scene, region_masks(scene, info["ground"], info["far_spheres"])


def region_masks(scene, ground, far_spheres, far_ground=FAR_GROUND, sub=2):
    """Bool masks (H, W), rows bottom first, of the pixels all of whose sub x sub rays hit
    "ground_far": the ground at `far_ground` metres or more; "spheres_far": one of `far_spheres`;
    "all": anything (not the sky); "ground_near": the ground nearer than `far_ground` (for
    information: little to filter there). Each is eroded by one pixel (the renders' pixel filters
    reach into the neighbours)."""
    width, height = scene.render.resolution_x, scene.render.resolution_y
    names, hit, distance = pixel_hits(scene, width, height, sub)

    def ids(wanted):
        return [names.index(n) for n in wanted if n in names]

    def every(ids_, extra=None):
        inside = np.isin(hit, ids_)
        if extra is not None:
            inside &= extra
        return image_error.erode(inside.all(axis=-1), 1)

    return {"ground_far": every(ids([ground]), distance >= far_ground),
            "spheres_far": every(ids(far_spheres)),
            "all": every(list(range(len(names)))),
            "ground_near": every(ids([ground]), distance < far_ground)}


# ---- error ----------------------------------------------------------------------------------------

# The figures: (table, engine whose renders are measured, reference image). "eevee_cycles" measures
# EEVEE against the Cycles reference, the ground truth of ../shared/DESIGN.md: EEVEE Next's own
# supersampled render of the fine normals loses much of what they reflect (docs/rendering.md,
# "EEVEE Next's reference"), so in 4.2+ that is EEVEE's figure.
FIGURES = (("eevee", "eevee", "eevee_reference"), ("cycles", "cycles", "cycles_reference"),
           ("eevee_cycles", "eevee", "cycles_reference"))


def measure(images, masks):
    """Per figure of FIGURES and region: each image's block error and pixel RMSE against the
    figure's reference, and the ratios ndfbake / naive."""
    result = {}
    for figure, engine, reference in FIGURES:
        names = [n for n in ("naive", "ndfbake") if "%s_%s" % (engine, n) in images]
        table = image_error.compare({n: images["%s_%s" % (engine, n)] for n in names}, images[reference], masks)
        for region, entry in table.items():
            if "naive" in entry and "ndfbake" in entry:
                entry["ratio_block"] = image_error.ratio(entry["ndfbake"]["block"], entry["naive"]["block"])
                entry["ratio_rmse"] = image_error.ratio(entry["ndfbake"]["rmse"], entry["naive"]["rmse"])
        result[figure] = table
    return result


def format_errors(errors, info=None):
    lines = []
    cycles_reference = "the Cycles reference"
    if info and "cycles_reference_band_samples" in info:
        cycles_reference += " (%d spp, its far band %d)" % (info["cycles_reference_samples"],
                                                            info["cycles_reference_band_samples"])
    elif info:
        cycles_reference += " (%d spp)" % info["cycles_reference_samples"]
    for figure, table in errors.items():
        title = {"eevee": "EEVEE: block error (4x4 mean luminance) vs %s" % (
                     "the %dx%d supersampled, point-sampled EEVEE render" % ((info["eevee_reference"]["factor"],) * 2)
                     if info else "the supersampled EEVEE render"),
                 "cycles": "Cycles: pixel RMSE (linear RGB) vs " + cycles_reference,
                 "eevee_cycles": "EEVEE: block error (4x4 mean luminance) vs " + cycles_reference}[figure]
        lines.append(title)
        lines.append("  %-12s %7s %7s | %8s %8s %8s | %8s %8s %6s | %8s %8s %6s" % (
            "region", "pixels", "windows", "ref Y", "naive Y", "ndfb Y", "blk nv", "blk ndfb", "ratio",
            "rmse nv", "rmse ndf", "ratio"))
        for region, e in table.items():
            lines.append("  %-12s %7d %7d | %8.4f %8.4f %8.4f | %8.4f %8.4f %6.3f | %8.4f %8.4f %6.3f" % (
                region, e["pixels"], e["windows"], e["reference"]["mean"], e["naive"]["mean"],
                e.get("ndfbake", {}).get("mean", float("nan")), e["naive"]["block"],
                e.get("ndfbake", {}).get("block", float("nan")), e.get("ratio_block", float("nan")),
                e["naive"]["rmse"], e.get("ndfbake", {}).get("rmse", float("nan")), e.get("ratio_rmse", float("nan"))))
    return "\n".join(lines)


# ---- montage --------------------------------------------------------------------------------------

def montage(rows, path, scene=None, gap=4):
    """rows: lists of linear images (H, W, 3) of one size, top row first -> one PNG (Filmic/Standard
    as the scene says), with `gap` pixels of grey between them."""
    h, w = rows[0][0].shape[:2]
    columns = max(len(r) for r in rows)
    out = np.full((len(rows) * h + (len(rows) - 1) * gap, columns * w + (columns - 1) * gap, 3), 0.18,
                  dtype=np.float32)
    for i, row in enumerate(rows):
        for j, image in enumerate(row):
            top = i * (h + gap)
            # Blender's rows start at the bottom: flip each image into top-first order and back.
            out[top:top + h, j * (w + gap):j * (w + gap) + w] = image[::-1]
    return save_pixels(out[::-1], path, scene)
