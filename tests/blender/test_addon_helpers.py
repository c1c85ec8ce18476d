"""Shared set-up for the add-on tests (tests/blender/test_addon_*.py), run inside `blender -b`:

    blender -b --factory-startup --python-exit-code 1 --python tests/blender/test_addon_X.py -- LIB [ZIP]

LIB is the built libndfbake.so (ndfbake.dll on Windows; NDFBAKE_LIBRARY is set to it), ZIP the add-on
zip the build made.
The add-on is imported from the source tree (addon/) and registered; test_addon_install.py checks
the zip path instead. Not a test itself (ctest runs the files it lists).
"""
import contextlib
import faulthandler
import os
import shutil
import subprocess
import sys
import tempfile
import time
import traceback

import bpy
import numpy as np

sys.dont_write_bytecode = True  # no __pycache__ in the source tree (addon/, tests/blender/)
# A crash inside Blender prints the Python stack of every thread to the test's log (ctest keeps
# it); Blender's own crash report goes to a file in /tmp, which CI does not keep.
faulthandler.enable(all_threads=True)

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.normpath(os.path.join(HERE, "..", ".."))
ADDON_PARENT = os.path.join(REPO, "addon")
sys.path.insert(0, os.path.join(REPO, "examples"))
import demo_build  # noqa: E402  (the demo's scene and map writers; it imports the add-on only when called)
# Blender 4.2 and later install add-ons as extensions (blender_manifest.toml, bl_ext.<repo>.<id>).
EXTENSIONS = bpy.app.version >= (4, 2, 0)


# The library's file on this system (native.LIBRARY_NAME, named here without importing the add-on).
LIBRARY_NAME = {"win32": "ndfbake.dll", "darwin": "libndfbake.dylib"}.get(sys.platform, "libndfbake.so")


def _script_arguments():
    """The arguments after Blender's `--`."""
    return sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []


def arguments():
    argv = _script_arguments()
    library = os.path.abspath(argv[0]) if argv else os.path.join(REPO, "build", "native", LIBRARY_NAME)
    zip_path = os.path.abspath(argv[1]) if len(argv) > 1 else ""
    return library, zip_path


# `blender -b BLEND --python SCRIPT -- ARGS` in the bpy module, which has no Blender binary: its
# Python opens BLEND, runs SCRIPT and exits as exit_now does (argv: BLEND SCRIPT -- ARGS).
_BPY_MODULE_LAUNCHER = """
import os, runpy, sys
import bpy
sys.path.insert(0, %r)
from test_addon_helpers import exit_now
blend, script = sys.argv[1], sys.argv[2]
bpy.ops.wm.open_mainfile(filepath=blend)
sys.argv = [script] + sys.argv[3:]
try:
    runpy.run_path(script, run_name="__main__")
    status = 0
except SystemExit as e:
    status = e.code if isinstance(e.code, int) else int(e.code is not None)
exit_now(status)
""" % HERE


def blender_command(script, *args, blend=None):
    """The command that runs `script` in a new background Blender like this one, on the file
    `blend` if given, `args` after `--`: the binary, or this Python where Blender is the bpy module
    (no binary_path)."""
    if bpy.app.binary_path:
        return [bpy.app.binary_path, "-b", "--factory-startup", *([blend] if blend else []),
                "--python-exit-code", "1", "--python", script, "--", *args]
    if blend:
        return [sys.executable, "-c", _BPY_MODULE_LAUNCHER, blend, script, "--", *args]
    return [sys.executable, script, "--", *args]


def import_addon(register=True):
    """Imports addon/ndfbake from the source tree against LIB; registers it once."""
    library, _ = arguments()
    os.environ["NDFBAKE_LIBRARY"] = library
    if ADDON_PARENT not in sys.path:
        sys.path.insert(0, ADDON_PARENT)
    import ndfbake
    if register and not hasattr(bpy.types.Material, "ndfbake_settings"):
        ndfbake.register()
    return ndfbake


class FakeLayout:
    """Enough of UILayout for Panel.draw: records the labels."""

    def __init__(self, labels):
        self.labels = labels
        self.enabled = True

    def box(self):
        return self

    def column(self, **_):
        return self

    def row(self, **_):
        return self

    def label(self, text="", icon="NONE"):
        self.labels.append(text)

    def prop(self, *args, **kwargs):
        pass

    def operator(self, *args, **kwargs):
        pass


def draw_panel(ui, material):
    """The labels the add-on's material panel (`ui`, its module) draws for `material`."""
    labels = []
    panel = type("P", (), {"layout": FakeLayout(labels)})()
    ui.NDFBAKE_PT_material.draw(panel, type("C", (), {"material": material, "scene": bpy.context.scene})())
    return labels


