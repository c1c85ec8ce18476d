"""Level of detail from the scene (addon/ndfbake/shading/scene_lod.py and the node groups that use it).

Run: blender -b --factory-startup --python-exit-code 1 --python tests/blender/test_addon_lod.py -- LIB

- camera_footprint: the pixel angle of perspective cameras (both sensor fits) and the pixel size of
  orthographic ones, against the pinhole formula worked by hand.
- material_lod: texel density of a plane with known UVs and the levels a camera reaches; only the
  faces that use the material count, on the UV map the Normal Map node names (or, with no name,
  the one active for rendering).
- The "NDFB Level of Detail" node group, rendered by Cycles as an emission, equals the footprint
  formula evaluated per pixel from the camera's intrinsics (independent of scene_lod's numpy).
- Both atlas paths (table, taps, four Closest lookups, bilinear in nodes; table, point, one Linear
  lookup in the level's frame) render exactly what Cycles' own bilinear (Linear) lookup of the
  level's file renders, with repeat across tile borders.
- A bake with a camera writes only the levels the camera reaches, and one atlas per lobe; the
  group's pixel angle follows the lens and the resolution through drivers; revert removes them.
- A material name near Blender's 63-byte limit: revert removes its atlas table, and re-bakes give
  its group and atlas table the first bake's names, with no stale table left; two names Blender
  would cut alike keep, cut, what each ID is (a group's .001 before " atlas", " lobe j").
- A Mapping node that tiles the texture 4x (Point) or 2x (Texture type, scale 0.5) multiplies the
  texel density by 4 (2), a muted one by 1, and so does a muted link from it into the texture (the
  group then gets no Vector input); a UV Map node reading a UV map tiled 4x gives 4x; coordinates
  from elsewhere (Object), a muted link into the Mapping, or a rotation out of the UV plane leave
  level 0 to the renderer.
"""
import json
import math
import os
import sys

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import test_addon_helpers as h  # noqa: E402


def _camera(location=(0.0, 0.0, 10.0), rotation=(0.0, 0.0, 0.0), lens=50.0, kind="PERSP"):
    bpy.ops.object.camera_add(location=location, rotation=rotation)
    camera = bpy.context.active_object
    camera.data.type = kind
    camera.data.lens = lens
    camera.data.sensor_width = 36.0
    camera.data.sensor_height = 24.0
    bpy.context.scene.camera = camera
    return camera


def _resolution(width, height):
    render = bpy.context.scene.render
    render.resolution_x, render.resolution_y, render.resolution_percentage = width, height, 100


def test_camera_footprint_is_the_pinhole_pixel_angle():
    from ndfbake.shading import scene_lod
    h.reset_scene()
    scene = bpy.context.scene
    camera = _camera(lens=50.0)
    _resolution(200, 100)
    f = scene_lod.camera_footprint(scene, camera)
    h.expect(abs(f.pixel_angle - 36.0 / 50.0 / 200.0) < 1e-9 and f.pixel_size == 0.0, "horizontal fit: %r" % (f,))
    _resolution(100, 200)  # AUTO fits the larger side: now the height
    f = scene_lod.camera_footprint(scene, camera)
    h.expect(abs(f.pixel_angle - 36.0 / 50.0 / 200.0) < 1e-9, "auto fit on the height: %r" % (f,))
    camera.data.sensor_fit = "VERTICAL"
    f = scene_lod.camera_footprint(scene, camera)
    h.expect(abs(f.pixel_angle - 24.0 / 50.0 / 200.0) < 1e-9, "vertical fit: %r" % (f,))
    scene.render.resolution_percentage = 50
    f = scene_lod.camera_footprint(scene, camera)
    h.expect(abs(f.pixel_angle - 24.0 / 50.0 / 100.0) < 1e-9, "50%% resolution: %r" % (f,))
    # Non-square pixels: the long side of a pixel, from Blender's own projection matrix.
    scene.render.resolution_percentage = 100
    for fit, aspect in (("AUTO", (2.0, 1.0)), ("VERTICAL", (1.0, 2.0)), ("HORIZONTAL", (1.0, 3.0))):
        camera.data.sensor_fit = fit
        scene.render.pixel_aspect_x, scene.render.pixel_aspect_y = aspect
        projection = camera.calc_matrix_camera(bpy.context.evaluated_depsgraph_get(), x=100, y=200,
                                               scale_x=aspect[0], scale_y=aspect[1])
        long_side = max(2.0 / 100 / projection[0][0], 2.0 / 200 / projection[1][1])  # tan θ ≈ θ per pixel
        f = scene_lod.camera_footprint(scene, camera)
        h.expect(abs(f.pixel_angle / long_side - 1.0) < 1e-6, "%s fit, pixel aspect %s: %r, the long side %r"
                 % (fit, aspect, f.pixel_angle, long_side))
    scene.render.pixel_aspect_x = scene.render.pixel_aspect_y = 1.0
    scene.render.resolution_percentage = 50
    camera.data.type = "ORTHO"
    camera.data.ortho_scale = 7.0
    camera.data.sensor_fit = "AUTO"
    f = scene_lod.camera_footprint(scene, camera)
    h.expect(f.pixel_angle == 0.0 and abs(f.pixel_size - 7.0 / 100.0) < 1e-9, "orthographic: %r" % (f,))


