"""Bad input: each case gives its own report, from bake.py (BakeError code + message) and from the
operator (the ERROR report, a RuntimeError in scripts), and nothing in the file or on disk changes.

Run: blender -b --factory-startup --python-exit-code 1 --python tests/blender/test_addon_bad_inputs.py -- LIB

Cases: a material without a normal map; an image missing on disk; a packed image; a generated
image; an 8-bit normal map whose Image datablock is sRGB (refused: see material_scan.py for why);
one tagged Linear with an alpha channel (Blender multiplies its colours by alpha);
an object-space Normal Map node; a read-only output folder (the .blend's folder made read-only;
as root, permission bits do not bind, so the bake runs under an unprivileged effective uid); a file
where the lobe folder would go (left alone: the bake takes the next folder name); an unsaved .blend; a corrupt image file; a Normal Map fed by
something other than an Image Texture; two different normal-map images in one material; a
material linked from a library .blend (Bake and Revert refuse it); an image with unsaved edits; a
muted Normal Map node; a muted link into the Principled's Normal or the Normal Map's Color; a
mesh whose UVs are not finite (the level of detail cannot be measured; the refused bakes keep no
folder name). Not refused: one file through two Image datablocks.
"""
import contextlib
import os
import sys
import warnings

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import test_addon_helpers as h  # noqa: E402

NOBODY = 65534


@contextlib.contextmanager
def unprivileged():
    """Runs the block with an unprivileged effective uid when the tests run as root (not on
    Windows, which has no uids)."""
    if not hasattr(os, "geteuid") or os.geteuid() != 0:
        yield
        return
    os.setegid(NOBODY)
    os.seteuid(NOBODY)
    try:
        yield
    finally:
        os.seteuid(0)
        os.setegid(0)


def expect_refused(material, code, fragments, directory, *, wrap=None):
    """The bake fails with `code`, its message holds every fragment, in bake.py and through the
    operator, and neither the material, the data-blocks nor the folder change."""
    from ndfbake.blender import bake
    before, data_before, files_before = h.dump_material(material), h.data_counts(), h.listing(directory)
    wrap = wrap or contextlib.nullcontext
    with wrap():
        e = h.raised(bake.BakeError, lambda: bake.bake_material(material, bake.BakeSettings(max_lobes=2)),
                     "%s: the bake succeeded" % code)
    h.expect(e.code == code, "expected %s, got %s: %s" % (code, e.code, e.message))
    for fragment in fragments:
        h.expect(fragment in e.message, "%s: %r not in %r" % (code, fragment, e.message))
    print("  %s: %s" % (code, e.message))
    with wrap():
        e = h.raised(RuntimeError, lambda: bpy.ops.ndfbake.bake(material=material.name),
                     "%s: the operator succeeded" % code)
    h.expect(all(f in str(e) for f in fragments), "%s: operator said %r" % (code, str(e)))
    h.expect(h.dump_material(material) == before, "%s: the material changed" % code)
    h.expect(h.data_counts() == data_before, "%s: data-blocks changed" % code)
    h.expect(h.listing(directory) == files_before, "%s: files changed: %s" % (code, h.listing(directory)))


def _case(setup):
    with h.scratch_dir() as directory:
        setup(directory)


def test_material_without_normal_map():
    def run(directory):
        h.reset_scene()
        material = bpy.data.materials.new("Plain")
        h.enable_nodes(material)
        h.plane_with(material)
        bpy.ops.wm.save_as_mainfile(filepath=os.path.join(directory, "scene.blend"))
        expect_refused(material, "NO_NORMAL_MAP", ["'Plain'", "Normal Map node"], directory)
    _case(run)


