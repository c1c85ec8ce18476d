"""The work of the add-on, shared by the Bake button, the operators and command-line scripts.

A bake has three steps, so that the UI can run the slow one on a worker thread:

    job = prepare(material, settings)   # main thread: checks everything; changes nothing
    job.run()  or  job.start()/poll     # any thread: the native bake into the lobe folder (no bpy)
    result = finish(job)                # main thread: images, node group, bypass, bake record

`bake_material()` runs the three in a row (scripts, `blender -b`). `revert()` undoes a bake:
the Principled BSDF's links come back, the group node, node groups and lobe images go; the lobe
files stay for Ctrl-Z (when they go: lobe_folders.py).

This module owns step 1 (prepare), whole bakes (bake_material, bake_materials) and the public names
(BakeSettings, BakeResult, BakeError, RECORD_KEY, finish, revert). Step 2 is core/bake_job.py
(BakeJob: no bpy there), step 3 bake_finish.py; lobe_folders.py commits or discards the pending
folder; revert() and the removal of a bake's nodes and images are bake_revert.py. Never calls
operators or ui.

Files (choices the design leaves open):
- The lobe textures go into a new folder beside the .blend named after the material,
  `//<material>.ndfbake/` (`~2`, `~3`… while earlier bakes' folders exist), and images refer to
  them with relative paths, so the .blend and its folders move together. lobe_folders.py says how
  folders are named and when they are deleted (only where no .blend, backup or recovery file can
  know them), so Ctrl-Z after a bake, a re-bake or a Revert always finds its files.
- The library writes the levels the scene's cameras reach (scene_lod.py), one MIP atlas per lobe
  slot, and report.json into a pending folder beside the new lobe folder, which finish() renames
  into place only after it has checked the material: a failed or cancelled bake changes no file
  and no node.
- An unsaved .blend has no "beside": baking it is refused (UNSAVED_BLEND). With `pack`, the
  level-0 textures are also packed into the .blend.
- Level of detail (BakeSettings.level_of_detail): "SCENE" (default) samples the atlases at the
  level the node group computes from the camera distance, the view angle and the constants
  scene_lod.py measured (texel density, pixel angle), in both engines; "RENDERER" samples
  level 0 with Linear interpolation and leaves filtering to the renderer (EEVEE MIP-maps it; Cycles
  only averages its pixel samples). A material no camera sees, a scene without a camera, a
  texture with box, sphere or tube projection (no UV for the atlas lookup) or with coordinates
  the nodes do not tie to one UV map (scene_lod.texture_uv) gets "RENDERER", and the summary
  says why.
  docs/rendering.md ("Level of detail") gives the measurement behind the default.
- Cycles lobes (BakeSettings.cycles_lobes): EEVEE draws the lobes as its generation needs them
  (nodes.default_grazing_narrowing: narrowed at grazing views in EEVEE Legacy, widened in EEVEE Next);
  Cycles draws them narrowed with its own constant (NARROWED, default: the far ground's
  converged brightness within 10% of the reference under most of Blender's studio worlds) or
  widened only (WIDENED: the fewest fireflies at low sample counts under a small bright light,
  too bright or too dark at grazing views). docs/rendering.md ("Grazing views") has the figures.
- Shader (BakeSettings.shader): "NODES" (default), the stock-node group; "OSL", where Cycles runs
  OSL on the CPU (osl_group.status), the same group with Cycles' lobes drawn by one OSL Script node
  that reads each slot's MIP-mapped file (native write option `mipmap`; every level is fitted, the
  renderer picks them by its ray differentials); EEVEE draws the stock group's lobes. osl_group.py.
"""
import math
from dataclasses import dataclass

import bpy

from ..core import bake_job, folder_names, native
from ..core.bake_job import BakeError  # noqa: F401  (bake.BakeError: what every caller catches)
from ..shading import bake_record, material_scan, nodes, osl_group, scene_lod
from . import bake_finish, bake_revert, image_pixels, lobe_folders
from .bake_finish import BakeResult, finish  # noqa: F401  (step 3: bake.finish, bake.BakeResult)

RECORD_KEY = bake_record.RECORD_KEY
revert = bake_revert.revert  # bake.revert: Revert (bake_revert.py)


