"""Benchmark: ndfbake's tangent frames against Blender's Mesh.calc_tangents() on one ~1M-triangle mesh.

Run (not part of ctest; takes ~1 minute):
  blender -b --factory-startup --python tests/blender/bench_tangents.py -- build/native/libndfbake.so [LEVELS]

The mesh is Suzanne with a Subdivision Surface modifier (LEVELS, default 5: ~1M triangles after
triangulation), smooth shaded, triangulated. Blender's loop normals are computed once beforehand
(calc_tangents would otherwise compute them on its first call), and the mesh is copied into plain
arrays once (not timed: that is the caller's data, as Blender's mesh is Blender's), and the output
array once (calc_tangents reuses its layer after the first call). Then, in the same
run, best of REPEATS wall times: calc_tangents() (Blender uses TBB on every core), ours on every
core, and ours on one thread. The results must be unchanged: identical on all cores and on one
thread, and equal to calc_tangents() in sign on every loop.
"""
import os
import sys
import time

import bmesh
import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from ndfb_mesh import library_from_argv, MeshArrays, write_bmesh  # noqa: E402
from ndfbake.shading import blender_compat  # noqa: E402  (ndfb_mesh put addon/ on the path)

REPEATS = 5


def build_mesh(levels):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.mesh.primitive_monkey_add()
    obj = bpy.context.object
    obj.modifiers.new("subsurf", "SUBSURF").levels = levels
    depsgraph = bpy.context.evaluated_depsgraph_get()
    me = bpy.data.meshes.new_from_object(obj.evaluated_get(depsgraph))
    bm = bmesh.new()
    bm.from_mesh(me)
    return write_bmesh(bm, me)


def best_time(fn):
    best = float("inf")
    result = None
    for _ in range(REPEATS):
        start = time.perf_counter()
        result = fn()
        best = min(best, time.perf_counter() - start)
    return best, result


def main():
    lib, args = library_from_argv("[subdivision levels]")
    levels = int(args[0]) if args else 5
    me = build_mesh(levels)
    blender_compat.ensure_loop_normals(me)
    arrays = MeshArrays.from_blender(me)
    cores = os.cpu_count()
    print("mesh: Suzanne, subdivision level %d, triangulated: %d triangles, %d vertices, %d loops; %d cores" % (
        levels, len(me.polygons), len(me.vertices), len(me.loops), cores))

    def blender():
        me.calc_tangents(uvmap=me.uv_layers.active.name)

    t_blender, _ = best_time(blender)
    nl = len(me.loops)
    ref_s = np.empty(nl, dtype=np.float32)
    me.loops.foreach_get("bitangent_sign", ref_s)
    ref_t = np.empty(nl * 3, dtype=np.float32)
    me.loops.foreach_get("tangent", ref_t)
    ref_t = ref_t.reshape(-1, 3)[arrays.loop_order]
    ref_s = ref_s[arrays.loop_order]

    # Like calc_tangents(), which reuses its tangent layer from the second call on, the output
    # array is allocated once; everything else is allocated and freed inside every call.
    out_all = np.zeros(len(me.loops) * 4, dtype=np.float32)
    out_one = np.zeros(len(me.loops) * 4, dtype=np.float32)
    t_all, ours_all = best_time(lambda: lib.tangents(arrays, threads=0, out=out_all))
    t_one, ours_one = best_time(lambda: lib.tangents(arrays, threads=1, out=out_one))

    identical = np.array_equal(ours_all, ours_one)
    signs_equal = int(np.count_nonzero(ours_all[:, 3] == ref_s))
    cosine = np.einsum("ij,ij->i", ours_all[:, :3].astype(np.float64), ref_t.astype(np.float64))
    cosine /= np.maximum(np.linalg.norm(ours_all[:, :3], axis=1) * np.linalg.norm(ref_t, axis=1), 1e-30)
    max_angle = float(np.arccos(np.clip(cosine, -1, 1)).max())
    print("calc_tangents():          %8.1f ms (Blender, TBB on %d cores)" % (1e3 * t_blender, cores))
    print("ndfb_tangents, all cores: %8.1f ms  -> %.2fx faster" % (1e3 * t_all, t_blender / t_all))
    print("ndfb_tangents, 1 thread:  %8.1f ms  -> %.2fx faster" % (1e3 * t_one, t_blender / t_one))
    print("results: all cores == 1 thread bit for bit: %s; signs equal to calc_tangents on %d of %d loops; "
          "max tangent angle %.2e rad" % (identical, signs_equal, nl, max_angle))
    ok = identical and signs_equal == nl and t_blender / t_all >= 3.0
    print("PASS" if ok else "FAIL (need >= 3x, identical results and equal signs)")
    sys.exit(0 if ok else 1)


main()