def test_material_without_nodes():
    """Before 5.0 a material can keep a node tree it does not render with (Use Nodes off): refused
    with NO_NODES. 5.0 always renders a material's tree and deprecates use_nodes: the bake reads
    nothing deprecated (a DeprecationWarning is an error here) and goes on to the tree itself."""
    def run(directory):
        h.reset_scene()
        material = bpy.data.materials.new("Nodeless")
        h.enable_nodes(material)
        h.plane_with(material)
        if bpy.app.version < (5, 0, 0):
            material.use_nodes = False
            bpy.ops.wm.save_as_mainfile(filepath=os.path.join(directory, "scene.blend"))
            expect_refused(material, "NO_NODES", ["'Nodeless'", "does not use nodes"], directory)
        else:
            bpy.ops.wm.save_as_mainfile(filepath=os.path.join(directory, "scene.blend"))
            expect_refused(material, "NO_NORMAL_MAP", ["'Nodeless'"], directory, wrap=_deprecation_is_error)
    _case(run)


@contextlib.contextmanager
def _deprecation_is_error():
    with warnings.catch_warnings():
        warnings.simplefilter("error", DeprecationWarning)
        yield


def test_missing_image_file():
    def run(directory):
        material = h.baked_scene(directory)
        os.remove(os.path.join(directory, "normal.png"))
        expect_refused(material, "MISSING_FILE", ["normal.png", "missing"], directory)
    _case(run)


def test_packed_image():
    def run(directory):
        material = h.baked_scene(directory)
        bpy.data.images["normal.png"].pack()
        expect_refused(material, "PACKED_IMAGE", ["'normal.png'", "packed", "Unpack"], directory)
    _case(run)


def test_generated_image():
    def run(directory):
        material = h.baked_scene(directory)
        generated = bpy.data.images.new("Painted", 32, 32)
        generated.colorspace_settings.name = "Non-Color"
        material.node_tree.nodes["Normal Texture"].image = generated
        expect_refused(material, "GENERATED_IMAGE", ["'Painted'", "generated", "Save As"], directory)
    _case(run)


def test_srgb_tagged_normal_map():
    def run(directory):
        material = h.baked_scene(directory, colorspace="sRGB")
        expect_refused(material, "COLOR_SPACE", ["'normal.png'", "'sRGB'", "Non-Color"], directory)
    _case(run)


def _with_alpha(directory, alpha=0.4):
    """normal.png's normals with an alpha channel of `alpha` (a height map, say), as an 8-bit RGBA
    PNG in `directory`; returns its path."""
    source = bpy.data.images.load(os.path.join(directory, "normal.png"), check_existing=False)
    width, height = source.size
    pixels = list(source.pixels)
    bpy.data.images.remove(source)
    pixels[3::4] = [alpha] * (width * height)
    image = bpy.data.images.new("with alpha", width, height, alpha=True)
    image.pixels = pixels
    path = os.path.join(directory, "normal_alpha.png")
    image.filepath_raw, image.file_format = path, "PNG"
    image.save()
    bpy.data.images.remove(image)
    return path