def test_material_lod_measures_texel_density_and_the_levels_reached():
    from ndfbake.shading import scene_lod
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory, pattern="bumps", size=64)  # plane of side 2, UVs 0..1
        scene = bpy.context.scene
        plane = bpy.data.objects["Plane"]
        plane.scale = (3.0, 3.0, 3.0)  # world side 6: 64 / 6 texels per unit
        _resolution(100, 100)
        camera = _camera(location=(0.0, 0.0, 40.0), lens=50.0)
        lod = scene_lod.material_lod(scene, material, (64, 64))
        print("  texels per unit %.4f, levels %d, largest footprint %.3f" % (
            lod.texels_per_unit, lod.levels, lod.footprint_max))
        h.expect(abs(lod.texels_per_unit - 64.0 / 6.0) < 1e-3, "texel density %r" % lod.texels_per_unit)
        # The far corners: distance sqrt(40² + 2·3²), facing 40 / distance.
        distance = math.sqrt(40.0 ** 2 + 18.0)
        footprint = distance * 36.0 / 50.0 / 100.0 * 64.0 / 6.0 / (40.0 / distance) ** scene_lod.STRETCH
        h.expect(abs(lod.footprint_max - footprint) < 1e-3 * footprint, "footprint %r vs %r" % (
            lod.footprint_max, footprint))
        h.expect(lod.levels == min(7, math.ceil(math.log2(footprint)) + 2), "levels %d" % lod.levels)
        camera.location = (0.0, 0.0, 4.0)  # close: one texel per pixel or more; two levels
        h.expect(scene_lod.material_lod(scene, material, (64, 64)).levels == 2, "close camera")
        plane.hide_render = True
        lod = scene_lod.material_lod(scene, material, (64, 64))
        h.expect(lod.texels_per_unit == 0.0 and lod.levels == 7, "no visible object: %r" % (lod,))


def _emission_material(name):
    material = bpy.data.materials.new(name)
    h.enable_nodes(material)
    tree = material.node_tree
    tree.nodes.remove(tree.nodes["Principled BSDF"])
    emission = tree.nodes.new("ShaderNodeEmission")
    tree.links.new(emission.outputs[0], tree.nodes["Material Output"].inputs["Surface"])
    return material, tree, emission


def _render_cycles(path, width, height):
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    h.configure_render(scene, width, height, cycles_samples=1)
    scene.cycles.filter_width = 0.01  # one ray through each pixel's centre
    scene.cycles.pixel_filter_type = "BOX"
    scene.cycles.use_adaptive_sampling = False
    scene.render.image_settings.color_depth = "32"
    return h.render_pixels(scene, path)


