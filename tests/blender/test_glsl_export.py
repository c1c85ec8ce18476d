"""The GLSL a bake writes beside its lobe textures (ndfbake.glsl), compiled and run on the GPU by
Blender's gpu module in a real window (under Xvfb: the module does not draw in background mode).

A 64² fBm map (no repeats at level 3: its texels differ) is baked by the library; a fragment
shader that includes ndfbake.glsl fetches level-3 lobe texels (8×8 fine normals each) from the
bake's EXR files. Checked:
- the file's constants are the add-on's (lobe_nodes.GGX_VMF_WIDENING, HALF_INV_KAPPA_RESOLUTION, and
  the grazing narrowing of Cycles' lobes, nodes.default_grazing_narrowing), so
  the shader and the Blender node group decode alike;
- the filtered GGX distribution, the Lambert cosine and the specular term (16 directions within
  40° of the normal) against the documented rule evaluated in numpy from the same texels;
- the filtered distribution against the exact one, the mean of D_α(h·n_q) over each texel's fine
  normals (relative L2 over the 16 directions, per texel, averaged): within half the error of
  shading the texel's averaged normal (plain MIP-mapping), and within 0.3; the texels and the fine
  normals correspond only in the right orientation;
- the specular term of a flat texel: reciprocal (f(v, l)/cos l = f(l, v)/cos v) and, integrated
  over the hemisphere with f0 = 1 from straight above, Smith GGX's single-scattering albedo
  (between 0.85 and 1 at α = 0.3: multiple scattering is what it leaves out).

Run: xvfb-run -a blender --factory-startup --python tests/blender/test_glsl_export.py -- LIB
The process exits 0 when every check holds, 1 otherwise.
"""
import math
import os
import re
import sys
import traceback

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import test_addon_helpers as h  # noqa: E402

LEVEL = 3
GGX_ALPHA = 0.2
FLAT_ALPHA = 0.3
DIRECTIONS = 16
MAX_CONE = math.radians(40.0)
VIEW = np.array([math.sin(0.4), 0.0, math.cos(0.4)], dtype=np.float32)  # 23° off the normal

VERTEX = """
in vec2 pos;
void main() { gl_Position = vec4(pos, 0.0, 1.0); }
"""

# mode 0: per (texel, direction k): filtered D(d_k), Lambert cosine of d_k, specular (f0 = 1) for
# view VIEW and light d_k. mode 1, a flat texel: f(d_k, d_k+1)/cos and f(d_k+1, d_k)/cos, and the
# specular for view +Z and light d_k (the furnace).
FRAGMENT = """
uniform sampler2D lobe0, lobe1, lobe2, lobe3, directions;
uniform float ggx_alpha;
uniform vec3 view;
uniform int direction_count, mode;
out vec4 result;
void main()
{
    ivec2 pixel = ivec2(gl_FragCoord.xy);
    int k = pixel.x % direction_count;
    ivec2 texel = ivec2(pixel.x / direction_count, pixel.y);
    vec3 d = texelFetch(directions, ivec2(k, 0), 0).xyz;
    vec4 texels[NDFB_LOBES];
    if (mode == 0) {
        texels[0] = texelFetch(lobe0, texel, 0);
        texels[1] = texelFetch(lobe1, texel, 0);
        texels[2] = texelFetch(lobe2, texel, 0);
        texels[3] = texelFetch(lobe3, texel, 0);
        result = vec4(ndfb_filtered_ggx_d(texels, ggx_alpha, d), ndfb_lambert_cosine(texels, d),
                      ndfb_ggx_specular(texels, ggx_alpha, vec3(1.0), view, d).r, 1.0);
    } else {
        texels[0] = vec4(1.0, 0.0, 0.0, 1.0);
        texels[1] = texels[2] = texels[3] = vec4(0.0);
        vec3 e = texelFetch(directions, ivec2((k + 1) % direction_count, 0), 0).xyz;
        result = vec4(ndfb_ggx_specular(texels, ggx_alpha, vec3(1.0), d, e).r / e.z,
                      ndfb_ggx_specular(texels, ggx_alpha, vec3(1.0), e, d).r / d.z,
                      ndfb_ggx_specular(texels, ggx_alpha, vec3(1.0), vec3(0.0, 0.0, 1.0), d).r, 1.0);
    }
}
"""


