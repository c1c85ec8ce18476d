"""Find the normal-map chain of a material and say what stands in the way of baking it.

The chain ndfbake filters is the one Blender users build for a tangent-space normal map:

    Image Texture (Color) -> Normal Map (tangent space, Color) -> Principled BSDF (Normal)

Reroute nodes between them are followed. Only Principled BSDFs that reach an active Material
Output (through any shader nodes) count, so stray nodes do not make a material "need" a bake. Once
a material is baked its Principled BSDFs are bypassed (no longer reach the output); the bake record
names them, so re-baking scans the same nodes. The nodes a record names carry their role in it
(bake_record.py), so that they are found again after the user renames them.

Choices the design leaves open, made here:
- One normal-map image per material. Several Principled BSDFs may share it (each gets its own
  filtered group); two different images are refused (SEVERAL_IMAGES): the lobe folder is named
  after the material, and the library's commit step owns the whole folder.
- The image must be a file on disk: the lobe files record it as their source and a re-bake reads
  it again. Packed, generated, movie, sequence and UDIM images are refused with a message saying
  what to do, and nothing changes. So is an image with unsaved edits (painted in Blender): what is
  baked is then what the file holds, as the lobe files say. Blender decodes the file
  (image_pixels.py).
- A muted Normal Map or Image Texture node is no normal map: the material renders without it. So
  is a muted link on the way (Normal Map -> Principled Normal, Image Texture -> Normal Map Color):
  a muted link is no link anywhere in the scan (upstream, reachable_principled), as in Blender's
  renders.
- A material linked from a library is refused (LINKED_MATERIAL): the bake changes the material
  and writes beside the .blend, and neither would outlive a reload; bake it in its own file. So is
  one whose Principled BSDF is animated by a linked action (LINKED_ANIMATION): the group node's
  keyframes would go into that action, which is not saved with this file.
- The Image datablock's colour space must be data (Non-Color, Raw or Linear). An sRGB-tagged
  normal map is refused (COLOR_SPACE), not baked raw: Blender renders such a material with the
  sRGB curve removed, so neither reading of the file would match both what the user sees now and
  what they meant; the fix is one click (Color Space -> Non-Color) and the message names it. This
  keeps the rule that a bad input changes nothing in the file. Linear, a colour space, is refused
  too where Blender multiplies the image's colours by its alpha channel (ALPHA_ASSOCIATED; when:
  _alpha_associated), with the same fix; most Linear-tagged normal maps have no alpha channel.
- The base BRDF is Blender's GGX with the Principled BSDF's Roughness. A linked Roughness
  (a texture) cannot be one number: the fit then uses 0.5 for its lobe budget and report, and the
  node group still widens each lobe from the per-pixel roughness at shading time.
"""
import os
from dataclasses import dataclass, field

import bpy

from . import bake_record, blender_compat, node_animation

DEFAULT_LINKED_ROUGHNESS = 0.5


@dataclass
class Problem:
    code: str
    message: str


@dataclass
class Target:
    """One Principled BSDF fed by the normal map: what the node group replaces."""
    principled: str
    normal_map: str
    image_texture: str


@dataclass
class ScanResult:
    material: str
    targets: list = field(default_factory=list)
    image: object = None           # bpy.types.Image
    image_path: str = ""           # absolute path of the normal map's file
    wrap: str = "REPEAT"           # the Image Texture's extension
    roughness: float = 0.5
    roughness_linked: bool = False
    problems: list = field(default_factory=list)

    @property
    def ok(self):
        return not self.problems

    @property
    def problem(self):
        return self.problems[0] if self.problems else None


def live_link(socket):
    """The link that feeds `socket`, or None: unlinked, or its link muted (Blender then renders the
    socket's own value, as if there were no link)."""
    for link in socket.links:
        if not link.is_muted:
            return link
    return None