def test_the_level_of_detail_group_renders_the_footprint_formula():
    from ndfbake.shading import lod_nodes
    from ndfbake.shading.scene_lod import STRETCH
    h.reset_scene()
    with h.scratch_dir() as directory:
        width, height, lens, depth = 48, 32, 18.0, 5.0  # wide angle: the view angle varies a lot
        bpy.ops.mesh.primitive_plane_add(size=100.0, location=(0.0, 0.0, -depth))
        plane = bpy.context.active_object
        material, tree, emission = _emission_material("Level")
        plane.data.materials.append(material)
        _camera(location=(0.0, 0.0, 0.0), lens=lens)
        lod = tree.nodes.new("ShaderNodeGroup")
        lod.node_tree = lod_nodes.level_of_detail_group()
        pixel_angle = 36.0 / lens / width
        texels_per_unit = 300.0
        lod.inputs["Texels per Unit"].default_value = texels_per_unit
        lod.inputs["Pixel Angle"].default_value = pixel_angle
        lod.inputs["Pixel Size"].default_value = 0.0
        lod.inputs["Max Level"].default_value = 20.0
        scale = tree.nodes.new("ShaderNodeMath")
        scale.operation = "DIVIDE"
        scale.inputs[1].default_value = 16.0
        tree.links.new(lod.outputs["Level"], scale.inputs[0])
        tree.links.new(scale.outputs[0], emission.inputs["Color"])
        bpy.context.scene.world = None
        rendered = _render_cycles(os.path.join(directory, "level.exr"), width, height)[..., 0] * 16.0
        # Pinhole: pixel (i, j) centre at sensor (x, y) = ((i + ½) − W/2, (j + ½) − H/2)·36/W mm.
        i, j = np.meshgrid(np.arange(width) + 0.5, np.arange(height) + 0.5)
        x, y = (i - width / 2.0) * 36.0 / width, (j - height / 2.0) * 36.0 / width
        length = np.sqrt(x * x + y * y + lens * lens)
        distance, facing = depth * length / lens, lens / length
        expected = np.clip(np.log2(distance * pixel_angle * texels_per_unit / facing ** STRETCH), 0.0, 20.0)
        error = np.abs(rendered - expected)
        print("  level %.3f..%.3f, largest difference %.2e" % (expected.min(), expected.max(), error.max()))
        h.expect(expected.max() - expected.min() > 0.3, "the view angle should change the level")
        h.expect(error.max() < 2e-3, "level differs from the formula by %.4f" % error.max())


def test_atlas_lookups_equal_bilinear_filtering_of_the_level_files():
    from ndfbake.shading import lod_nodes
    h.reset_scene()
    with h.scratch_dir() as directory:
        normal_map = h.write_normal_map(os.path.join(directory, "weave.png"), pattern="weave", size=32)
        out = os.path.join(directory, "lobes")
        h.bake_image_file(normal_map, out, max_lobes=2, roughness=0.3, atlas=True)
        import json
        with open(os.path.join(out, "report.json")) as f:
            layout = json.load(f)["atlas"]
        atlas_image = bpy.data.images.load(os.path.join(out, "atlas_lobe1.exr"))
        atlas_image.colorspace_settings.name = "Non-Color"
        atlas = lod_nodes.AtlasLayout(layout["width"], layout["height"], layout["levels"])

        # A plane seen from above by an orthographic camera; UVs 0..2.5 so the texture tiles.
        bpy.ops.mesh.primitive_plane_add(size=2.0)
        plane = bpy.context.active_object
        for loop in plane.data.uv_layers.active.data:
            loop.uv = (loop.uv[0] * 2.5 - 0.3, loop.uv[1] * 2.5 - 0.7)
        camera = _camera(location=(0.0, 0.0, 5.0), kind="ORTHO")
        camera.data.ortho_scale = 2.0
        bpy.context.scene.world = None
        worst = {}
        for level in (0, 1, 3):
            ours = {}
            for group, sample in ((lod_nodes.atlas_taps_group(), lod_nodes.sample_atlas),
                                  (lod_nodes.atlas_point_group(), lod_nodes.sample_atlas_linear)):
                material, tree, emission = _emission_material("Atlas %d %s" % (level, group.name))
                plane.data.materials.clear()
                plane.data.materials.append(material)
                uv = tree.nodes.new("ShaderNodeTexCoord").outputs["UV"]
                table = tree.nodes.new("ShaderNodeGroup")
                table.node_tree = lod_nodes.atlas_table_group("table %d" % level, atlas)
                table.inputs["Level"].default_value = float(level)
                address = lod_nodes.address_levels(tree, group, [table], atlas, True, uv, 0)
                color, _alpha = sample(tree, atlas_image, address * 2, 0.0, 0, 0)
                tree.links.new(color, emission.inputs["Color"])
                ours[group.name] = _render_cycles(os.path.join(directory, "atlas%d.exr" % level), 64, 64)[..., :3]

            plain, tree, emission = _emission_material("Level %d" % level)
            plane.data.materials.clear()
            plane.data.materials.append(plain)
            tex = tree.nodes.new("ShaderNodeTexImage")
            tex.image = bpy.data.images.load(os.path.join(out, "level%02d_lobe1.exr" % level))
            tex.image.colorspace_settings.name = "Non-Color"
            tex.interpolation = "Linear"
            tex.extension = "REPEAT"
            tree.links.new(tex.outputs["Color"], emission.inputs["Color"])
            theirs = _render_cycles(os.path.join(directory, "level%d.exr" % level), 64, 64)[..., :3]
            h.expect(float(np.abs(theirs).max()) > 0.05, "level %d renders black" % level)
            for name, image in ours.items():
                difference = float(np.abs(image - theirs).max())
                worst[name] = max(worst.get(name, 0.0), difference)
                print("  level %d, %s: largest difference %.2e (values up to %.3f)" % (
                    level, name, difference, float(np.abs(theirs).max())))
        for name, difference in worst.items():
            h.expect(difference < 2e-3, "the atlas lookups of %s differ from bilinear filtering by %.4f" % (
                name, difference))