def cap_directions(count, max_angle):
    """Fibonacci points on the cap of half-angle max_angle about +Z."""
    golden = math.pi * (3.0 - math.sqrt(5.0))
    result = []
    for i in range(count):
        z = 1.0 - (1.0 - math.cos(max_angle)) * (i + 0.5) / count
        r = math.sqrt(1.0 - z * z)
        result.append((r * math.cos(golden * i), r * math.sin(golden * i), z))
    return np.array(result, dtype=np.float32)


def ggx_d(cos_theta, alpha):
    a2 = alpha * alpha
    d = cos_theta * cos_theta * (a2 - 1.0) + 1.0
    return np.where(cos_theta > 0.0, a2 / (math.pi * d * d), 0.0)


def smith_g1(cos_theta, alpha):
    """Smith masking for GGX as 2 / (1 + sqrt(1 + α² tan²θ)) (the shader writes another form)."""
    tan2 = np.maximum(1.0 - cos_theta ** 2, 0.0) / np.maximum(cos_theta ** 2, 1e-12)
    return np.where(cos_theta > 0.0, 2.0 / (1.0 + np.sqrt(1.0 + alpha * alpha * tan2)), 0.0)


def image_pixels(path):
    """RGBA float pixels of an image file as Blender reads it (rows bottom-up), as data."""
    image = bpy.data.images.load(path, check_existing=False)
    image.colorspace_settings.name = "Non-Color"
    image.alpha_mode = "CHANNEL_PACKED"
    pixels = np.empty(len(image.pixels), dtype=np.float32)
    image.pixels.foreach_get(pixels)
    result = pixels.reshape(image.size[1], image.size[0], 4)
    bpy.data.images.remove(image)
    return result


def shader_constant(source, name):
    match = re.search(r"#define %s (\S+)" % name, source)
    h.expect(match is not None, "ndfbake.glsl defines no %s" % name)
    return float(match.group(1))


def documented_rule(texels, directions, widening, resolution, narrowing):
    """(filtered D, Lambert cosine, specular with f0 = 1 for VIEW) per texel and direction, as
    ndfbake.glsl's header states them (the specular's α narrowed toward VIEW)."""
    weight = np.maximum(texels[..., 0], 0.0)                       # (lobes, H, W)
    r = texels[..., 1:] / np.maximum(texels[..., :1], 1e-6)
    R = np.minimum(np.linalg.norm(r, axis=-1), 1.0)
    mu = r + np.array([0.0, 0.0, 1e-5])
    mu /= np.linalg.norm(mu, axis=-1, keepdims=True)
    inv_kappa = np.maximum((1.0 - R * R) / np.maximum(R * (3.0 - R * R), 1e-6) - resolution, 0.0)
    alpha = np.sqrt(np.minimum(GGX_ALPHA ** 2 + widening * inv_kappa, 1.0))[..., None]
    cos = np.einsum("lyxc,dc->lyxd", mu, directions)
    half = directions + VIEW
    half /= np.linalg.norm(half, axis=-1, keepdims=True)
    cos_view = np.einsum("lyxc,c->lyx", mu, VIEW)[..., None]
    cos_half = np.einsum("lyxc,dc->lyxd", mu, half)
    # α_c² = max(α'² / (1 + C·α'² tan²θ_v), α²), cos θ_v floored at 1e-3.
    c = np.maximum(cos_view, 1e-3)
    tan2 = (1.0 - c * c) / (c * c)
    narrowed = np.sqrt(np.maximum(alpha ** 2 / (1.0 + narrowing * alpha ** 2 * tan2), GGX_ALPHA ** 2))
    # f · cos l about the lobe's normal = D G1(v) G1(l) / (4 cos v), where both cosines are > 0.
    specular = np.where((cos > 0) & (cos_view > 0), ggx_d(cos_half, narrowed) * smith_g1(cos_view, narrowed)
                        * smith_g1(cos, narrowed) / (4.0 * np.maximum(cos_view, 1e-6)), 0.0)
    total = weight.sum(axis=0)[..., None]
    w = weight[..., None]
    return ((w * ggx_d(cos, alpha)).sum(axis=0) / total, (w * np.maximum(cos, 0.0)).sum(axis=0) / total,
            (w * specular).sum(axis=0) / total)