def test_linear_normal_map_with_alpha():
    """Linear is a colour space: Blender multiplies such an image's RGB by its alpha, so with an
    alpha channel it renders other normals than the file holds, which the library reads. Refused
    with the fix; accepted as Non-Color, with Alpha Channel Packed, as an OpenEXR marked
    Premultiplied, and where there is no alpha."""
    from ndfbake.shading import blender_compat, material_scan
    linear = blender_compat.linear_color_space()

    def run(directory):
        material = h.baked_scene(directory, colorspace=linear)
        texture = material.node_tree.nodes["Normal Texture"]
        h.expect(material_scan.scan(material).ok, "a Linear normal map without alpha is refused: %s"
                 % material_scan.scan(material).problem)
        texture.image = bpy.data.images.load(_with_alpha(directory))
        texture.image.colorspace_settings.name = linear
        h.expect(texture.image.alpha_mode == "STRAIGHT" and texture.image.depth == 32, "not an RGBA PNG")
        bpy.ops.wm.save_mainfile()
        expect_refused(material, "ALPHA_ASSOCIATED", ["'normal_alpha.png'", "'%s'" % linear, "alpha channel",
                                                      "multiplies", "Non-Color"], directory)
        texture.image.alpha_mode = "CHANNEL_PACKED"
        h.expect(material_scan.scan(material).ok, "Channel Packed: %s" % material_scan.scan(material).problem)
        texture.image.alpha_mode = "STRAIGHT"
        texture.image.colorspace_settings.name = "Non-Color"
        h.expect(material_scan.scan(material).ok, "Non-Color: %s" % material_scan.scan(material).problem)
        # An RGBA OpenEXR marked Premultiplied (Blender's default for EXR) renders its stored RGB.
        exr = bpy.data.images.new("exr", 4, 4, alpha=True, float_buffer=True)
        exr.pixels = [0.5, 0.5, 1.0, 0.4] * 16
        exr.filepath_raw, exr.file_format = os.path.join(directory, "normal_alpha.exr"), "OPEN_EXR"
        exr.save()
        bpy.data.images.remove(exr)
        texture.image = bpy.data.images.load(os.path.join(directory, "normal_alpha.exr"))
        # 5.0 tags the file Blender itself saved by its colorInteropID ("srgb_rec709_display"), so
        # the colour space is set there; an EXR without one (OpenImageIO's) loads as Linear in 5.0.
        if bpy.app.version < (5, 0, 0):
            h.expect(texture.image.colorspace_settings.name == linear, "the EXR is not loaded as %s" % linear)
        texture.image.colorspace_settings.name = linear
        h.expect((texture.image.alpha_mode, texture.image.depth) == ("PREMUL", 128),
                 "not an RGBA EXR with Blender's defaults")
        h.expect(material_scan.scan(material).ok, "Premultiplied EXR: %s" % material_scan.scan(material).problem)
        texture.image.alpha_mode = "STRAIGHT"
        h.expect(material_scan.scan(material).problem.code == "ALPHA_ASSOCIATED", "a Straight EXR is accepted")
    _case(run)


def test_object_space_normal_map():
    def run(directory):
        material = h.baked_scene(directory)
        material.node_tree.nodes["Normal Map"].space = "OBJECT"
        expect_refused(material, "NOT_TANGENT_SPACE", ["'Normal Map'", "set to Object Space", "tangent-space"], directory)
    _case(run)


def _denies_new_files(directory):
    """Whether the bake (run unprivileged) cannot make a folder in `directory`. A folder's read-only
    attribute on Windows binds nothing (it is for files), nor does a Linux mode under wine as root."""
    probe = os.path.join(directory, "probe")
    try:
        with unprivileged():
            os.mkdir(probe)
    except PermissionError:
        return True
    os.rmdir(probe)
    return False


def test_read_only_output_folder():
    def run(directory):
        material = h.baked_scene(directory)
        os.chmod(directory, 0o555)
        try:
            if not _denies_new_files(directory):
                print("  skipped: a read-only folder takes new files here (%s)" % sys.platform)
                return
            expect_refused(material, "OUTPUT_NOT_WRITABLE", ["cannot write the lobe folder",
                                                            os.path.join(directory, "Bumpy.ndfbake"),
                                                            "Permission denied"], directory, wrap=unprivileged)
        finally:
            os.chmod(directory, 0o755)
    _case(run)


def test_file_in_place_of_the_output_folder():
    def run(directory):
        from ndfbake.blender import bake
        material = h.baked_scene(directory)
        in_the_way = os.path.join(directory, "Bumpy.ndfbake")
        with open(in_the_way, "w") as f:
            f.write("not a folder")
        result = bake.bake_material(material, bake.BakeSettings(max_lobes=2))
        h.expect(result.folder == "//Bumpy~2.ndfbake", "baked into %s" % result.folder)
        with open(in_the_way) as f:
            h.expect(f.read() == "not a folder", "the file in the way changed")
    _case(run)


