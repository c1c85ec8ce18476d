"""ctypes access to libndfbake (native/include/ndfbake.h): no bpy here.

The library is looked for, in order:
1. the file named by the environment variable NDFBAKE_LIBRARY (tests, development);
2. LIBRARY_NAME (ndfbake.dll, libndfbake.dylib or libndfbake.so) in this add-on's folder, beside
   its __init__.py (what the platform's extension zip and the add-on zip carry);
3. build/native/libndfbake.so of the source checkout this folder sits in (the full library, with
   image files; addon/ndfbake used straight from the repository after `bash scripts/build.sh`);
   only inside a checkout.

The add-on's library reads no image files: Blender decodes the normal map (image_pixels.py) and
the pixels are handed over (normal_map, then bake). Loading never raises out of `status()`: a
missing library, one that cannot be loaded or one of another ABI gives a single readable message
that the UI shows in place of the Bake button. `load()` raises LibraryError with that same message.

Calls into the library release the GIL (ctypes.CDLL), so a bake can run on a worker thread; the
progress callback then runs on that worker thread (the library calls it on the calling thread) and
must not touch bpy. Each thread uses its own Context (a context is single-threaded).
"""
import ctypes
import os
import sys
import threading

from . import bake_output
from .native_abi import (ABI_MAJOR, ABI_MINOR, BRDF_GGX, CONVENTION_OPENGL, ERROR_INVALID_ARGUMENT, OK,
                         PER_CORNER, PER_VERTEX, PROGRESS_FN, WRAP_REPEAT, AtlasFrame, BakeFile, DecodeOptions,
                         FitOptions, Mesh, WriteOptions)

# The library's file on each platform (each platform's extension zip carries its own).
if sys.platform == "win32":
    LIBRARY_NAME = "ndfbake.dll"
elif sys.platform == "darwin":
    LIBRARY_NAME = "libndfbake.dylib"
else:
    LIBRARY_NAME = "libndfbake.so"
ENV_VARIABLE = "NDFBAKE_LIBRARY"

# Room for any version of an option structure the library's *_init may write (see init_options).
_SCRATCH_BYTES = 4096


class Error(Exception):
    """A failed library call: status code, its name (NDFB_ERROR_...) and the library's message."""

    def __init__(self, status, status_name, message):
        super().__init__("%s: %s" % (status_name, message) if message else status_name)
        self.status = status
        self.status_name = status_name
        self.message = message


class LibraryError(Exception):
    """The library is missing, cannot be loaded, or is of another ABI. str() is the UI message."""


def _encode(path):
    return os.fsencode(path)


def candidate_paths():
    # The add-on's folder (this file is in its core/); realpath: an add-on folder linked into the
    # user scripts path finds its checkout's build.
    here = os.path.dirname(os.path.dirname(os.path.realpath(__file__)))
    paths = []
    env = os.environ.get(ENV_VARIABLE)
    if env:
        paths.append(os.path.abspath(env))
    paths.append(os.path.join(here, LIBRARY_NAME))
    checkout = os.path.normpath(os.path.join(here, "..", ".."))
    if os.path.isfile(os.path.join(checkout, "native", "include", "ndfbake.h")):  # a source checkout
        paths.append(os.path.join(checkout, "build", "native", LIBRARY_NAME))
    return paths


