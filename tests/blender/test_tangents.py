"""Blender-side acceptance test of ndfbake's tangent frames against Mesh.calc_tangents().

Run: blender -b --factory-startup --python-exit-code 1 --python tests/blender/test_tangents.py -- LIB
where LIB is the path to libndfbake.so.

For every mesh (Blender's primitives, a mirrored Suzanne with mirrored UVs, generated meshes with
mirrored / rotated / flipped / degenerate UV islands, and models from Debian's assimp-testmodels
imported with Blender's own importers) it compares per loop:
  - the bitangent sign: must be equal on every loop;
  - the tangent: angle below 1e-3 rad on every loop that is not degenerate (a loop of a face with
    coincident positions or zero UV area, where MikkTSpace copies or defaults frames).
It also checks mirroring-safe splits on the mirrored Suzanne, and prints the counts compared.
"""
import math
import os
import sys

import bpy  # first: the bpy module (4.x wheels) provides bmesh once it is imported
import bmesh
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from ndfb_mesh import library_from_argv, MeshArrays, blender_tangents, write_bmesh  # noqa: E402
from test_addon_helpers import exit_now  # noqa: E402

ANGLE_TOLERANCE = 1e-3
FLT_MIN = np.float32(1.17549435e-38)
ASSIMP = "/usr/share/assimp/models"


def reset_scene():
    bpy.ops.wm.read_factory_settings(use_empty=True)


def degenerate_faces(arrays):
    """Faces MikkTSpace cannot give frames of their own: a triangle (after its quad split) with two
    coincident positions, or with no UV area or derivative (computed in float32 like the reference)."""
    sizes = arrays.face_sizes.astype(np.int64)
    offsets = np.concatenate(([0], np.cumsum(sizes)[:-1]))
    pos = arrays.positions.reshape(-1, 3)[arrays.corner_vertices]
    uv = arrays.uvs.reshape(-1, 2)
    bad = np.zeros(sizes.size, dtype=bool)
    for f, (o, n) in enumerate(zip(offsets, sizes)):
        if n == 3:
            tris = [(0, 1, 2)]
        else:
            d02 = np.float32(np.sum((uv[o + 2] - uv[o]) ** 2, dtype=np.float32))
            d13 = np.float32(np.sum((uv[o + 3] - uv[o + 1]) ** 2, dtype=np.float32))
            if d02 != d13:
                split02 = d02 < d13
            else:
                p02 = np.sum((pos[o + 2] - pos[o]) ** 2, dtype=np.float32)
                p13 = np.sum((pos[o + 3] - pos[o + 1]) ** 2, dtype=np.float32)
                split02 = not (p13 < p02)
            tris = [(0, 1, 2), (0, 2, 3)] if split02 else [(0, 1, 3), (1, 2, 3)]
        for a, b, c in tris:
            pa, pb, pc = pos[o + a], pos[o + b], pos[o + c]
            if np.array_equal(pa, pb) or np.array_equal(pa, pc) or np.array_equal(pb, pc):
                bad[f] = True
                continue
            t21 = uv[o + b] - uv[o + a]
            t31 = uv[o + c] - uv[o + a]
            area = np.float32(t21[0] * t31[1] - t21[1] * t31[0])
            vos = t31[1] * (pb - pa) - t21[1] * (pc - pa)
            vot = -t31[0] * (pb - pa) + t21[0] * (pc - pa)
            if abs(area) <= FLT_MIN or np.sum(vos * vos) <= FLT_MIN or np.sum(vot * vot) <= FLT_MIN:
                bad[f] = True
    return np.repeat(bad, sizes)


class Totals:
    def __init__(self):
        self.meshes = 0
        self.loops = 0
        self.angle_loops = 0
        self.degenerate_loops = 0
        self.degenerate_agreeing = 0
        self.max_angle = 0.0
        self.failures = []


