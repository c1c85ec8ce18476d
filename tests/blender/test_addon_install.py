"""The add-on as users get it: installed from its zip the way an artist installs it, the library
inside it, and one clear message (never a traceback) when the library is missing or unusable.

Run: blender -b --factory-startup --python-exit-code 1 --python tests/blender/test_addon_install.py -- LIB ZIP
 or: python tests/blender/test_addon_install.py -- LIB ZIP     (Blender as the bpy module)

ZIP is the extension of this platform (ndfbake-<version>-linux_x64.zip, -windows_x64.zip) in Blender
4.2 and later, the legacy add-on (ndfbake-<version>.zip) before.
- The zip holds the add-on's modules (and, as an extension, blender_manifest.toml) with the
  library (libndfbake.so, ndfbake.dll on Windows) and the libraries it bundles, and nothing else.
- 4.2+: bpy.ops.extensions.package_install_files into a repository of a temporary folder (Get
  Extensions > Install from Disk); before: bpy.ops.preferences.addon_install + addon_utils.enable
  into a temporary script directory. The library is loaded from the installed folder (no
  NDFBAKE_LIBRARY); a bake and a revert work through the operators; the declared version
  (manifest or bl_info) is the library's; the OSL check says what this build has.
- In separate Blender processes the installed add-on gets no library, a file that is not a
  library, a library of another ABI (compiled here when a C compiler is available), and a Python
  without NumPy: the add-on still enables, the panel draws the one message, the operator reports
  it; no traceback. The checkout's add-on folder linked into the scripts path (or an extension
  repository) looks for the checkout's build/native/libndfbake.so (where the system lets this
  process make a symbolic link: Windows without Developer Mode does not).
"""
import contextlib
import io
import os
import re
import shutil
import subprocess
import sys
import zipfile

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import test_addon_helpers as h  # noqa: E402

ADDON_SOURCE = os.path.join(h.REPO, "addon", "ndfbake")
# The package's modules in their subpackages and the OSL variant's shader source (osl_group.py), as
# paths in the zip.
MODULES = {os.path.relpath(os.path.join(folder, n), ADDON_SOURCE).replace(os.sep, "/")
           for folder, _, names in os.walk(ADDON_SOURCE) if "__pycache__" not in folder
           for n in names if n.endswith((".py", ".osl"))}
LIBRARY = h.LIBRARY_NAME  # the library in this platform's zip
# The library's bundled dependencies (OpenEXR's): shared objects beside it, found through $ORIGIN
# (DLLs beside it on Windows, found in the folder of the DLL loaded by its path).
if sys.platform == "win32":
    BUNDLED_LIBRARY = re.compile(r"[A-Za-z0-9_+.-]+\.dll$", re.IGNORECASE)
else:
    BUNDLED_LIBRARY = re.compile(r"lib[A-Za-z0-9_+-]+(-[0-9_]+)?\.(so(\.[0-9]+)*|dylib)$")
TEST_REPOSITORY = "ndfbake_test"  # the module name of the temporary extension repository


def _zip():
    _, zip_path = h.arguments()
    h.expect(zip_path and os.path.isfile(zip_path), "the add-on zip is missing: %r (build first)" % zip_path)
    return zip_path


def _add_repository(directory, module=TEST_REPOSITORY):
    """An extension repository (4.2+) whose packages live in `directory`."""
    return bpy.context.preferences.extensions.repos.new(name=module, module=module, custom_directory=directory)


def _install(zip_path, directory):
    """Installs and enables the zip into `directory` as an artist does; returns the module and the
    folder it was installed to."""
    import addon_utils
    if h.EXTENSIONS:
        repository = _add_repository(directory)
        result = bpy.ops.extensions.package_install_files(filepath=zip_path, repo=repository.module,
                                                         enable_on_install=True)
        h.expect(result == {"FINISHED"}, "package_install_files: %s" % result)
        name = "bl_ext.%s.ndfbake" % repository.module
        h.expect(name in bpy.context.preferences.addons, "the extension did not enable")
        return sys.modules[name], os.path.join(directory, "ndfbake")
    os.makedirs(os.path.join(directory, "addons"), exist_ok=True)
    bpy.context.preferences.filepaths.script_directory = directory
    bpy.utils.refresh_script_paths()
    result = bpy.ops.preferences.addon_install(filepath=zip_path, target="PREFS", overwrite=True)
    h.expect(result == {"FINISHED"}, "addon_install: %s" % result)
    module = addon_utils.enable("ndfbake", default_set=True, handle_error=None)
    h.expect(module is not None, "the add-on did not enable")
    return module, os.path.join(directory, "addons", "ndfbake")