def temp_dir(prefix="ndfb-addon-"):
    path = tempfile.mkdtemp(prefix=prefix)
    os.chmod(path, 0o755)  # readable by the unprivileged uid the read-only test switches to
    return path


# The demo's map writer (examples/demo_build.py): the library's, or Blender's where the library
# writes no image files.
write_normal_map = demo_build.write_normal_map
save_normals_png = demo_build.save_normals_png


def bake_image_file(path, out_dir, atlas=False, **settings):
    """Bakes the normal map in the image file `path` into `out_dir` as the add-on does: Blender
    decodes it (image_pixels), the library bakes the pixels (`settings`: native.Context.fit_options')."""
    from ndfbake.core import native
    from ndfbake.blender import image_pixels
    image = bpy.data.images.load(path, check_existing=True)
    image.colorspace_settings.name = "Non-Color"
    p = image_pixels.read(image)
    with native.load().context() as ctx, ctx.normal_map(p.data, p.width, p.height, p.channels, p.signed) as m:
        return ctx.bake(m, out_dir, ctx.fit_options(**settings), source_name=path, atlas=atlas)


def reset_scene():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    if not hasattr(bpy.types.Material, "ndfbake_settings"):
        import ndfbake
        ndfbake.register()


def enable_nodes(id_with_nodes):
    """Gives a material or world its node tree in this Blender (blender_compat)."""
    from ndfbake.shading import blender_compat
    return blender_compat.enable_nodes(id_with_nodes)


def normal_mapped_material(name, image_path, roughness=0.35, metallic=0.0, colorspace="Non-Color"):
    """Image Texture -> Normal Map (tangent) -> Principled BSDF -> Material Output."""
    material = bpy.data.materials.new(name)
    enable_nodes(material)
    tree = material.node_tree
    principled = tree.nodes["Principled BSDF"]
    principled.inputs["Roughness"].default_value = roughness
    principled.inputs["Metallic"].default_value = metallic
    principled.inputs["Base Color"].default_value = (0.6, 0.4, 0.3, 1.0)
    texture = tree.nodes.new("ShaderNodeTexImage")
    texture.name = "Normal Texture"
    texture.location = (-700, -300)
    if image_path is not None:
        image = bpy.data.images.load(image_path, check_existing=True)
        image.colorspace_settings.name = colorspace
        texture.image = image
    normal_map = tree.nodes.new("ShaderNodeNormalMap")
    normal_map.name = "Normal Map"
    normal_map.location = (-400, -300)
    tree.links.new(texture.outputs["Color"], normal_map.inputs["Color"])
    tree.links.new(normal_map.outputs["Normal"], principled.inputs["Normal"])
    return material


def plane_with(material, name="Plane", size=2.0):
    bpy.ops.mesh.primitive_plane_add(size=size)
    obj = bpy.context.active_object
    obj.name = name
    obj.data.materials.append(material)
    return obj


def baked_scene(directory, pattern="bumps", size=64, material_name="Bumpy", **material_args):
    """A saved .blend in `directory` with a plane whose material uses a PNG normal map on disk."""
    reset_scene()
    image_path = write_normal_map(os.path.join(directory, "normal.png"), pattern, size)
    material = normal_mapped_material(material_name, image_path, **material_args)
    plane_with(material)
    bpy.ops.wm.save_as_mainfile(filepath=os.path.join(directory, "scene.blend"))
    return bpy.data.materials[material_name]


def _value(value):
    """A property's value as plain data that outlives the file (no Blender struct kept: one read
    after the file it came from is closed crashes)."""
    if hasattr(value, "__len__") and not isinstance(value, str):
        return tuple(_value(v) for v in value)
    if isinstance(value, float):
        return round(value, 6)
    if hasattr(value, "name"):
        return ("ID", value.name)
    if isinstance(value, bpy.types.bpy_struct):  # a struct without a name (5.3's node panel states)
        return tuple((p.identifier, _value(getattr(value, p.identifier))) for p in value.bl_rna.properties
                     if p.identifier != "rna_type" and p.type not in {"POINTER", "COLLECTION"})
    return value


_SKIP_PROPERTIES = {"rna_type", "inputs", "outputs", "internal_links", "dimensions", "type", "bl_idname",
                    "bl_label", "bl_description", "bl_icon", "bl_static_type", "bl_width_default",
                    "bl_width_min", "bl_width_max", "bl_height_default", "bl_height_min", "bl_height_max",
                    "texture_mapping", "color_mapping", "image_user", "interface"}


