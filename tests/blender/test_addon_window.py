"""The Bake button's path in a real Blender window (under Xvfb): the panel draws, the modal
operator bakes on a worker thread while the UI keeps running, and Esc cancels part way.

Run: xvfb-run -a -s "-screen 0 1280x800x24" blender --factory-startup --enable-event-simulate \
         --python tests/blender/test_addon_window.py -- LIB ZIP OUTDIR

Steps, driven by bpy.app.timers from Blender's own event loop:
1. A saved scene (a plane, a 64² normal map); the Properties editor shows the material tab.
2. ndfbake.bake is invoked as the button does (INVOKE_DEFAULT in the Properties editor): it must
   return RUNNING_MODAL at once, and Blender's timers must keep firing while the worker fits;
   it finishes with the material baked. A screenshot of the window (the Properties editor
   scrolled to the ndfbake panel) goes to OUTDIR.
3. A re-bake with other settings is started and an Esc press is simulated while the worker fits:
   the bake stops, the previous bake's files and nodes are untouched.
4. Ctrl-Z (ed.undo, as the key does) after the bake restores the material as it was before the
   bake, and Ctrl-Shift-Z (ed.redo) brings the baked material back.
5. Bake All from the UI with a second material: Esc while the second material fits leaves both
   materials and all files as they were (the first one's finished bake is discarded); so does Esc
   pressed when the first material's bake has just finished, before the operator has seen it; run
   again to the end, it bakes both, into folders without a ~2 (the cancelled bakes gave their folder
   names back).
6. The second material is reverted and Blender quits without saving (wm.quit_blender): after
   Blender writes quit.blend (File > Recover > Last Session) and the add-on's exit handler runs,
   both bakes' folders are still there, although no save used them: quit.blend holds the first
   bake, and an autosave may hold the second (with a window, lobe_folders deletes nothing by
   itself). Checked by an atexit function that runs after the add-on's.
The worker is held at its first "fit" progress call until the main thread has seen what it
checks (a gate in BakeJob.run), so the test does not race the fit on a loaded machine.
It prints PASS when every check holds, FAIL otherwise, and Blender quits normally either way.
"""
import atexit
import faulthandler
import hashlib
import os
import sys
import time

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import test_addon_helpers as h  # noqa: E402

# A segfault seen twice in Debian's Blender 3.4 here, with no Python stack in Blender's crash file
# (docs/hardening.md): should it come again, every thread's Python stack goes to stderr.
faulthandler.enable(all_threads=True)

state = {"step": "start", "ticks": 0, "deadline": time.time() + 150, "hold": {"Window"}}


def _install_gate():
    """Holds the worker thread of a material in state["hold"] at its first "fit" progress call
    until the main thread lets it go or the job is cancelled, so that what the test observes does not depend on how fast the
    machine fits (the progress callback runs on the worker; the modal operator on the main thread)."""
    from ndfbake.core import bake_job
    original = bake_job.BakeJob.run

    def gated_run(self, progress=None):
        def gate(stage, fraction):
            deadline = time.time() + 60
            while (stage == "fit" and self.material_name in state["hold"] and not self.cancelled
                   and time.time() < deadline):
                time.sleep(0.01)
            return False
        return original(self, gate)
    bake_job.BakeJob.run = gated_run


def _finish(ok, message, quitting=False):
    h.finish_window_test("test_addon_window", state, ok, message, quitting)


def _properties_area():
    window = bpy.context.window_manager.windows[0]
    areas = sorted(window.screen.areas, key=lambda a: a.width * a.height, reverse=True)
    area = next((a for a in areas if a.type == "PROPERTIES"), None)
    if area is None:  # make the largest area a Properties editor
        area = areas[0]
        area.type = "PROPERTIES"
    area.spaces.active.context = "MATERIAL"
    region = next(r for r in area.regions if r.type == "WINDOW")
    return window, area, region


def _snapshot(directory):
    result = {}
    for name in h.listing(directory):
        path = os.path.join(directory, name)
        result[name] = hashlib.sha256(open(path, "rb").read()).hexdigest() if os.path.isfile(path) else "dir"
    return result


def _press_esc():
    window = bpy.context.window_manager.windows[0]
    window.event_simulate(type="ESC", value="PRESS")
    window.event_simulate(type="ESC", value="RELEASE")


def _expect_as_before_bake_all(when):
    materials, files = state["all_before"]
    now = {m.name: h.dump_material(m) for m in bpy.data.materials if m.node_tree}
    h.expect(now == materials, "Esc in Bake All (%s) changed materials: %s" % (when, h.differences(materials, now)))
    h.expect(_snapshot(state["dir"]) == files, "Esc in Bake All (%s) changed files: %s" % (when, sorted(
        set(_snapshot(state["dir"])) ^ set(files))))
    print("Esc during Bake All (%s): no material and no file changed" % when, flush=True)


def _invoke_bake(operator=None):
    """Invokes ndfbake.bake (or `operator`) as its button does, in the Properties editor."""
    window, area, region = _properties_area()
    with bpy.context.temp_override(window=window, area=area, region=region):
        return (operator or bpy.ops.ndfbake.bake)("INVOKE_DEFAULT")