def test_unsaved_blend():
    def run(directory):
        h.reset_scene()
        png = h.write_normal_map(os.path.join(directory, "normal.png"))
        material = h.normal_mapped_material("Unsaved", png)
        h.plane_with(material)
        expect_refused(material, "UNSAVED_BLEND", ["save the .blend first", "'Unsaved'"], directory)
    _case(run)


def test_corrupt_image_file():
    def run(directory):
        material = h.baked_scene(directory)
        with open(os.path.join(directory, "normal.png"), "wb") as f:
            f.write(b"\x89PNG\r\n\x1a\n" + b"\x5a" * 100)
        expect_refused(material, "BAD_IMAGE", ["normal.png", "cannot be read"], directory)
    _case(run)


def test_normal_map_not_from_an_image_texture():
    def run(directory):
        material = h.baked_scene(directory)
        tree = material.node_tree
        rgb = tree.nodes.new("ShaderNodeRGB")
        tree.links.new(rgb.outputs[0], tree.nodes["Normal Map"].inputs["Color"])
        expect_refused(material, "NO_IMAGE_TEXTURE", ["'Normal Map'", "Image Texture"], directory)
    _case(run)


def _mix_in_a_normal_mapped_principled(material, image_path):
    """A second Principled BSDF, mixed into the output, whose Normal comes from `image_path`
    through its own Image datablock (loaded again even where the file is loaded already)."""
    tree = material.node_tree
    second = tree.nodes.new("ShaderNodeBsdfPrincipled")
    mix = tree.nodes.new("ShaderNodeMixShader")
    tree.links.new(tree.nodes["Principled BSDF"].outputs[0], mix.inputs[1])
    tree.links.new(second.outputs[0], mix.inputs[2])
    tree.links.new(mix.outputs[0], tree.nodes["Material Output"].inputs["Surface"])
    tex = tree.nodes.new("ShaderNodeTexImage")
    tex.image = bpy.data.images.load(image_path, check_existing=False)
    tex.image.colorspace_settings.name = "Non-Color"
    nm = tree.nodes.new("ShaderNodeNormalMap")
    tree.links.new(tex.outputs["Color"], nm.inputs["Color"])
    tree.links.new(nm.outputs["Normal"], second.inputs["Normal"])
    bpy.ops.wm.save_mainfile()


def test_two_normal_map_images():
    def run(directory):
        material = h.baked_scene(directory)
        other = h.write_normal_map(os.path.join(directory, "other.png"), "fbm", 32)
        _mix_in_a_normal_mapped_principled(material, other)
        expect_refused(material, "SEVERAL_IMAGES", ["2 normal-map images", "normal.png", "other.png"], directory)
    _case(run)


def test_one_file_through_two_image_datablocks():
    """Not refused: two Image datablocks of one file (loaded twice) are one normal map."""
    def run(directory):
        from ndfbake.blender import bake
        material = h.baked_scene(directory)
        _mix_in_a_normal_mapped_principled(material, os.path.join(directory, "normal.png"))
        h.expect(len(bpy.data.images) == 2, "images: %s" % [i.name for i in bpy.data.images])
        result = bake.bake_material(material, bake.BakeSettings(max_lobes=1))
        groups = [n for n in material.node_tree.nodes if n.bl_idname == "ShaderNodeGroup"]
        h.expect(len(groups) == 2, "one group per Principled BSDF: %s" % result.summary)
    _case(run)


def test_linked_material():
    def run(directory):
        from ndfbake.blender import bake
        library = h.baked_scene(directory, material_name="Shared Metal")
        bake.bake_material(library, bake.BakeSettings(max_lobes=2))  # baked in its own file
        library.use_fake_user = True
        bpy.ops.wm.save_mainfile()
        material = h.shot_with_material_from(directory, "Shared Metal", link=True)
        expect_refused(material, "LINKED_MATERIAL", ["'Shared Metal'", "linked from", "scene.blend"], directory)
        h.expect(not bake.materials_needing_bake(bpy.context.scene), "Bake All would bake a linked material")
        before, files_before = h.dump_material(material), h.listing(directory)
        e = h.raised(bake.BakeError, lambda: bake.revert(material), "revert of a linked material succeeded")
        h.expect(e.code == "LINKED_MATERIAL" and "revert it in that file" in e.message, "%s: %s" % (e.code, e.message))
        h.expect(h.dump_material(material) == before and h.listing(directory) == files_before,
                 "a refused revert changed the material or the files")
    _case(run)