def shot_with_material_from(directory, name, link):
    """A new scene.blend's material `name` linked (or appended) into a new file, shot.blend in
    `directory`, on a plane; returns the material."""
    reset_scene()
    with bpy.data.libraries.load(os.path.join(directory, "scene.blend"), link=link) as (source, target):
        target.materials = [name]
    material = bpy.data.materials[name]
    plane_with(material)
    bpy.ops.wm.save_as_mainfile(filepath=os.path.join(directory, "shot.blend"))
    return material


def dump_tree(tree):
    """Every node (its RNA properties, sockets and values), link and custom property of a node tree."""
    nodes = {}
    for node in tree.nodes:
        props = {}
        for prop in node.bl_rna.properties:
            key = prop.identifier
            if key in _SKIP_PROPERTIES:
                continue
            try:
                props[key] = _value(getattr(node, key))
            except AttributeError:
                continue
        props["custom"] = sorted(node.keys())
        sockets = []
        for kind, collection in (("in", node.inputs), ("out", node.outputs)):
            for s in collection:
                sockets.append((kind, s.identifier, s.name, s.enabled, s.hide, s.hide_value,
                                _value(s.default_value) if hasattr(s, "default_value") else None))
        props["sockets"] = sockets
        nodes[node.name] = (node.bl_idname, props)
    links = sorted((l.from_node.name, l.from_socket.identifier, l.to_node.name, l.to_socket.identifier,
                    l.is_muted, l.is_valid) for l in tree.links)
    return {"nodes": nodes, "links": links}


def tree_fcurves(tree):
    """The F-curves of the tree's active action, through the slot it uses (blender_compat)."""
    from ndfbake.shading import blender_compat
    animation = tree.animation_data
    return blender_compat.action_fcurves(animation.action, blender_compat.animation_slot(animation))


def dump_material(material):
    """dump_tree of its nodes, plus the material's own settings and custom properties."""
    data = dump_tree(material.node_tree)
    data["active_node"] = material.node_tree.nodes.active.name if material.node_tree.nodes.active else None
    data["custom"] = sorted(material.keys())
    animation = material.node_tree.animation_data
    data["drivers"] = sorted(f.data_path for f in animation.drivers) if animation is not None else None
    settings = {}
    for prop in material.bl_rna.properties:
        # session_uid (4.x): an id for this session only, new when the file is opened again.
        # Deprecated properties (5.0's use_nodes, always True) say nothing and warn when read.
        if prop.type in {"BOOLEAN", "INT", "FLOAT", "STRING", "ENUM"} \
                and prop.identifier not in ("rna_type", "session_uid") and not getattr(prop, "is_deprecated", False):
            settings[prop.identifier] = _value(getattr(material, prop.identifier))
    data["settings"] = settings
    return data


def differences(before, after, path="", limit=8):
    """Where two dumps differ, as readable paths (at most `limit`)."""
    found = []
    if isinstance(before, dict) and isinstance(after, dict):
        for key in sorted(set(before) | set(after), key=str):
            if key not in before or key not in after:
                found.append("%s/%s only %s" % (path, key, "after" if key in after else "before"))
            elif before[key] != after[key]:
                found += differences(before[key], after[key], "%s/%s" % (path, key), limit)
            if len(found) >= limit:
                break
    elif before != after:
        found.append("%s: %r -> %r" % (path, before, after))
    return found[:limit]


def data_counts():
    return {"images": sorted(i.name for i in bpy.data.images),
            "node_groups": sorted(g.name for g in bpy.data.node_groups),
            "materials": sorted(m.name for m in bpy.data.materials)}


def listing(directory):
    result = []
    for root, dirs, files in os.walk(directory):
        for name in dirs + files:
            result.append(os.path.relpath(os.path.join(root, name), directory))
    return sorted(result)


def close_file():
    """What closing the .blend does to lobe folders (opening another file, File > Revert, quit:
    lobe_folders' load_pre and exit handlers): deletes those the file as saved no longer uses, and
    the undo steps that could bring back a bake go."""
    from ndfbake.blender import lobe_folders
    outcome = lobe_folders.delete_unused_folders()
    lobe_folders.forget_undo_steps()
    return outcome


def bake_record(material):
    """The bake's record on `material` (bake_record.record), or None."""
    from ndfbake.shading import bake_record
    return bake_record.record(material)


def bake_group_nodes(material):
    """The group nodes that bakes put into `material`'s tree."""
    return [n for n in material.node_tree.nodes if n.bl_idname == "ShaderNodeGroup" and n.get("ndfbake")]


