"""ctypes access to libndfbake's tangent-frame API for the Blender-side tests and benchmark.

Only the standard library, numpy and bpy (both ship with Blender) are used. Arrays go in and out
as numpy buffers; a Blender mesh is turned into the plain arrays the C API takes.
"""
import ctypes
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "addon"))
from ndfbake.core.native import Mesh  # noqa: E402  (one definition of ndfb_mesh, the add-on's)


class SplitStats(ctypes.Structure):
    _fields_ = [(name, ctypes.c_uint64) for name in (
        "input_vertices", "output_vertices", "uv_seams", "hard_edges", "mirror_seams", "tangent_splits")]


class MeshReport(ctypes.Structure):
    _fields_ = [(name, ctypes.c_uint64) for name in (
        "faces", "triangles", "quads", "ngons", "degenerate_triangles", "zero_area_uv_triangles",
        "uv_islands", "mirrored_islands", "flipped_islands", "flipped_triangles", "inverted_normal_faces")] + [
        (name, ctypes.c_int64) for name in (
            "ngon_first", "degenerate_first", "zero_area_uv_first", "flipped_first", "inverted_normal_first")]


class SpaceOptions(ctypes.Structure):
    _fields_ = [("struct_size", ctypes.c_uint32), ("padding", ctypes.c_uint32), ("threads", ctypes.c_uint32),
                ("frame_normal", ctypes.c_uint32)]


# ndfb_frame_normal
FRAME_NORMAL_INTERPOLATED = 0
FRAME_NORMAL_UNIT = 1


def _ptr(array, ctype):
    return array.ctypes.data_as(ctypes.POINTER(ctype))