class Library:
    """The loaded library with the signatures this add-on calls declared."""

    def __init__(self, path, expected_abi=ABI_MAJOR):
        try:
            lib = ctypes.CDLL(path)
        except OSError as e:
            raise LibraryError("the native library %s could not be loaded (%s)" % (path, e)) from None
        try:
            lib.ndfb_abi_version.restype = ctypes.c_uint32
            lib.ndfb_abi_version.argtypes = []
        except AttributeError:
            raise LibraryError("%s is not the ndfbake library (no ndfb_abi_version)" % path) from None
        abi = lib.ndfb_abi_version()
        if abi != expected_abi:
            raise LibraryError(
                "the native library %s has ABI version %d, this add-on needs %d; "
                "install the add-on zip built with that library" % (path, abi, expected_abi))
        self.path = path
        self.lib = lib
        self._declare()
        minor = lib.ndfb_abi_minor()
        if minor < ABI_MINOR:
            raise LibraryError("the native library %s has ABI version %d.%d, this add-on needs %d.%d or later; "
                               "install the add-on zip built with that library" % (path, abi, minor, abi, ABI_MINOR))
        self.version = lib.ndfb_version().decode()
        self._check_struct_sizes()
        # The library's limit and default of Maximum Lobes: the panel, the command line and the
        # bake take them from here.
        self.max_lobes = int(lib.ndfb_max_lobes())
        self.default_max_lobes = int(self.init_options(FitOptions, lib.ndfb_fit_options_init).max_lobes)

    def _declare(self):
        lib = self.lib
        c = ctypes
        vp = c.c_void_p
        sig = {
            "ndfb_version": (c.c_char_p, []),
            "ndfb_abi_minor": (c.c_uint32, []),
            "ndfb_max_lobes": (c.c_uint32, []),
            "ndfb_context_create": (c.c_int, [c.POINTER(vp)]),
            "ndfb_context_destroy": (None, [vp]),
            "ndfb_last_error": (c.c_char_p, [vp]),
            "ndfb_status_name": (c.c_char_p, [c.c_int]),
            "ndfb_decode_options_init": (None, [c.POINTER(DecodeOptions)]),
            "ndfb_fit_options_init": (None, [c.POINTER(FitOptions)]),
            "ndfb_write_options_init": (None, [c.POINTER(WriteOptions)]),
            "ndfb_normal_map_from_pixels": (c.c_int, [vp, c.POINTER(c.c_float), c.c_size_t, c.c_uint32, c.c_uint32,
                                                      c.c_uint32, c.c_int32, c.POINTER(DecodeOptions), c.POINTER(vp)]),
            "ndfb_fit_options_check": (c.c_int, [vp, c.POINTER(FitOptions)]),
            "ndfb_bake_map": (c.c_int, [vp, vp, c.c_char_p, c.POINTER(FitOptions), c.POINTER(WriteOptions),
                                        PROGRESS_FN, vp, c.POINTER(vp)]),
            "ndfb_bake_result_destroy": (None, [vp]),
            "ndfb_bake_result_level_count": (c.c_uint32, [vp]),
            "ndfb_bake_result_level_size": (c.c_int, [vp, c.c_uint32, c.POINTER(c.c_uint32), c.POINTER(c.c_uint32)]),
            "ndfb_bake_result_lobe_slots": (c.c_uint32, [vp]),
            "ndfb_bake_result_slots_used": (c.c_int, [vp, c.POINTER(c.c_uint8), c.c_size_t]),
            "ndfb_bake_result_atlas_size": (c.c_int, [vp, c.POINTER(c.c_uint32), c.POINTER(c.c_uint32)]),
            "ndfb_bake_result_atlas_frame": (c.c_int, [vp, c.c_uint32, c.POINTER(AtlasFrame)]),
            "ndfb_bake_result_file_count": (c.c_uint32, [vp]),
            "ndfb_bake_result_file": (c.c_int, [vp, c.c_uint32, c.POINTER(BakeFile)]),
            "ndfb_is_bake_file": (c.c_int32, [c.c_char_p]),
            "ndfb_synthesize": (c.c_int, [vp, c.c_char_p, c.c_uint32, c.c_uint32, c.c_uint32, c.POINTER(vp)]),
            "ndfb_normal_map_save": (c.c_int, [vp, vp, c.c_char_p]),
            "ndfb_normal_map_destroy": (None, [vp]),
            "ndfb_normal_map_size": (c.c_int, [vp, c.POINTER(c.c_uint32), c.POINTER(c.c_uint32)]),
            "ndfb_normal_map_read": (c.c_int, [vp, c.POINTER(c.c_float), c.c_size_t]),
            "ndfb_mesh_init": (None, [c.POINTER(Mesh)]),
            "ndfb_texel_density": (c.c_int, [vp, c.POINTER(Mesh), c.POINTER(c.c_float), c.c_size_t,
                                             c.POINTER(c.c_double)]),
        }
        for name, (restype, argtypes) in sig.items():
            try:
                fn = getattr(lib, name)
            except AttributeError:
                raise LibraryError("the native library %s lacks %s; rebuild it" % (self.path, name)) from None
            fn.restype = restype
            fn.argtypes = argtypes

    def _check_struct_sizes(self):
        # Every *_init must work (a library without them is not one we can drive).
        for struct, init in ((DecodeOptions, self.lib.ndfb_decode_options_init),
                             (FitOptions, self.lib.ndfb_fit_options_init),
                             (WriteOptions, self.lib.ndfb_write_options_init)):
            options = self.init_options(struct, init)
            if options.struct_size < ctypes.sizeof(ctypes.c_uint32):
                raise LibraryError("%s's %s has no size" % (self.path, init.__name__))

    @staticmethod
    def init_options(struct, init):
        """An option structure filled by the library's *_init, by the header's versioning rule:
        the library writes its own (possibly larger, newer) structure into a scratch buffer large
        enough for any version, and struct_size is then set to what both sides know, so a newer
        library keeps its defaults for fields this module does not declare, and an older one is
        never told of fields it lacks."""
        scratch = (ctypes.c_char * _SCRATCH_BYTES)()
        init(ctypes.cast(scratch, ctypes.POINTER(struct)))
        options = struct.from_buffer_copy(scratch, 0)
        options.struct_size = min(options.struct_size, ctypes.sizeof(struct))
        return options

    def is_bake_file(self, name):
        """Whether `name` (no folder) is one of the files a bake writes (ndfb_is_bake_file)."""
        return bool(self.lib.ndfb_is_bake_file(name.encode("utf-8", "surrogateescape")))

    def status_name(self, status):
        name = self.lib.ndfb_status_name(status)
        return name.decode() if name else "NDFB_STATUS_%d" % status

    def context(self):
        return Context(self)