def compare(lib, me, name, totals, uv_layer=""):
    """Compares our frames with calc_tangents() on every loop of `me`; returns our tangents."""
    ref_t, ref_s = blender_tangents(me, uv_layer)
    arrays = MeshArrays.from_blender(me, uv_layer or None)
    ours = lib.tangents(arrays)
    ref_t, ref_s = ref_t[arrays.loop_order], ref_s[arrays.loop_order]
    sign_mismatch = np.nonzero(ours[:, 3] != ref_s)[0]
    skip = degenerate_faces(arrays)
    a, b = ours[:, :3].astype(np.float64), ref_t.astype(np.float64)
    la, lb = np.linalg.norm(a, axis=1), np.linalg.norm(b, axis=1)
    both_zero = (la == 0) & (lb == 0)
    cosine = np.einsum("ij,ij->i", a, b) / np.maximum(la * lb, 1e-30)
    angle = np.where(both_zero, 0.0, np.arccos(np.clip(cosine, -1.0, 1.0)))
    angle = np.where((la == 0) != (lb == 0), math.pi, angle)
    checked = ~skip
    bad_angle = np.nonzero(checked & (angle > ANGLE_TOLERANCE))[0]
    worst = float(angle[checked].max()) if checked.any() else 0.0
    totals.meshes += 1
    totals.loops += len(ours)
    totals.angle_loops += int(checked.sum())
    totals.degenerate_loops += int(skip.sum())
    totals.degenerate_agreeing += int((skip & (angle <= ANGLE_TOLERANCE)).sum())
    totals.max_angle = max(totals.max_angle, worst)
    status = "ok"
    if len(sign_mismatch) or len(bad_angle):
        status = "FAIL"
        totals.failures.append("%s: %d sign mismatches (first loop %s), %d tangents over %.0e rad (worst %.3g)" % (
            name, len(sign_mismatch), sign_mismatch[:3].tolist(), len(bad_angle), ANGLE_TOLERANCE, worst))
    print("  %-46s loops %7d  signs equal %7d  tangents compared %7d (degenerate %5d)  max angle %.2e  %s" % (
        name, len(ours), len(ours) - len(sign_mismatch), int(checked.sum()), int(skip.sum()), worst, status))
    return arrays, ours


def new_object(me, name):
    obj = bpy.data.objects.new(name, me)
    bpy.context.scene.collection.objects.link(obj)
    bpy.context.view_layer.objects.active = obj
    obj.select_set(True)
    return obj


def apply_modifiers(obj):
    depsgraph = bpy.context.evaluated_depsgraph_get()
    evaluated = obj.evaluated_get(depsgraph)
    me = bpy.data.meshes.new_from_object(evaluated)
    obj.modifiers.clear()
    obj.data = me
    return me


def primitives():
    """Blender's primitives with UVs, smooth and flat shaded."""
    ops = bpy.ops.mesh
    makers = [
        ("cube", lambda: ops.primitive_cube_add()),
        ("plane", lambda: ops.primitive_plane_add()),
        ("grid", lambda: ops.primitive_grid_add(x_subdivisions=12, y_subdivisions=9)),
        ("uv_sphere", lambda: ops.primitive_uv_sphere_add(segments=32, ring_count=16)),
        ("ico_sphere", lambda: ops.primitive_ico_sphere_add(subdivisions=3)),
        ("cylinder", lambda: ops.primitive_cylinder_add(vertices=24, end_fill_type="TRIFAN")),
        ("cone", lambda: ops.primitive_cone_add(vertices=24, end_fill_type="TRIFAN")),
        ("torus", lambda: ops.primitive_torus_add(major_segments=48, minor_segments=12, generate_uvs=True)),
        ("monkey", lambda: ops.primitive_monkey_add()),
        ("circle_trifan", lambda: ops.primitive_circle_add(vertices=32, fill_type="TRIFAN")),
    ]
    for name, make in makers:
        for smooth in (True, False):
            reset_scene()
            make()
            me = bpy.context.object.data
            if not me.uv_layers:
                continue
            for p in me.polygons:
                p.use_smooth = smooth
            yield "%s (%s)" % (name, "smooth" if smooth else "flat"), me


