"""Tiny renders of a baked material in EEVEE (surfaceless EGL in `blender -b`) and Cycles (CPU).

Run: blender -b --factory-startup --python-exit-code 1 --python tests/blender/test_addon_render.py -- LIB

A tilted plane with a 64² bumps normal map, baked with 4 lobes and with the most the library fits
(8), lit by a sun, seen by a camera: 64² renders (EEVEE 4 TAA samples, Cycles 4 samples, no
denoiser) must run without errors and give finite, non-black images, and close to the unbaked
material's (this is a close-up: filtering must not change the overall brightness much). The
material's Emission is linked (a Noise Texture, weak): eight lobes, or a linked emission drawn
in every lobe, once overflowed Cycles' shader stack, which draws such a material black. An
emitting, half-transparent material renders as before once baked (the group draws the emission
once). Then a white furnace: a metal plane whose tiled map puts ~75 texels in a pixel, under a
uniform sky, keeps the original's energy within 3% once baked, in Cycles and EEVEE (0.885 before
the shader dropped brdf.h's amplitude; see lobe_nodes.py); and a flat map's bake equals the plain
material within 2% at view angles down to 2°, in Cycles and in EEVEE Next. Last, what
blender_compat says of EEVEE's film and the view exposure, checked on fine emitting checks, and
the panel's note that follows it. Image errors against references: test_addon_image_error.py.
"""
import math
import os
import sys

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import test_addon_helpers as h  # noqa: E402

SIZE = 64


def setup_scene():
    return h.sun_lit_scene(SIZE, cycles_samples=4, eevee_samples=4)


def render(scene, engine, path):
    scene.render.engine = engine
    return h.render_pixels(scene, path)[..., :3]


def straight_down_view(world_name, world_color, size, cycles_samples, eevee_samples):
    """The current scene seen by an orthographic camera 3 m above the origin looking straight down
    at 1.5 m of the plane there, under a uniform world, size² pixels (h.configure_render)."""
    scene = bpy.context.scene
    bpy.ops.object.camera_add(location=(0.0, 0.0, 3.0))
    scene.camera = bpy.context.active_object
    scene.camera.data.type = "ORTHO"
    scene.camera.data.ortho_scale = 1.5
    h.uniform_world(scene, world_name, world_color)
    h.configure_render(scene, size, size, cycles_samples=cycles_samples, eevee_samples=eevee_samples)
    return scene


def test_eevee_and_cycles_render_the_baked_material():
    from ndfbake.core import native
    from ndfbake.shading import blender_compat
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory, pattern="bumps", size=64, roughness=0.35, metallic=0.5)
        tree = material.node_tree
        principled = tree.nodes["Principled BSDF"]
        noise = tree.nodes.new("ShaderNodeTexNoise")
        tree.links.new(noise.outputs["Color"], principled.inputs[blender_compat.principled_input("Emission")])
        principled.inputs["Emission Strength"].default_value = 0.05
        scene = setup_scene()
        plain = {engine: render(scene, engine, os.path.join(directory, "plain-%s.exr" % engine))
                 for engine in (blender_compat.eevee_engine(), "CYCLES")}
        for lobes in (4, native.load().max_lobes):
            result = bake.bake_material(material, bake.BakeSettings(max_lobes=lobes))
            h.expect(result.lobes == lobes, "%d lobes asked, %d baked" % (lobes, result.lobes))
            for engine in (blender_compat.eevee_engine(), "CYCLES"):
                path = os.path.join(directory, "baked-%d-%s.exr" % (lobes, engine))
                pixels = render(scene, engine, path)
                h.expect(os.path.isfile(path), "%s wrote no image" % engine)
                h.expect(np.isfinite(pixels).all(), "%s: non-finite pixels" % engine)
                mean, plain_mean = float(pixels.mean()), float(plain[engine].mean())
                lit = float((pixels.max(axis=-1) > 0.02).mean())
                print("  %d lobes, %s: mean %.4f (unbaked %.4f), max %.3f, %.0f%% of pixels lit" % (
                    lobes, engine, mean, plain_mean, float(pixels.max()), 100 * lit))
                h.expect(mean > 0.01 and lit > 0.3, "%d lobes, %s: the baked material renders black" % (lobes, engine))
                h.expect(0.6 < mean / plain_mean < 1.4, "%d lobes, %s: baked %.4f vs unbaked %.4f" % (
                    lobes, engine, mean, plain_mean))