class NormalMap:
    def __init__(self, context, handle):
        self._context = context
        self.handle = handle

    def save(self, path):
        """ndfb_normal_map_save: needs a library built with image files (the add-on's has none)."""
        self._context.check(self._context.lib.lib.ndfb_normal_map_save(self._context.handle, self.handle,
                                                                       _encode(path)))

    def read(self):
        """The decoded unit normals: a (height, width, 3) float32 array, rows top to bottom."""
        import numpy as np
        lib = self._context.lib.lib
        width, height = ctypes.c_uint32(), ctypes.c_uint32()
        if lib.ndfb_normal_map_size(self.handle, ctypes.byref(width), ctypes.byref(height)) != OK:
            raise Error(ERROR_INVALID_ARGUMENT, "NDFB_ERROR_INVALID_ARGUMENT", "not a normal map")
        normals = np.empty((height.value, width.value, 3), dtype=np.float32)
        if lib.ndfb_normal_map_read(self.handle, normals.ctypes.data_as(ctypes.POINTER(ctypes.c_float)),
                                    normals.size) != OK:
            raise Error(ERROR_INVALID_ARGUMENT, "NDFB_ERROR_INVALID_ARGUMENT", "could not read the normal map")
        return normals

    def close(self):
        if self.handle:
            self._context.lib.lib.ndfb_normal_map_destroy(self.handle)
            self.handle = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


