"""The receding-surface benchmark: real normal maps on a plane that recedes to the horizon, plain
against baked with the add-on's defaults (and with 8 lobes), in EEVEE and Cycles, at view exposure 0.

    python examples/receding_bench.py -- --out DIR [--maps DIR] [--map fabric,...] [--light ...]
            [--width W --height H] [--reference-samples N] [--repeats R]
    blender -b --factory-startup --python examples/receding_bench.py -- --out DIR ...

Where normal-map filtering matters most is a floor, a road or a deck seen at a grazing angle, under
a low light. Each map (scripts/install-normal-maps.sh takes five real ones out of Debian's
packages: woven fabric, a fine carpet grain, brushed aluminium, cobbled stone, walnut) covers a
plane from 1 m in front of a camera 1.6 m up to 61 m away, 1.5 degrees short of the horizon, tiled as
MAPS says; the material is a Principled BSDF of MAPS' roughness and metalness with the map through
a Normal Map node, as an artist would make it. Three lights (LIGHTS): a sun 15 degrees above the far
end (the highlight the plane reflects toward the camera), a sun 15 degrees up from the side, and
Blender's courtyard studio world. Standard view transform, exposure 0.

Truth is each engine's own render of the full-resolution map:
- EEVEE: the scene at 8x8 the resolution with the map point-sampled (Closest: no MIP-mapping),
  box-downsampled (demo_render.reference_taa_samples: about 1024 map samples a pixel);
- Cycles: --reference-samples samples a pixel (two halves with different seeds; half their
  difference is the reference's own noise, printed beside the plain map's error).
Plain and ndfbake are rendered as an artist would: EEVEE at 16 TAA samples, Cycles at 16 spp.
The error is image_error's block error (the RMS over 4x4-pixel windows of the difference in mean
luminance) over the plane's pixels; the ratio is ndfbake's error over the plain map's.

Each map is baked with the add-on's defaults (bake.BakeSettings(): 4 lobes, the scene camera's
level of detail, narrowed Cycles lobes) and again with 8 lobes. Per map, the bake's seconds and
the frame time of each variant (a warm-up render, then the median of --repeats, one run) under the
first light are printed beside the errors. Writes DIR/receding.json, DIR/receding.txt (the
table) and DIR/montage.png (a row per map and light: EEVEE reference, plain, 4 lobes, 8 lobes,
then the same in Cycles).
"""
import argparse
import json
import math
import os
import statistics
import sys
import time

sys.dont_write_bytecode = True  # no __pycache__ in examples/ or addon/

import bpy  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
if HERE not in sys.path:
    sys.path.insert(0, HERE)
import demo_build  # noqa: E402
import demo_scene  # noqa: E402
import demo_render  # noqa: E402
import image_error  # noqa: E402

# scripts/install-normal-maps.sh's folder (tests/CMakeLists.txt names it in NDFBAKE_NORMAL_MAPS).
DEFAULT_MAPS = os.environ.get("NDFBAKE_NORMAL_MAPS") or os.path.join(
    os.environ.get("NDFBAKE_CACHE") or os.path.expanduser("~/.cache/ndfbake"), "normal-maps")
# name: the material an artist would give the map; tile: metres one repeat of the map covers.
MAPS = {
    "fabric": dict(color=(0.42, 0.10, 0.08), roughness=0.5, metallic=0.0, tile=0.25),
    "carpet": dict(color=(0.20, 0.22, 0.30), roughness=0.45, metallic=0.0, tile=0.25),
    "aluminium": dict(color=(0.91, 0.92, 0.92), roughness=0.25, metallic=1.0, tile=0.5),
    "stone": dict(color=(0.45, 0.42, 0.38), roughness=0.4, metallic=0.0, tile=1.0),
    "walnut": dict(color=(0.30, 0.16, 0.08), roughness=0.2, metallic=0.0, tile=0.5),
}
LIGHTS = ("sun_far", "sun_side", "courtyard")
SUN_ELEVATION = 15.0       # degrees above the horizon
SUN_STRENGTH = 4.0         # W/m²: the sunlit plane's diffuse near 0.5 at exposure 0
CAMERA_HEIGHT = 1.6        # metres
CAMERA_PITCH_DOWN = 25.0   # degrees: the bottom row sees the plane 1.1 m ahead, the top row the sky
CAMERA_ANGLE_Y = 60.0      # degrees, vertical field of view
# 60 m ahead the plane's far edge is 1.5 degrees below the horizon, two pixels at 128x72. (A plane of
# 300 m by 600 m, 0.3 degrees short of it, took EEVEE Next minutes a frame on llvmpipe in 5.0,
# plain as baked; this one takes seconds.)
PLANE_START, PLANE_LENGTH, PLANE_WIDTH = 1.0, 60.0, 120.0
REFERENCE_FACTOR = 8       # EEVEE's reference: 8x8 the resolution, box-downsampled
SAMPLES = 16               # EEVEE's TAA samples and Cycles' samples of plain and ndfbake renders
VARIANTS = (("plain", None), ("ndfbake", {}), ("ndfbake8", {"max_lobes": 8}))