def _tick():
    from ndfbake.shading import bake_record
    from ndfbake.core import folder_names
    from ndfbake.blender import bake, lobe_folders, operators
    state["ticks"] += 1
    step = state["step"]
    if step == "start":
        directory = state["dir"] = h.temp_dir()
        material = h.normal_mapped_material("Window", h.write_normal_map(os.path.join(directory, "normal.png"),
                                                                         "bumps", 64))
        for other in list(bpy.data.objects):  # the startup cube, camera and light
            bpy.data.objects.remove(other)
        obj = h.plane_with(material)
        bpy.context.view_layer.objects.active = obj
        obj.select_set(True)
        bpy.ops.wm.save_as_mainfile(filepath=os.path.join(directory, "scene.blend"))
        window, area, region = _properties_area()
        with bpy.context.temp_override(window=window, area=area, region=region):
            bpy.ops.ed.undo_push(message="ndfbake test scene")  # what Ctrl-Z returns to
        state["unbaked"] = h.dump_material(material)
        area.tag_redraw()
        state["step"] = "invoke"
        return 0.5  # the Properties editor picks up the active object's material when it redraws
    elif step == "invoke":
        result = _invoke_bake()
        h.expect(result == {"RUNNING_MODAL"}, "the Bake button did not start a modal bake: %s" % result)
        state["ticks_while_fitting"] = 0
        state["step"] = "baking"
    elif step == "baking":
        job = operators.running_job
        if job is not None:
            if job.stage == "fit" and not job.done:
                state["ticks_while_fitting"] += 1  # Blender's event loop runs while the worker fits
            if state["ticks_while_fitting"] >= 5:
                state["hold"] = set()
            return 0.05
        material = bpy.data.materials["Window"]
        h.expect(bake.is_baked(material), "the modal bake did not bake the material")
        state["baked_dump"] = h.dump_material(material)
        h.expect(state["ticks_while_fitting"] >= 5, "the UI loop did not run during the bake")
        _properties_area()[1].tag_redraw()
        state["step"] = "screenshot"
        return 0.5  # let the panel redraw with the result
    elif step == "screenshot":
        # The Properties editor full-window, scrolled to its end, where the ndfbake panel is.
        window, area, region = _properties_area()
        with bpy.context.temp_override(window=window, area=area, region=region):
            bpy.ops.screen.screen_full_area()
        state["step"] = "scroll"
        return 0.5
    elif step == "scroll":
        window, area, region = _properties_area()
        with bpy.context.temp_override(window=window, area=area, region=region):
            for _ in range(40):
                bpy.ops.view2d.scroll_down(deltay=200)
        area.tag_redraw()
        state["step"] = "shoot"
        return 0.5
    elif step == "shoot":
        window, area, region = _properties_area()
        path = os.path.join(state["out"], "ndfbake-panel.png")
        with bpy.context.temp_override(window=window, area=area, region=region):
            bpy.ops.screen.screenshot(filepath=path)
            bpy.ops.screen.back_to_previous()
        h.expect(os.path.isfile(path) and os.path.getsize(path) > 1000, "no screenshot")
        print("screenshot of the panel: %s" % path, flush=True)
        # Re-bake with other settings (a finished re-bake would change nodes and files), Esc while it fits.
        directory = state["dir"]
        material = bpy.data.materials["Window"]
        material.ndfbake_settings.max_lobes = 2
        state["hold"] = {"Window"}
        state["baked"] = (h.dump_material(material), _snapshot(directory))
        h.expect(_invoke_bake() == {"RUNNING_MODAL"}, "re-bake did not start")
        state["step"] = "cancel"
    elif step == "cancel":
        job = operators.running_job
        if job is None:
            _finish(False, "the re-bake ended before it could be cancelled")
        if job.stage != "fit":
            return 0.02
        state["job"] = job
        state["esc_at"] = (job.stage, job.fraction, time.time())
        _press_esc()
        state["step"] = "cancelled"
        return 0.05
    elif step == "cancelled":
        if operators.running_job is not None:
            return 0.05
        job = state["job"]
        print("Esc during %s at %.0f%%: the bake ended %.2f s later with %s" % (
            state["esc_at"][0], 100 * state["esc_at"][1], time.time() - state["esc_at"][2],
            job.error and job.error.code), flush=True)
        h.expect(job.cancelled and job.error is not None and job.error.code == "CANCELLED",
                 "Esc did not cancel the bake")
        material = bpy.data.materials["Window"]
        # The scene image was rewritten on disk for the re-bake; compare the bake's own files.
        nodes_before, files_before = state["baked"]
        h.expect(h.dump_material(material) == nodes_before, "the cancelled re-bake changed the material")
        files_after = _snapshot(state["dir"])
        h.expect(files_after == files_before, "the cancelled re-bake changed files: %s" % sorted(
            name for name in set(files_before) | set(files_after) if files_before.get(name) != files_after.get(name)))
        state["step"] = "undo"
    elif step == "undo":
        window, area, region = _properties_area()
        with bpy.context.temp_override(window=window, area=area, region=region):
            h.expect(bpy.ops.ed.undo() == {"FINISHED"}, "Ctrl-Z did nothing")
        material = bpy.data.materials["Window"]
        h.expect(not bake.is_baked(material), "Ctrl-Z left the material baked")
        now = h.dump_material(material)
        h.expect(now == state["unbaked"], "Ctrl-Z did not restore the material exactly: %s"
                 % h.differences(state["unbaked"], now))
        with bpy.context.temp_override(window=window, area=area, region=region):
            h.expect(bpy.ops.ed.redo() == {"FINISHED"}, "Ctrl-Shift-Z did nothing")
        material = bpy.data.materials["Window"]
        h.expect(bake.is_baked(material) and h.dump_material(material) == state["baked_dump"],
                 "Ctrl-Shift-Z did not bring the bake back")
        print("Ctrl-Z restored the unbaked material; Ctrl-Shift-Z the baked one", flush=True)
        state["step"] = "all_start"
    elif step == "all_start":
        directory = state["dir"]
        second = h.normal_mapped_material("Second", h.write_normal_map(os.path.join(directory, "second.png"),
                                                                       "weave", 64))
        h.plane_with(second, name="Second plane").location = (3.0, 0.0, 0.0)
        second.ndfbake_settings.max_lobes = 3  # (the panel drawing it would create the settings anyway)
        state["all_before"] = ({m.name: h.dump_material(m) for m in bpy.data.materials if m.node_tree}, _snapshot(directory))
        state["hold"] = {"Second"}
        h.expect(_invoke_bake(bpy.ops.ndfbake.bake_all) == {"RUNNING_MODAL"}, "Bake All did not start")
        state["step"] = "all_cancel"
    elif step == "all_cancel":
        job = operators.running_job
        h.expect(job is not None, "Bake All ended before the second material")
        if job.material_name != "Second" or job.stage != "fit":
            return 0.02
        _press_esc()
        state["step"] = "all_cancelled"
    elif step == "all_cancelled":
        if operators.running_job is not None:
            return 0.05
        _expect_as_before_bake_all("second material fitting")
        state["hold"] = set()
        h.expect(_invoke_bake(bpy.ops.ndfbake.bake_all) == {"RUNNING_MODAL"}, "Bake All did not start")
        # Esc after the first material's bake has finished but before the operator saw it (its
        # timer cannot run while this callback waits): that bake must be dropped too.
        job = operators.running_job
        deadline = time.time() + 60
        while not job.done and time.time() < deadline:
            time.sleep(0.005)
        _press_esc()
        state["step"] = "all_cancelled_late"
    elif step == "all_cancelled_late":
        if operators.running_job is not None:
            return 0.05
        _expect_as_before_bake_all("first material just finished")
        h.expect(_invoke_bake(bpy.ops.ndfbake.bake_all) == {"RUNNING_MODAL"}, "Bake All did not start")
        state["step"] = "all_done"
    elif step == "all_done":
        if operators.running_job is not None:
            return 0.05
        h.expect(all(bake.is_baked(bpy.data.materials[n]) for n in ("Window", "Second")), "Bake All did not bake both")
        second_folder = lobe_folders.record_folder(bake_record.record(bpy.data.materials["Second"]))
        h.expect(os.path.basename(second_folder) == "Second.ndfbake", "the cancelled bakes kept their folder names: "
                 "Second went to %s" % second_folder)
        h.expect(not [n for n in os.listdir(state["dir"]) if n.endswith(folder_names.PENDING_SUFFIX)], "pending folders left")
        print("Bake All from the UI baked both materials", flush=True)
        _quit_without_saving()
    return 0.05