def test_a_bake_with_a_camera_writes_only_the_levels_it_reaches():
    from ndfbake.shading import nodes, scene_lod
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory, pattern="fbm", size=128)
        _resolution(64, 64)
        _camera(location=(0.0, 0.0, 6.0), lens=50.0)  # the plane's 128 texels over ~36 pixels
        result = bake.bake_material(material, bake.BakeSettings(max_lobes=2))
        files = sorted(os.listdir(bpy.path.abspath(result.folder)))
        levels = sorted({int(name[5:7]) for name in files if name.startswith("level")})
        print("  %s\n  files: %s" % (result.summary, " ".join(files)))
        h.expect(files.count("atlas_lobe0.exr") == 1 and files.count("atlas_lobe1.exr") == 1, "atlases: %s" % files)
        h.expect(levels == list(range(len(levels))) and 2 <= len(levels) < 8, "levels written: %s" % levels)
        h.expect("level of detail from the camera" in result.summary, result.summary)
        group = material.node_tree.nodes["ndfbake"]
        h.expect(abs(group.inputs["Texels per Unit"].default_value - 64.0) < 0.01, "texel density on the node")
        # The pixel angle follows the camera and the resolution through drivers that need no Python.
        scene = bpy.context.scene
        drivers = material.node_tree.animation_data.drivers
        h.expect(len(drivers) == 1 and drivers[0].driver.is_simple_expression and drivers[0].driver.is_valid,
                 "one valid simple-expression driver expected: %s" % [d.data_path for d in drivers])
        baked_angle = group.inputs["Pixel Angle"].default_value
        h.expect(abs(baked_angle - 36.0 / 50.0 / 64.0) < 1e-7, "pixel angle %r" % baked_angle)
        scene.render.resolution_percentage = 50
        scene.camera.data.lens = 25.0
        bpy.context.view_layer.update()
        driven = material.node_tree.nodes["ndfbake"].inputs["Pixel Angle"].default_value
        print("  pixel angle %.6f at 100%%, 50 mm; %.6f at 50%%, 25 mm" % (baked_angle, driven))
        h.expect(abs(driven - 4.0 * baked_angle) < 1e-7, "the driven pixel angle is %r, not 4x %r" % (
            driven, baked_angle))
        # The sensor fit and the pixel aspect are followed too.
        scene.camera.data.sensor_fit = "VERTICAL"
        scene.render.pixel_aspect_x, scene.render.pixel_aspect_y = 1.0, 2.0
        bpy.context.view_layer.update()
        driven = material.node_tree.nodes["ndfbake"].inputs["Pixel Angle"].default_value
        expected = scene_lod.camera_footprint(scene, scene.camera).pixel_angle
        h.expect(abs(driven / expected - 1.0) < 1e-6, "driven %r after a sensor fit and aspect change, not %r"
                 % (driven, expected))
        scene.camera.data.sensor_fit = "AUTO"
        scene.render.pixel_aspect_x = scene.render.pixel_aspect_y = 1.0
        scene.render.resolution_percentage = 100
        scene.camera.data.lens = 50.0
        h.expect(nodes.lobe_count(group.node_tree) == 2, "two lobes")
        bake.revert(material)
        bpy.ops.wm.save_mainfile()
        h.close_file()
        h.expect(not os.path.exists(bpy.path.abspath(result.folder)), "revert, save and close left the folder")
        leftovers = [g.name for g in bpy.data.node_groups]
        h.expect(not leftovers, "revert left node groups: %s" % leftovers)
        h.expect(material.node_tree.animation_data is None, "revert left the drivers' animation data")


def _lookups(tree, socket):
    """The interpolations of the image lookups that group `tree`'s output `socket` reads."""
    found, stack, seen = set(), [socket.node.inputs[socket.name]], set()
    while stack:
        for link in stack.pop().links:
            node = link.from_node
            if node.name not in seen:
                seen.add(node.name)
                if node.bl_idname == "ShaderNodeTexImage":
                    found.add(node.interpolation)
                stack.extend(node.inputs)
    return found


