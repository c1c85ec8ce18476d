"""Operators: thin wrappers over bake.py.

- ndfbake.bake: the active material (or `material=`). From a script or `blender -b` (execute) it
  bakes on the calling thread. From the Bake button (invoke, with a window) it runs the native
  bake on a worker thread and polls it from a modal timer: progress in the window manager's
  progress bar and the status bar, Esc cancels (the library's progress callback returns non-zero
  and the bake stops, leaving no file and no changed node). bpy is touched on the main thread only.
- ndfbake.bake_all: every material the scene needs (bake.materials_needing_bake), synchronously.
- ndfbake.revert: undoes the bake of the active material (or `material=`).
Failures are reported as one ERROR line each; from Python, bpy.ops raises RuntimeError then.
"""
import bpy
from bpy.props import StringProperty

from . import bake

# The job the Bake button is running (one at a time), for the panel.
running_job = None


def _material(context, name):
    if name:
        return bpy.data.materials.get(name)
    material = getattr(context, "material", None)
    if material is None:
        obj = getattr(context, "object", None)
        material = obj.active_material if obj is not None else None
    return material


class NDFBAKE_OT_bake(bpy.types.Operator):
    bl_idname = "ndfbake.bake"
    bl_label = "Bake"
    bl_description = "Fit the normal map's lobes and shade the material through them (Esc cancels)"
    bl_options = {"REGISTER", "UNDO"}

    material: StringProperty(name="Material", description="Material to bake; empty: the active material")

    _timer = None
    _job = None

    def execute(self, context):
        material = _material(context, self.material)
        if material is None:
            self.report({"ERROR"}, "ndfbake: no material to bake" + (" named '%s'" % self.material
                                                                     if self.material else ""))
            return {"CANCELLED"}
        try:
            result = bake.bake_material(material, bake.settings_from_material(material))
        except bake.BakeError as e:
            self.report({"ERROR"}, "ndfbake: " + e.message)
            return {"CANCELLED"}
        self.report({"INFO"}, "ndfbake: %s: %s" % (result.material, result.summary))
        return {"FINISHED"}

    def invoke(self, context, event):
        global running_job
        if bpy.app.background or context.window is None:
            return self.execute(context)
        if running_job is not None:
            self.report({"WARNING"}, "ndfbake: a bake is already running (Esc cancels it)")
            return {"CANCELLED"}
        material = _material(context, self.material)
        if material is None:
            self.report({"ERROR"}, "ndfbake: no material to bake")
            return {"CANCELLED"}
        try:
            job = bake.prepare(material, bake.settings_from_material(material))
        except bake.BakeError as e:
            self.report({"ERROR"}, "ndfbake: " + e.message)
            return {"CANCELLED"}
        self._job = running_job = job
        job.start()
        wm = context.window_manager
        wm.progress_begin(0, 100)
        self._timer = wm.event_timer_add(0.1, window=context.window)
        wm.modal_handler_add(self)
        self._status(context)
        return {"RUNNING_MODAL"}

    def _status(self, context):
        job = self._job
        text = "ndfbake: baking '%s': %s %d%%%s" % (job.material_name, job.stage or "starting",
                                                   int(job.fraction * 100), ", cancelling" if job.cancelled
                                                   else " (Esc to cancel)")
        if context.workspace is not None:
            context.workspace.status_text_set(text)
        context.window_manager.progress_update(int(job.fraction * 100))
        for area in context.screen.areas if context.screen else ():
            if area.type == "PROPERTIES":
                area.tag_redraw()

    def _end(self, context):
        global running_job
        wm = context.window_manager
        if self._timer is not None:
            wm.event_timer_remove(self._timer)
            self._timer = None
        wm.progress_end()
        if context.workspace is not None:
            context.workspace.status_text_set(None)
        running_job = None

    def modal(self, context, event):
        job = self._job
        if event.type == "ESC" and event.value == "PRESS":
            job.cancel()
            self._status(context)
            return {"RUNNING_MODAL"}
        if event.type != "TIMER":
            return {"PASS_THROUGH"}
        if not job.done:
            self._status(context)
            return {"PASS_THROUGH"}
        job.join()
        self._end(context)
        if job.error is not None:
            level = {"INFO"} if job.error.code == "CANCELLED" else {"ERROR"}
            self.report(level, "ndfbake: " + job.error.message)
            return {"CANCELLED"}
        try:
            result = bake.finish(job)
        except bake.BakeError as e:
            self.report({"ERROR"}, "ndfbake: " + e.message)
            return {"CANCELLED"}
        self.report({"INFO"}, "ndfbake: %s: %s" % (result.material, result.summary))
        return {"FINISHED"}

    def cancel(self, context):
        # Blender ends the modal operator (a file is loaded, the window closes): stop the bake.
        if self._job is not None:
            self._job.cancel()
            self._job.join()
        self._end(context)


class NDFBAKE_OT_bake_all(bpy.types.Operator):
    bl_idname = "ndfbake.bake_all"
    bl_label = "Bake All"
    bl_description = "Bake every material with a normal map on the objects the scene renders"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        materials = bake.materials_needing_bake(context.scene)
        if not materials:
            self.report({"WARNING"}, "ndfbake: no material in scene '%s' uses a normal map" % context.scene.name)
            return {"CANCELLED"}
        wm = context.window_manager
        wm.progress_begin(0, len(materials))
        outcomes = []
        try:
            for i, material in enumerate(materials):
                wm.progress_update(i)
                outcomes.extend(bake.bake_materials([material]))
        finally:
            wm.progress_end()
        failed = [(name, o) for name, o in outcomes if isinstance(o, bake.BakeError)]
        for name, outcome in outcomes:
            if not isinstance(outcome, bake.BakeError):
                self.report({"INFO"}, "ndfbake: %s: %s" % (name, outcome.summary))
        for name, error in failed:
            self.report({"ERROR"}, "ndfbake: %s" % error.message)
        return {"FINISHED"} if len(failed) < len(outcomes) else {"CANCELLED"}


class NDFBAKE_OT_revert(bpy.types.Operator):
    bl_idname = "ndfbake.revert"
    bl_label = "Revert"
    bl_description = "Restore the material's original nodes and delete its lobe textures"
    bl_options = {"REGISTER", "UNDO"}

    material: StringProperty(name="Material", description="Material to revert; empty: the active material")

    def execute(self, context):
        material = _material(context, self.material)
        try:
            removed, left = bake.revert(material)
        except bake.BakeError as e:
            self.report({"ERROR"}, "ndfbake: " + e.message)
            return {"CANCELLED"}
        if left:
            self.report({"WARNING"}, "ndfbake: %s reverted; could not delete %s" % (material.name, ", ".join(left)))
        else:
            self.report({"INFO"}, "ndfbake: %s reverted, %d files deleted" % (material.name, removed))
        return {"FINISHED"}


classes = (NDFBAKE_OT_bake, NDFBAKE_OT_bake_all, NDFBAKE_OT_revert)