def test_emission_is_drawn_once_as_the_principled_draws_it():
    """A black, non-specular material that emits a Noise Texture's colour (Strength 2) at Alpha
    0.5: nearly all it renders is its emission, which the group draws once, beside the lobes,
    weighted by Alpha as the Principled weights it. Baked with 8 lobes, each engine's mean
    within 2% of the unbaked material's (EEVEE 4 TAA samples, Cycles 4 samples, 64²)."""
    from ndfbake.core import native
    from ndfbake.shading import blender_compat
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory, pattern="bumps", size=64, roughness=0.35, metallic=0.0)
        tree = material.node_tree
        principled = tree.nodes["Principled BSDF"]
        principled.inputs["Base Color"].default_value = (0.0, 0.0, 0.0, 1.0)
        principled.inputs[blender_compat.principled_input("Specular")].default_value = 0.0
        principled.inputs["Emission Strength"].default_value = 2.0
        principled.inputs["Alpha"].default_value = 0.5
        tree.links.new(tree.nodes.new("ShaderNodeTexNoise").outputs["Color"],
                       principled.inputs[blender_compat.principled_input("Emission")])
        scene = setup_scene()
        engines = (blender_compat.eevee_engine(), "CYCLES")
        plain = {e: float(render(scene, e, os.path.join(directory, "plain-%s.exr" % e)).mean()) for e in engines}
        bake.bake_material(material, bake.BakeSettings(max_lobes=native.load().max_lobes))
        group = material.node_tree.nodes["ndfbake"].node_tree
        emitters = [n.name for n in group.nodes if n.bl_idname == "ShaderNodeEmission"]
        h.expect(emitters == ["Emission"], "the group's emission nodes: %s" % emitters)
        for engine in engines:
            baked = float(render(scene, engine, os.path.join(directory, "baked-%s.exr" % engine)).mean())
            print("  %s: emission-lit mean %.4f, unbaked %.4f" % (engine, baked, plain[engine]))
            h.expect(abs(baked / plain[engine] - 1.0) < 0.02, "%s: baked %.4f vs unbaked %.4f"
                     % (engine, baked, plain[engine]))


def test_white_furnace_keeps_the_energy_of_the_fine_normals():
    """A metal plane whose normal map repeats 50 times, seen from above under a uniform white sky:
    each fine normal reflects about all the light, so the filtered lobes (far-off levels) must too.
    Cycles at 64 spp and EEVEE at 16 samples, 32² pixels of about 75 texels each; the baked mean
    within 3% of the original's in each (5.0: Cycles 0.981, EEVEE Next 0.990; 3.4: 1.000, EEVEE 0.993)."""
    from ndfbake.shading import blender_compat
    from ndfbake.blender import bake
    engines = ("CYCLES", blender_compat.eevee_engine())
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory, pattern="bumps", size=64, roughness=0.15, metallic=1.0)
        material.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (0.9, 0.9, 0.9, 1.0)
        for loop in bpy.data.objects["Plane"].data.uv_layers.active.data:
            loop.uv = (loop.uv[0] * 50.0, loop.uv[1] * 50.0)
        scene = straight_down_view("Furnace", (1.0, 1.0, 1.0), 32, cycles_samples=64, eevee_samples=16)

        def means(name):
            return {e: float(render(scene, e, os.path.join(directory, name + ".exr")).mean()) for e in engines}

        plain = means("plain")
        result = bake.bake_material(material, bake.BakeSettings(max_lobes=4))
        baked = means("baked")
        print("  %s" % result.summary)
        for engine in engines:
            ratio = baked[engine] / plain[engine]
            print("  furnace, %s: original %.4f, ndfbake %.4f (ratio %.3f)"
                  % (engine, plain[engine], baked[engine], ratio))
            h.expect(abs(ratio - 1.0) < 0.03, "%s: the filtered lobes change the furnace's energy: %.3f"
                     % (engine, ratio))