def test_cycles_alone_reads_each_level_with_one_linear_lookup():
    """Where the bake gives EEVEE an output of its own, the group's BSDF output (drawn by Cycles
    alone) reads each atlas level with one Linear lookup, EEVEE BSDF with four Closest ones; and
    Cycles renders the same through either. Where EEVEE draws the BSDF output too (the Principled
    feeds the user's Mix Shader; a re-bake after the user deleted the EEVEE output), it reads the
    Closest lookups only: EEVEE would MIP-map a Linear one and break at the atlas's tile seams."""
    from ndfbake.shading import group_node, node_builders, nodes
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory, pattern="fbm", size=128, metallic=0.0)
        _resolution(48, 48)
        _camera(location=(0.0, 2.0, 2.0), rotation=(math.radians(45.0), 0.0, math.radians(180.0)))
        h.uniform_world(bpy.context.scene, "Grey", (0.2, 0.2, 0.2))
        bpy.ops.object.light_add(type="SUN", rotation=(math.radians(-40.0), 0.0, 0.0))
        bake.bake_material(material, bake.BakeSettings(max_lobes=2))
        tree = material.node_tree
        group = tree.nodes["ndfbake"].node_tree
        gout = next(n for n in group.nodes if n.bl_idname == "NodeGroupOutput")
        cycles, eevee = (_lookups(group, gout.inputs[name]) for name in ("BSDF", nodes.EEVEE_BSDF))
        print("  with an EEVEE output: BSDF reads %s, EEVEE BSDF %s" % (sorted(cycles), sorted(eevee)))
        h.expect(group_node.EEVEE_OUTPUT in tree.nodes, "the bake added no EEVEE output")
        h.expect(cycles == {"Linear"} and eevee == {"Closest"}, "lookups: BSDF %s, EEVEE BSDF %s" % (cycles, eevee))

        linear = _render_cycles(os.path.join(directory, "linear.exr"), 48, 48)[..., :3]
        for j in range(nodes.lobe_count(group)):  # Cycles' lobes (and base) through EEVEE's lookups
            decode, taps = (group.nodes[nodes.DECODE[read] % j] for read in (nodes.LINEAR, nodes.TAPS))
            for output in decode.outputs:
                for link in list(output.links):
                    group.links.new(taps.outputs[output.name], link.to_socket)
        h.expect(_lookups(group, gout.inputs["BSDF"]) == {"Closest"}, "relinking left Linear lookups")
        closest = _render_cycles(os.path.join(directory, "closest.exr"), 48, 48)[..., :3]
        difference = float(np.abs(linear - closest).mean())
        print("  Cycles, one Linear against four Closest lookups a level: mean %.2e, largest %.2e (mean value %.3f)"
              % (difference, float(np.abs(linear - closest).max()), float(closest.mean())))
        h.expect(closest.mean() > 0.02 and difference < 1e-3 * closest.mean(),
                 "the Linear lookups render %.2e apart from the Closest ones" % difference)

        tree.nodes.remove(tree.nodes[group_node.EEVEE_OUTPUT])  # EEVEE now draws the group's BSDF
        bake.bake_material(material, bake.BakeSettings(max_lobes=2))
        group = tree.nodes["ndfbake"].node_tree
        gout = next(n for n in group.nodes if n.bl_idname == "NodeGroupOutput")
        shared = _lookups(group, gout.inputs["BSDF"])
        print("  re-baked without the EEVEE output: BSDF reads %s" % sorted(shared))
        h.expect(shared == {"Closest"}, "re-baked without the EEVEE output, BSDF reads %s" % shared)

        bake.revert(material)
        mix = tree.nodes.new("ShaderNodeMixShader")
        tree.links.new(tree.nodes["Principled BSDF"].outputs["BSDF"], mix.inputs[1])
        tree.links.new(mix.outputs[0], tree.nodes["Material Output"].inputs["Surface"])
        bake.bake_material(material, bake.BakeSettings(max_lobes=2))
        group = tree.nodes["ndfbake"].node_tree
        gout = next(n for n in group.nodes if n.bl_idname == "NodeGroupOutput")
        shared = _lookups(group, gout.inputs["BSDF"])
        h.expect(group_node.EEVEE_OUTPUT not in tree.nodes and shared == {"Closest"},
                 "behind the user's mix, BSDF reads %s" % shared)
        bake.revert(material)  # the shared groups go with the last bake using them, the Linear path's too
        left = [g.name for g in bpy.data.node_groups if g.get(node_builders.TAG)]
        h.expect(not left, "node groups left after Revert: %s" % left)


