"""Operators: thin wrappers over bake.py (and bake_job.py's job API for the modal bakes).

- ndfbake.bake: the active material (or `material=`). From a script or `blender -b` (execute) it
  bakes on the calling thread. From the Bake button (invoke, with a window) it runs the native
  bake on a worker thread and polls it from a modal timer: progress in the window manager's
  progress bar and the status bar, Esc cancels (the library's progress callback returns non-zero
  and the bake stops, leaving no file and no changed node). bpy is touched on the main thread only.
- ndfbake.bake_all: every material the scene needs (bake.materials_needing_bake); from a script,
  one after another on the calling thread; from the UI, modal like ndfbake.bake, every native bake
  into a pending folder and all finished together, so that Esc leaves every material as it was.
- ndfbake.revert: undoes the bake of the active material (or `material=`); the lobe textures stay
  for Ctrl-Z (when they go: lobe_folders.py).
- ndfbake.delete_unused_folders: deletes, after a confirmation dialog listing them, the lobe
  textures of the folders beside the .blend that the file does not use.
Failures are reported as one ERROR line each; from Python, bpy.ops raises RuntimeError then.

May call: bake (a job from bake.prepare: its run/start/cancel), lobe_folders (discard_pending). Called by: ui,
__init__ (registration).
"""
import os
import time

import bpy
from bpy.props import StringProperty

from . import bake, lobe_folders

# The job the Bake button is running (one at a time), for the panel, and the modal operator
# running it (stop_running_bakes).
running_job = None
_running_bakes = None
PREVIEW_WAIT = 10.0  # seconds (_ModalBakes._preview_running)


def _material(context, name):
    if name:
        return bpy.data.materials.get(name)
    material = getattr(context, "material", None)
    if material is None:
        obj = getattr(context, "object", None)
        material = obj.active_material if obj is not None else None
    return material


def _report_outcomes(operator, outcomes):
    """One INFO line per baked material, one ERROR line per failure; FINISHED if any succeeded."""
    failed = [(name, o) for name, o in outcomes if isinstance(o, bake.BakeError)]
    for name, outcome in outcomes:
        if not isinstance(outcome, bake.BakeError):
            operator.report({"INFO"}, "ndfbake: %s: %s" % (name, outcome.summary))
    for name, error in failed:
        operator.report({"ERROR"}, "ndfbake: " + error.message)
    return {"FINISHED"} if len(failed) < len(outcomes) else {"CANCELLED"}