def input_may_matter(node, name):
    """Whether input `name` of a node (a Principled BSDF, or the group node holding its inputs since
    a bake) may change what renders: live-linked, animated or non-zero. False where it has none."""
    return node.inputs.find(name) >= 0 and constant_input(node, name) != 0.0


def constant_input(node, name):
    """The value of input `name` of a node (as input_may_matter's) where nothing changes it while
    rendering: no live link, no animation. None where something may, or where it has no such input."""
    index = node.inputs.find(name)
    if index < 0:
        return None
    socket = node.inputs[index]
    if live_link(socket) is not None or node_animation.input_animated(node.id_data, node, index):
        return None
    return socket.default_value


def _trace(socket):
    """(node, output socket, None) feeding `socket` through reroutes; (None, None, the muted link)
    where a muted link cuts the chain; (None, None, None) where nothing feeds it. Links, not
    is_linked: Blender's tree updates clear is_linked where the link is muted."""
    seen = set()
    while socket is not None and socket.links:
        link = socket.links[0]
        if link.is_muted:
            return None, None, link
        node = link.from_node
        if node.bl_idname == "NodeReroute" and node.name not in seen:
            seen.add(node.name)
            socket = node.inputs[0]
            continue
        return node, link.from_socket, None
    return None, None, None


def upstream(socket):
    """The node and output socket feeding `socket`, through reroutes; (None, None) if unlinked or
    cut by a muted link (a muted link is no link: Blender renders as if it were not there)."""
    node, output, _ = _trace(socket)
    return node, output