def _uninstall(module):
    import addon_utils
    addon_utils.disable(module.__name__, default_set=True)
    if h.EXTENSIONS:
        repos = bpy.context.preferences.extensions.repos
        repos.remove(repos[TEST_REPOSITORY])


def _declared_version(module):
    """The version the installed package declares: its manifest's (extension) or bl_info's."""
    if h.EXTENSIONS:
        import tomllib
        with open(os.path.join(os.path.dirname(module.__file__), "blender_manifest.toml"), "rb") as f:
            return tuple(int(x) for x in tomllib.load(f)["version"].split("."))
    return module.bl_info["version"]


def test_zip_holds_the_addon_and_the_library():
    with zipfile.ZipFile(_zip()) as z:
        names = {n for n in z.namelist() if not n.endswith("/")}
    if h.EXTENSIONS:  # an extension: its files at the top level
        files = names
    else:
        h.expect(all(n.startswith("ndfbake/") for n in names), "zip contents: %s" % sorted(names))
        files = {n.split("/", 1)[1] for n in names}
    expected = MODULES | {LIBRARY, "blender_manifest.toml"}
    h.expect(expected <= files, "missing from the zip: %s" % sorted(expected - files))
    others = files - expected
    h.expect(all(BUNDLED_LIBRARY.match(n) for n in others), "unexpected files in the zip: %s" % sorted(others))
    print("  %d files; bundled libraries: %s" % (len(files), ", ".join(sorted(others)) or "none"))


def test_installed_zip_loads_its_own_library_and_bakes():
    os.environ.pop("NDFBAKE_LIBRARY", None)
    with h.scratch_dir("ndfb-install-") as target, h.scratch_dir() as directory:
        module, installed = _install(_zip(), target)
        h.expect(os.path.dirname(os.path.abspath(module.__file__)) == installed, "module from %s" % module.__file__)
        lib = module.core.native.load()
        h.expect(module.core.native.LIBRARY_NAME == LIBRARY, "the add-on looks for %s" % module.core.native.LIBRARY_NAME)
        h.expect(lib.path == os.path.join(installed, LIBRARY), "library from %s" % lib.path)
        version = tuple(int(x) for x in lib.version.split("."))
        h.expect(_declared_version(module) == version, "declared %s vs library %s" % (_declared_version(module),
                                                                                   lib.version))
        available, message = module.shading.osl_group.build_status()
        offered = bool(bpy.app.build_options.cycles_osl) and module.shading.blender_compat.osl_texture_wraps()
        h.expect(available == offered and "OSL" in message, message)
        print("  installed %s as %s (library %s); %s" % (installed, module.__name__, lib.version, message))

        # A scene built with the installed module (its library makes the test normal map).
        _scene_for(module, directory)
        material = bpy.data.materials["Installed"]
        before = h.dump_material(material)
        h.expect(bpy.ops.ndfbake.bake(material="Installed") == {"FINISHED"}, "bake")
        h.expect(module.blender.bake.is_baked(material), "not baked")
        h.expect(bpy.ops.ndfbake.revert(material="Installed") == {"FINISHED"}, "revert")
        h.expect(h.dump_material(material) == before, "revert did not restore the material")
        _uninstall(module)


def _scene_for(module, directory):
    """A saved scene.blend in `directory` with one normal-mapped material, "Installed", its map
    made by the installed module's library (which writes no image files); returns its path."""
    if h.ADDON_PARENT not in sys.path:  # the helpers' `ndfbake` (enable_nodes): the source tree's, unregistered
        sys.path.insert(0, h.ADDON_PARENT)
    bpy.ops.wm.read_homefile(use_empty=True)  # keeps the enabled add-on (no factory reset)
    png = os.path.join(directory, "normal.png")
    with module.core.native.load().context() as ctx, ctx.synthesize("bumps", 32, 32, 1) as normal_map:
        h.save_normals_png(normal_map.read(), png)
    h.plane_with(h.normal_mapped_material("Installed", png))
    blend = os.path.join(directory, "scene.blend")
    bpy.ops.wm.save_as_mainfile(filepath=blend)
    return blend