def bake_with_a_bug_in(material, function, **settings):
    """Bakes with <function> of the node modules (nodes, group_node, lod_nodes) raising, and returns
    the BakeError the bake must end with."""
    from ndfbake.shading import group_node, lod_nodes, nodes
    from ndfbake.blender import bake
    module = next(m for m in (nodes, group_node, lod_nodes) if hasattr(m, function))
    original = getattr(module, function)

    def broken(*args, **kwargs):
        raise RuntimeError("simulated bug")
    setattr(module, function, broken)
    try:
        return raised(bake.BakeError, lambda: bake.bake_material(material, bake.BakeSettings(**settings)),
                      "the simulated bug in %s.%s did not surface" % (module.__name__, function))
    finally:
        setattr(module, function, original)


def raised(error_type, call, failure):
    """The error_type exception that call() raises; fails the test with `failure` if it returns."""
    try:
        call()
    except error_type as e:
        return e
    raise AssertionError(failure)


def expect(condition, message):
    if not condition:
        raise AssertionError(message)


def run(tests):
    """Runs test functions, printing each one's result and time; exits non-zero on any failure.
    NDFBAKE_TEST_ONLY=<substring> runs only the tests whose names contain it (for working on one).
    NDFBAKE_TEST_SKIP=<name>:<why> skips the test of that exact name, printing SKIP and why (for a
    setup that lacks what it needs: tests/CMakeLists.txt says where)."""
    only = os.environ.get("NDFBAKE_TEST_ONLY")
    if only:
        tests = [test for test in tests if only in test.__name__]
    skip_name, _, skip_why = os.environ.get("NDFBAKE_TEST_SKIP", "").partition(":")
    failures = skipped = 0
    total = time.perf_counter()
    for test in tests:
        if test.__name__ == skip_name:
            print("SKIP %s (%s)" % (test.__name__, skip_why or "NDFBAKE_TEST_SKIP"), flush=True)
            skipped += 1
            continue
        start = time.perf_counter()
        try:
            test()
            print("PASS %s (%.1f s)" % (test.__name__, time.perf_counter() - start), flush=True)
        except Exception:
            failures += 1
            traceback.print_exc()
            print("FAIL %s (%.1f s)" % (test.__name__, time.perf_counter() - start), flush=True)
    print("%d of %d passed%s in %.1f s" % (len(tests) - failures - skipped, len(tests),
                                           ", %d skipped" % skipped if skipped else "", time.perf_counter() - total),
          flush=True)
    exit_now(1 if failures else 0)


def exit_now(status):
    """Ends the test with `status` as a script would, through Python's and Blender's own exit, so
    that a hang or crash at exit fails the test (the bpy module's at 4.2 and 4.5 was the add-on's
    handlers and classes keeping bpy alive; test_addon_exit names it). In the bpy module: SystemExit.
    In Blender's binary, whose --python-exit-code only sees uncaught exceptions: a failure raises
    one; a pass returns, and `blender -b` quits as after any script."""
    sys.stdout.flush()
    sys.stderr.flush()
    if not bpy.app.binary_path:
        sys.exit(status)
    if status:
        raise TestsFailed("the test ended with status %d" % status)


class TestsFailed(Exception):
    """Raised at the end of a script run by Blender's binary whose tests failed."""


def cleanup(directory):
    shutil.rmtree(directory, ignore_errors=True)


@contextlib.contextmanager
def scratch_dir(prefix="ndfb-addon-"):
    """A new folder (temp_dir) for the with-block, deleted after it whatever happens."""
    directory = temp_dir(prefix)
    try:
        yield directory
    finally:
        cleanup(directory)


def load_pixels(path):
    """An image file's pixels as Blender reads them, (height, width, 4) float32, rows bottom to top."""
    image = bpy.data.images.load(path)
    width, height = image.size
    pixels = np.empty(width * height * 4, dtype=np.float32)
    image.pixels.foreach_get(pixels)
    bpy.data.images.remove(image)
    return pixels.reshape(height, width, 4)


def uniform_world(scene, name, color):
    """A new world of one colour for `scene`: World.color, and the Background node where the world
    has nodes (Blender 5.0 gives a new world a node tree, which then overrides World.color)."""
    world = bpy.data.worlds.new(name)
    world.color = color
    if world.node_tree is not None:
        background = next(n for n in world.node_tree.nodes if n.bl_idname == "ShaderNodeBackground")
        background.inputs["Color"].default_value = tuple(color) + (1.0,)
        background.inputs["Strength"].default_value = 1.0
    scene.world = world
    return world