# ---- the scene ------------------------------------------------------------------------------------

def build(map_path, material, width, height):
    """The plane with the map, the camera and the three lights, in the current (empty) file.
    Returns the material's name."""
    scene = bpy.context.scene
    mat = demo_build.normal_mapped_material("Receding " + os.path.splitext(os.path.basename(map_path))[0],
                                            map_path, material["roughness"], material["color"],
                                            material["metallic"])
    mesh = bpy.data.meshes.new("Plane")
    x, y0, y1 = PLANE_WIDTH / 2, PLANE_START, PLANE_START + PLANE_LENGTH
    mesh.from_pydata([(-x, y0, 0), (x, y0, 0), (x, y1, 0), (-x, y1, 0)], [], [(0, 1, 2, 3)])
    uv = mesh.uv_layers.new(name="UVMap")
    tile = material["tile"]
    for loop, (u, v) in zip(uv.data, ((0, 0), (PLANE_WIDTH, 0), (PLANE_WIDTH, PLANE_LENGTH), (0, PLANE_LENGTH))):
        loop.uv = (u / tile, v / tile)
    mesh.materials.append(mat)
    plane = bpy.data.objects.new("Plane", mesh)
    scene.collection.objects.link(plane)

    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    camera.location = (0.0, 0.0, CAMERA_HEIGHT)
    camera.rotation_euler = (math.radians(90.0 - CAMERA_PITCH_DOWN), 0.0, 0.0)
    camera.data.sensor_fit = "VERTICAL"
    camera.data.angle_y = math.radians(CAMERA_ANGLE_Y)
    camera.data.clip_end = 1000.0
    scene.collection.objects.link(camera)
    scene.camera = camera

    # The suns' light travels along their -Z: toward the camera from beyond the far end, and
    # from the right across the view.
    elevation = math.radians(90.0 - SUN_ELEVATION)
    for name, rotation in (("sun_far", (-elevation, 0.0, 0.0)), ("sun_side", (0.0, elevation, 0.0))):
        light = bpy.data.lights.new(name, "SUN")
        light.energy = SUN_STRENGTH
        light.angle = math.radians(0.5)
        sun = bpy.data.objects.new(name, light)
        sun.rotation_euler = rotation
        scene.collection.objects.link(sun)
    black = bpy.data.worlds.new("Black")
    black.use_fake_user = True   # unused while the courtyard lights the saved file
    demo_build.enable_nodes(black)
    black.node_tree.nodes["Background"].inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
    demo_build.studio_world(scene, "courtyard")

    scene.render.resolution_x, scene.render.resolution_y = int(width), int(height)
    scene.render.resolution_percentage = 100
    scene.render.film_transparent = False
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    scene.cycles.device = "CPU"
    scene.cycles.use_denoising = False
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.max_bounces = 4
    scene.frame_set(1)
    return mat.name


def light_scene(scene, light):
    """Lights the scene with one of LIGHTS alone."""
    for name in ("sun_far", "sun_side"):
        scene.objects[name].hide_render = name != light
    scene.world = bpy.data.worlds["Courtyard" if light == "courtyard" else "Black"]


def plane_mask(scene):
    """Pixels (rows bottom first) whose 2x2 rays all hit the plane, eroded by one pixel."""
    names, hit, _ = demo_render.pixel_hits(scene, scene.render.resolution_x, scene.render.resolution_y)
    if "Plane" not in names:
        raise RuntimeError("the camera sees no plane")
    return image_error.erode((hit == names.index("Plane")).all(axis=-1), 1)


# ---- rendering ------------------------------------------------------------------------------------