class Context:
    """One ndfb_context: use it from one thread at a time."""

    def __init__(self, lib):
        self.lib = lib
        handle = ctypes.c_void_p()
        status = lib.lib.ndfb_context_create(ctypes.byref(handle))
        if status != OK:
            raise Error(status, lib.status_name(status), (lib.lib.ndfb_last_error(None) or b"").decode())
        self.handle = handle

    def close(self):
        if self.handle:
            self.lib.lib.ndfb_context_destroy(self.handle)
            self.handle = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __del__(self):
        try:
            self.close()
        except Exception:
            pass

    def check(self, status):
        if status != OK:
            message = self.lib.lib.ndfb_last_error(self.handle) or b""
            raise Error(status, self.lib.status_name(status), message.decode(errors="replace"))

    def normal_map(self, pixels, width, height, channels, signed, convention=CONVENTION_OPENGL):
        """ndfb_normal_map_from_pixels: `pixels` (numpy, width * height * channels values, rows top to
        bottom) encoded in [0, 1], or in [-1, 1] where `signed`."""
        import numpy as np
        data = np.ascontiguousarray(pixels, dtype=np.float32)
        lib = self.lib.lib
        decode = Library.init_options(DecodeOptions, lib.ndfb_decode_options_init)
        decode.convention = convention
        handle = ctypes.c_void_p()
        self.check(lib.ndfb_normal_map_from_pixels(self.handle, data.ctypes.data_as(ctypes.POINTER(ctypes.c_float)),
                                                   data.size, width, height, channels, 1 if signed else 0,
                                                   ctypes.byref(decode), ctypes.byref(handle)))
        return NormalMap(self, handle)

    def fit_options(self, *, max_lobes=None, tolerance=0.0, roughness=0.5, wrap=WRAP_REPEAT, refine=False,
                    threads=0, max_levels=0):
        """ndfb_fit_options with a GGX base BRDF of Blender roughness `roughness`, checked by the library
        (ndfb_fit_options_check: raises Error naming the bad field); max_lobes None: the library's
        default."""
        fit = Library.init_options(FitOptions, self.lib.lib.ndfb_fit_options_init)
        if max_lobes is not None:
            fit.max_lobes = int(max_lobes)
        fit.tolerance = float(tolerance)
        fit.brdf = BRDF_GGX
        fit.brdf_parameter = float(roughness)
        fit.wrap = wrap
        fit.threads = int(threads)
        fit.max_levels = int(max_levels)
        fit.refine = 1 if refine else 0
        self.check(self.lib.lib.ndfb_fit_options_check(self.handle, ctypes.byref(fit)))
        return fit

    def bake(self, normal_map, out_dir, fit, *, source_name=None, progress=None, atlas=False, mipmap=False):
        """ndfb_bake_map with `fit` (fit_options()); `source_name` is what the files and report.json
        record as the map's origin (None: the library's "memory"). Returns what it wrote, a
        bake_output.BakeOutput.

        progress(stage, fraction) -> bool: return True to cancel. Exceptions inside it cancel too.
        Raises Error on failure (status ERROR_CANCELLED when progress asked to stop)."""
        lib = self.lib.lib

        def trampoline(_user, stage, fraction):
            try:
                return 1 if progress(stage.decode() if stage else "", float(fraction)) else 0
            except BaseException:  # never let an exception unwind through C: cancel instead
                return 1
        callback = PROGRESS_FN(trampoline) if progress is not None else PROGRESS_FN()  # alive for the call
        write = Library.init_options(WriteOptions, lib.ndfb_write_options_init)
        name = _encode(source_name) if source_name else None  # kept alive by this frame for the call
        write.source_name = name
        write.atlas = 1 if atlas else 0
        write.mipmap = 1 if mipmap else 0
        result = ctypes.c_void_p()
        self.check(lib.ndfb_bake_map(self.handle, normal_map.handle, _encode(out_dir), ctypes.byref(fit),
                                     ctypes.byref(write), callback, None, ctypes.byref(result)))
        try:
            return bake_output.read(lib, result)
        finally:
            lib.ndfb_bake_result_destroy(result)

    def texel_density(self, positions, face_sizes, corner_vertices, vertex_normals, corner_uvs):
        """ndfb_texel_density over a whole mesh: UV units per world unit, sqrt(UV area / world
        area). Arrays (numpy, C-contiguous): positions (n, 3) float32, face_sizes uint32,
        corner_vertices uint32 in face order, vertex_normals (n, 3) float32, corner_uvs (corners, 2)
        float32."""
        import numpy as np
        arrays = [np.ascontiguousarray(positions, dtype=np.float32), np.ascontiguousarray(face_sizes, dtype=np.uint32),
                  np.ascontiguousarray(corner_vertices, dtype=np.uint32),
                  np.ascontiguousarray(vertex_normals, dtype=np.float32), np.ascontiguousarray(corner_uvs, dtype=np.float32)]
        position, sizes, corners, normals, uvs = arrays

        def pointer(array, kind):
            return array.ctypes.data_as(ctypes.POINTER(kind))
        lib = self.lib.lib
        mesh = Mesh()
        lib.ndfb_mesh_init(ctypes.byref(mesh))
        mesh.positions, mesh.vertex_count = pointer(position, ctypes.c_float), position.size // 3
        mesh.face_sizes, mesh.face_count = pointer(sizes, ctypes.c_uint32), sizes.size
        mesh.corner_vertices, mesh.corner_count = pointer(corners, ctypes.c_uint32), corners.size
        mesh.normals, mesh.normal_domain = pointer(normals, ctypes.c_float), PER_VERTEX
        mesh.uvs, mesh.uv_domain = pointer(uvs, ctypes.c_float), PER_CORNER
        per_face = np.empty(sizes.size, dtype=np.float32)
        total = ctypes.c_double()
        self.check(lib.ndfb_texel_density(self.handle, ctypes.byref(mesh), pointer(per_face, ctypes.c_float),
                                          per_face.size, ctypes.byref(total)))
        return float(total.value)

    def synthesize(self, pattern, width, height, seed=1):
        handle = ctypes.c_void_p()
        self.check(self.lib.lib.ndfb_synthesize(self.handle, pattern.encode(), width, height, seed,
                                                ctypes.byref(handle)))
        return NormalMap(self, handle)