def run_shader(shader_source, lobes, directions, mode, alpha):
    import gpu
    from gpu_extras.batch import batch_for_shader
    height, width = lobes[0].shape[:2]
    count = len(directions)
    shader = gpu.types.GPUShader(VERTEX, shader_source + FRAGMENT)

    def texture(array):
        rows, columns = array.shape[:2]
        data = gpu.types.Buffer("FLOAT", rows * columns * 4, array.astype(np.float32).ravel().tolist())
        return gpu.types.GPUTexture((columns, rows), format="RGBA32F", data=data)
    textures = [texture(lobe) for lobe in lobes]
    direction_texture = texture(np.concatenate([directions, np.zeros((count, 1), np.float32)], axis=1)[None])
    batch = batch_for_shader(shader, "TRI_FAN", {"pos": [(-1, -1), (1, -1), (1, 1), (-1, 1)]})
    offscreen = gpu.types.GPUOffScreen(width * count, height, format="RGBA32F")
    with offscreen.bind():
        framebuffer = gpu.state.active_framebuffer_get()
        shader.bind()
        for j, t in enumerate(textures):
            shader.uniform_sampler("lobe%d" % j, t)
        shader.uniform_sampler("directions", direction_texture)
        shader.uniform_float("ggx_alpha", alpha)
        shader.uniform_float("view", tuple(float(c) for c in VIEW))
        shader.uniform_int("direction_count", count)
        shader.uniform_int("mode", mode)
        batch.draw(shader)
        buffer = framebuffer.read_color(0, 0, width * count, height, 4, 0, "FLOAT")
    offscreen.free()
    buffer.dimensions = width * count * height * 4
    return np.array(buffer, dtype=np.float32).reshape(height, width, count, 4)


def fine_normals(path, level):
    """The fine normals of each level texel: (H, W, texels per footprint, 3), rows bottom-up."""
    rgb = image_pixels(path)[..., :3].astype(np.float64) * 2.0 - 1.0
    n = rgb / np.linalg.norm(rgb, axis=-1, keepdims=True)
    span = 1 << level
    rows, columns = n.shape[0] // span, n.shape[1] // span
    return n.reshape(rows, span, columns, span, 3).transpose(0, 2, 1, 3, 4).reshape(rows, columns, span * span, 3)


def relative_l2(approximation, exact):
    return np.sqrt(((approximation - exact) ** 2).sum(axis=-1) / (exact ** 2).sum(axis=-1))


def check_level(source, out, normal_map, widening, resolution, narrowing):
    lobes = [image_pixels(os.path.join(out, "level%02d_lobe%d.exr" % (LEVEL, j))) for j in range(4)]
    distinct = len({tuple(np.round(t, 4).ravel()) for t in np.stack(lobes, axis=2).reshape(-1, 16)})
    h.expect(distinct >= 32, "only %d distinct level-%d texels: the map repeats" % (distinct, LEVEL))
    directions = cap_directions(DIRECTIONS, MAX_CONE)
    out_gpu = run_shader(source, lobes, directions, 0, GGX_ALPHA)
    rule = documented_rule(np.stack(lobes), directions, widening, resolution, narrowing)
    gaps = [float(np.max(np.abs(out_gpu[..., i] - rule[i]) / np.maximum(np.abs(rule[i]), 1e-2))) for i in range(3)]
    print("GLSL against its documented rule (%d distinct texels): filtered D %.1e, Lambert cosine %.1e, "
          "specular %.1e (relative)" % (distinct, *gaps))
    h.expect(max(gaps) < 1e-3, "the shader does not compute the rule it documents")

    normals = fine_normals(normal_map, LEVEL)                                   # (H, W, Q, 3)
    exact = ggx_d(np.einsum("yxqc,dc->yxqd", normals, directions), GGX_ALPHA).mean(axis=2)
    mean = normals.mean(axis=2)
    mean /= np.linalg.norm(mean, axis=-1, keepdims=True)
    naive = ggx_d(np.einsum("yxc,dc->yxd", mean, directions), GGX_ALPHA)
    lobes_error = float(relative_l2(out_gpu[..., 0], exact).mean())
    naive_error = float(relative_l2(naive, exact).mean())
    print("filtered GGX distribution at level %d (α = %g) against the fine normals' mean: lobes %.3f, "
          "averaged normal %.3f" % (LEVEL, GGX_ALPHA, lobes_error, naive_error))
    h.expect(lobes_error < 0.5 * naive_error and lobes_error < 0.3,
             "the exported shader is not closer to the exact distribution than plain MIP-mapping")