@dataclass
class BakeSettings:
    max_lobes: int = None       # lobes per texel at most; None: the library's default (native.Library)
    tolerance: float = 0.0      # relative effective-BRDF error a texel may keep (0: max_lobes everywhere)
    refine: bool = False        # refine the lobes for the material's roughness (100-300x the fit time)
    threads: int = 0            # 0: every core
    pack: bool = False          # also pack the lobe textures into the .blend
    level_of_detail: str = "SCENE"  # "SCENE": atlases at a level from the camera; "RENDERER": level 0
    cycles_lobes: str = nodes.NARROWED  # what Cycles draws: lobes NARROWED toward grazing views, or WIDENED only
    shader: str = "NODES"       # "NODES": the stock-node group; "OSL": Cycles' lobes through OSL (osl_group.py)
    # C of the grazing narrowing per group output, for studies of other constants (studies/
    # world_sweep.py); None: nodes.default_grazing_narrowing(). Not in the panel.
    grazing_narrowing: dict = None


def is_baked(material):
    return material is not None and bake_record.record(material) is not None


def settings_from_material(material):
    """BakeSettings from the material's panel properties (defaults when the add-on is not registered)."""
    # Reading the pointer property would create it (a change to the material): only read settings
    # the user has set; the property group's defaults are BakeSettings' defaults. Not keys():
    # Blender 5.0 keeps bpy.props apart from the ID's custom properties.
    if material is None or not material.is_property_set("ndfbake_settings"):
        return BakeSettings()
    props = getattr(material, "ndfbake_settings", None)
    if props is None:
        return BakeSettings()
    return BakeSettings(max_lobes=props.max_lobes, tolerance=props.tolerance, refine=props.refine,
                        pack=props.pack, level_of_detail=props.level_of_detail, cycles_lobes=props.cycles_lobes,
                        shader=getattr(props, "shader", "NODES"))


# ---- step 1: prepare ------------------------------------------------------------------------------

def _plan_lod(material, scan, settings):
    """The scene's level of detail for the material (scene_lod.plan), or None: level 0 filtered
    by the renderer; and why not, where the material asked for the scene's."""
    if settings.level_of_detail != "SCENE":
        return None, ""
    tree = material.node_tree
    textures = [tree.nodes[t.image_texture] for t in scan.targets]
    for texture in textures:
        if texture.projection != "FLAT":
            return None, "Image Texture '%s' has %s projection" % (texture.name, texture.projection.lower())
    uvs = {scene_lod.texture_uv(t) for t in textures}
    if None in uvs or len(uvs) > 1:
        return None, "its texture coordinates do not come from one UV map (through Mapping nodes)"
    repeat, uv_map = uvs.pop()
    try:
        return scene_lod.plan(bpy.context.scene, material, tuple(scan.image.size), uv_map, repeat)
    except native.Error as e:
        raise BakeError("BAD_MESH", "cannot measure the texel density of the meshes using '%s' (%s): fix the mesh, "
                                    "or set Level of Detail to Renderer" % (material.name, e.message)) from None


