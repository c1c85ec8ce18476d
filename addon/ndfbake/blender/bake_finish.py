"""Step 3 of a bake (bake.py has the three): finish(job) on the main thread, once the native step
wrote the pending folder. It checks that the material is still what prepare() scanned, moves the
folder into place, loads the lobe images, builds the node group, swaps it in (replacing a previous
bake's nodes) and writes the bake record; on any failure nothing of the material or its files has
changed. Returns a BakeResult."""
import json
import os
from dataclasses import dataclass, field

import bpy

from ..core import folder_names, id_names, native_abi
from ..core.bake_job import BakeError
from ..shading import (bake_record, group_node, lod_nodes, material_scan, node_builders, nodes, osl_group,
                       transparent_shadow)
from . import bake_revert, lobe_folders


def native_wrap(scan):
    """The library's wrap mode for the scanned image's extension."""
    return native_abi.WRAP_REPEAT if scan.wrap == "REPEAT" else native_abi.WRAP_CLAMP


def target_names(scan):
    """(Principled BSDF, Normal Map, Image Texture) node names of each chain the bake filters."""
    return [(t.principled, t.normal_map, t.image_texture) for t in scan.targets]


@dataclass
class BakeResult:
    material: str
    folder: str                 # relative to the .blend ('//…')
    lobes: int                  # lobe slots the node group shades
    seconds: float
    report: dict = field(default_factory=dict)
    summary: str = ""




def _read_report(out_dir):
    try:
        with open(os.path.join(out_dir, "report.json"), encoding="utf-8") as f:
            return json.load(f)
    except (OSError, ValueError):
        return {}


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
    elif target_names(scan) != list(job.targets):
        why = "its normal-map nodes changed"
    elif native_wrap(scan) != job.wrap:
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
    lobe_folders.commit_pending(job)
    report = _read_report(job.out_dir)  # its error figures, for the summary
    output = job.output
    # The cheapest group that does: only the slots that hold lobes.
    textures = output.lobe_textures(atlas=job.lod is not None)
    paths = [os.path.join(job.out_dir, textures[j]) for j in sorted(textures)]
    if not paths:
        raise BakeError("NATIVE_ERROR", "the bake wrote no lobe texture into %s" % job.out_dir)
    atlas = None
    if job.lod is not None:
        width, height = output.atlas_size
        atlas = lod_nodes.AtlasLayout(width=width, height=height, levels=output.atlas_frames)
    mip_files = {j: os.path.join(job.out_dir, name)
                 for j, name in output.used_slot_files(native_abi.FILE_MIP).items()}

    old = bake_record.record(material) or {}
    # The group nodes of the previous bake, by the Principled BSDF they stand for: replaced in place.
    replacing, gone = {}, []
    for found in bake_record.recorded_targets(tree, old):
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
                    tree.nodes[normal_map_name], tree.nodes[texture_name], images, mip_files, atlas,
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
        folder_names.delete_bake_files(job.out_dir, [f.name for f in output.files])
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
        "version": bake_record.RECORD_VERSION,
        "folder": job.folder,
        "images": sorted(created),
        "targets": targets,
        "lobes": len(images),
        "packed": bool(job.settings.pack),
        "summary": summary,
        "settings": {"max_lobes": output.slots, "tolerance": job.settings.tolerance,
                     "refine": job.settings.refine, "roughness": job.roughness, "level_of_detail": "SCENE" if job.lod else "RENDERER",
                     "cycles_lobes": job.settings.cycles_lobes, "shader": job.settings.shader},
    }
    shadow = transparent_shadow.settle(material, old)
    if shadow is not None:
        rec[transparent_shadow.RECORD_FIELD] = shadow
    material[bake_record.RECORD_KEY] = json.dumps(rec)
    return BakeResult(material=material.name, folder=job.folder, lobes=len(images), seconds=job.seconds,
                      report=report, summary=summary)


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
