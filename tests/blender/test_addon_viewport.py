"""The viewport preview: Material Preview in a real 3D viewport (under Xvfb) shows the filtered
material, as the EEVEE render does.

Run: xvfb-run -a -s "-screen 0 800x500x24" blender --factory-startup \
         --python tests/blender/test_addon_viewport.py -- LIB ZIP OUTDIR

A receding plane with a tiled, glossy normal-mapped metal under one of Blender's HDR worlds, seen
through the scene camera in a full-screen 3D viewport in Material Preview (scene world, no
overlays). The render resolution is set to the camera frame's size in the viewport, so that the
bake's level of detail fits both. Then:
- EEVEE renders the plain material ("naive") and, after the bake, the baked one;
- the viewport, once its samples have settled, is drawn by Blender's viewport code into an
  offscreen buffer (GPUOffScreen.draw_view3d) and cropped to the camera frame;
- in blocks of 8×8 pixels, the viewport is closer to the baked render than to the naive one
  (at most half the difference), and close to it in absolute terms.
Images go to OUTDIR: viewport.png, eevee-naive.png, eevee-ndfbake.png. Exits 0 when every check
holds, 1 otherwise (printed).
"""
import os
import sys
import time

import bpy
import gpu
import numpy as np
from bpy_extras import view3d_utils

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import test_addon_helpers as h  # noqa: E402

WORLD = os.path.join(bpy.utils.system_resource("DATAFILES", path="studiolights/world"), "sunset.exr")
BLOCK = 8
state = {"step": "start", "deadline": time.time() + 240, "shots": 0}


def _finish(ok, message):
    h.finish_window_test("test_addon_viewport", state, ok, message)


def _view3d():
    window = bpy.context.window_manager.windows[0]
    area = next(a for a in window.screen.areas if a.type == "VIEW_3D")
    region = next(r for r in area.regions if r.type == "WINDOW")
    return window, area, region


def _build_scene(directory):
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj)
    normal_path = h.write_normal_map(os.path.join(directory, "normal.png"), "bumps", 128, seed=5)
    material = h.normal_mapped_material("Metal", normal_path, roughness=0.15, metallic=1.0)
    material.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (0.9, 0.9, 0.9, 1.0)
    bpy.ops.mesh.primitive_plane_add(size=1.0)
    plane = bpy.context.active_object
    plane.scale = (8.0, 40.0, 1.0)
    plane.location = (0.0, 16.0, 0.0)
    for loop in plane.data.uv_layers.active.data:  # 4 repeats across, 20 along
        loop.uv = (loop.uv[0] * 4.0, loop.uv[1] * 20.0)
    plane.data.materials.append(material)
    bpy.ops.object.camera_add(location=(0.0, -4.0, 0.8), rotation=(1.45, 0.0, 0.0))
    scene = bpy.context.scene
    scene.camera = bpy.context.active_object
    scene.camera.data.lens = 35.0
    world = bpy.data.worlds.new("Sunset")
    h.enable_nodes(world)
    environment = world.node_tree.nodes.new("ShaderNodeTexEnvironment")
    environment.image = bpy.data.images.load(WORLD)
    world.node_tree.links.new(environment.outputs["Color"], world.node_tree.nodes["Background"].inputs["Color"])
    scene.world = world
    from ndfbake.shading import blender_compat
    scene.render.engine = blender_compat.eevee_engine()
    scene.eevee.taa_render_samples = 16
    scene.eevee.taa_samples = 16
    scene.view_settings.view_transform = "Standard"
    bpy.ops.wm.save_as_mainfile(filepath=os.path.join(directory, "viewport.blend"))
    return material


def _setup_viewport():
    window, area, region = _view3d()
    with bpy.context.temp_override(window=window, area=area, region=region):
        bpy.ops.screen.screen_full_area()
    window, area, region = _view3d()
    space = area.spaces.active
    space.shading.type = "MATERIAL"
    space.shading.use_scene_world = True
    space.shading.use_scene_lights = True
    space.overlay.show_overlays = False
    space.show_gizmo = False
    space.show_region_header = False
    space.show_region_toolbar = False
    space.show_region_ui = False
    space.region_3d.view_perspective = "CAMERA"
    with bpy.context.temp_override(window=window, area=area, region=region):
        bpy.ops.view3d.view_center_camera()


def _camera_frame():
    """The camera frame's rectangle in the 3D view's region: (x0, y0, x1, y1), y up."""
    window, area, region = _view3d()
    scene = bpy.context.scene
    camera = scene.camera
    corners = [camera.matrix_world @ c for c in camera.data.view_frame(scene=scene)]
    points = [view3d_utils.location_3d_to_region_2d(region, area.spaces.active.region_3d, c) for c in corners]
    xs, ys = [p.x for p in points], [p.y for p in points]
    return (int(round(min(xs))), int(round(min(ys))), int(round(max(xs))), int(round(max(ys))))


