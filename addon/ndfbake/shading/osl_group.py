"""The OSL variant of the per-material group (BakeSettings.shader == "OSL"): Cycles draws the lobes
through one OSL Script node, osl/ndfbake_lobes.osl, which reads each lobe slot's MIP-mapped file
(mip_lobeJ.exr, native write option `mipmap`) with OSL's texture(). OpenImageIO's texture system
then picks and filters the level from the ray's own differentials (anisotropic, trilinear): camera
rays, reflections and refractions, any camera, instances at any scale, animated cameras, with no
drivers and no camera estimate.

The group is the stock-node group (nodes.build_material_group) built with its EEVEE lobes only
(cycles_lobes NARROWED), so that EEVEE, which runs no OSL, draws what it draws after any bake
through the EEVEE output; its BSDF output, what Cycles draws, is the Script node's closure
instead. The group's inputs, its node in the material, the bypass, the record, a re-bake and
Revert are the stock group's (bake.py and nodes.py handle it as any group).

Where it is offered (status): the Blender build has OSL, up to 5.1, the scene renders with Cycles'
Open Shading Language on the CPU. Not from 5.2 on: Cycles' texture cache then serves OSL's
texture() and ignores its wrap mode, so a tiling map reads black outside the first UV tile
(blender_compat.osl_texture_wraps). Not on the GPU: OptiX runs OSL, but Cycles' GPU texture() loads
a named file through its own image manager, which keeps level 0 only and takes no ray differentials
(Cycles' OSLRenderServices::get_texture_handle), so nothing would be filtered. And not for
materials whose Principled BSDF has coat, sheen, transmission, subsurface or thin film that may
matter (unsupported_inputs): the shader draws the specular-split rule only (specular_split.py),
specular lobes over one diffuse at the mean normal, which those layers do not follow.

The Script node reads its files by absolute path (OSL takes no '//' paths): moving the .blend and
its lobe folder elsewhere needs a re-bake for Cycles (EEVEE's images stay relative).
"""
import functools
import glob
import os
import sys

import bpy

from . import blender_compat, material_scan, nodes, specular_albedo_table, specular_split
from .node_builders import GROUP_VERSION, TAG

SHADER_FILE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "osl", "ndfbake_lobes.osl")
TEXT_NAME = "ndfbake_lobes.osl"   # the internal text datablock the Script node compiles
SCRIPT_NODE = "Lobes (OSL)"
FRAME_NODE = "Tangent Frame"      # the live Normal Map node that makes Cycles provide the UV map's tangent
UV_NODE = "OSL UV"
LOBE_INPUT = "Lobe%d"  # the Script node's input for a slot's MIP-mapped file ("" : a slot not drawn)
# Principled layers the shader does not draw: a material where one may matter keeps the stock group.
UNSUPPORTED_INPUTS = specular_split.LAYERED_INPUTS + ("Subsurface Weight", "Thin Film Thickness")


def script_inputs():
    """Principled inputs the Script node takes, by the group's socket name: its parameter is the
    name without spaces (the emission colour's name is blender_compat's)."""
    return ("Base Color", "Metallic", "Roughness", "IOR", "Specular IOR Level", "Specular Tint", "Anisotropic",
            "Anisotropic Rotation", "Tangent", "Diffuse Roughness", blender_compat.principled_input("Emission"),
            "Emission Strength", "Alpha")


def _oslquery_path():
    """Cycles compiles a Script node with its `oslquery` module, which Blender's own Python finds
    but the bpy module (PyPI) keeps in <version>/python/lib/python3.X/site-packages
    (<version>/python/lib/site-packages on Windows): add it."""
    try:
        import oslquery  # noqa: F401
        return True
    except ImportError:
        pass
    lib = os.path.join(bpy.utils.resource_path("LOCAL"), "python", "lib")
    for path in glob.glob(os.path.join(lib, "python3*", "site-packages")) + [os.path.join(lib, "site-packages")]:
        if os.path.isdir(os.path.join(path, "oslquery")) and path not in sys.path:
            sys.path.append(path)
    try:
        import oslquery  # noqa: F401,F811
        return True
    except ImportError:
        return False


