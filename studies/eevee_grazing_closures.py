"""How EEVEE and Cycles light a few Principled BSDFs with fixed normals on a plane seen at a grazing
angle, under a low sun: the case where EEVEE Next loses a low sun's glare on ndfbake's lobes
(docs/rendering.md, "Open problems"). No add-on, no normal map: each closure is a metallic
Principled BSDF (Multiscatter GGX, roughness 0.2) whose Normal is a constant tilted off the plane's,
the closures weighted equally and added.

    python studies/eevee_grazing_closures.py -- [--sun-elevation 8] [--view-elevation 3]
    blender -b --factory-startup --python studies/eevee_grazing_closures.py -- ...

Prints, per set of closures, the mean of a 16x16 EEVEE render (16 TAA samples) and of a Cycles
render (64 spp) of the plane around the sun's mirror direction. Tilts are in degrees: "toward" and
"away" tilt the normal toward or away from the viewer, "side" across the view.
"""
import argparse
import math
import os
import sys
import tempfile

import bpy
import mathutils

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "examples"))  # the demo
import demo_build  # noqa: E402
import demo_render  # noqa: E402

# (name, [(tilt across the view, tilt away from the viewer)] in degrees; negative: toward)
CLOSURE_SETS = [
    ("flat", [(0, 0)]),
    ("flat x3", [(0, 0)] * 3),
    ("side 20", [(20, 0)]),
    ("flat + side ±20", [(0, 0), (20, 0), (-20, 0)]),
    ("away 3", [(0, 3)]),
    ("away 10", [(0, 10)]),
    ("toward 20", [(0, -20)]),
    ("flat + toward 20", [(0, 0), (0, -20)]),
    ("toward 20 + flat", [(0, -20), (0, 0)]),
    ("flat + away 20", [(0, 0), (0, 20)]),
    ("flat + toward/away 20", [(0, 0), (0, -20), (0, 20)]),
]
DISTANCE = 20.0        # metres from the camera to the plane point at the image centre


def build(sun_elevation, view_elevation):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    demo_build.import_addon()  # for demo_build's version checks (eevee_engine, enable_nodes)
    scene = bpy.context.scene
    scene.world = bpy.data.worlds.new("Black")
    demo_build.enable_nodes(scene.world)
    scene.world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
    bpy.ops.mesh.primitive_plane_add(size=20.0 * DISTANCE)
    plane = bpy.context.active_object
    # The sun ahead of the camera (which looks along +Y), sun_elevation degrees up.
    bpy.ops.object.light_add(type="SUN", rotation=(math.radians(sun_elevation - 90.0), 0.0, 0.0))
    bpy.context.active_object.data.energy = 3.0
    bpy.context.active_object.data.angle = math.radians(1.0)
    height = DISTANCE * math.tan(math.radians(view_elevation))
    bpy.ops.object.camera_add(location=(0.0, -DISTANCE, height), rotation=(math.radians(90.0 - view_elevation), 0.0, 0.0))
    scene.camera = bpy.context.active_object
    scene.camera.data.lens = 200.0
    scene.render.resolution_x = scene.render.resolution_y = 16
    scene.view_settings.view_transform = "Standard"
    scene.cycles.device = "CPU"
    return scene, plane


def closures_material(tilts):
    material = bpy.data.materials.new("closures")
    demo_build.enable_nodes(material)
    tree = material.node_tree
    tree.nodes.clear()
    total = None
    for across, away in tilts:
        bsdf = tree.nodes.new("ShaderNodeBsdfPrincipled")
        bsdf.distribution = "MULTI_GGX"
        bsdf.inputs["Metallic"].default_value = 1.0
        bsdf.inputs["Roughness"].default_value = 0.2
        normal = tree.nodes.new("ShaderNodeCombineXYZ")
        direction = mathutils.Vector((math.sin(math.radians(across)), math.sin(math.radians(away)), 1.0)).normalized()
        for socket, value in zip(normal.inputs, direction):
            socket.default_value = value
        tree.links.new(normal.outputs[0], bsdf.inputs["Normal"])
        mix = tree.nodes.new("ShaderNodeMixShader")
        mix.inputs["Fac"].default_value = 1.0 / len(tilts)
        tree.links.new(bsdf.outputs[0], mix.inputs[2])
        if total is None:
            total = mix.outputs[0]
        else:
            add = tree.nodes.new("ShaderNodeAddShader")
            tree.links.new(total, add.inputs[0])
            tree.links.new(mix.outputs[0], add.inputs[1])
            total = add.outputs[0]
    tree.links.new(total, tree.nodes.new("ShaderNodeOutputMaterial").inputs["Surface"])
    return material


def main():
    parser = argparse.ArgumentParser(prog="studies/eevee_grazing_closures.py --")
    parser.add_argument("--sun-elevation", type=float, default=8.0)
    parser.add_argument("--view-elevation", type=float, default=3.0)
    args = demo_build.script_arguments(parser)
    scene, plane = build(args.sun_elevation, args.view_elevation)
    print("sun %.1f deg up, view %.1f deg above the plane (Blender %s): mean of the render"
          % (args.sun_elevation, args.view_elevation, bpy.app.version_string))
    print("  %-24s %10s %10s" % ("closures", "EEVEE", "Cycles"))
    with tempfile.TemporaryDirectory() as directory:
        for name, tilts in CLOSURE_SETS:
            plane.data.materials.clear()
            plane.data.materials.append(closures_material(tilts))
            eevee = demo_render.render(scene, demo_build.eevee_engine(), os.path.join(directory, "e.exr"), 16)
            cycles = demo_render.render(scene, "CYCLES", os.path.join(directory, "c.exr"), 64)
            print("  %-24s %10.3f %10.3f" % (name, float(eevee.mean()), float(cycles.mean())), flush=True)


if __name__ == "__main__":
    main()