class Library:
    def __init__(self, path):
        lib = ctypes.CDLL(path)
        self.lib = lib
        lib.ndfb_context_create.argtypes = [ctypes.POINTER(ctypes.c_void_p)]
        lib.ndfb_last_error.restype = ctypes.c_char_p
        lib.ndfb_last_error.argtypes = [ctypes.c_void_p]
        lib.ndfb_mesh_init.argtypes = [ctypes.POINTER(Mesh)]
        lib.ndfb_tangents.argtypes = [ctypes.c_void_p, ctypes.POINTER(Mesh), ctypes.c_uint32,
                                      ctypes.POINTER(ctypes.c_float), ctypes.c_size_t,
                                      ctypes.POINTER(ctypes.c_float), ctypes.c_size_t]
        lib.ndfb_split_vertices.argtypes = [ctypes.c_void_p, ctypes.POINTER(Mesh), ctypes.POINTER(ctypes.c_float),
                                            ctypes.c_size_t, ctypes.c_uint32, ctypes.POINTER(ctypes.c_uint32),
                                            ctypes.c_size_t, ctypes.POINTER(ctypes.c_uint32), ctypes.c_size_t,
                                            ctypes.POINTER(SplitStats)]
        lib.ndfb_mesh_diagnose.argtypes = [ctypes.c_void_p, ctypes.POINTER(Mesh), ctypes.POINTER(MeshReport),
                                           ctypes.c_char_p, ctypes.c_size_t, ctypes.POINTER(ctypes.c_size_t)]
        lib.ndfb_space_options_init.argtypes = [ctypes.POINTER(SpaceOptions)]
        for name in ("ndfb_object_to_tangent", "ndfb_tangent_to_object"):
            getattr(lib, name).argtypes = [
                ctypes.c_void_p, ctypes.POINTER(Mesh), ctypes.POINTER(ctypes.c_float), ctypes.c_size_t,
                ctypes.POINTER(ctypes.c_float), ctypes.c_uint32, ctypes.c_uint32, ctypes.c_size_t,
                ctypes.POINTER(SpaceOptions), ctypes.POINTER(ctypes.c_float), ctypes.POINTER(ctypes.c_uint8)]
        self.ctx = ctypes.c_void_p()
        if lib.ndfb_context_create(ctypes.byref(self.ctx)) != 0:
            raise RuntimeError("ndfb_context_create failed")

    def _check(self, status, what):
        if status != 0:
            raise RuntimeError("%s failed (%d): %s" % (what, status, self.lib.ndfb_last_error(self.ctx).decode()))

    def tangents(self, arrays, threads=0, magnitudes=False, out=None):
        """Per corner (x, y, z, sign) as an (n, 4) array; `out` (n*4 float32) is reused if given."""
        m = arrays.struct(self)
        if out is None:
            out = np.zeros(arrays.corner_count * 4, dtype=np.float32)
        out = out.reshape(-1)
        mags = np.zeros(arrays.corner_count * 2, dtype=np.float32) if magnitudes else None
        self._check(self.lib.ndfb_tangents(self.ctx, ctypes.byref(m), threads, _ptr(out, ctypes.c_float), out.size,
                                           _ptr(mags, ctypes.c_float) if magnitudes else None,
                                           mags.size if magnitudes else 0), "ndfb_tangents")
        out = out.reshape(-1, 4)
        return (out, mags.reshape(-1, 2)) if magnitudes else out

    def split_vertices(self, arrays, tangents=None):
        m = arrays.struct(self)
        corner_to_vertex = np.zeros(arrays.corner_count, dtype=np.uint32)
        source = np.zeros(arrays.corner_count, dtype=np.uint32)
        stats = SplitStats()
        t = None if tangents is None else np.ascontiguousarray(tangents, dtype=np.float32).reshape(-1)
        self._check(self.lib.ndfb_split_vertices(
            self.ctx, ctypes.byref(m), None if t is None else _ptr(t, ctypes.c_float), 0 if t is None else t.size, 0,
            _ptr(corner_to_vertex, ctypes.c_uint32), corner_to_vertex.size, _ptr(source, ctypes.c_uint32),
            source.size, ctypes.byref(stats)), "ndfb_split_vertices")
        return corner_to_vertex, source[:stats.output_vertices], stats

    def diagnose(self, arrays):
        m = arrays.struct(self)
        report = MeshReport()
        text = ctypes.create_string_buffer(4096)
        self._check(self.lib.ndfb_mesh_diagnose(self.ctx, ctypes.byref(m), ctypes.byref(report), text, 4096, None),
                    "ndfb_mesh_diagnose")
        return report, text.value.decode()

    def convert(self, arrays, image, width, height, to_tangent, padding=16, tangents=None,
                frame_normal=FRAME_NORMAL_INTERPOLATED):
        m = arrays.struct(self)
        opts = SpaceOptions()
        self.lib.ndfb_space_options_init(ctypes.byref(opts))
        opts.padding = padding
        opts.frame_normal = frame_normal
        src = np.ascontiguousarray(image, dtype=np.float32).reshape(-1)
        out = np.zeros(width * height * 3, dtype=np.float32)
        coverage = np.zeros(width * height, dtype=np.uint8)
        t = None if tangents is None else np.ascontiguousarray(tangents, dtype=np.float32).reshape(-1)
        fn = self.lib.ndfb_object_to_tangent if to_tangent else self.lib.ndfb_tangent_to_object
        self._check(fn(self.ctx, ctypes.byref(m), None if t is None else _ptr(t, ctypes.c_float),
                       0 if t is None else t.size, _ptr(src, ctypes.c_float), width, height, src.size,
                       ctypes.byref(opts), _ptr(out, ctypes.c_float), _ptr(coverage, ctypes.c_uint8)),
                    "ndfb_object_to_tangent" if to_tangent else "ndfb_tangent_to_object")
        return out.reshape(height, width, 3), coverage.reshape(height, width)