FURNACE_ELEVATIONS = (90.0, 45.0, 20.0, 10.0, 5.0, 2.0)  # degrees between the view and the plane
FURNACE_BOUND = 0.02
FURNACE_EEVEE_SAMPLES = 4
# Known misses, held to regression bounds (README, "White furnace"): (material, Principled
# version) -> (the elevations below which the bound is missed, the regression bound there).
# Principled v1 (3.x): the lobes' Multiscatter GGX against the original's GGX, which loses more
# energy at grazing views (3.4: 1.10 at 10°, 1.13 at 5°). Principled v2 meets the bound (5.0: the
# dielectrics' bases within 0.92% at every angle, the add-on's table against Cycles' own).
FURNACE_MISSES = {("metal", 1): (45.0, 0.15), ("dielectric", 1): (45.0, 0.15), ("half metal, alpha 0.5", 1): (45.0, 0.15)}


def test_flat_map_furnace_at_every_view_angle():
    """A flat normal map's baked material reflects what the plain one does, under a uniform white
    sky, seen from above down to 2° above the plane: a metal (conductor lobes only), a dielectric
    (in Principled v2 the base's diffuse under specular-only lobes; in v1 whole copies) and a half
    metal at Alpha 0.5 (both lobes mixed by Metallic, the transparency mixed in once), and in v2 a
    tinted GGX dielectric of IOR 1.33 and Specular IOR Level 0.7. Cycles, an orthographic camera on
    a large plane, 32² pixels at 64 spp; the means within 2% but where FURNACE_MISSES says
    otherwise."""
    flat_map_furnace("CYCLES", ("metal", "dielectric", "half metal, alpha 0.5", "tinted GGX dielectric"))


def test_flat_map_furnace_in_eevee_next():
    """The same furnace in EEVEE Next (4.2+), for the materials with a base, which EEVEE's output
    darkens by EEVEE's own split-sum estimate (specular_split._eevee_layer_albedo): the dielectric,
    the half metal and the tinted GGX dielectric, within 2% at every angle (5.0: 0.43% at most;
    with Cycles' estimate instead 2.4% at 5°, and 2.2% at 90° before the table's slices had their
    edge columns repeated). The metal's lobes alone are EEVEE's own Principled, as the plain
    material's (1.0000 in 5.0); not drawn again here."""
    from ndfbake.shading import blender_compat
    if not blender_compat.eevee_next():
        print("  skipped: EEVEE Legacy draws Principled v1, whose lobes are whole copies")
        return
    flat_map_furnace(blender_compat.eevee_engine(),
                     ("dielectric", "half metal, alpha 0.5", "tinted GGX dielectric"))


# The checks' luminance in the film-weighting test: well above the 4 of the film's 1 / (4 + luma · s),
# so that its weighting shows (5.0: ±0.5 render 0.30 of exposure 0).
CHECK_LUMINANCE = 20.0