def _compiler_ready():
    """Whether Cycles' Script node compiler can run: Blender 4.5 and later compile through the
    `oslquery` module (_oslquery_path), 4.2 through Cycles' own C++."""
    try:
        import inspect
        import cycles.osl
        needs_oslquery = "oslquery" in inspect.getsource(cycles.osl.update_script_node)
    except ImportError:
        return False
    except (OSError, TypeError):
        needs_oslquery = True
    return not needs_oslquery or _oslquery_path()


@functools.cache
def build_status():
    """(available, why not): whether this Blender build can compile and run the OSL variant. Asked
    once a session (the panel asks at every redraw): the build does not change while it runs."""
    if not getattr(bpy.app.build_options, "cycles_osl", False):
        return False, "this Blender build has no OSL (bpy.app.build_options.cycles_osl is False)"
    if not _compiler_ready():
        return False, "this Blender build has OSL but Cycles' Script node compiler does not load"
    if not blender_compat.osl_texture_wraps():
        return False, ("Blender %d.%d's Cycles ignores the wrap mode of OSL texture lookups (black outside the "
                       "first UV tile, since 5.2), which the OSL variant's tiling needs: bake with Stock Nodes"
                       % bpy.app.version[:2])
    return True, ("OSL is available in this Blender build: the OSL variant needs Cycles with Open Shading "
                  "Language on the CPU")


def status(scene):
    """(available, message) for the OSL variant in `scene`: the build (build_status), Cycles with
    Open Shading Language on, on the CPU."""
    ok, why = build_status()
    if not ok:
        return False, why
    if scene is None or scene.render.engine != "CYCLES":
        return False, "the OSL variant is for Cycles: set the render engine to Cycles"
    cycles = getattr(scene, "cycles", None)
    if cycles is None or not cycles.shading_system:
        return False, "turn on Open Shading Language (Render Properties > Cycles) to bake the OSL variant"
    if cycles.device != "CPU":
        return False, ("Cycles renders on the GPU: OptiX runs OSL but reads texture() files at level 0 only "
                       "(no MIP levels, no ray differentials); set Device to CPU for the OSL variant")
    return True, "OSL available: the lobes' MIP files are filtered by the renderer's ray differentials"


def unsupported_inputs(principled, holder):
    """The Principled inputs of `principled` (whose inputs `holder` holds now) that may matter and
    that the OSL shader does not draw; [] where it draws the material."""
    if "Specular IOR Level" not in principled.inputs:
        return ["Principled BSDF v1"]
    return [name for name in UNSUPPORTED_INPUTS if material_scan.input_may_matter(holder, name)]


def shader_source():
    """The add-on's .osl source with the specular layer's table written in (ndfb_layer_table)."""
    with open(SHADER_FILE, encoding="utf-8") as f:
        source = f.read()
    for name, values in (("NDFB_FRESNEL_SHAPE", specular_albedo_table.FRESNEL_SHAPE),
                         ("NDFB_GGX_ALBEDO", specular_albedo_table.GGX_ALBEDO),
                         ("NDFB_MULTISCATTER_FRESNEL", specular_albedo_table.MULTISCATTER_FRESNEL)):
        source = source.replace(name, ", ".join("%.4f" % v for v in values))
    return source


def shader_text():
    """The internal text the Script node compiles: shader_source(), kept up to date."""
    source = shader_source()
    text = bpy.data.texts.get(TEXT_NAME)
    if text is None or text.get(TAG) is None:
        text = bpy.data.texts.new(TEXT_NAME)
        text[TAG] = GROUP_VERSION
    if text.as_string() != source:
        text.clear()
        text.write(source)
    return text


def compile_script(node):
    """Compiles the Script node's text (Cycles' own compiler, as the node's Update button); returns
    (ok, messages)."""
    _compiler_ready()
    import cycles.osl
    messages = []

    def report(kind, message):
        messages.append("%s: %s" % (",".join(sorted(kind)), message))

    ok = cycles.osl.update_script_node(node, report)
    return bool(ok) and set(p.name for p in node.outputs) >= {"BSDF"}, messages