def test_revert_removes_the_atlas_table_of_a_long_material_name():
    """Blender cuts names at 63 bytes, so the atlas table of 'NDFB <name>' is no '<group> atlas':
    Revert finds it through the group's nodes."""
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory, size=32, material_name="M" * 63)
        _camera(location=(0.0, 0.0, 6.0), lens=50.0)
        result = bake.bake_material(material, bake.BakeSettings(max_lobes=1))
        h.expect("level of detail from the camera" in result.summary, result.summary)
        h.expect(len(bpy.data.node_groups) >= 2, "groups: %s" % [g.name for g in bpy.data.node_groups])
        bake.revert(material)
        leftovers = [g.name for g in bpy.data.node_groups]
        h.expect(not leftovers, "revert left node groups: %s" % leftovers)


def test_a_rebake_of_a_long_material_name_names_its_atlas_table():
    """A re-bake's node group and atlas table take the names a first bake gives them, however long
    the material's name: Blender cuts ID names at 63 bytes, so "<group> atlas" cannot be how the
    table is found, and its name keeps " atlas" within those 63 bytes (renaming it to the group's
    cut name would rename the group: Blender 3.4 gives a taken name to the ID renamed)."""
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        name = "M" * 60
        material = h.baked_scene(directory, size=32, material_name=name)
        _camera(location=(0.0, 0.0, 6.0), lens=50.0)
        group_name = ("NDFB " + name)[:63]
        table_name = ("NDFB " + name)[:63 - len(" atlas")] + " atlas"
        for bake_number in (1, 2, 3):
            result = bake.bake_material(material, bake.BakeSettings(max_lobes=2))
            h.expect("level of detail from the camera" in result.summary, result.summary)
            group = material.node_tree.nodes["ndfbake"].node_tree
            tables = {n.node_tree.name for n in group.nodes
                      if n.bl_idname == "ShaderNodeGroup" and n.node_tree.name.startswith("NDFB M")}
            material_groups = sorted(g.name for g in bpy.data.node_groups if g.name.startswith("NDFB M"))
            print("  bake %d: group %r, table %s" % (bake_number, group.name, sorted(tables)))
            h.expect(group.name == group_name, "bake %d: group %r, expected %r" % (bake_number, group.name, group_name))
            h.expect(tables == {table_name}, "bake %d: atlas tables %s, expected %r"
                     % (bake_number, tables, table_name))
            h.expect(material_groups == sorted([group_name, table_name]),
                     "bake %d: stale or duplicate groups: %s" % (bake_number, material_groups))
            h.expect(json.loads(material[bake.RECORD_KEY])["targets"][0]["node_group"] == group_name,
                     "bake %d: the record names another group" % bake_number)
        bake.revert(material)
        leftovers = [g.name for g in bpy.data.node_groups]
        h.expect(not leftovers, "revert left node groups: %s" % leftovers)


def test_long_names_that_blender_cuts_alike_keep_what_each_id_is():
    """Two materials whose groups' names Blender would cut to the same 63 bytes ('NDFB ', 20 CJK
    characters, A or B: 66 bytes of UTF-8): the second bake's group takes a .001, and every name still
    says what it is: the atlas tables end in " atlas" after their group's number, the images in
    " lobe j" (before a .001 of their own), all valid UTF-8 within 63 bytes; re-bakes keep them."""
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        stem = "\u6f22" * 20
        first = h.baked_scene(directory, size=32, material_name=stem + "A")
        second = h.normal_mapped_material(stem + "B", bpy.path.abspath(first.node_tree.nodes["Normal Texture"]
                                                                      .image.filepath))
        h.plane_with(second, "Second")
        _camera(location=(0.0, 0.0, 6.0), lens=50.0)
        bpy.ops.wm.save_mainfile()
        for round_ in (1, 2):
            for material in (first, second):
                bake.bake_material(material, bake.BakeSettings(max_lobes=2))
            names = {}
            for material in (first, second):
                group = material.node_tree.nodes["ndfbake"].node_tree
                tables = [n.node_tree.name for n in group.nodes if n.name.startswith("Atlas Level")]
                record = json.loads(material[bake.RECORD_KEY])
                names[material.name] = (group.name, sorted(set(tables)), sorted(record["images"]))
            print("  round %d: %s" % (round_, names))
            (group_a, tables_a, images_a), (group_b, tables_b, images_b) = names[first.name], names[second.name]
            h.expect(group_b.endswith(".001") and group_a.startswith(group_b[:-len(".001")]),
                     "groups %r and %r" % (group_a, group_b))
            for group, tables, tail in ((group_a, tables_a, " atlas"), (group_b, tables_b, ".001 atlas")):
                h.expect(len(tables) == 1 and tables[0].endswith(tail)
                         and group.startswith(tables[0][:-len(tail)]), "%r's atlas tables: %s" % (group, tables))
            for images in (images_a, images_b):
                h.expect(len(images) == 2 and all(" lobe %d" % j in name for j, name in enumerate(images)),
                         "lobe images %s" % images)
            for name in [group_a, group_b] + tables_a + tables_b + images_a + images_b:
                h.expect(len(name.encode("utf-8")) <= 63, "%r is %d bytes" % (name, len(name.encode("utf-8"))))
        for material in (first, second):
            bake.revert(material)
        h.expect(not bpy.data.node_groups, "revert left node groups: %s" % [g.name for g in bpy.data.node_groups])