def mirrored_suzanne(mirror_uv):
    """Suzanne cut in half and triangulated, then rebuilt by a Mirror modifier (all applied), with
    the copy's UVs mirrored in U (mirror_uv) or left overlapping the original's. Triangulating
    before mirroring makes the copy an exact mirror image, so its frames must be too (a quad may
    legitimately be split along the other diagonal on the other side, and a Subdivision Surface
    modifier's face-varying UVs differ in their last bits from loop to loop, which changes the
    bitwise welding on one side only)."""
    reset_scene()
    bpy.ops.mesh.primitive_monkey_add()
    obj = bpy.context.object
    me = obj.data
    bm = bmesh.new()
    bm.from_mesh(me)
    bmesh.ops.delete(bm, geom=[v for v in bm.verts if v.co.x < -1e-5], context="VERTS")
    for v in bm.verts:
        if abs(v.co.x) < 1e-5:
            v.co.x = 0.0
    # Keep the kept half's UVs in the left half of the square so the mirrored copy lands beside it.
    layer = bm.loops.layers.uv.active
    for f in bm.faces:
        for loop in f.loops:
            u, v = loop[layer].uv
            loop[layer].uv = (0.5 * u, v)
    bm.to_mesh(me)
    bm.free()
    obj.modifiers.new("triangulate", "TRIANGULATE")
    mod = obj.modifiers.new("mirror", "MIRROR")
    mod.use_axis[0] = True
    mod.use_clip = True
    mod.use_mirror_merge = True
    mod.use_mirror_u = mirror_uv
    me = apply_modifiers(obj)
    for p in me.polygons:
        p.use_smooth = True
    return me


def island_grid(seed, triangulate, degenerate_positions):
    """A bumpy grid whose faces form random UV islands (2x2 faces each), every island placed with
    its own random rotation, scale and possibly a mirror or a collapse; optionally with vertices
    pulled onto their neighbours so that some triangles and quad halves become degenerate."""
    rng = np.random.default_rng(seed)
    reset_scene()
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=17, y_subdivisions=17, size=2.0)
    obj = bpy.context.object
    me = obj.data
    bm = bmesh.new()
    bm.from_mesh(me)
    for v in bm.verts:
        v.co.z = 0.15 * math.sin(3.0 * v.co.x) * math.cos(2.0 * v.co.y)
    layer = bm.loops.layers.uv.active
    kinds = ["plain", "rotated", "mirrored", "flipped", "collapsed", "collinear"]
    for f in bm.faces:
        c = f.calc_center_median()
        island = (int((c.x + 1.0) * 4.0), int((c.y + 1.0) * 4.0))
        r = np.random.default_rng([seed, island[0], island[1]])
        kind = kinds[int(r.integers(len(kinds)))]
        angle = r.uniform(0, 2 * math.pi) if kind != "plain" else 0.0
        scale = r.uniform(0.3, 1.5)
        offset = r.uniform(0.0, 1.0, 2)
        for loop in f.loops:
            x, y = loop.vert.co.x, loop.vert.co.y
            if kind == "mirrored":
                x = -x
            if kind == "flipped":
                y = -y
            u = scale * (math.cos(angle) * x - math.sin(angle) * y) + offset[0]
            v = scale * (math.sin(angle) * x + math.cos(angle) * y) + offset[1]
            if kind == "collapsed":
                u, v = offset
            if kind == "collinear":
                v = offset[1]
            loop[layer].uv = (u, v)
    if degenerate_positions:
        verts = list(bm.verts)
        for v in verts:
            if rng.random() < 0.04 and v.link_edges:
                other = v.link_edges[0].other_vert(v)
                v.co = other.co.copy()
    return write_bmesh(bm, me, triangulate)


class Quiet:
    """Silences the C-level chatter of Blender's importers (file descriptors 1 and 2)."""

    def __enter__(self):
        sys.stdout.flush()
        sys.stderr.flush()
        self.saved = (os.dup(1), os.dup(2))
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, 1)
        os.dup2(null, 2)
        os.close(null)

    def __exit__(self, *exc):
        sys.stdout.flush()
        sys.stderr.flush()
        os.dup2(self.saved[0], 1)
        os.dup2(self.saved[1], 2)
        os.close(self.saved[0])
        os.close(self.saved[1])


# Debian pairs Blender 3.4's glTF importer with numpy 1.24, which removed the np.bool alias the
# importer still uses; restore the alias so glTF files can be imported at all.
if "bool" not in vars(np):
    np.bool = bool