_ENABLE_AND_SAVE_PREFERENCES = """
import bpy, sys
repository = bpy.context.preferences.extensions.repos.new(name=%(repo)r, module=%(repo)r, custom_directory=%(dir)r)
result = bpy.ops.extensions.package_install_files(filepath=%(zip)r, repo=repository.module, enable_on_install=True)
assert result == {"FINISHED"}, result
bpy.ops.wm.save_userpref()
"""


def test_blender_command_bakes_a_saved_file():
    """`blender -c ndfbake FILE.blend --max-lobes 2` (Blender 4.2+, the extension enabled in the
    user's preferences) bakes FILE and saves it, and `blender -c ndfbake` with no file exits 2.
    Blender's binary runs the command in new processes whose preferences have the extension
    installed; the bpy module, which has no binary, calls the function it registered."""
    if not h.EXTENSIONS:
        print("  Blender %d.%d has no command-line commands (4.2+): skipped" % bpy.app.version[:2])
        return
    os.environ.pop("NDFBAKE_LIBRARY", None)
    with h.scratch_dir("ndfb-install-") as target, h.scratch_dir() as directory:
        module, _ = _install(_zip(), target)
        blend = _scene_for(module, directory)
        if bpy.app.binary_path:
            _uninstall(module)
            user = os.path.join(directory, "user")
            env = dict(os.environ, BLENDER_USER_RESOURCES=user)
            setup = _ENABLE_AND_SAVE_PREFERENCES % {"repo": TEST_REPOSITORY, "dir": os.path.join(directory, "repo"),
                                                    "zip": _zip()}
            proc = subprocess.run([bpy.app.binary_path, "-b", "--python-exit-code", "1", "--python-expr", setup],
                                  env=env, capture_output=True, text=True, timeout=120)
            h.expect(proc.returncode == 0, "installing into the preferences: %s" % proc.stderr[-2000:])

            def command(*args):
                proc = subprocess.run([bpy.app.binary_path, "-c", "ndfbake", *args], env=env, capture_output=True,
                                      text=True, timeout=300)
                return proc.returncode, proc.stdout + proc.stderr
        else:
            def command(*args):
                printed = io.StringIO()
                with contextlib.redirect_stdout(printed), contextlib.redirect_stderr(printed):
                    code = module.blender.command_line.command(list(args))
                return code, printed.getvalue()
        code, output = command(blend, "--max-lobes", "2")
        h.expect(code == 0, "blender -c ndfbake %s: exit %s\n%s" % (blend, code, output[-3000:]))
        bpy.ops.wm.open_mainfile(filepath=blend)
        record = module.shading.bake_record.record(bpy.data.materials["Installed"])
        h.expect(record is not None and record["settings"]["max_lobes"] == 2, "the saved file's record: %s" % record)
        code, output = command()
        h.expect(code == 2 and "name the .blend" in output, "with no file: exit %s\n%s" % (code, output[-2000:]))
        if not bpy.app.binary_path:
            _uninstall(module)


# ---- an unusable library, each in its own Blender process ------------------------------------

def _enable_installed():
    """In the child: enables the add-on installed in the folder the parent named (an extension
    repository's folder, 4.2+) or in BLENDER_USER_SCRIPTS (before)."""
    import addon_utils
    if h.EXTENSIONS:
        _add_repository(sys.argv[sys.argv.index("--child") + 2])
        return addon_utils.enable("bl_ext.%s.ndfbake" % TEST_REPOSITORY, default_set=True, handle_error=None)
    return addon_utils.enable("ndfbake", default_set=True, handle_error=None)