def references(scene, material, directory, reference_samples):
    """(EEVEE's reference, Cycles' reference, the two halves Cycles' is the mean of)."""
    eevee = demo_render.render_eevee_reference(scene, [material], os.path.join(directory, "eevee_big.exr"),
                                               REFERENCE_FACTOR, demo_render.reference_taa_samples(REFERENCE_FACTOR))
    half = max(1, reference_samples // 2)
    a = demo_render.render(scene, "CYCLES", os.path.join(directory, "cycles_a.exr"), half, seed=1)
    b = demo_render.render(scene, "CYCLES", os.path.join(directory, "cycles_b.exr"), half, seed=2)
    return eevee, 0.5 * (a + b), (a, b)


def frame_seconds(scene, engine, path, repeats):
    """A warm-up render, then the median of `repeats` (EEVEE's TAA and Cycles' samples: SAMPLES)."""
    demo_render.render(scene, engine, path, SAMPLES)
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        demo_render.render(scene, engine, path, SAMPLES)
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def run_map(name, map_path, directory, lights, width, height, reference_samples, repeats, variants=VARIANTS,
            log=print):
    """Every light and variant of one map, built in the current (empty) file with the add-on
    imported: {"cases": {light: {...}}, "bakes": {...}, "frames": {...}} (no frames with repeats 0)."""
    from ndfbake.blender import bake
    os.makedirs(directory, exist_ok=True)
    material = build(map_path, MAPS[name], width, height)
    scene = bpy.context.scene
    bpy.ops.wm.save_as_mainfile(filepath=os.path.join(directory, name + ".blend"))
    mask = plane_mask(scene)
    engines = {"eevee": demo_build.eevee_engine(), "cycles": "CYCLES"}
    cases = {light: {"images": {}} for light in lights}
    for light in lights:
        light_scene(scene, light)
        start = time.perf_counter()
        eevee, cycles, halves = references(scene, material, directory, reference_samples)
        cases[light]["images"].update(eevee_reference=eevee, cycles_reference=cycles)
        for engine, pixels in (("eevee", eevee), ("cycles", cycles)):
            demo_render.save_pixels(pixels, os.path.join(directory, "%s_%s_reference.exr" % (light, engine)), scene)
        cases[light]["reference_noise"] = 0.5 * image_error.block_error(halves[0], halves[1], mask)
        log("  %s / %s: references in %.0f s" % (name, light, time.perf_counter() - start))
    bakes, frames = {}, {}
    for variant, settings in variants:
        if settings is not None:
            start = time.perf_counter()
            outcomes = bake.bake_materials([bpy.data.materials[material]],
                                           settings_for=lambda m: bake.BakeSettings(**settings))
            _, outcome = outcomes[0]
            if isinstance(outcome, bake.BakeError):
                raise RuntimeError("%s: bake failed: [%s] %s" % (name, outcome.code, outcome.message))
            bakes[variant] = {"seconds": round(time.perf_counter() - start, 2), "lobes": outcome.lobes,
                              "summary": outcome.summary}
            log("  %s: baked %s in %.1f s: %s" % (name, variant, bakes[variant]["seconds"], outcome.summary))
        for light in lights:
            light_scene(scene, light)
            for engine, engine_id in engines.items():
                cases[light]["images"]["%s_%s" % (engine, variant)] = demo_render.render(
                    scene, engine_id, os.path.join(directory, "%s_%s_%s.exr" % (light, engine, variant)), SAMPLES)
        if not repeats:
            continue
        light_scene(scene, lights[0])
        frames[variant] = {engine: frame_seconds(scene, engine_id, os.path.join(directory, "frame.exr"), repeats)
                           for engine, engine_id in engines.items()}
    for light in lights:
        case = cases[light]
        errors = {}
        for engine in engines:
            reference = case["images"]["%s_reference" % engine]
            errors[engine] = {variant: image_error.block_error(case["images"]["%s_%s" % (engine, variant)],
                                                               reference, mask) for variant, _ in variants}
        case["errors"] = errors
    return {"cases": cases, "bakes": bakes, "frames": frames, "pixels": int(mask.sum())}


# ---- the report -----------------------------------------------------------------------------------

def table(results, engine_names):
    """The Markdown table: per map, light and engine the plain map's error, ndfbake's with the
    defaults and with 8 lobes, and the ratios."""
    lines = ["| map | light | engine | plain | ndfbake (defaults) | ratio | 8 lobes | ratio | reference noise |",
             "|---|---|---|---:|---:|---:|---:|---:|---:|"]
    for name, result in results.items():
        for light, case in result["cases"].items():
            for engine, e in case["errors"].items():
                e = {"ndfbake8": float("nan"), **e}   # a run of the defaults alone
                noise = case["reference_noise"] if engine == "cycles" else float("nan")
                lines.append("| %s | %s | %s | %.4f | %.4f | %.2f | %.4f | %.2f | %s |" % (
                    name, light, engine_names[engine], e["plain"], e["ndfbake"], e["ndfbake"] / e["plain"],
                    e["ndfbake8"], e["ndfbake8"] / e["plain"], "" if math.isnan(noise) else "%.4f" % noise))
    return lines


def speed_table(results, engine_names):
    lines = ["| map | bake (defaults) | bake (8 lobes) | %s |" % " | ".join(
                 "%s plain | 4 lobes | 8 lobes" % engine_names[e] for e in ("eevee", "cycles")),
             "|---|---:|---:|" + "---:|" * 6]
    for name, result in results.items():
        f, b = result["frames"], result["bakes"]
        cells = []
        for engine in ("eevee", "cycles"):
            plain = f["plain"][engine]
            cells += ["%.2f s" % plain] + ["%.2f s (%.2fx)" % (f[v][engine], f[v][engine] / plain)
                                           for v in ("ndfbake", "ndfbake8")]
        lines.append("| %s | %.1f s | %.1f s | %s |" % (name, b["ndfbake"]["seconds"], b["ndfbake8"]["seconds"],
                                                         " | ".join(cells)))
    return lines


def write_montage(results, path):
    rows = []
    for result in results.values():
        for case in result["cases"].values():
            rows.append([case["images"]["%s_%s" % (engine, v)] for engine in ("eevee", "cycles")
                         for v in ("reference", "plain", "ndfbake", "ndfbake8")
                         if "%s_%s" % (engine, v) in case["images"]])
    demo_render.montage(rows, path)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", required=True)
    parser.add_argument("--maps", default=DEFAULT_MAPS, help="scripts/install-normal-maps.sh's folder")
    parser.add_argument("--map", default=",".join(MAPS), help="comma-separated names of MAPS")
    parser.add_argument("--light", default=",".join(LIGHTS), help="comma-separated names of LIGHTS")
    parser.add_argument("--width", type=int, default=128)
    parser.add_argument("--height", type=int, default=72)
    parser.add_argument("--reference-samples", type=int, default=2048)
    parser.add_argument("--repeats", type=int, default=3)
    args = demo_build.script_arguments(parser)
    out = os.path.abspath(args.out)
    lights = tuple(args.light.split(","))
    started = time.perf_counter()
    results = {}
    for name in args.map.split(","):
        map_path = os.path.join(args.maps, name + ".png")
        if not os.path.exists(map_path):
            raise SystemExit("%s is missing: run scripts/install-normal-maps.sh" % map_path)
        bpy.ops.wm.read_factory_settings(use_empty=True)
        demo_build.import_addon()
        results[name] = run_map(name, map_path, os.path.join(out, name), lights, args.width, args.height,
                                args.reference_samples, args.repeats)
    engine = demo_build.eevee_engine()
    engine_names = {"eevee": "EEVEE Next" if engine == "BLENDER_EEVEE_NEXT" or bpy.app.version >= (5, 0, 0)
                    else "EEVEE", "cycles": "Cycles"}
    write_montage(results, os.path.join(out, "montage.png"))
    lines = (["ndfbake receding-surface benchmark, Blender %s, %dx%d, exposure 0, Standard; EEVEE %d TAA "
              "(reference %dx%d point-sampled), Cycles %d spp (reference %d spp); block error over the plane"
              % (bpy.app.version_string, args.width, args.height, SAMPLES, REFERENCE_FACTOR, REFERENCE_FACTOR,
                 SAMPLES, args.reference_samples), ""]
             + table(results, engine_names)
             + (["", *speed_table(results, engine_names)] if args.repeats else [])
             + ["", "montage: %s (rows: map x light; EEVEE reference, plain, 4, 8 lobes | Cycles the same)"
                % os.path.join(out, "montage.png"), "total %.0f s" % (time.perf_counter() - started)])
    text = "\n".join(lines)
    with open(os.path.join(out, "receding.txt"), "w") as f:
        f.write(text + "\n")
    with open(os.path.join(out, "receding.json"), "w") as f:
        json.dump({"blender": bpy.app.version_string, "width": args.width, "height": args.height,
                   "reference_samples": args.reference_samples,
                   "results": {n: {"bakes": r["bakes"], "frames": r["frames"], "pixels": r["pixels"],
                                   "cases": {l: {"errors": c["errors"], "reference_noise": c["reference_noise"]}
                                             for l, c in r["cases"].items()}}
                               for n, r in results.items()}}, f, indent=2)
    print(text)


if __name__ == "__main__":
    demo_scene.run_as_script(main)
