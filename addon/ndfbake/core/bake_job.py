"""Step 2 of a bake: the native bake into the pending lobe folder, on any thread; and BakeError.

    job = bake.prepare(material, settings)   # main thread (bake.py): a BakeJob
    job.run()  or  job.start() / job.done    # here, on any thread: the library fits and writes
    bake.finish(job)                         # main thread (bake.py): lobe_folders.commit_pending() first

No bpy here, so that the thread rule can be seen: run() and start()'s worker read only the job's
own fields (the pixels prepare() decoded, paths, settings) and call only native.py and
folder_names.delete_bake_files (plain file removal). blender/lobe_folders.py's commit_pending() and
discard_pending() move or delete the pending folder on the main thread.
"""
import os
import threading
import time

from . import folder_names, native, native_abi

# Weights of the library's progress stages in the overall fraction (each reports 0..1); Blender
# decodes the map in prepare(), before the job starts.
_STAGES = (("fit", 0.62), ("measure", 0.30), ("write", 0.08))


class BakeError(Exception):
    """A bake or revert that did not happen. `code` is stable (tests, scripts); str() is for people."""

    def __init__(self, code, message):
        super().__init__(message)
        self.code = code
        self.message = message


class BakeJob:
    """The native part of a bake. run() works on any thread; start()/cancel()/done/progress let
    a modal operator drive it from Blender's main thread."""

    def __init__(self, material_name, image_path, pixels, folder, out_dir, final_dir, wrap, roughness, settings,
                 targets, lod=None, lod_note="", material_pointer=0):
        self.material_name = material_name
        self.material_pointer = material_pointer  # Material.as_pointer() when prepared: follows a rename
        self.image_path = image_path  # the normal map's file: what the lobe files record as their source
        self.pixels = pixels          # image_pixels.Pixels: the map as Blender decoded it
        self.folder = folder
        self.out_dir = out_dir   # where the library writes: the pending folder, final_dir once committed
        self.final_dir = final_dir
        self.wrap = wrap
        self.roughness = roughness
        self.settings = settings
        self.targets = targets
        self.lod = lod           # scene_lod.LodPlan, or None: level 0 filtered by the renderer
        self.lod_note = lod_note  # why not the scene's level of detail, where it was asked for
        self.stage = ""
        self.fraction = 0.0
        self.seconds = 0.0
        self.error = None        # BakeError after a failed run
        self.output = None       # bake_output.BakeOutput after a successful run: what the library wrote
        self._cancel = threading.Event()
        self._thread = None
        self._done = threading.Event()

    # Overall fraction from the library's (stage, fraction-of-stage).
    def _overall(self, stage, fraction):
        start = 0.0
        for name, weight in _STAGES:
            if name == stage:
                return min(1.0, start + weight * max(0.0, min(1.0, fraction)))
            start += weight
        return self.fraction

    def cancel(self):
        self._cancel.set()

    @property
    def cancelled(self):
        return self._cancel.is_set()

    @property
    def done(self):
        return self._done.is_set()

    def run(self, progress=None):
        """The native bake. progress(stage, overall_fraction) may return True to cancel.
        Raises BakeError; a folder this bake created is removed again on failure."""
        try:
            self._run(progress)
        except BakeError as e:
            self.error = e
            raise
        finally:
            self._done.set()

    def _run(self, progress):
        lib, message = native.status()
        if lib is None:
            raise BakeError("NO_LIBRARY", message)
        existed = os.path.isdir(self.out_dir)

        def callback(stage, fraction):
            self.stage = stage
            self.fraction = self._overall(stage, fraction)
            if progress is not None and progress(stage, self.fraction):
                self._cancel.set()
            return self._cancel.is_set()

        start = time.perf_counter()
        try:
            if self._cancel.is_set():
                raise native.Error(native_abi.ERROR_CANCELLED, "NDFB_ERROR_CANCELLED", "cancelled before it started")
            p = self.pixels
            with lib.context() as ctx, ctx.normal_map(p.data, p.width, p.height, p.channels, p.signed) as normal_map:
                fit = fit_options(ctx, self.settings, self.roughness, self.wrap,
                                  max_levels=self.lod.levels if self.lod and self.settings.shader != "OSL" else 0)
                self.output = ctx.bake(normal_map, self.out_dir, fit, source_name=self.image_path, progress=callback,
                                       atlas=self.lod is not None, mipmap=self.settings.shader == "OSL")
        except native.Error as e:
            if not existed:
                folder_names.delete_bake_files(self.out_dir, [])  # the empty folder, if the library left it
            raise _bake_error(e, self) from None
        finally:
            self.seconds = time.perf_counter() - start
            self.pixels = None  # the decoded map can be large; finish() does not need it

    def start(self):
        """Runs the native bake on a worker thread; poll `done`, then call finish() on the main thread."""
        def work():
            try:
                self.run()
            except BakeError:
                pass  # kept in self.error
            except Exception as e:  # never lose a failure on the worker thread
                self.error = BakeError("INTERNAL", "bake of '%s' failed: %s" % (self.material_name, e))
                self._done.set()
        self._thread = threading.Thread(target=work, name="ndfbake-" + self.material_name, daemon=True)
        self._thread.start()

    def join(self, timeout=None):
        if self._thread is not None:
            self._thread.join(timeout)


def fit_options(ctx, settings, roughness, wrap, max_levels=0):
    """The library's fit options for a bake's settings, checked by the library (native.Error names
    a bad one): where Maximum Lobes and the tolerance are validated, and the only place."""
    return ctx.fit_options(max_lobes=settings.max_lobes, tolerance=settings.tolerance, roughness=roughness,
                           wrap=wrap, refine=settings.refine, threads=settings.threads, max_levels=max_levels)


def _bake_error(error, job):
    name = job.material_name
    if error.status == native_abi.ERROR_CANCELLED:
        return BakeError("CANCELLED", "bake of '%s' cancelled: no file and no node changed" % name)
    if error.status == native_abi.ERROR_IO:
        return BakeError("OUTPUT_NOT_WRITABLE", "cannot write the lobe folder %s: %s" % (job.final_dir, error.message))
    if error.status == native_abi.ERROR_OUT_OF_MEMORY:
        return BakeError("TOO_LARGE", error.message)
    return BakeError("NATIVE_ERROR", "%s (%s)" % (error.message, error.status_name))