class _ModalBakes:
    """Bakes a list of materials from the UI: each native bake on a worker thread, polled from a
    modal timer, with progress in the progress bar and the status bar; Esc cancels. The bakes are
    pending (bake.prepare) and finished together at the end, so that Esc at any point leaves every
    material and file as it was."""

    _timer = None
    _jobs = None      # prepared jobs still to run, in order
    _done = None      # jobs whose native bake succeeded, waiting for finish()
    _outcomes = None  # (material name, BakeResult or BakeError)
    _job = None
    _collected = False  # whether _job's outcome is in _done or _outcomes yet
    _count = 0
    _cancelled = False  # Esc: whatever the jobs' own outcomes, nothing is applied
    _preview_wait_start = None
    _workspace = None   # whose status bar shows the progress (the user may switch workspaces)

    def start_bakes(self, context, materials):
        global running_job, _running_bakes
        if running_job is not None:
            self.report({"WARNING"}, "ndfbake: a bake is already running (Esc cancels it)")
            return {"CANCELLED"}
        self._jobs, self._done, self._outcomes = [], [], []
        for material in materials:
            try:
                self._jobs.append(bake.prepare(material, bake.settings_from_material(material)))
            except bake.BakeError as e:
                self._outcomes.append((material.name, e))
        if not self._jobs:
            return _report_outcomes(self, self._outcomes)
        self._count = len(self._jobs)
        self._cancelled = False
        self._preview_wait_start = None
        self._workspace = context.workspace
        self._next_job()
        _running_bakes = self
        wm = context.window_manager
        wm.progress_begin(0, 100)
        self._timer = wm.event_timer_add(0.1, window=context.window)
        wm.modal_handler_add(self)
        self._status(context)
        return {"RUNNING_MODAL"}

    def _next_job(self):
        global running_job
        self._job = running_job = self._jobs.pop(0)
        self._collected = False
        self._job.start()

    def _fraction(self):
        finished = self._count - len(self._jobs) - 1
        return (finished + self._job.fraction) / self._count

    def _status(self, context):
        job = self._job
        which = " (%d of %d)" % (self._count - len(self._jobs), self._count) if self._count > 1 else ""
        text = "ndfbake: baking '%s'%s: %s %d%%%s" % (job.material_name, which, job.stage or "starting",
                                                     int(job.fraction * 100), ", cancelling" if job.cancelled
                                                     else " (Esc to cancel)")
        self._status_text(text)
        context.window_manager.progress_update(int(self._fraction() * 100))
        for area in context.screen.areas if context.screen else ():
            if area.type == "PROPERTIES":
                area.tag_redraw()

    def _status_text(self, text):
        try:
            if self._workspace is not None:
                self._workspace.status_text_set(text)
        except ReferenceError:  # the workspace was deleted meanwhile
            self._workspace = None

    def _end(self, context):
        global running_job, _running_bakes
        wm = context.window_manager
        if self._timer is not None:
            wm.event_timer_remove(self._timer)
            self._timer = None
        wm.progress_end()
        self._status_text(None)
        running_job = None
        _running_bakes = None

    def _preview_running(self):
        """Whether to wait before building nodes: Blender renders material previews (icons, the
        Preview panel) on a job thread that reads the materials' node groups, and node groups
        built or removed meanwhile came out without their sockets (seen 1 time in 6 in the window
        test). Waits at most PREVIEW_WAIT seconds: previews restart whenever a material changes."""
        if not bpy.app.is_job_running("RENDER_PREVIEW"):
            return False
        if self._preview_wait_start is None:
            self._preview_wait_start = time.monotonic()
        return time.monotonic() - self._preview_wait_start < PREVIEW_WAIT

    @staticmethod
    def _drop(jobs):
        """Throws jobs away: what they wrote into their pending folders, and the folder names they
        reserved (prepared jobs not started too)."""
        for job in jobs:
            lobe_folders.discard_pending(job)

    def modal(self, context, event):
        job = self._job
        if event.type == "ESC" and event.value == "PRESS":
            self._cancelled = True
            job.cancel()
            self._drop(self._jobs)  # and the ones not started
            self._jobs = []
            self._status(context)
            return {"RUNNING_MODAL"}
        if event.type != "TIMER":
            return {"PASS_THROUGH"}
        if not job.done:
            self._status(context)
            return {"PASS_THROUGH"}
        job.join()
        if not self._collected:  # once: the ticks of a wait for previews find the last job done
            self._collected = True
            if job.error is not None and job.error.code != "CANCELLED":
                self._drop([job])
                self._outcomes.append((job.material_name, job.error))
            else:
                self._done.append(job)
        if self._cancelled or (job.error is not None and job.error.code == "CANCELLED"):
            # Esc may come after this job's bake finished, or during the wait: dropped all the same.
            self._drop(self._done)
            self._done = []
            self._end(context)
            self.report({"INFO"}, "ndfbake: bake of '%s' cancelled: no file and no node changed%s" % (
                job.material_name, "; no other material changed either" if self._count > 1 else ""))
            return {"CANCELLED"}
        if self._jobs:
            self._next_job()
            self._status(context)
            return {"PASS_THROUGH"}
        if self._preview_running():
            return {"PASS_THROUGH"}
        self._end(context)
        for done in self._done:
            try:
                self._outcomes.append((done.material_name, bake.finish(done)))
            except bake.BakeError as e:
                lobe_folders.discard_pending(done)
                self._outcomes.append((done.material_name, e))
        self._done = []
        return _report_outcomes(self, self._outcomes)

    def cancel(self, context):
        # Blender ends the modal operator (a file is loaded, the window closes): stop the bakes
        # and drop them all, the running one too if it finished meanwhile.
        if self._job is not None:
            self._job.cancel()
            self._job.join()
            self._drop([self._job])
        self._drop(self._done + self._jobs)
        self._done, self._jobs = [], []
        self._end(context)


def stop_running_bakes(context):
    """Cancels the Bake button's bakes, if any (the add-on is being turned off: Blender frees a
    modal operator of an unregistered class without calling its cancel())."""
    if _running_bakes is not None:
        _running_bakes.cancel(context)