def test_a_mapping_node_scales_the_texel_density():
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory, pattern="fbm", size=128)
        _resolution(64, 64)
        _camera(location=(0.0, 0.0, 6.0), lens=50.0)
        tree = material.node_tree
        coords, mapping = tree.nodes.new("ShaderNodeTexCoord"), tree.nodes.new("ShaderNodeMapping")
        tree.links.new(coords.outputs["UV"], mapping.inputs["Vector"])
        tree.links.new(mapping.outputs["Vector"], tree.nodes["Normal Texture"].inputs["Vector"])
        for vector_type, scale, expected in (("POINT", 4.0, 256.0), ("TEXTURE", 0.5, 128.0)):
            mapping.vector_type = vector_type
            mapping.inputs["Scale"].default_value = (scale, scale, 1.0)
            bpy.ops.wm.save_mainfile()
            result = bake.bake_material(material, bake.BakeSettings(max_lobes=1))
            density = tree.nodes["ndfbake"].inputs["Texels per Unit"].default_value
            print("  %s scale %g: %.2f texels per unit" % (vector_type, scale, density))
            h.expect(abs(density - expected) < 0.05, "%s scale %g: texel density %.3f, expected %g (64 untiled)"
                     % (vector_type, scale, density, expected))
        mapping.mute = True  # passes the UVs through: no tiling
        result = bake.bake_material(material, bake.BakeSettings(max_lobes=1))
        density = tree.nodes["ndfbake"].inputs["Texels per Unit"].default_value
        h.expect(abs(density - 64.0) < 0.05, "a muted Mapping node: %.3f texels per unit, expected 64" % density)
        mapping.mute = False
        # A muted link is no link. Into the texture: it reads its UVs untiled, and so does the group
        # (no Vector input: its lookups read the UVs too). Into the Mapping: it maps no UVs. A first
        # bake (reverted before): a re-bake's removal of the old nodes has Blender update the tree,
        # which clears is_linked of a socket whose link is muted, and the old code read is_linked.
        bake.revert(material)
        texture_vector = tree.nodes["Normal Texture"].inputs["Vector"]
        texture_vector.links[0].is_muted = True
        h.expect(texture_vector.is_linked, "Blender no longer says a muted link is linked: the test checks nothing")
        result = bake.bake_material(material, bake.BakeSettings(max_lobes=1))
        group = tree.nodes["ndfbake"]
        density = group.inputs["Texels per Unit"].default_value
        h.expect(abs(density - 64.0) < 0.05, "a muted link into the texture: %.3f texels per unit, expected 64"
                 % density)
        h.expect("Vector" not in group.inputs, "the group has a Vector input (linked: %s) where the texture's "
                 "link is muted" % ("Vector" in group.inputs and group.inputs["Vector"].is_linked))
        texture_vector.links[0].is_muted = False
        mapping.inputs["Vector"].links[0].is_muted = True
        result = bake.bake_material(material, bake.BakeSettings(max_lobes=1))
        h.expect("level 0 filtered by the renderer (its texture coordinates do not come from one UV map" in result.summary,
                 "a muted link into the Mapping: " + result.summary)
        mapping.inputs["Vector"].links[0].is_muted = False
        mapping.inputs["Rotation"].default_value = (math.pi / 2, 0.0, 0.0)  # out of the UV plane
        result = bake.bake_material(material, bake.BakeSettings(max_lobes=1))
        h.expect("level 0 filtered by the renderer (its texture coordinates do not come from one UV map" in result.summary,
                 result.summary)
        mapping.inputs["Rotation"].default_value = (0.0, 0.0, 0.0)
        # A UV Map node reading another UV map, tiled 4x there: measured on that map.
        mesh = bpy.data.objects["Plane"].data
        tiled = mesh.uv_layers.new(name="Tiled")
        for loop, uv in zip(tiled.data, mesh.uv_layers["UVMap"].data):
            loop.uv = (4.0 * uv.uv[0], 4.0 * uv.uv[1])
        uv_node = tree.nodes.new("ShaderNodeUVMap")
        uv_node.uv_map = "Tiled"
        tree.links.new(uv_node.outputs["UV"], tree.nodes["Normal Texture"].inputs["Vector"])
        result = bake.bake_material(material, bake.BakeSettings(max_lobes=1))
        density = tree.nodes["ndfbake"].inputs["Texels per Unit"].default_value
        h.expect(abs(density - 256.0) < 0.05, "a UV Map node on a 4x UV map: %.3f texels per unit, expected 256"
                 % density)
        tree.links.new(coords.outputs["Object"], mapping.inputs["Vector"])
        tree.links.new(mapping.outputs["Vector"], tree.nodes["Normal Texture"].inputs["Vector"])
        result = bake.bake_material(material, bake.BakeSettings(max_lobes=1))
        h.expect("level 0 filtered by the renderer (its texture coordinates do not come from one UV map" in result.summary,
                 result.summary)


