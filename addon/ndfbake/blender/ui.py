"""The Material Properties panel and the per-material settings: a thin skin over bake.py."""
import textwrap

import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty

from ..core import native
from ..shading import bake_record, blender_compat, nodes, osl_group
from . import bake, lobe_folders, operators, panel_state


def max_lobes_property(lib):
    """Maximum Lobes, bounded and defaulted by the library (native.Library.max_lobes and
    default_max_lobes); without a library, where the panel says why and nothing bakes, 1."""
    maximum, default = (lib.max_lobes, lib.default_max_lobes) if lib is not None else (1, 1)
    return IntProperty(name="Maximum Lobes", description="vMF lobes per texel at most (each costs a BSDF in the "
                       "node group)", default=default, min=1, max=maximum)


class NDFBakeSettings(bpy.types.PropertyGroup):
    # max_lobes: max_lobes_property(), set by registration.register() from the library
    tolerance: FloatProperty(name="Tolerance", description="Relative effective-BRDF error a texel may keep: "
                             "fewer lobes where it suffices (0: the maximum everywhere)",
                             default=0.0, min=0.0, max=1.0, precision=3, step=1)
    refine: BoolProperty(name="Refine for Roughness", description="Move the lobes to where they shade closest "
                         "to the exact filtered look at the material's roughness: lower error, 100-300x the "
                         "fitting time", default=False)
    pack: BoolProperty(name="Pack Textures", description="Also pack the lobe textures into the .blend",
                       default=False)
    level_of_detail: EnumProperty(
        name="Level of Detail", default="SCENE",
        items=(("SCENE", "Scene Camera", "Pick the MIP level per pixel from the scene camera's distance, focal "
                "length and resolution and the mesh's texel density (both engines; bakes only the levels "
                "the cameras reach)"),
               ("RENDERER", "Renderer", "Sample level 0 and leave filtering to the renderer (EEVEE MIP-maps it; "
                "Cycles does not)")))
    cycles_lobes: EnumProperty(
        name="Cycles Lobes", default=nodes.NARROWED,
        items=((nodes.NARROWED, "Narrowed", "Cycles draws each lobe narrowed toward grazing views, as the normal map "
                "it stands for reflects there: the filtered look's brightness at grazing views"),
               (nodes.WIDENED, "Widened", "Cycles draws each lobe widened by its spread only: the fewest fireflies "
                "at low sample counts under a small bright light (an HDR's sun), too bright or too dark at "
                "grazing views")))
    shader: EnumProperty(
        name="Cycles Shader", default="NODES",
        items=(("NODES", "Nodes", "Stock shader nodes, in both engines"),
               ("OSL", "OSL Script", "Cycles draws the lobes through one OSL Script node that reads a MIP-mapped "
                "file per lobe slot: the renderer picks the level from its ray differentials (reflections, any "
                "camera, instances). Cycles on the CPU with Open Shading Language on; EEVEE draws the nodes")))


def _wrapped(layout, text, icon="NONE", width=60):
    lines = textwrap.wrap(text, width, break_on_hyphens=False) or [""]
    column = layout.column(align=True)
    for i, line in enumerate(lines):
        column.label(text=line, icon=icon if i == 0 else "BLANK1")


class NDFBAKE_PT_material(bpy.types.Panel):
    bl_label = "ndfbake"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "material"

    @classmethod
    def poll(cls, context):
        return getattr(context, "material", None) is not None

    def draw(self, context):
        layout = self.layout
        material = context.material
        lib, message = native.status()
        if lib is None:
            _wrapped(layout.box(), message, icon="ERROR")
            # Revert and the folder cleanup need no library.
            if bake.is_baked(material):
                layout.operator(operators.NDFBAKE_OT_revert.bl_idname, icon="LOOP_BACK")
            layout.operator(operators.NDFBAKE_OT_delete_unused_folders.bl_idname, icon="TRASH")
            return

        job = operators.running_job
        if job is not None:
            box = layout.box()
            box.label(text="Baking '%s': %s %d%%" % (job.material_name, job.stage or "starting",
                                                     int(job.fraction * 100)), icon="TIME")
            box.label(text="Esc cancels", icon="BLANK1")

        scan = panel_state.scan(material)
        box = layout.box()
        if scan.ok:
            nm = material.node_tree.nodes[scan.targets[0].normal_map]
            box.label(text="Normal map: %s" % scan.image.name, icon="IMAGE_DATA")
            box.label(text="%s, tangent space, UV %s" % (nm.name, nm.uv_map or "(active render)"), icon="BLANK1")
            if scan.roughness_linked:
                box.label(text="Base BRDF: GGX, roughness linked (per pixel; fit uses %.2f)" % scan.roughness,
                          icon="SHADING_RENDERED")
            else:
                box.label(text="Base BRDF: GGX, roughness %.3f" % scan.roughness, icon="SHADING_RENDERED")
        else:
            _wrapped(box, scan.problem.message, icon="ERROR")

        settings = material.ndfbake_settings
        column = layout.column()
        column.prop(settings, "max_lobes")
        column.prop(settings, "tolerance")
        column.prop(settings, "refine")
        column.prop(settings, "level_of_detail")
        column.prop(settings, "cycles_lobes")
        osl_available, osl_message = osl_group.status(context.scene)
        if osl_available or settings.shader == "OSL":
            column.prop(settings, "shader")
        column.prop(settings, "pack")

        baked = bake.is_baked(material)
        row = layout.row(align=True)
        bake_row = row.row(align=True)
        bake_row.enabled = scan.ok and job is None
        bake_row.operator(operators.NDFBAKE_OT_bake.bl_idname, text="Re-bake" if baked else "Bake",
                          icon="RENDER_STILL")
        revert_row = row.row(align=True)
        revert_row.enabled = baked and job is None
        revert_row.operator(operators.NDFBAKE_OT_revert.bl_idname, icon="LOOP_BACK")
        layout.operator(operators.NDFBAKE_OT_bake_all.bl_idname, icon="MATERIAL")
        layout.operator(operators.NDFBAKE_OT_delete_unused_folders.bl_idname, icon="TRASH")

        if baked:
            rec = bake_record.record(material)
            # Where the images are, as a path from the .blend: Save As and appending move them.
            folder = lobe_folders.record_folder(rec)
            _wrapped(layout.box(), "Baked into %s: %s" % (bpy.path.relpath(folder) if folder else "",
                                                           rec.get("summary", "")), icon="CHECKMARK")
            _wrapped(layout, "The ndfbake node now holds the material's inputs (colour, roughness, ...): edit "
                             "them there; the original Principled BSDF is kept, bypassed, for Revert.", icon="INFO")
        _wrapped(layout, osl_message, icon="INFO" if osl_available or settings.shader != "OSL" else "ERROR")
        exposure_note = blender_compat.eevee_exposure_note(context.scene)
        if exposure_note:
            _wrapped(layout, exposure_note, icon="INFO")


classes = (NDFBakeSettings, NDFBAKE_PT_material)