def test_eevee_film_weighting_follows_the_view_exposure():
    """What blender_compat.eevee_film_darkens_with_exposure says of this Blender's EEVEE, checked:
    a plane of fine emitting black-and-white checks (about 37 to a pixel, so that each sample sees
    one or the other) under a black world, 8² pixels at 16 samples, at view exposures 0, +0.5 and
    −0.5. Where the film weighs luma by exposure², ±0.5 render the same and darker than 0; where
    EEVEE averages its samples, all three render the same. The panel's note follows it: shown in
    EEVEE at −0.5 where the film darkens, never at 0 nor in Cycles."""
    from ndfbake.shading import blender_compat
    h.reset_scene()
    scene = bpy.context.scene
    material = bpy.data.materials.new("Checks")
    h.enable_nodes(material)
    tree = material.node_tree
    output = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial")
    for node in [n for n in tree.nodes if n != output]:
        tree.nodes.remove(node)
    checker = tree.nodes.new("ShaderNodeTexChecker")
    checker.inputs["Scale"].default_value = 400.0
    checker.inputs["Color1"].default_value = (1.0, 1.0, 1.0, 1.0)
    checker.inputs["Color2"].default_value = (0.0, 0.0, 0.0, 1.0)
    emission = tree.nodes.new("ShaderNodeEmission")
    emission.inputs["Strength"].default_value = CHECK_LUMINANCE
    tree.links.new(checker.outputs["Color"], emission.inputs["Color"])
    tree.links.new(emission.outputs["Emission"], output.inputs["Surface"])
    h.plane_with(material)
    straight_down_view("Black", (0.0, 0.0, 0.0), 8, cycles_samples=1, eevee_samples=16)
    scene.render.engine = blender_compat.eevee_engine()
    darkens = blender_compat.eevee_film_darkens_with_exposure()
    means = {}
    with h.scratch_dir() as directory:
        for exposure in (0.0, 0.5, -0.5):
            scene.view_settings.exposure = exposure
            pixels = h.render_pixels(scene, os.path.join(directory, "checks%+g.exr" % exposure))[..., :3]
            means[exposure] = float(pixels.mean())
    print("  EEVEE, fine checks of luminance %g: mean at exposure 0 %.3f, +0.5 %.3f, -0.5 %.3f (the film "
          "%s)" % (CHECK_LUMINANCE, means[0.0], means[0.5], means[-0.5],
                   "darkens with exposure²" if darkens else "averages"))
    h.expect(means[0.0] > 0.2 * CHECK_LUMINANCE, "the checks render %.3f at exposure 0" % means[0.0])
    h.expect(abs(means[0.5] - means[-0.5]) <= 0.01 * means[0.0],
             "exposure +0.5 and -0.5 render %.3f and %.3f" % (means[0.5], means[-0.5]))
    if darkens:
        h.expect(means[0.5] < 0.85 * means[0.0], "blender_compat says EEVEE's film darkens away from exposure 0, "
                 "but ±0.5 render %.3f of exposure 0" % (means[0.5] / means[0.0]))
    else:
        h.expect(abs(means[0.5] - means[0.0]) <= 0.02 * means[0.0], "blender_compat says EEVEE averages, but "
                 "exposure 0.5 renders %.3f of exposure 0" % (means[0.5] / means[0.0]))
    scene.view_settings.exposure = -0.5
    note = blender_compat.eevee_exposure_note(scene)
    h.expect(bool(note) == darkens and (not note or "-0.5" in note), "the note at -0.5 in EEVEE: %r" % note)
    scene.view_settings.exposure = 0.0
    h.expect(blender_compat.eevee_exposure_note(scene) == "", "a note at exposure 0")
    scene.view_settings.exposure = -0.5
    scene.render.engine = "CYCLES"
    h.expect(blender_compat.eevee_exposure_note(scene) == "", "a note in Cycles")