def sun_lit_scene(size, cycles_samples, eevee_samples=None):
    """The current scene with a camera looking down at the origin's plane from 2.6 m, a sun and a dim
    uniform world, rendering size² pixels (configure_render)."""
    scene = bpy.context.scene
    bpy.ops.object.camera_add(location=(0.0, -2.6, 1.6), rotation=(1.05, 0.0, 0.0))
    scene.camera = bpy.context.active_object
    bpy.ops.object.light_add(type="SUN", rotation=(0.6, 0.3, 0.4))
    bpy.context.active_object.data.energy = 4.0
    uniform_world(scene, "World", (0.05, 0.05, 0.05))
    configure_render(scene, size, size, cycles_samples=cycles_samples, eevee_samples=eevee_samples)
    return scene


def configure_render(scene, width, height, cycles_samples, eevee_samples=None):
    """What every test render shares: `width` x `height` at 100%, a linear EXR through the Standard
    view transform, Cycles on the CPU with `cycles_samples` and no denoising (Debian's Blender has
    no OpenImageDenoise); EEVEE's render samples when given."""
    scene.render.resolution_x, scene.render.resolution_y = width, height
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.view_settings.view_transform = "Standard"
    scene.cycles.samples = cycles_samples
    scene.cycles.use_denoising = False
    scene.cycles.device = "CPU"
    if eevee_samples is not None:
        scene.eevee.taa_render_samples = eevee_samples


def render_pixels(scene, path):
    """Renders the scene with its own settings (the caller chose engine and file format) into
    `path` and returns the saved image's pixels (load_pixels)."""
    scene.render.filepath = path
    bpy.ops.render.render(write_still=True)
    return load_pixels(path)


def run_bake_blend(blend, *args, timeout=120):
    """examples/bake_blend.py on `blend` in a separate Blender (blender_command); prints its result
    lines and returns (exit status, its whole output)."""
    library, _ = arguments()
    env = dict(os.environ, NDFBAKE_LIBRARY=library, PYTHONDONTWRITEBYTECODE="1")  # keep addon/ clean
    proc = subprocess.run(blender_command(os.path.join(REPO, "examples", "bake_blend.py"), *args, blend=blend),
                          env=env, capture_output=True, text=True, timeout=timeout)
    lines = [l for l in proc.stdout.splitlines() if l.startswith(("baked", "FAILED", "reverted", "ndfbake:"))]
    lines += [l for l in proc.stderr.splitlines() if l.startswith(("ndfbake:", "usage:", "blender"))]
    print("  bake_blend.py %s -> exit %d\n    %s" % (" ".join(args), proc.returncode, "\n    ".join(lines)),
          flush=True)
    return proc.returncode, proc.stdout + proc.stderr


# ---- tests in a real Blender window (under Xvfb) ---------------------------------------------------

class WindowTestFinished(Exception):
    """Raised by finish_window_test to stop the step that called it (run_window_test's timer)."""


def finish_window_test(name, state, ok, message, quitting=False):
    """Ends a window test: its scratch folder (state["dir"]) goes, PASS/FAIL is printed (ctest
    reads it: a window has no --python-exit-code, and Blender with a window exits 0 whatever a
    script did), and Blender quits as File > Quit does (wm.quit_blender), so that a crash or hang at
    exit fails the test too. quitting: called while Blender already quits (an atexit function)."""
    if "dir" in state:
        cleanup(state["dir"])
    print(("PASS " if ok else "FAIL ") + name + ": " + message, flush=True)
    if not quitting:
        bpy.ops.wm.quit_blender()
        raise WindowTestFinished(name)


def run_window_test(name, state, step):
    """Runs `step` from Blender's own event loop (bpy.app.timers; its return value is the delay
    to the next call) until it calls finish_window_test. OUTDIR, the third argument after `--`
    (else a temporary folder), goes to state["out"]; the add-on is imported first. An exception,
    or time.time() passing state["deadline"], fails the test."""
    argv = _script_arguments()
    state["out"] = os.path.abspath(argv[2]) if len(argv) > 2 else temp_dir("ndfb-%s-" % name)
    os.makedirs(state["out"], exist_ok=True)
    import_addon()
    bpy.context.preferences.view.show_splash = False

    def tick():
        try:
            if time.time() > state["deadline"]:
                finish_window_test(name, state, False, "timed out in step %s" % state["step"])
            return step()
        except WindowTestFinished:
            return None
        except Exception:
            traceback.print_exc()
            finish_window_test(name, state, False, "exception")
    bpy.app.timers.register(tick, first_interval=1.0)
