"""Cancelling a bake part way leaves no files and no changed material.

Run: blender -b --factory-startup --python-exit-code 1 --python tests/blender/test_addon_cancel.py -- LIB

- Cancelled from the progress callback during the fit, and during the write (after some lobe
  textures exist in the library's staging folder): no file, no folder, material unchanged.
- The Bake button's path: the native bake on a worker thread (BakeJob.start), cancelled from the
  main thread while it fits (what Esc does in the modal operator): the same.
- A cancelled re-bake keeps the previous bake's files byte for byte and its nodes.
- The Bake button's modal operator, driven by timer events while a material preview renders:
  the finished bake is applied once, after the wait; Esc during the wait applies nothing.
"""
import hashlib
import os
import sys
import time
import types

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import test_addon_helpers as h  # noqa: E402


def _snapshot(directory):
    digest = {}
    for name in h.listing(directory):
        path = os.path.join(directory, name)
        if os.path.isfile(path):
            with open(path, "rb") as f:
                digest[name] = hashlib.sha256(f.read()).hexdigest()
        else:
            digest[name] = "dir"
    return digest


def _expect_unchanged(material, directory, before, files_before, what):
    h.expect(h.dump_material(material) == before, "%s: the material changed" % what)
    h.expect(_snapshot(directory) == files_before, "%s: files changed: %s" % (what, h.listing(directory)))


def _cancel_at(stage_wanted):
    seen = []

    def progress(stage, fraction):
        seen.append(stage)
        # fraction > 0: part way through the stage (for "write", level 0's textures are staged)
        return stage == stage_wanted and fraction > 0.0
    return progress, seen


def test_cancel_during_fit_and_during_write():
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory, size=128)
        before, files_before = h.dump_material(material), _snapshot(directory)
        for stage in ("fit", "write"):
            progress, seen = _cancel_at(stage)
            e = h.raised(bake.BakeError,
                         lambda: bake.bake_material(material, bake.BakeSettings(max_lobes=4), progress=progress),
                         "not cancelled at %s (stages seen: %s)" % (stage, sorted(set(seen))))
            h.expect(e.code == "CANCELLED", "%s: %s %s" % (stage, e.code, e.message))
            h.expect("cancelled" in e.message and "'Bumpy'" in e.message, e.message)
            h.expect(seen[-1] == stage, "cancelled at %s, last stage %s" % (stage, seen[-1]))
            _expect_unchanged(material, directory, before, files_before, "cancel during " + stage)
            print("  cancelled during %s: nothing written, material unchanged" % stage)


def test_cancel_worker_thread_from_main_thread():
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory, pattern="fbm", size=256)
        before, files_before = h.dump_material(material), _snapshot(directory)
        job = bake.prepare(material, bake.BakeSettings(max_lobes=4, threads=1))
        job.start()
        deadline = time.time() + 30
        while job.stage != "fit" and not job.done and time.time() < deadline:
            time.sleep(0.005)  # the main thread keeps running: Blender's UI would stay live
        h.expect(job.stage == "fit" and not job.done, "the worker did not reach the fit (stage %r, done %s)"
                 % (job.stage, job.done))
        fraction = job.fraction
        job.cancel()
        job.join(30)
        h.expect(job.done, "the worker did not stop")
        h.expect(job.error is not None and job.error.code == "CANCELLED", "error: %r" % job.error)
        e = h.raised(bake.BakeError, lambda: bake.finish(job), "finish() after a cancelled job must fail")
        h.expect(e.code == "CANCELLED", e.code)
        _expect_unchanged(material, directory, before, files_before, "worker cancel")
        print("  worker cancelled at %.0f%% of the bake" % (100 * fraction))


def test_cancelled_rebake_keeps_the_previous_bake():
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory, size=128)
        bake.bake_material(material, bake.BakeSettings(max_lobes=2))
        baked, files_baked = h.dump_material(material), _snapshot(directory)
        data_baked = h.data_counts()
        for stage in ("fit", "write"):
            progress, _ = _cancel_at(stage)
            e = h.raised(bake.BakeError,
                         lambda: bake.bake_material(material, bake.BakeSettings(max_lobes=3), progress=progress),
                         "re-bake not cancelled")
            h.expect(e.code == "CANCELLED", e.code)
            _expect_unchanged(material, directory, baked, files_baked, "cancelled re-bake at " + stage)
            h.expect(h.data_counts() == data_baked, "data-blocks changed")


def _drive_modal(material, previews, escape_at=None):
    """Runs the Bake button's modal operator on `material` with timer events, a material preview
    rendering for the first `previews` ticks after the bake; Esc at tick `escape_at` of that wait.
    Returns (what modal returned, how often finish() ran, the reports)."""
    from ndfbake.blender import bake, operators

    class Operator(operators._ModalBakes):
        reports = []

        def report(self, kind, message):
            self.reports.append((kind, message))

    finished = []
    real_finish = bake.finish
    bake.finish = lambda job: finished.append(job) or real_finish(job)
    try:
        op = Operator()
        op._jobs, op._done, op._outcomes = [bake.prepare(material, bake.BakeSettings(max_lobes=1))], [], []
        op._count, op._cancelled, op._preview_wait_start = 1, False, None
        op._next_job()
        ticks = []

        def preview_running():
            ticks.append(None)
            return len(ticks) <= previews

        op._preview_running = preview_running
        context = types.SimpleNamespace(window_manager=bpy.context.window_manager, screen=None)
        timer, escape = types.SimpleNamespace(type="TIMER", value="NOTHING"), types.SimpleNamespace(
            type="ESC", value="PRESS")
        deadline = time.time() + 30
        while time.time() < deadline:
            time.sleep(0.01)
            if escape_at is not None and len(ticks) == escape_at:
                op.modal(context, escape)
            result = op.modal(context, timer)
            if result != {"PASS_THROUGH"}:
                return result, len(finished), Operator.reports
        raise AssertionError("the modal operator did not end")
    finally:
        bake.finish = real_finish


def test_the_modal_operator_applies_a_bake_once_after_the_preview_wait():
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory)
        result, finishes, reports = _drive_modal(material, previews=3)
        h.expect(result == {"FINISHED"} and finishes == 1 and bake.is_baked(material),
                 "returned %s, finish() ran %d times, reports %s" % (result, finishes, reports))
        bake.revert(material)
        before, files_before = h.dump_material(material), _snapshot(directory)
        result, finishes, reports = _drive_modal(material, previews=3, escape_at=2)
        h.expect(result == {"CANCELLED"} and finishes == 0, "Esc in the wait: %s, %d" % (result, finishes))
        _expect_unchanged(material, directory, before, files_before, "Esc during the preview wait")


if __name__ == "__main__":
    h.import_addon()
    h.run([test_cancel_during_fit_and_during_write, test_cancel_worker_thread_from_main_thread,
           test_cancelled_rebake_keeps_the_previous_bake,
           test_the_modal_operator_applies_a_bake_once_after_the_preview_wait])