def build_material_group(name, principled, normal_map, image_texture, lobe_images, mip_files, atlas=None, lod=None,
                         current=None, cycles_lobes=nodes.NARROWED, narrowing=None):
    """The OSL variant of nodes.build_material_group: the same inputs and outputs; EEVEE BSDF as the
    stock group's (narrowed lobes, from `lobe_images`), BSDF from the Script node reading the
    MIP-mapped file of each slot in `mip_files` ({slot: path}, as the library named them; a slot
    left out is not drawn). Raises RuntimeError where the script does not compile or has no input
    for a slot."""
    tree = nodes.build_material_group(name, principled, normal_map, image_texture, lobe_images, atlas, lod,
                                      current=current, cycles_lobes=None, narrowing=narrowing)
    gin = next(n for n in tree.nodes if n.bl_idname == "NodeGroupInput")
    gout = next(n for n in tree.nodes if n.bl_idname == "NodeGroupOutput")

    script = tree.nodes.new("ShaderNodeScript")
    script.name = script.label = SCRIPT_NODE
    script.location = (gout.location.x - 400, 900)
    script.mode = "INTERNAL"
    script.script = shader_text()
    ok, messages = compile_script(script)
    if not ok:
        raise RuntimeError("the OSL lobe shader does not compile: %s" % "; ".join(messages))
    inputs = script.inputs
    for slot, path in mip_files.items():
        if LOBE_INPUT % slot not in inputs:
            raise RuntimeError("the OSL lobe shader reads at most %d lobe slots, the bake has slot %d"
                               % (len([i for i in inputs if i.name.startswith("Lobe")]), slot))
        inputs[LOBE_INPUT % slot].default_value = bpy.path.abspath(path)
    inputs["Repeat"].default_value = 1 if image_texture.extension == "REPEAT" else 0
    inputs["UVMapName"].default_value = normal_map.uv_map
    inputs["Narrowing"].default_value = nodes.grazing_narrowing("BSDF", cycles_lobes, narrowing)
    inputs["distribution"].default_value = "multi_ggx" if principled.distribution in ("GGX", "MULTI_GGX") else "ggx"
    inputs["Multiscatter"].default_value = specular_split.multiscatter(principled)

    # The texture coordinate the original image read, with its ray differentials (connected).
    if "Vector" in gin.outputs:
        tree.links.new(gin.outputs["Vector"], inputs["UV"])
    else:
        coordinates = tree.nodes.new("ShaderNodeTexCoord")
        coordinates.name = coordinates.label = UV_NODE
        coordinates.location = (script.location.x - 300, 1100)
        tree.links.new(coordinates.outputs["UV"], inputs["UV"])
    tree.links.new(gin.outputs["Normal Strength"], inputs["NormalStrength"])
    for key in script_inputs():
        parameter = key.replace(" ", "")
        if key in gin.outputs and parameter in inputs:
            tree.links.new(gin.outputs[key], inputs[parameter])
    # Cycles gives a shader a UV map's tangent only where a Normal Map node of that map is in it.
    frame = tree.nodes.new("ShaderNodeNormalMap")
    frame.name = frame.label = FRAME_NODE
    frame.space = "TANGENT"
    frame.uv_map = normal_map.uv_map
    frame.location = (script.location.x - 300, 700)
    tree.links.new(gin.outputs["Normal Strength"], frame.inputs["Strength"])
    tree.links.new(frame.outputs["Normal"], inputs["TangentFrame"])
    tree.links.new(script.outputs["BSDF"], gout.inputs["BSDF"])
    return tree


def script_node(group_tree):
    """The group's Script node, or None (a stock-node group)."""
    node = group_tree.nodes.get(SCRIPT_NODE) if group_tree is not None else None
    return node if node is not None and node.bl_idname == "ShaderNodeScript" else None


def remove_unused_text():
    """Removes the shader's text once no Script node of a group uses it (after Revert)."""
    text = bpy.data.texts.get(TEXT_NAME)
    if text is None or text.get(TAG) is None:
        return
    for tree in bpy.data.node_groups:
        if script_node(tree) is not None and script_node(tree).script == text:
            return
    if text.users - (1 if text.use_fake_user else 0) == 0:  # a new text has a fake user
        bpy.data.texts.remove(text)