def test_texel_density_counts_only_the_material_faces_and_the_render_uv_map():
    from ndfbake.shading import scene_lod
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory, pattern="bumps", size=64)
        other = bpy.data.materials.new("Other")
        # Two 2x2 quads side by side: ours with UVs 0..1 (0.5 UV per unit), the other's 0..10.
        mesh = bpy.data.meshes.new("Two")
        mesh.from_pydata([(-2, -1, 0), (0, -1, 0), (0, 1, 0), (-2, 1, 0), (2, -1, 0), (2, 1, 0)], [],
                         [(0, 1, 2, 3), (1, 4, 5, 2)])
        for name in ("Render", "Edit"):
            mesh.uv_layers.new(name=name)
        # Looked up once both exist: adding a layer may move the others (a reference taken before
        # reads freed memory; valgrind showed it in test_tangents).
        render_uv, edit_uv = mesh.uv_layers["Render"], mesh.uv_layers["Edit"]
        square = [(0, 0), (1, 0), (1, 1), (0, 1)]
        for face, scale in ((0, 1.0), (1, 10.0)):
            for corner, loop in enumerate(mesh.polygons[face].loop_indices):
                render_uv.data[loop].uv = [scale * c for c in square[corner]]
                edit_uv.data[loop].uv = [2.0 * scale * c for c in square[corner]]
        mesh.polygons[1].material_index = 1
        render_uv.active_render, mesh.uv_layers.active = True, edit_uv
        obj = bpy.data.objects.new("Two", mesh)
        bpy.context.scene.collection.objects.link(obj)
        obj.data.materials.append(material)
        obj.data.materials.append(other)
        bpy.data.objects["Plane"].hide_render = True
        lod = scene_lod.material_lod(bpy.context.scene, material, (64, 64))
        print("  texels per unit %.3f (the material's faces, the render UV map: 32)" % lod.texels_per_unit)
        h.expect(abs(lod.texels_per_unit - 32.0) < 1e-3, "texel density %r, expected 32" % lod.texels_per_unit)
        lod = scene_lod.material_lod(bpy.context.scene, material, (64, 64), uv_map="Edit")
        h.expect(abs(lod.texels_per_unit - 64.0) < 1e-3, "named UV map: %r, expected 64" % lod.texels_per_unit)


if __name__ == "__main__":
    h.import_addon()
    h.run([test_camera_footprint_is_the_pinhole_pixel_angle,
           test_material_lod_measures_texel_density_and_the_levels_reached,
           test_the_level_of_detail_group_renders_the_footprint_formula,
           test_atlas_lookups_equal_bilinear_filtering_of_the_level_files,
           test_a_bake_with_a_camera_writes_only_the_levels_it_reaches,
           test_cycles_alone_reads_each_level_with_one_linear_lookup,
           test_revert_removes_the_atlas_table_of_a_long_material_name,
           test_a_rebake_of_a_long_material_name_names_its_atlas_table,
           test_long_names_that_blender_cuts_alike_keep_what_each_id_is,
           test_a_mapping_node_scales_the_texel_density,
           test_texel_density_counts_only_the_material_faces_and_the_render_uv_map])