class NDFBAKE_OT_bake(_ModalBakes, bpy.types.Operator):
    bl_idname = "ndfbake.bake"
    bl_label = "Bake"
    bl_description = "Fit the normal map's lobes and shade the material through them (Esc cancels)"
    bl_options = {"REGISTER", "UNDO"}

    material: StringProperty(name="Material", description="Material to bake; empty: the active material")

    def _target(self, context):
        material = _material(context, self.material)
        if material is None:
            self.report({"ERROR"}, "ndfbake: no material to bake" + (" named '%s'" % self.material
                                                                     if self.material else ""))
        return material

    def execute(self, context):
        material = self._target(context)
        if material is None:
            return {"CANCELLED"}
        return _report_outcomes(self, bake.bake_materials([material]))

    def invoke(self, context, event):
        if bpy.app.background or context.window is None:
            return self.execute(context)
        material = self._target(context)
        if material is None:
            return {"CANCELLED"}
        return self.start_bakes(context, [material])


class NDFBAKE_OT_bake_all(_ModalBakes, bpy.types.Operator):
    bl_idname = "ndfbake.bake_all"
    bl_label = "Bake All"
    bl_description = ("Bake every material with a normal map on the objects the scene renders "
                      "(Esc cancels all of them)")
    bl_options = {"REGISTER", "UNDO"}

    def _materials(self, context):
        materials = bake.materials_needing_bake(context.scene)
        if not materials:
            self.report({"WARNING"}, "ndfbake: no material of this file in scene '%s' uses a normal map (materials "
                                     "linked from a library are baked in their own file)" % context.scene.name)
        return materials

    def execute(self, context):
        materials = self._materials(context)
        if not materials:
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
        return _report_outcomes(self, outcomes)

    def invoke(self, context, event):
        if bpy.app.background or context.window is None:
            return self.execute(context)
        materials = self._materials(context)
        if not materials:
            return {"CANCELLED"}
        return self.start_bakes(context, materials)


class NDFBAKE_OT_revert(bpy.types.Operator):
    bl_idname = "ndfbake.revert"
    bl_label = "Revert"
    bl_description = ("Restore the material's original nodes (the lobe textures stay on disk while a saved "
                      ".blend may use them)")
    bl_options = {"REGISTER", "UNDO"}

    material: StringProperty(name="Material", description="Material to revert; empty: the active material")

    def execute(self, context):
        material = _material(context, self.material)
        try:
            folder, kept_for = bake.revert(material)
        except bake.BakeError as e:
            self.report({"ERROR"}, "ndfbake: " + e.message)
            return {"CANCELLED"}
        if kept_for:
            self.report({"INFO"}, "ndfbake: %s reverted; its lobe textures stay, %s use%s them" % (
                material.name, ", ".join(kept_for), "s" if len(kept_for) == 1 else ""))
        elif folder and lobe_folders.deleted_at_close(folder):
            self.report({"INFO"}, "ndfbake: %s reverted; its lobe textures (%s) are deleted when the file is "
                                  "closed" % (material.name, folder))
        else:
            self.report({"INFO"}, "ndfbake: %s reverted; its lobe textures stay in %s for Ctrl-Z and for the .blend "
                                  "files that may use them (saved, autosaved, quit.blend): once this file is reopened, "
                                  "Delete Unused Lobe Folders in the ndfbake panel removes them"
                        % (material.name, folder or "?"))
        return {"FINISHED"}


class NDFBAKE_OT_delete_unused_folders(bpy.types.Operator):
    bl_idname = "ndfbake.delete_unused_folders"
    bl_label = "Delete Unused Lobe Folders"
    bl_description = ("Delete the lobe textures in the .ndfbake folders beside this .blend that none of its "
                      "materials and images use (other .blend files may: the dialog lists the folders)")
    bl_options = {"REGISTER"}  # files on disk: not undoable, hence the confirmation dialog

    def invoke(self, context, event):
        if not lobe_folders.unused_folders():
            self.report({"INFO"}, "ndfbake: no unused lobe folder beside this .blend")
            return {"CANCELLED"}
        return context.window_manager.invoke_props_dialog(self, width=480)

    def draw(self, context):
        layout = self.layout
        layout.label(text="Delete the lobe textures in these folders?", icon="ERROR")
        for folder in lobe_folders.unused_folders():
            layout.label(text=os.path.basename(folder), icon="FILE_FOLDER")
        layout.label(text="No material of this file uses them; another .blend beside it might.")

    def execute(self, context):
        folders = lobe_folders.unused_folders()
        removed, left = lobe_folders.delete_folders(folders)
        if left:
            self.report({"WARNING"}, "ndfbake: could not delete %s" % ", ".join(left))
        else:
            self.report({"INFO"}, "ndfbake: deleted %d files in %d unused lobe folders" % (removed, len(folders)))
        return {"FINISHED"}


classes = (NDFBAKE_OT_bake, NDFBAKE_OT_bake_all, NDFBAKE_OT_revert, NDFBAKE_OT_delete_unused_folders)