def _render(path):
    scene = bpy.context.scene
    scene.render.image_settings.file_format = "PNG"
    return h.render_pixels(scene, path)[..., :3]


def _blocks(rgb):
    hb, wb = rgb.shape[0] // BLOCK, rgb.shape[1] // BLOCK
    cropped = rgb[:hb * BLOCK, :wb * BLOCK]
    return cropped.reshape(hb, BLOCK, wb, BLOCK, 3).mean(axis=(1, 3))


def _shoot():
    """The viewport's camera frame as Blender draws it (display values, rows bottom-up): the 3D
    view drawn by Blender's own viewport code (GPUOffScreen.draw_view3d: that view's engine,
    shading and matrices) into one offscreen buffer, drawn again until two draws agree (_tick).
    Not a screenshot: 4.3's window reads back black under Xvfb."""
    window, area, region = _view3d()
    if state.get("offscreen") is None:
        state["offscreen"] = gpu.types.GPUOffScreen(region.width, region.height)
    offscreen = state["offscreen"]
    region_3d = area.spaces.active.region_3d
    with bpy.context.temp_override(window=window, area=area, region=region):
        offscreen.draw_view3d(bpy.context.scene, bpy.context.view_layer, area.spaces.active, region,
                              region_3d.view_matrix, region_3d.window_matrix, do_color_management=True)
    with offscreen.bind():
        framebuffer = gpu.state.active_framebuffer_get()
        buffer = framebuffer.read_color(0, 0, region.width, region.height, 4, 0, "FLOAT")
    buffer.dimensions = region.width * region.height * 4
    full = np.array(buffer, dtype=np.float32).reshape(region.height, region.width, 4)[..., :3]
    x0, y0, x1, y1 = state["frame"]
    return full[y0:y1, x0:x1]


def _tick():
    from ndfbake.blender import bake
    step = state["step"]
    if step == "start":
        state["dir"] = h.temp_dir()
        state["material"] = _build_scene(state["dir"]).name
        _setup_viewport()
        state["step"] = "frame"
        return 1.0
    if step == "frame":
        x0, y0, x1, y1 = state["frame"] = _camera_frame()
        width, height = x1 - x0, y1 - y0
        h.expect(width > 200 and height > 100, "camera frame too small in the viewport: %s" % (state["frame"],))
        scene = bpy.context.scene
        scene.render.resolution_x, scene.render.resolution_y = width, height
        scene.render.resolution_percentage = 100
        state["naive"] = _render(os.path.join(state["out"], "eevee-naive.png"))
        material = bpy.data.materials[state["material"]]
        result = bake.bake_material(material, bake.BakeSettings(max_lobes=4))
        print("baked: %s" % result.summary, flush=True)
        state["baked"] = _render(os.path.join(state["out"], "eevee-ndfbake.png"))
        _view3d()[1].tag_redraw()
        state["step"] = "settle"
        return 2.0
    if step == "settle":
        shot = _shoot()
        previous = state.get("shot")
        state["shot"] = shot
        state["shots"] += 1
        if previous is None or previous.shape != shot.shape or np.abs(previous - shot).mean() > 1e-3:
            _view3d()[1].tag_redraw()
            return 2.0  # shaders still compiling or samples still accumulating
        bpy.data.images.new("shot", shot.shape[1], shot.shape[0])
        path = os.path.join(state["out"], "viewport.png")
        image = bpy.data.images["shot"]
        image.pixels.foreach_set(np.concatenate([shot, np.ones(shot.shape[:2] + (1,), np.float32)], axis=2).ravel())
        image.filepath_raw = path
        image.file_format = "PNG"
        image.save()
        naive, baked = state["naive"], state["baked"]
        h.expect(shot.shape == baked.shape, "viewport %s vs render %s" % (shot.shape, baked.shape))
        s, b, n = _blocks(shot), _blocks(baked), _blocks(naive)
        to_baked, to_naive, baked_naive = (float(np.abs(s - b).mean()), float(np.abs(s - n).mean()),
                                           float(np.abs(b - n).mean()))
        print("viewport (Material Preview) vs EEVEE render, mean |difference| of %dx%d blocks: ndfbake render %.4f, "
              "naive render %.4f (ndfbake vs naive renders %.4f); %d draws to settle"
              % (BLOCK, BLOCK, to_baked, to_naive, baked_naive, state["shots"]), flush=True)
        h.expect(baked_naive > 0.01, "the filtered and naive renders hardly differ: nothing to compare")
        h.expect(to_baked <= 0.5 * to_naive, "the viewport is not closer to the filtered render than to the naive one")
        h.expect(to_baked < 0.03, "the viewport differs from the EEVEE render by %.4f" % to_baked)
        _finish(True, "Material Preview shows the filtered material")
    return 1.0


h.run_window_test("test_addon_viewport", state, _tick)