def active_outputs(tree):
    return [n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial" and n.is_active_output]


def reachable_principled(tree):
    """Principled BSDF nodes that feed an active Material Output's Surface, in a stable order."""
    found, stack, seen = [], [], set()
    for output in active_outputs(tree):
        stack.append(output.inputs["Surface"])
    while stack:
        socket = stack.pop()
        for link in socket.links:
            if link.is_muted:  # renders as no link
                continue
            node = link.from_node
            if node.name in seen:
                continue
            seen.add(node.name)
            if node.bl_idname == "ShaderNodeBsdfPrincipled":
                found.append(node)
            else:
                stack.extend(s for s in node.inputs if s.is_linked and s.type == "SHADER")
                if node.bl_idname == "NodeReroute":
                    stack.extend(node.inputs)
    return sorted(found, key=lambda n: n.name)


def image_file_path(image):
    """Absolute path of an image's file, as Blender resolves it (library-relative paths too). A
    '//' path saved on Windows may separate its folders with '\\', which Blender reads as '/' on
    every system (BLI_path_abs): so does this, where '\\' is no separator."""
    path = image.filepath
    if path.startswith("//") and os.sep == "/":
        path = path.replace("\\", "/")
    return os.path.normpath(bpy.path.abspath(path, library=image.library))


def check_image(image, node_name):
    """The first problem that keeps `image` from being baked as a normal map, or None."""
    if image is None:
        return Problem("NO_IMAGE", "Image Texture '%s' has no image" % node_name)
    name = image.name
    if image.source == "GENERATED":
        return Problem("GENERATED_IMAGE", "image '%s' is generated in Blender, not a file: save it as a file "
                                          "(Image > Save As) and bake again" % name)
    if image.packed_file is not None:
        return Problem("PACKED_IMAGE", "image '%s' is packed into the .blend: unpack it to a file "
                                       "(Image > Unpack) so the lobe files can name it" % name)
    if image.source != "FILE":
        return Problem("UNSUPPORTED_SOURCE", "image '%s' is a %s, not a single image file" % (
            name, image.source.lower()))
    path = image_file_path(image)
    if not image.filepath or not os.path.isfile(path):
        return Problem("MISSING_FILE", "the file of image '%s' is missing: %s" % (name, path or "(no path)"))
    if image.is_dirty:
        return Problem("UNSAVED_IMAGE", "image '%s' has edits that are not saved to its file: save it (Image > "
                                        "Save) so that ndfbake bakes what you see" % name)
    colorspace = image.colorspace_settings.name
    # Colour spaces whose transform is the identity on the stored values (is_data covers the first
    # two; Linear is named so in 3.x, Linear Rec.709 from 4.0).
    if not image.colorspace_settings.is_data and colorspace not in {"Non-Color", "Raw",
                                                                    blender_compat.linear_color_space()}:
        return Problem("COLOR_SPACE", "image '%s' has Color Space '%s': a normal map is data, set its Color "
                                      "Space to Non-Color (ndfbake does not guess which decoding you meant)" % (
                                          name, colorspace))
    if not image.colorspace_settings.is_data and _alpha_associated(image):
        return Problem("ALPHA_ASSOCIATED", "image '%s' has Color Space '%s' and an alpha channel: Blender multiplies "
                                           "its colours by alpha, so the normals it renders are not the file's, which "
                                           "ndfbake would filter; set its Color Space to Non-Color (or its Alpha to "
                                           "Channel Packed)" % (name, colorspace))
    return None


def _alpha_associated(image):
    """Whether Blender renders a colour (not data) image's RGB multiplied by its alpha: where it has
    an alpha channel, unless its Alpha mode is Channel Packed or None, or it is an OpenEXR file
    marked Premultiplied (Blender's default for EXR: both engines then render the stored RGB). The
    bake takes the stored RGB (Image.pixels) and ignores alpha. Measured in Blender 3.4, Cycles and EEVEE, RGB
    (0.9, 0.5, 0.7) at alpha 0.4: an 8-bit PNG renders it times 0.4 (Straight or Premultiplied),
    a 16-bit PNG marked Premultiplied times 0.4 in Cycles and as stored in EEVEE. Decided from the
    ImBuf's planes (Image.depth), not the pixels: an alpha channel that is 1 everywhere is refused
    too (one click fixes it), but the panel, which scans on every redraw, reads no pixels."""
    if image.alpha_mode in ("CHANNEL_PACKED", "NONE"):
        return False
    if image.alpha_mode == "PREMUL" and image.file_format == "OPEN_EXR":
        return False
    depth = image.depth  # bits per pixel of the loaded buffer (0 if it cannot be loaded: the bake says why)
    planes = depth // 4 if image.is_float else depth
    return planes == 32


def _linked_animation(tree, principled):
    """The LINKED_ANIMATION problem, where a linked action animates the Principled's inputs."""
    linked = node_animation.linked_curves(tree, principled.name)
    if not linked:
        return None
    return Problem("LINKED_ANIMATION", "Principled BSDF '%s' is animated by action %s, linked from a library: "
                                      "the bake's keyframes could not be saved in it; make the action local "
                                      "(Outliner: right-click > Make Local) and bake again"
                   % (principled.name, ", ".join("'%s'" % n for n in linked)))


def scan(material):
    """Everything bake.py needs to know about `material`, or the problems that stop it."""
    result = ScanResult(material=material.name if material else "")
    if material is None:
        result.problems.append(Problem("NO_MATERIAL", "no active material"))
        return result
    if material.library is not None:
        result.problems.append(Problem(
            "LINKED_MATERIAL", "material '%s' is linked from %s: bake it in that file (ndfbake changes the material "
                               "and writes its lobe textures beside the .blend)" % (
                                   material.name, material.library.filepath)))
        return result
    if not blender_compat.uses_nodes(material):
        result.problems.append(Problem("NO_NODES", "material '%s' does not use nodes" % material.name))
        return result
    tree = material.node_tree
    rec = bake_record.record(material)
    groups = {}  # Principled name: the group node that stands for it since the bake
    if rec:
        principled = []
        for t, p, group, _ in bake_record.recorded_targets(tree, rec):
            if p is None:
                result.problems.append(Problem(
                    "PRINCIPLED_GONE", "the Principled BSDF '%s' that ndfbake's node group stands in for in material "
                                       "'%s' was deleted: Revert brings it back from the group node's inputs; then "
                                       "bake again" % (t.get("principled", ""), material.name)))
                return result
            principled.append(p)
            if group is not None and "Roughness" in group.inputs:
                groups[p.name] = group
    else:
        if not active_outputs(tree):
            result.problems.append(Problem("NO_OUTPUT", "material '%s' has no active Material Output" % material.name))
            return result
        principled = reachable_principled(tree)
        if not principled:
            result.problems.append(Problem(
                "NO_PRINCIPLED", "material '%s' has no Principled BSDF reaching its output" % material.name))
            return result

    normal_maps, muted = [], []
    for p in principled:
        node, _, cut = _trace(p.inputs["Normal"])
        if node is None and cut is not None and cut.from_node.bl_idname == "ShaderNodeNormalMap":
            muted.append("the link from '%s' to '%s'" % (cut.from_node.name, p.name))
        if node is not None and node.bl_idname == "ShaderNodeNormalMap":
            texture, _, cut = _trace(node.inputs["Color"])
            if node.mute or (texture is not None and texture.mute):
                muted.append(node.name if node.mute else texture.name)
            elif texture is None and cut is not None:
                muted.append("the link from '%s' to '%s'" % (cut.from_node.name, node.name))
            else:
                normal_maps.append((p, node))
    if not normal_maps:
        why = ("its normal map is muted (%s)" % ", ".join(sorted(set(muted))) if muted else
               "no Principled BSDF takes its Normal from a Normal Map node")
        result.problems.append(Problem("NO_NORMAL_MAP", "material '%s' has no normal map: %s" % (material.name, why)))
        return result

    images = {}
    for p, nm in normal_maps:
        if nm.space != "TANGENT":
            result.problems.append(Problem(
                "NOT_TANGENT_SPACE", "Normal Map node '%s' is set to %s: ndfbake filters tangent-space normal "
                                     "maps only" % (nm.name, nm.bl_rna.properties["space"].enum_items[nm.space].name)))
            return result
        tex, out = upstream(nm.inputs["Color"])
        if tex is None or tex.bl_idname != "ShaderNodeTexImage" or out.name != "Color":
            result.problems.append(Problem(
                "NO_IMAGE_TEXTURE", "Normal Map node '%s' does not take its Color from an Image Texture node" % nm.name))
            return result
        problem = check_image(tex.image, tex.name) or _linked_animation(tree, p)
        if problem:
            result.problems.append(problem)
            return result
        # By file: two Image datablocks of one file are one normal map.
        images.setdefault(os.path.normcase(image_file_path(tex.image)), tex.image)
        result.targets.append(Target(principled=p.name, normal_map=nm.name, image_texture=tex.name))
    if len(images) > 1:
        result.problems.append(Problem(
            "SEVERAL_IMAGES", "material '%s' uses %d normal-map images (%s): ndfbake bakes one per material" % (
                material.name, len(images), ", ".join(sorted(i.name for i in images.values())))))
        return result

    result.image = next(iter(images.values()))
    result.image_path = image_file_path(result.image)
    first_tex = tree.nodes[result.targets[0].image_texture]
    result.wrap = first_tex.extension
    first = tree.nodes[result.targets[0].principled]
    # Baked, the group node holds the Principled's inputs as the user edits them now.
    first = groups.get(first.name, first)
    rough = first.inputs["Roughness"]
    result.roughness_linked = live_link(rough) is not None
    result.roughness = DEFAULT_LINKED_ROUGHNESS if result.roughness_linked else float(rough.default_value)
    return result


def uses_normal_map(material):
    """True if the material has a Normal Map node chain worth baking (problems or not)."""
    res = scan(material)
    return res.ok or (res.problem.code not in ("NO_MATERIAL", "NO_NODES", "NO_OUTPUT", "NO_PRINCIPLED",
                                                "NO_NORMAL_MAP"))