def check_flat_specular(source):
    """Reciprocity and the furnace, on the midpoint grid of the hemisphere in (cos θ, φ)."""
    rings, sectors = 64, 64
    cos_theta = (np.arange(rings) + 0.5) / rings
    phi = 2.0 * math.pi * (np.arange(sectors) + 0.5) / sectors
    c, p = np.meshgrid(cos_theta, phi, indexing="ij")
    s = np.sqrt(1.0 - c * c)
    grid = np.stack([s * np.cos(p), s * np.sin(p), c], axis=-1).reshape(-1, 3).astype(np.float32)
    flat = [np.zeros((1, 1, 4), np.float32) for _ in range(4)]
    values = run_shader(source, flat, grid, 1, FLAT_ALPHA)[0, 0]
    reciprocity = float(np.max(np.abs(values[:, 0] - values[:, 1]) / np.maximum(values[:, 0], 1e-3)))
    albedo = float(values[:, 2].sum() * 2.0 * math.pi / (rings * sectors))  # ∫ f cos dω, dω = dcosθ dφ
    print("flat texel, α = %g: reciprocity %.1e (relative), albedo from straight above %.3f"
          % (FLAT_ALPHA, reciprocity, albedo))
    h.expect(reciprocity < 1e-3, "ndfb_ggx_specular is not reciprocal")
    h.expect(0.85 < albedo < 1.0, "ndfb_ggx_specular's albedo %.3f is not GGX's" % albedo)


def check(directory):
    from ndfbake.shading import lobe_nodes, nodes
    normal_map = h.write_normal_map(os.path.join(directory, "fbm.png"), "fbm", 64)
    out = os.path.join(directory, "bake")
    h.bake_image_file(normal_map, out, max_lobes=4)
    shader_path = os.path.join(out, "ndfbake.glsl")
    h.expect(os.path.isfile(shader_path), "the bake wrote no ndfbake.glsl: %s" % sorted(os.listdir(out)))
    source = open(shader_path).read()
    h.expect(shader_constant(source, "NDFB_LOBES") == 4, "ndfbake.glsl is not for 4 lobes")
    widening = shader_constant(source, "NDFB_GGX_VMF_WIDENING")
    resolution = shader_constant(source, "NDFB_INV_KAPPA_RESOLUTION")
    narrowing = shader_constant(source, "NDFB_GRAZING_NARROWING")
    h.expect(widening == lobe_nodes.GGX_VMF_WIDENING and resolution == lobe_nodes.HALF_INV_KAPPA_RESOLUTION
             and narrowing == nodes.CYCLES_GRAZING_NARROWING,
             "ndfbake.glsl's constants (%g, %g, %g) are not the node group's" % (widening, resolution, narrowing))
    check_level(source, out, normal_map, widening, resolution, narrowing)
    check_flat_specular(source)


def main():
    h.import_addon(register=False)
    try:
        with h.scratch_dir("ndfb-glsl-") as directory:
            check(directory)
        print("PASS test_glsl_export", flush=True)
    except Exception:
        traceback.print_exc()
        print("FAIL test_glsl_export", flush=True)
    bpy.ops.wm.quit_blender()  # as File > Quit: a crash or hang at exit fails ctest's timeout


bpy.app.timers.register(main, first_interval=0.5)