class MeshArrays:
    """A Blender mesh as plain arrays, corners in face order (loop_start order may differ)."""

    def __init__(self, positions, face_sizes, corner_vertices, normals, uvs, loop_order):
        self.positions = np.ascontiguousarray(positions, dtype=np.float32).reshape(-1)
        self.face_sizes = np.ascontiguousarray(face_sizes, dtype=np.uint32)
        self.corner_vertices = np.ascontiguousarray(corner_vertices, dtype=np.uint32)
        self.normals = np.ascontiguousarray(normals, dtype=np.float32).reshape(-1)
        self.uvs = np.ascontiguousarray(uvs, dtype=np.float32).reshape(-1)
        self.loop_order = loop_order  # corner k of ours is Blender loop loop_order[k]
        self.corner_count = self.corner_vertices.size

    def struct(self, library):
        m = Mesh()
        library.lib.ndfb_mesh_init(ctypes.byref(m))
        m.positions = _ptr(self.positions, ctypes.c_float)
        m.vertex_count = self.positions.size // 3
        m.face_sizes = _ptr(self.face_sizes, ctypes.c_uint32)
        m.face_count = self.face_sizes.size
        m.corner_vertices = _ptr(self.corner_vertices, ctypes.c_uint32)
        m.corner_count = self.corner_count
        m.normals = _ptr(self.normals, ctypes.c_float)
        m.uvs = _ptr(self.uvs, ctypes.c_float)
        return m

    @staticmethod
    def from_blender(me, uv_layer=None):
        """Needs loop normals: call blender_compat.ensure_loop_normals(me) (or calc_tangents()) first."""
        nv, nl, nf = len(me.vertices), len(me.loops), len(me.polygons)
        co = np.empty(nv * 3, dtype=np.float32)
        me.vertices.foreach_get("co", co)
        starts = np.empty(nf, dtype=np.int64)
        totals = np.empty(nf, dtype=np.int64)
        me.polygons.foreach_get("loop_start", starts)
        me.polygons.foreach_get("loop_total", totals)
        if nf and np.all(starts == np.concatenate(([0], np.cumsum(totals)[:-1]))):
            order = np.arange(nl)
        else:
            order = np.concatenate([np.arange(s, s + t) for s, t in zip(starts, totals)])
        verts = np.empty(nl, dtype=np.int64)
        me.loops.foreach_get("vertex_index", verts)
        normals = np.empty(nl * 3, dtype=np.float32)
        me.loops.foreach_get("normal", normals)
        layer = me.uv_layers[uv_layer] if uv_layer else me.uv_layers.active
        uvs = np.empty(nl * 2, dtype=np.float32)
        layer.data.foreach_get("uv", uvs)
        return MeshArrays(co, totals, verts[order], normals.reshape(-1, 3)[order], uvs.reshape(-1, 2)[order], order)


def library_from_argv(usage_arguments=""):
    """(Library of the path after `--`, the further arguments); prints the usage and exits 2
    without one."""
    args = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    if not args:
        script = os.path.basename(sys.argv[sys.argv.index("--python") + 1]) if "--python" in sys.argv else "SCRIPT"
        print("usage: blender -b --python %s -- /path/to/libndfbake.so %s" % (script, usage_arguments))
        sys.exit(2)
    return Library(args[0]), args[1:]


def write_bmesh(bm, me, triangulate=True):
    """Writes `bm` into `me` (triangulated first if asked), frees it and shades `me` smooth (so
    corner normals vary and the frames are per corner)."""
    import bmesh
    if triangulate:
        bmesh.ops.triangulate(bm, faces=bm.faces[:])
    bm.to_mesh(me)
    bm.free()
    for p in me.polygons:
        p.use_smooth = True
    return me


def blender_tangents(me, uv_layer=""):
    """Mesh.calc_tangents() per loop: (tangent xyz, bitangent sign)."""
    me.calc_tangents(uvmap=uv_layer or me.uv_layers.active.name)
    nl = len(me.loops)
    t = np.empty(nl * 3, dtype=np.float32)
    s = np.empty(nl, dtype=np.float32)
    me.loops.foreach_get("tangent", t)
    me.loops.foreach_get("bitangent_sign", s)
    return t.reshape(-1, 3), s