_lock = threading.Lock()
_loaded = None   # Library
_failure = None  # LibraryError message


def load():
    """The library, loaded once; raises LibraryError (a one-line message) if it cannot be used."""
    global _loaded, _failure
    with _lock:
        if _loaded is not None:
            return _loaded
        if _failure is not None:
            raise LibraryError(_failure)
        try:
            import numpy  # noqa: F401  (the mesh arrays of texel_density; official Blender builds carry it)
        except ImportError:
            _failure = ("NumPy is missing from Blender's Python, and the bake needs it "
                        "(Debian: apt install python3-numpy)")
            raise LibraryError(_failure) from None
        tried = []
        env = os.environ.get(ENV_VARIABLE)
        if env and not os.path.isfile(env):  # asked for: not silently another library
            _failure = "%s=%s is not a file; point it at %s or unset it" % (ENV_VARIABLE, env, LIBRARY_NAME)
            raise LibraryError(_failure)
        for path in candidate_paths():
            if not os.path.isfile(path):
                tried.append(path)
                continue
            try:
                _loaded = Library(path)
                return _loaded
            except LibraryError as e:
                _failure = str(e)  # a library that is there but unusable: say why, do not look further
                raise
        _failure = ("native library not found (looked for %s); install the extension (or add-on) zip "
                    "from the build folder, or set %s" % (", ".join(tried), ENV_VARIABLE))
        raise LibraryError(_failure)


def status():
    """(library or None, message): never raises. The message is '' when the library is usable."""
    try:
        return load(), ""
    except LibraryError as e:
        return None, str(e)


def reset():
    """Forget the loaded library or the failure (tests; after installing a library)."""
    global _loaded, _failure
    with _lock:
        _loaded = None
        _failure = None