def flat_map_furnace(engine, kinds):
    """The furnace of the two tests above in `engine`, for the materials named in `kinds` (those of
    this Principled version)."""
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        h.reset_scene()
        flat = np.zeros((16, 16, 3))
        flat[..., 2] = 1.0
        image_path = h.save_normals_png(flat, os.path.join(directory, "flat.png"))
        materials = {"metal": h.normal_mapped_material("Flat Metal", image_path, roughness=0.3, metallic=1.0),
                     "dielectric": h.normal_mapped_material("Flat Dielectric", image_path, roughness=0.4),
                     "half metal, alpha 0.5": h.normal_mapped_material("Flat Mixed", image_path, roughness=0.25,
                                                                       metallic=0.5)}
        principled = materials["metal"].node_tree.nodes["Principled BSDF"]
        principled.inputs["Base Color"].default_value = (0.9, 0.8, 0.7, 1.0)
        materials["half metal, alpha 0.5"].node_tree.nodes["Principled BSDF"].inputs["Alpha"].default_value = 0.5
        version = 2 if "Specular IOR Level" in principled.inputs else 1
        if version == 2:
            # The layer's table off its usual path: GGX (no multiscatter term), another IOR, a
            # Specular IOR Level that moves it, a tint (the largest channel darkens the diffuse).
            materials["tinted GGX dielectric"] = h.normal_mapped_material("Flat Tinted", image_path, roughness=0.6)
            tinted = materials["tinted GGX dielectric"].node_tree.nodes["Principled BSDF"]
            tinted.distribution = "GGX"
            tinted.inputs["IOR"].default_value = 1.33
            tinted.inputs["Specular IOR Level"].default_value = 0.7
            tinted.inputs["Specular Tint"].default_value = (1.0, 0.7, 0.4, 1.0)
        plane = h.plane_with(materials["metal"], size=200.0)
        bpy.ops.wm.save_as_mainfile(filepath=os.path.join(directory, "scene.blend"))
        scene = bpy.context.scene
        bpy.ops.object.camera_add()
        camera = scene.camera = bpy.context.active_object
        camera.data.type = "ORTHO"
        camera.data.ortho_scale = 0.5
        h.uniform_world(scene, "Furnace", (1.0, 1.0, 1.0))
        # EEVEE: a uniform sky over a flat plane has nothing for more samples to converge.
        h.configure_render(scene, 32, 32, cycles_samples=64, eevee_samples=FURNACE_EEVEE_SAMPLES)

        def means(material):
            plane.data.materials[0] = material
            found = []
            for elevation in FURNACE_ELEVATIONS:
                e = math.radians(elevation)
                camera.location = (0.0, -10.0 * math.cos(e), 10.0 * math.sin(e))
                camera.rotation_euler = (math.pi / 2 - e, 0.0, 0.0)
                found.append(float(render(scene, engine, os.path.join(directory, "furnace.exr")).mean()))
            return np.array(found)

        for kind in [k for k in kinds if k in materials]:
            material = materials[kind]
            plain = means(material)
            result = bake.bake_material(material, bake.BakeSettings(max_lobes=4))
            baked = means(material)
            ratio = baked / plain
            below, regression = FURNACE_MISSES.get((kind, version), (0.0, FURNACE_BOUND))
            bounds = np.where(np.array(FURNACE_ELEVATIONS) < below, regression, FURNACE_BOUND)
            print("  %s, %s, Principled v%d (%s): plain %s, baked %s; ratio %s" % (
                engine, kind, version, result.summary.split(";")[0], np.round(plain, 4), np.round(baked, 4),
                np.round(ratio, 4)))
            h.expect(np.all(np.isfinite(baked)) and np.all(np.abs(ratio - 1.0) < bounds),
                     "%s, %s: the baked flat map reflects %s of the plain material's furnace at elevations %s"
                     " (bounds %s)" % (engine, kind, np.round(ratio, 4), FURNACE_ELEVATIONS, bounds))


if __name__ == "__main__":
    h.import_addon()
    h.run([test_eevee_and_cycles_render_the_baked_material, test_emission_is_drawn_once_as_the_principled_draws_it,
           test_white_furnace_keeps_the_energy_of_the_fine_normals, test_flat_map_furnace_at_every_view_angle,
           test_flat_map_furnace_in_eevee_next, test_eevee_film_weighting_follows_the_view_exposure])