IMPORTERS = {
    ".obj": lambda path: bpy.ops.wm.obj_import(filepath=path),
    ".ply": lambda path: bpy.ops.import_mesh.ply(filepath=path),
    ".gltf": lambda path: bpy.ops.import_scene.gltf(filepath=path),
    ".glb": lambda path: bpy.ops.import_scene.gltf(filepath=path),
    ".fbx": lambda path: bpy.ops.import_scene.fbx(filepath=path),
    ".dae": lambda path: bpy.ops.wm.collada_import(filepath=path),
}


def import_model(path):
    """Imports a model with Blender's importer for its format; returns the meshes with UVs, with
    n-gons triangulated (calc_tangents refuses them) and everything else kept as it is."""
    reset_scene()
    ext = os.path.splitext(path)[1].lower()
    try:
        with Quiet():
            IMPORTERS[ext](path)
    except Exception as e:  # an importer that refuses a file is not what this test checks
        print("  (skipped %s: %s)" % (os.path.basename(path), str(e).splitlines()[0][:80]))
        return []
    meshes = []
    for obj in bpy.context.scene.objects:
        if obj.type != "MESH" or not obj.data.uv_layers or len(obj.data.polygons) == 0:
            continue
        me = obj.data
        if me in meshes:
            continue
        if any(p.loop_total > 4 for p in me.polygons):
            bm = bmesh.new()
            bm.from_mesh(me)
            bmesh.ops.triangulate(bm, faces=[f for f in bm.faces if len(f.verts) > 4])
            bm.to_mesh(me)
            bm.free()
        meshes.append(me)
    return meshes


ASSIMP_FILES = [
    "OBJ/WusonOBJ.obj", "OBJ/spider.obj", "OBJ/box.obj", "OBJ/regr01.obj",
    "PLY/cube_uv.ply",
    "glTF2/BoxTextured-glTF/BoxTextured.gltf", "glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb",
    "glTF/CesiumMilkTruck/CesiumMilkTruck.gltf", "glTF2/BoxTexcoords-glTF/boxTexcoords.gltf",
    "FBX/spider.fbx", "FBX/huesitos.fbx", "FBX/box.fbx", "FBX/cubes_with_mirroring_and_pivot.fbx",
    "Collada/duck.dae", "Collada/earthCylindrical.DAE", "Collada/teapots.DAE", "Collada/cube_with_2UVs.DAE",
]