def prepare(material, settings=None):
    """Checks the material and the library; returns a BakeJob or raises BakeError. Changes nothing.
    The native bake writes into a sibling folder '<lobe folder>.pending' that finish() moves into
    place once it has checked the material, so that a bake (or several, bake_all) can fail or be
    cancelled before any file changes; lobe_folders.discard_pending() throws one away."""
    settings = settings or BakeSettings()
    lib, message = native.status()
    if lib is None:
        raise BakeError("NO_LIBRARY", message)
    scan = material_scan.scan(material)
    if not scan.ok:
        raise BakeError(scan.problem.code, scan.problem.message)
    roughness = min(max(scan.roughness, 0.01), 1.0)
    try:  # the library's own check, before any work: the one place the settings are validated
        with lib.context() as ctx:
            bake_job.fit_options(ctx, settings, roughness, bake_finish.native_wrap(scan))
    except native.Error as e:
        raise BakeError("BAD_SETTINGS", "bad bake settings: %s" % e.message) from None
    if settings.level_of_detail not in ("SCENE", "RENDERER"):
        raise BakeError("BAD_SETTINGS", "level of detail must be SCENE or RENDERER, got %r" % settings.level_of_detail)
    if settings.cycles_lobes not in (nodes.WIDENED, nodes.NARROWED):
        raise BakeError("BAD_SETTINGS", "Cycles lobes must be %s or %s, got %r" % (nodes.WIDENED, nodes.NARROWED,
                                                                                  settings.cycles_lobes))
    if settings.shader not in ("NODES", "OSL"):
        raise BakeError("BAD_SETTINGS", "shader must be NODES or OSL, got %r" % settings.shader)
    narrowing = settings.grazing_narrowing
    if narrowing is not None and (set(narrowing) != {"BSDF", nodes.EEVEE_BSDF} or not all(
            math.isfinite(c) and c >= 0.0 for c in narrowing.values())):
        raise BakeError("BAD_SETTINGS", "grazing narrowing must give a finite C >= 0 for each of %s, got %r"
                        % (sorted({"BSDF", nodes.EEVEE_BSDF}), narrowing))
    if settings.shader == "OSL":
        available, why = osl_group.status(bpy.context.scene)
        if not available:
            raise BakeError("OSL_UNAVAILABLE", "cannot bake '%s' for OSL: %s" % (material.name, why))
        found = bake_record.recorded_targets(material.node_tree, bake_record.record(material) or {})
        for target in scan.targets:
            principled = material.node_tree.nodes[target.principled]
            # A re-bake: the group node holds the Principled's inputs as the user edits them now.
            holder = next((f.group_node for f in found if f.principled is not None
                           and f.principled.name == principled.name and f.group_node is not None), principled)
            unsupported = osl_group.unsupported_inputs(principled, holder)
            if unsupported:
                raise BakeError("OSL_UNSUPPORTED", "the OSL variant draws no %s (on '%s' of '%s'): bake it with "
                                "the stock-node shader" % (", ".join(unsupported), principled.name, material.name))
    lod, lod_note = _plan_lod(material, scan, settings)
    try:
        pixels = image_pixels.read(scan.image)
    except image_pixels.ImageReadError as e:
        raise BakeError("BAD_IMAGE", "the normal map of '%s' cannot be read: %s" % (material.name, e)) from None
    # Reserved last: nothing after it can fail, so no failed prepare keeps a folder name.
    try:
        relative, absolute = lobe_folders.new_folder(material)
    except lobe_folders.FolderError as e:
        raise BakeError("FOLDER_IN_USE", str(e)) from None
    if not absolute:
        raise BakeError("UNSAVED_BLEND", "save the .blend first: the lobe textures of '%s' are written beside it"
                        % material.name)
    return bake_job.BakeJob(material_name=material.name, material_pointer=material.as_pointer(),
                            image_path=scan.image_path, pixels=pixels, folder=relative,
                            out_dir=absolute + folder_names.PENDING_SUFFIX, final_dir=absolute,
                            wrap=bake_finish.native_wrap(scan),
                            roughness=roughness, settings=settings,
                            targets=bake_finish.target_names(scan),
                            lod=lod, lod_note=lod_note)


# ---- step 2: the native bake on any thread, no bpy: bake_job.py ----------------------------------

# ---- whole bakes ---------------------------------------------------------------------------------

def bake_material(material, settings=None, progress=None):
    """prepare + run + finish on the calling thread (scripts, `blender -b`, operator execute())."""
    job = prepare(material, settings)
    try:
        job.run(progress)
        return finish(job)
    except BakeError:
        lobe_folders.discard_pending(job)
        raise


def materials_needing_bake(scene):
    """Materials of this file (not linked from a library: they are baked in their own) with a
    normal-map chain on objects the scene renders, in name order."""
    found = {}
    for obj in scene_lod.rendered_objects(scene):
        for slot in obj.material_slots:
            material = slot.material
            if material is not None and material.library is None and material.name not in found \
                    and material_scan.uses_normal_map(material):
                found[material.name] = material
    return [found[name] for name in sorted(found)]


def bake_materials(materials, settings_for=None, progress=None):
    """Bakes each material; returns [(material name, BakeResult or BakeError)]. One failure does not
    stop the others; each failure leaves its material and files unchanged."""
    outcomes = []
    for material in materials:
        settings = settings_for(material) if settings_for else settings_from_material(material)
        try:
            outcomes.append((material.name, bake_material(material, settings, progress)))
        except BakeError as e:
            outcomes.append((material.name, e))
    return outcomes
