"""The add-on's library driven as the add-on drives it, through its own ctypes module
(ndfbake.core.native, imported from the add-on's folder by a plain Python: no bpy), with the library NDFBAKE_LIBRARY names: what
run_in_debian11.sh runs on a Linux older than Debian 12 (Python 3.9 there).

Pixels in as Blender hands them over (RGBA floats, rows top to bottom), read back as unit normals;
a bake with a progress callback and the MIP atlas the level of detail reads; a cancelled bake,
which leaves no files; a texel density of a known quad. Prints one line per check.
Usage: python3 bake_with_native.py <addon folder, the one holding ndfbake/> <out folder>; exit 0 when
all pass.
"""
import json
import os
import sys

import numpy as np

failures = 0


def check(ok, what):
    global failures
    print("%s: %s" % ("ok" if ok else "FAIL", what))
    failures += 0 if ok else 1


def main(addon_folder, out):
    sys.path.insert(0, addon_folder)
    from ndfbake.core import native, native_abi
    print("glibc %s, Python %s" % (os.confstr("CS_GNU_LIBC_VERSION"), sys.version.split()[0]))
    library = native.load()
    check(library.version != "", "loaded %s, version %s" % (library.path, library.version))

    # A 32x32 map of four facets, tilted ±0.3 in x and y: encoded as Blender's pixels give it.
    size = 32
    x = np.where((np.arange(size) // 8) % 2 == 0, 0.3, -0.3)
    normals = np.zeros((size, size, 3), np.float32)
    normals[..., 0] = x[None, :]
    normals[..., 1] = x[:, None]
    normals[..., 2] = 1.0
    normals /= np.linalg.norm(normals, axis=2, keepdims=True)
    rgba = np.concatenate([normals * 0.5 + 0.5, np.ones((size, size, 1), np.float32)], axis=2)
    with library.context() as ctx:
        normal_map = ctx.normal_map(rgba.ravel(), size, size, 4, signed=False)
        read = normal_map.read()
        check(float(np.abs(read - normals).max()) < 1e-5, "pixels in, the same unit normals out (%.1e)"
              % float(np.abs(read - normals).max()))
        stages = set()
        output = ctx.bake(normal_map, out, ctx.fit_options(max_lobes=2), source_name="facets", atlas=True,
                          progress=lambda stage, fraction: stages.add(stage) and False)
        check(stages == {"fit", "measure", "write"}, "progress stages %s" % sorted(stages))
        with open(os.path.join(out, "report.json")) as f:
            report = json.load(f)
        files = sorted(os.listdir(out))
        check({"level00_lobe0.exr", "level00_lobe1.exr", "atlas_lobe0.exr", "atlas_lobe1.exr"} <= set(files),
              "files %s" % " ".join(files))
        # What the library says it wrote is what is there, and what the report says.
        check(sorted(f.name for f in output.files) == files and output.files[-1].name == "report.json",
              "the bake's output names the folder's files: %s" % [f.name for f in output.files])
        check(output.lobe_textures(atlas=True) == {0: "atlas_lobe0.exr", 1: "atlas_lobe1.exr"}
              and output.lobe_textures(atlas=False) == {0: "level00_lobe0.exr", 1: "level00_lobe1.exr"},
              "lobe textures %s" % output.lobe_textures(atlas=True))
        check(output.levels == [(level["width"], level["height"]) for level in report["levels"]]
              and output.slots == 2 and output.slots_used == report["slots_used"],
              "levels %s, slots %d %s" % (output.levels, output.slots, output.slots_used))
        check([output.atlas_size[0], output.atlas_size[1]] == [report["atlas"]["width"], report["atlas"]["height"]]
              and output.atlas_frames == report["atlas"]["levels"],
              "atlas %s %s against the report's %s" % (output.atlas_size, output.atlas_frames, report["atlas"]))
        check(library.max_lobes == 8 and library.default_max_lobes == 4,
              "limits %d, default %d" % (library.max_lobes, library.default_max_lobes))
        try:
            ctx.fit_options(max_lobes=library.max_lobes + 1)
            check(False, "max_lobes past the library's limit is accepted")
        except native.Error as e:
            check("max_lobes must be in 1..8, got 9" in e.message, "the library's check: %s" % e.message)
        levels = len(report.get("atlas", {}).get("levels", []))
        check(report["input"]["source"] == "facets" and report["input"]["format"] == "memory"
              and levels == len(report["levels"]) == 6, "report.json: input %s (%s), %d levels in the atlas"
              % (report["input"]["source"], report["input"]["format"], levels))
        cancelled = out + "-cancelled"
        try:
            ctx.bake(normal_map, cancelled, ctx.fit_options(max_lobes=2), progress=lambda stage, fraction: True)
            check(False, "a cancelled bake returned")
        except native.Error as e:
            check(e.status == native_abi.ERROR_CANCELLED, "a cancelled bake raises %s" % e.status_name)
        check(not os.path.exists(cancelled), "a cancelled bake leaves no folder")
        normal_map.close()

        # A 2 x 1 world-unit quad with UVs 0..1: sqrt(UV area / world area) = sqrt(1 / 2).
        density = ctx.texel_density(
            positions=[(0, 0, 0), (2, 0, 0), (2, 1, 0), (0, 1, 0)], face_sizes=[4], corner_vertices=[0, 1, 2, 3],
            vertex_normals=[(0, 0, 1)] * 4, corner_uvs=[(0, 0), (1, 0), (1, 1), (0, 1)])
        check(abs(density - 0.5 ** 0.5) < 1e-6, "texel density %.6f" % density)
    print("PASS bake_with_native" if failures == 0 else "FAIL bake_with_native: %d checks" % failures)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:3]))