def child_case(case):
    """Runs inside the child Blender: the installed add-on has a bad library (or, "linked", is
    this checkout's folder linked there). Prints 'CHILD OK <message>' when every check holds."""
    if case == "linked":
        module = _enable_installed()
        assert module is not None, "the linked add-on did not enable"
        built = os.path.join(h.REPO, "build", "native", LIBRARY)
        assert built in module.core.native.candidate_paths(), module.core.native.candidate_paths()
        print("CHILD OK looks for " + built)
        return
    if case == "numpy":
        sys.modules["numpy"] = None  # `import numpy` now raises ImportError: a Blender without NumPy
    module = _enable_installed()
    assert module is not None, "the add-on must enable without its library"
    lib, message = module.core.native.status()
    assert lib is None and message, (lib, message)
    expected = {"missing": "native library not found", "broken": "could not be loaded",
                "abi": "has ABI version 99, this add-on needs %d" % module.core.native_abi.ABI_MAJOR,
                "numpy": "NumPy is missing from Blender's Python"}[case]
    assert expected in message, message
    assert "\n" not in message
    material = bpy.data.materials.new("M")
    labels = h.draw_panel(module.blender.ui, material)
    assert "".join("".join(labels).split()) == "".join(message.split()), labels  # the message, wrapped
    e = h.raised(RuntimeError, lambda: bpy.ops.ndfbake.bake(material="M"), "the bake must fail without a library")
    assert "ndfbake: " + message in " ".join(str(e).split()), str(e)
    print("CHILD OK " + message)


def _fake_abi_library(path):
    compiler = shutil.which("cc") or shutil.which("gcc")
    if compiler is None:
        return False
    source = path + ".c"
    with open(source, "w") as f:
        f.write("unsigned ndfb_abi_version(void) { return 99; }\n")
    ok = subprocess.run([compiler, "-shared", "-fPIC", "-o", path, source]).returncode == 0
    os.remove(source)
    return ok


def test_unusable_library_gives_one_message():
    zip_path = _zip()
    for case in ("missing", "broken", "abi", "numpy", "linked"):
        with h.scratch_dir("ndfb-install-") as target:
            # Where the package goes: an extension repository's folder, or a scripts path's addons/.
            packages = target if h.EXTENSIONS else os.path.join(target, "addons")
            installed = os.path.join(packages, "ndfbake")
            os.makedirs(packages, exist_ok=True)
            if case == "linked":  # the checkout's add-on folder linked in: it finds the checkout's build
                try:
                    os.symlink(ADDON_SOURCE, installed, target_is_directory=True)
                except OSError as e:  # Windows lets only Developer Mode or an administrator link
                    print("  linked: no symbolic link here (%s); skipped" % e)
                    continue
                if not os.path.isdir(installed):  # wine 8.0 reports success and links nothing
                    print("  linked: the symbolic link leads nowhere here; skipped")
                    continue
            else:
                with zipfile.ZipFile(zip_path) as z:
                    z.extractall(installed if h.EXTENSIONS else packages)
            library = os.path.join(installed, LIBRARY)
            if case not in ("numpy", "linked"):  # numpy keeps the library and loses NumPy (child_case)
                os.remove(library)
            if case == "broken":
                with open(library, "wb") as f:
                    f.write(b"not a shared object")
            elif case == "abi" and not _fake_abi_library(library):
                print("  abi: no C compiler to build a fake library; skipped")
                continue
            env = {k: v for k, v in os.environ.items() if k != "NDFBAKE_LIBRARY"}
            env["BLENDER_USER_SCRIPTS"] = target
            proc = subprocess.run(h.blender_command(os.path.abspath(__file__), "--child", case, target),
                                  env=env, capture_output=True, text=True, timeout=120)
            output = proc.stdout + proc.stderr
            h.expect(proc.returncode == 0 and "CHILD OK" in output, "%s: exit %d\n%s" % (case, proc.returncode, output))
            h.expect("Traceback" not in output, "%s: a traceback was printed:\n%s" % (case, output))
            print("  %s: %s" % (case, output.split("CHILD OK ", 1)[1].splitlines()[0]))


if __name__ == "__main__":
    if "--child" in sys.argv:
        child_case(sys.argv[sys.argv.index("--child") + 1])
    else:
        h.run([test_zip_holds_the_addon_and_the_library, test_installed_zip_loads_its_own_library_and_bakes,
               test_blender_command_bakes_a_saved_file, test_unusable_library_gives_one_message])