def check_mirror(lib, arrays, ours, mirror_uv, totals):
    """The Mirror modifier's copy must get mirror-image frames, with a split along the mirror plane.
    Reflecting x and keeping the UVs reverses the UV winding against the (flipped) position
    winding: t' = reflect(t), sign' = -sign, and seam corners that share position, normal and UV
    still may not share a vertex (only the sign differs: a mirror seam). Mirroring the UVs in U as
    well gives t' = -reflect(t) with the same sign, and the seam is a UV seam."""
    corner_to_vertex, source, stats = lib.split_vertices(arrays, ours)
    signs_of = {}
    for out_vertex, sign in zip(corner_to_vertex.tolist(), ours[:, 3].tolist()):
        signs_of.setdefault(out_vertex, set()).add(sign)
    mixed = sum(1 for s in signs_of.values() if len(s) > 1)
    print("  splits: %d input -> %d output vertices (uv seams %d, hard edges %d, mirror seams %d, "
          "tangent splits %d); output vertices holding both signs: %d" % (
              stats.input_vertices, stats.output_vertices, stats.uv_seams, stats.hard_edges, stats.mirror_seams,
              stats.tangent_splits, mixed))
    if mixed:
        totals.failures.append("mirrored Suzanne: %d output vertices weld corners of both signs" % mixed)
    if not mirror_uv and stats.mirror_seams == 0:
        totals.failures.append("mirrored Suzanne with overlapping UVs: no mirror-seam split")
    pos = arrays.positions.reshape(-1, 3)[arrays.corner_vertices]
    nrm = arrays.normals.reshape(-1, 3)
    uv = arrays.uvs.reshape(-1, 2)

    def key(p, n, t):
        return (round(float(p[0]), 5), round(float(p[1]), 5), round(float(p[2]), 5),
                round(float(n[0]), 3), round(float(n[1]), 3), round(float(n[2]), 3),
                round(float(t[0]), 4), round(float(t[1]), 4))

    lookup = {}
    for k in range(len(pos)):
        lookup.setdefault(key(pos[k], nrm[k], uv[k]), []).append(k)
    flip = np.array([-1.0, 1.0, 1.0])
    expected_sign = 1.0 if mirror_uv else -1.0
    pairs, worst, wrong_signs = 0, 0.0, 0
    for k in range(len(pos)):
        if pos[k, 0] <= 1e-4:
            continue
        mirror_uv_of_k = (1.0 - uv[k, 0], uv[k, 1]) if mirror_uv else uv[k]
        partners = lookup.get(key(pos[k] * flip, nrm[k] * flip, mirror_uv_of_k))
        if not partners:
            continue
        t = ours[k, :3] * flip * (-1.0 if mirror_uv else 1.0)
        best = min(partners, key=lambda j: np.linalg.norm(ours[j, :3] - t))
        worst = max(worst, float(np.linalg.norm(ours[best, :3] - t)))
        wrong_signs += ours[best, 3] != expected_sign * ours[k, 3]
        pairs += 1
    print("  mirror symmetry: %d corner pairs, max |t' - %sreflect(t)| = %.2e, signs %s: %s" % (
        pairs, "-" if mirror_uv else "", worst, "equal" if mirror_uv else "opposite", wrong_signs == 0))
    if pairs < len(pos) // 3 or worst > 1e-4 or wrong_signs:
        totals.failures.append("mirrored Suzanne: frames are not mirror images (%d pairs, %.2e, %d signs)" % (
            pairs, worst, wrong_signs))


def main():
    lib, _ = library_from_argv()
    totals = Totals()

    print("Blender primitives:")
    for name, me in primitives():
        compare(lib, me, name, totals)

    print("Mirrored Suzanne (Mirror modifier applied):")
    for mirror_uv in (True, False):
        me = mirrored_suzanne(mirror_uv)
        arrays, ours = compare(lib, me, "suzanne mirrored, UVs %s" % ("mirrored" if mirror_uv else "overlapping"),
                               totals)
        check_mirror(lib, arrays, ours, mirror_uv, totals)

    print("Generated UV islands (mirrored, rotated, flipped, collapsed, collinear):")
    for seed in range(4):
        for triangulate in (False, True):
            for degenerate in (False, True):
                me = island_grid(seed, triangulate, degenerate)
                compare(lib, me, "islands seed %d %s%s" % (seed, "tris" if triangulate else "quads",
                                                           ", degenerate positions" if degenerate else ""), totals)

    print("assimp-testmodels imported by Blender:")
    imported = 0
    for rel in ASSIMP_FILES:
        path = os.path.join(ASSIMP, rel)
        if not os.path.exists(path):
            print("  (missing %s)" % rel)
            continue
        for k, me in enumerate(import_model(path)):
            # Names first: calc_tangents adds loop layers, which moves the UV layers in memory, so a
            # UV layer (or the collection's iterator) kept across compare() reads freed memory.
            for name in [layer.name for layer in me.uv_layers]:
                compare(lib, me, "%s[%d] uv '%s'" % (os.path.basename(rel), k, name)[:46], totals, uv_layer=name)
                imported += 1

    print("compared %d meshes, %d loops: signs on all %d, tangents on %d (%d on degenerate faces skipped, of which "
          "%d agree anyway), max tangent angle %.2e rad; %d imported meshes" % (
              totals.meshes, totals.loops, totals.loops, totals.angle_loops, totals.degenerate_loops,
              totals.degenerate_agreeing, totals.max_angle, imported))
    if imported == 0:
        totals.failures.append("no assimp-testmodels mesh could be imported")
    if totals.failures:
        print("FAILURES:")
        for f in totals.failures:
            print("  " + f)
        exit_now(1)
    print("all tangent comparisons passed")


if __name__ == "__main__":
    main()
    exit_now(0)