def test_image_with_unsaved_edits():
    def run(directory):
        material = h.baked_scene(directory)
        image = bpy.data.images["normal.png"]
        pixels = list(image.pixels)
        pixels[0] = 1.0 - pixels[0]
        image.pixels = pixels  # what painting in the Image Editor does
        h.expect(image.is_dirty, "the image did not become dirty")
        expect_refused(material, "UNSAVED_IMAGE", ["'normal.png'", "not saved", "Image > Save"], directory)
    _case(run)


def test_muted_normal_map():
    def run(directory):
        from ndfbake.blender import bake
        material = h.baked_scene(directory)
        material.node_tree.nodes["Normal Map"].mute = True
        expect_refused(material, "NO_NORMAL_MAP", ["'Bumpy'", "muted", "Normal Map"], directory)
        h.expect(not bake.materials_needing_bake(bpy.context.scene), "Bake All would bake a muted normal map")
    _case(run)


def test_muted_normal_map_link():
    """A muted link is no link (Blender renders the socket's own value): with the Normal Map ->
    Principled Normal link or the Image Texture -> Normal Map Color link muted, the material
    renders flat, and the bake says that its normal map is muted, naming the link."""
    for to_node, to_socket, from_node in (("Principled BSDF", "Normal", "Normal Map"),
                                          ("Normal Map", "Color", "Normal Texture")):
        def run(directory):
            from ndfbake.blender import bake
            material = h.baked_scene(directory)
            material.node_tree.nodes[to_node].inputs[to_socket].links[0].is_muted = True
            bpy.ops.wm.save_mainfile()
            expect_refused(material, "NO_NORMAL_MAP", ["'Bumpy'", "muted", "the link from '%s' to '%s'"
                                                       % (from_node, to_node)], directory)
            h.expect(not bake.materials_needing_bake(bpy.context.scene), "Bake All would bake a muted link")
        _case(run)


def test_non_finite_uvs():
    def run(directory):
        material = h.baked_scene(directory)
        bpy.ops.object.camera_add(location=(0.0, 0.0, 5.0))
        bpy.context.scene.camera = bpy.context.active_object
        bpy.data.objects["Plane"].data.uv_layers.active.data[0].uv = (float("nan"), 0.0)
        bpy.ops.wm.save_mainfile()
        expect_refused(material, "BAD_MESH", ["'Bumpy'", "not finite", "Level of Detail to Renderer"], directory)
        # The refused bakes kept no folder name: once the mesh is mended, the bake takes the first.
        from ndfbake.blender import bake
        bpy.data.objects["Plane"].data.uv_layers.active.data[0].uv = (0.0, 0.0)
        result = bake.bake_material(material, bake.BakeSettings(max_lobes=1))
        h.expect(result.folder == "//Bumpy.ndfbake", "the mended bake went to %s" % result.folder)
    _case(run)


if __name__ == "__main__":
    h.import_addon()
    h.run([test_linked_material, test_image_with_unsaved_edits, test_muted_normal_map, test_muted_normal_map_link,
           test_non_finite_uvs, test_material_without_normal_map, test_material_without_nodes, test_missing_image_file, test_packed_image,
           test_generated_image, test_srgb_tagged_normal_map, test_linear_normal_map_with_alpha,
           test_object_space_normal_map, test_read_only_output_folder, test_file_in_place_of_the_output_folder,
           test_unsaved_blend, test_corrupt_image_file, test_normal_map_not_from_an_image_texture,
           test_two_normal_map_images, test_one_file_through_two_image_datablocks])