def _quit_without_saving():
    from ndfbake.shading import bake_record
    from ndfbake.blender import bake, lobe_folders
    folders = {name: lobe_folders.record_folder(bake_record.record(bpy.data.materials[name]))
               for name in ("Window", "Second")}
    bake.revert(bpy.data.materials["Second"])
    # quit.blend goes to Blender's temporary directory: this test's, not the user's.
    bpy.context.preferences.filepaths.temporary_directory = state["dir"]
    state["quit"] = {"kept": [folders["Window"], folders["Second"]],
                     "recovery": os.path.join(state["dir"], "quit.blend")}
    bpy.ops.wm.quit_blender()


def _after_quit():
    """Registered before the add-on is imported, so it runs after the add-on's exit handler."""
    quit = state.get("quit")
    if quit is None:
        return
    failures = ([] if os.path.isfile(quit["recovery"]) else ["no quit.blend was written"]) + [
        "a lobe folder was deleted: %s" % folder for folder in quit["kept"] if not os.path.isdir(folder)]
    print("quit without saving: quit.blend written, both lobe folders kept" if not failures
          else "quit without saving: " + "; ".join(failures), flush=True)
    _finish(not failures, "modal bake, screenshot, Esc cancel, undo, Bake All and quit work (%d UI ticks)"
            % state["ticks"], quitting=True)


atexit.register(_after_quit)
h.run_window_test("test_addon_window", state, _tick)
_install_gate()
