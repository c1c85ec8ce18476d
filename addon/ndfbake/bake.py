"""The work of the add-on, shared by the Bake button, the operators and command-line scripts.

A bake has three steps, so that the UI can run the slow one on a worker thread:

    job = prepare(material, settings)   # main thread: checks everything; changes nothing
    job.run()  or  job.start()/poll     # any thread: the native bake into the lobe folder (no bpy)
    result = finish(job)                # main thread: images, node group, bypass, bake record

`bake_material()` runs the three in a row (scripts, `blender -b`). `revert()` undoes a bake:
the Principled BSDF's links come back, the group node, node groups and lobe images go; the lobe
files stay for Ctrl-Z (when they go: lobe_folders.py).

This module owns steps 1 and 3, whole bakes (bake_material, bake_materials) and the public names
(BakeSettings, BakeResult, BakeError, RECORD_KEY, revert). Step 2 is bake_job.py (BakeJob,
commit_pending, discard_pending: no bpy there); revert() and the removal of a bake's nodes and
images are bake_revert.py. May call: bake_job, bake_revert and the Blender-data and plain layers
below (group_node, nodes, osl_group, lod_nodes, node_builders, scene_lod, lobe_folders,
material_scan, image_pixels, native, id_names, transparent_shadow); never operators or ui.

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
import json
import math
import os
import re
from dataclasses import dataclass, field

import bpy

from . import (bake_job, bake_revert, group_node, id_names, image_pixels, lobe_folders, lod_nodes, material_scan,
               native, node_builders, nodes, osl_group, scene_lod, transparent_shadow)
from .bake_job import BakeError  # bake.BakeError: what every caller catches

RECORD_KEY = material_scan.RECORD_KEY
revert = bake_revert.revert  # bake.revert: Revert (bake_revert.py)
RECORD_VERSION = 1


@dataclass
class BakeSettings:
    max_lobes: int = 4          # 1..8 lobes per texel
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


@dataclass
class BakeResult:
    material: str
    folder: str                 # relative to the .blend ('//…')
    lobes: int                  # lobe slots the node group shades
    seconds: float
    report: dict = field(default_factory=dict)
    summary: str = ""


def is_baked(material):
    return material is not None and material_scan.record(material) is not None


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


def _native_wrap(scan):
    return native.WRAP_REPEAT if scan.wrap == "REPEAT" else native.WRAP_CLAMP


def _target_names(scan):
    """(Principled BSDF, Normal Map, Image Texture) node names of each chain the bake filters."""
    return [(t.principled, t.normal_map, t.image_texture) for t in scan.targets]


def prepare(material, settings=None):
    """Checks the material and the library; returns a BakeJob or raises BakeError. Changes nothing.
    The native bake writes into a sibling folder '<lobe folder>.pending' that finish() moves into
    place once it has checked the material, so that a bake (or several, bake_all) can fail or be
    cancelled before any file changes; bake_job.discard_pending() throws one away."""
    settings = settings or BakeSettings()
    lib, message = native.status()
    if lib is None:
        raise BakeError("NO_LIBRARY", message)
    scan = material_scan.scan(material)
    if not scan.ok:
        raise BakeError(scan.problem.code, scan.problem.message)
    if not 1 <= settings.max_lobes <= native.MAX_LOBES:
        raise BakeError("BAD_SETTINGS", "maximum lobes must be 1..%d, got %d" % (native.MAX_LOBES, settings.max_lobes))
    if not 0.0 <= settings.tolerance <= 1.0:
        raise BakeError("BAD_SETTINGS", "tolerance must be in [0, 1], got %g" % settings.tolerance)
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
        found = material_scan.recorded_targets(material.node_tree, material_scan.record(material) or {})
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
                            out_dir=absolute + lobe_folders.PENDING_SUFFIX, final_dir=absolute,
                            wrap=_native_wrap(scan),
                            roughness=min(max(scan.roughness, 0.01), 1.0), settings=settings,
                            targets=_target_names(scan),
                            lod=lod, lod_note=lod_note)


# ---- step 2: the native bake on any thread, no bpy: bake_job.py ----------------------------------

# ---- step 3: finish (main thread) ----------------------------------------------------------------

def _read_report(out_dir):
    try:
        with open(os.path.join(out_dir, "report.json"), encoding="utf-8") as f:
            return json.load(f)
    except (OSError, ValueError):
        return {}


def _lobe_textures(out_dir, atlas):
    """The textures the node group samples: atlas_lobeJ.exr, or level00_lobeJ.exr."""
    prefix = "atlas_lobe" if atlas else "level00_lobe"
    pattern = re.compile(re.escape(prefix) + r"(\d+)\.exr$")
    indices = sorted(int(m.group(1)) for m in (pattern.match(n) for n in os.listdir(out_dir)) if m)
    return [os.path.join(out_dir, "%s%d.exr" % (prefix, j)) for j in indices]


def _relative(path):
    """`path` relative to the .blend ('//…'), with '/' between folders whatever the system: Blender
    reads both separators on Windows but only '/' on other systems' Python side
    (material_scan.image_file_path), so a .blend baked on Windows opens anywhere."""
    try:
        return bpy.path.relpath(path).replace("\\", "/")
    except ValueError:  # another drive
        return path


def _load_lobe_images(material_name, paths, pack, created):
    """Lobe images (Non-Color, channel-packed alpha: A is data, α·r_z), named "<material> lobe j"
    (while a previous bake's images hold those names, another: _take_names), all new (a bake's
    folder is new: lobe_folders.new_folder); their names are appended to `created` as they are
    made, for the caller to remove on an error."""
    images = []
    for j, path in enumerate(paths):
        image = bpy.data.images.load(path)
        image.name = id_names.free(bpy.data.images, *nodes.lobe_image_name(material_name, j))
        image[node_builders.TAG] = node_builders.GROUP_VERSION
        created.append(image.name)
        image.filepath = _relative(path)
        image.colorspace_settings.name = "Non-Color"
        image.alpha_mode = "CHANNEL_PACKED"
        if pack:
            image.pack()
        images.append(image)
    return images


def summarize(report, seconds, lobes):
    levels = report.get("levels", [])
    means = []
    for level in levels:
        histogram = level.get("lobe_histogram", [])
        texels = sum(histogram)
        means.append(sum(k * n for k, n in enumerate(histogram)) / texels if texels else 0.0)

    def mean_of(key):
        values = [lv.get(key, {}).get("mean") for lv in levels if lv.get(key)]
        values = [v for v in values if v is not None]
        return sum(values) / len(values) if values else float("nan")

    return ("%d lobe%s, %d levels, lobes per texel by level: %s; error %.3f (naive normal map %.3f, single vMF "
            "%.3f, Toksvig %.3f); %.1f s"
            % (lobes, "" if lobes == 1 else "s", len(levels), " ".join("%.1f" % m for m in means),
               mean_of("error"), mean_of("error_naive"), mean_of("error_single_vmf"), mean_of("error_toksvig"),
               seconds))


def _job_material(job):
    """The material the job was prepared for, renamed or not; by name where an undo during the
    bake rebuilt the data (then _check_unchanged decides whether it is still the same)."""
    for material in bpy.data.materials:
        if material.as_pointer() == job.material_pointer:
            return material
    return bpy.data.materials.get(job.material_name)


def _check_unchanged(material, job):
    """Refuses to apply a bake to a material whose normal map changed while it ran: another
    image, another chain of nodes, a Normal Map no longer in tangent space, another extension."""
    scan = material_scan.scan(material)
    if not scan.ok:
        why = scan.problem.message
    elif scan.image_path != job.image_path:
        why = "its normal map is now %s" % scan.image_path
    elif _target_names(scan) != list(job.targets):
        why = "its normal-map nodes changed"
    elif _native_wrap(scan) != job.wrap:
        why = "its image's extension changed"
    else:
        return
    raise BakeError("MATERIAL_CHANGED", "material '%s' changed during the bake (%s); bake it again"
                    % (material.name, why))


def finish(job):
    """After a successful run(): moves a pending job's files into place, loads the lobe textures,
    builds the node group, bypasses the Principled BSDF(s) and stores the bake record. Replaces a
    previous bake's nodes, images and record only once the new ones are all built and wired
    (group_node.replace_group_node): on an error the material is as it was before this bake, its
    previous bake included. (One exception: where the user deleted a previous bake's group node,
    its Principled BSDF is first wired back to where it was before that bake, as Revert does.)"""
    if job.error is not None:
        raise job.error
    material = _job_material(job)
    if material is None or material.node_tree is None:
        raise BakeError("MATERIAL_GONE", "material '%s' went away during the bake" % job.material_name)
    _check_unchanged(material, job)
    tree = material.node_tree
    bake_job.commit_pending(job)
    report = _read_report(job.out_dir)
    # The cheapest group that does: slots no texel uses (a tolerance left them empty) are all zero.
    used = report.get("slots_used")
    paths = [p for j, p in enumerate(_lobe_textures(job.out_dir, job.lod is not None))
             if used is None or j >= len(used) or used[j]]
    slots = [j for j, _ in enumerate(_lobe_textures(job.out_dir, job.lod is not None))
             if used is None or j >= len(used) or used[j]]
    if not paths:
        raise BakeError("NATIVE_ERROR", "the bake wrote no lobe texture into %s" % job.out_dir)
    atlas = None
    if job.lod is not None:
        layout = report.get("atlas") or {}
        if not layout.get("levels"):
            raise BakeError("NATIVE_ERROR", "report.json in %s has no atlas layout" % job.out_dir)
        atlas = lod_nodes.AtlasLayout(width=layout["width"], height=layout["height"], levels=layout["levels"])

    old = material_scan.record(material) or {}
    # The group nodes of the previous bake, by the Principled BSDF they stand for: replaced in place.
    replacing, gone = {}, []
    for found in material_scan.recorded_targets(tree, old):
        node = found.group_node
        if node is not None and found.principled is not None and node.bl_idname == "ShaderNodeGroup":
            replacing[found.principled.name] = found
        else:
            gone.append(found.target)
    if gone:  # group nodes the user deleted: their Principled BSDFs get their links back first
        bake_revert.remove_nodes(material, {"targets": gone})
    # By name: removing a dropped target's nodes below may remove one of these first; the new ones
    # are given other names while these exist.
    old_groups = [name for name in (t.get("node_group", "") for t in old.get("targets", []))
                  if name in bpy.data.node_groups]
    old_images = [name for name in old.get("images", []) if name in bpy.data.images]

    targets, images, created, inserted, replacements = [], [], [], [], []
    groups_before = set(bpy.data.node_groups.keys())
    try:
        images = _load_lobe_images(material.name, paths, job.settings.pack, created)
        groups = []
        for principled_name, normal_map_name, texture_name in job.targets:
            current = replacing[principled_name].group_node if principled_name in replacing else None
            if job.settings.shader == "OSL":
                groups.append(osl_group.build_material_group(
                    nodes.material_group_name(material.name), tree.nodes[principled_name],
                    tree.nodes[normal_map_name], tree.nodes[texture_name], images, job.out_dir, slots, atlas,
                    job.lod, current=current, cycles_lobes=job.settings.cycles_lobes,
                    narrowing=job.settings.grazing_narrowing))
                continue
            # Where EEVEE draws an output of its own, Cycles' lobes read the atlas with fewer lookups.
            cycles_only = group_node.eevee_draws_own_output(tree, tree.nodes[principled_name],
                                                           replacing.get(principled_name))
            groups.append(nodes.build_material_group(
                nodes.material_group_name(material.name), tree.nodes[principled_name], tree.nodes[normal_map_name],
                tree.nodes[texture_name], images, atlas, job.lod, current=current,
                cycles_lobes=job.settings.cycles_lobes, cycles_only=cycles_only,
                narrowing=job.settings.grazing_narrowing))
        for (principled_name, normal_map_name, texture_name), group in zip(job.targets, groups):
            principled = tree.nodes[principled_name]
            normal_map = tree.nodes[normal_map_name]
            texture = tree.nodes[texture_name]
            targets.append({"principled": principled_name, "normal_map": normal_map_name, "group_node": "",
                            "node_group": group.name, "bypassed": [], "eevee_output": "",
                            "principled_settings": group_node.principled_settings(principled)})
            if principled_name in replacing:
                previous = replacing[principled_name]
                replacement = group_node.replace_group_node(tree, group, principled, normal_map, texture,
                                                       previous.group_node, previous.eevee_output)
                replacements.append((targets[-1], replacement))
                node = tree.nodes[replacement.node]
                targets[-1].update(bypassed=replacement.bypassed, eevee_output=replacement.eevee_output)
            else:
                node, bypassed, eevee_output = group_node.insert_group_node(tree, group, principled, normal_map, texture)
                inserted.append(targets[-1])
                targets[-1].update(group_node=node.name, bypassed=bypassed, eevee_output=eevee_output)
            if job.lod is not None and bpy.context.scene.camera is not None:
                lod_nodes.drive_lod_inputs(node, bpy.context.scene, bpy.context.scene.camera)
    except Exception as e:
        # A bug, not bad input: take away what this bake added (its nodes, node groups, images and
        # files), so that the material is as it was before it, a previous bake included; say so.
        for _, replacement in reversed(replacements):
            group_node.undo_replacement(tree, replacement)
        bake_revert.remove_nodes(material, {"targets": inserted}, keep_edits=False)
        nodes.remove_unused_groups([name for name in bpy.data.node_groups.keys() if name not in groups_before])
        bake_revert.remove_images(created)
        lobe_folders.delete_bake_files(job.out_dir, os.listdir(job.out_dir))
        raise BakeError("INTERNAL", "building the node group of '%s' failed (%s: %s); the material is as it was "
                        "before this bake" % (material.name, type(e).__name__, e)) from e

    # Everything is built: the previous bake's nodes, node groups and images go (its files stay for
    # Ctrl-Z: lobe_folders.py), and the new ones take their names.
    for target, replacement in replacements:
        target["group_node"] = group_node.commit_replacement(tree, replacement).name
    baked = {principled_name for principled_name, _, _ in job.targets}  # each replaced above
    bake_revert.remove_nodes(material, {"targets": [found.target for name, found in replacing.items()
                                                    if name not in baked]})
    nodes.remove_unused_groups(old_groups)
    osl_group.remove_unused_text()
    bake_revert.remove_images(old_images)
    _take_names(material, targets, images)
    created = [image.name for image in images]

    summary = summarize(report, job.seconds, len(images))
    if job.lod is not None:
        summary += "; level of detail from the camera (%.1f texels per unit, largest footprint %.0f texels)" % (
            job.lod.texels_per_unit, job.lod.footprint_max)
    else:
        summary += "; level 0 filtered by the renderer" + (" (%s)" % job.lod_note if job.lod_note else "")
    if job.settings.shader == "OSL":
        summary += "; Cycles draws the lobes through OSL, at the levels its ray differentials pick"
    if job.settings.cycles_lobes == nodes.WIDENED:
        summary += "; Cycles draws the lobes widened only (not narrowed at grazing views)"
    rec = {
        "version": RECORD_VERSION,
        "folder": job.folder,
        "images": sorted(created),
        "targets": targets,
        "lobes": len(images),
        "packed": bool(job.settings.pack),
        "summary": summary,
        "settings": {"max_lobes": job.settings.max_lobes, "tolerance": job.settings.tolerance,
                     "refine": job.settings.refine, "roughness": job.roughness, "level_of_detail": "SCENE" if job.lod else "RENDERER",
                     "cycles_lobes": job.settings.cycles_lobes, "shader": job.settings.shader},
    }
    shadow = transparent_shadow.settle(material, old)
    if shadow is not None:
        rec[transparent_shadow.RECORD_FIELD] = shadow
    material[RECORD_KEY] = json.dumps(rec)
    return BakeResult(material=material.name, folder=job.folder, lobes=len(images), seconds=job.seconds,
                      report=report, summary=summary)


# ---- whole bakes ---------------------------------------------------------------------------------

def _take_names(material, targets, images):
    """The new bake's images and node groups take the names a first bake gives them ("<material>
    lobe j", "NDFB <material>", .001… where taken), which the previous bake's, now gone, held
    while both existed."""
    for j, image in enumerate(images):
        image.name = id_names.free(bpy.data.images, *nodes.lobe_image_name(material.name, j), own=image)
    for target in targets:
        group = bpy.data.node_groups.get(target["node_group"])
        if group is None:
            continue
        group.name = id_names.free(bpy.data.node_groups, nodes.material_group_name(material.name), own=group)
        table = lod_nodes.atlas_table(group)  # named after it
        if table is not None:
            table.name = id_names.free(bpy.data.node_groups, *lod_nodes.atlas_table_name(group.name), own=table)
        target["node_group"] = group.name


def bake_material(material, settings=None, progress=None):
    """prepare + run + finish on the calling thread (scripts, `blender -b`, operator execute())."""
    job = prepare(material, settings)
    try:
        job.run(progress)
        return finish(job)
    except BakeError:
        bake_job.discard_pending(job)
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
