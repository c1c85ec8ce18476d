"""The GLSL a bake writes beside its lobe textures (ndfbake.glsl), compiled and run on the GPU by
Blender's gpu module in a real window (under Xvfb: the module does not draw in background mode).

A 64² bumps map is baked by the library; a fragment shader that includes ndfbake.glsl fetches the
level-3 lobe texels (8×8 fine normals each) from the bake's EXR files and evaluates, for 16 half
vectors within 40° of the normal, the filtered GGX distribution and the Lambert cosine. Checked:
- against the documented decoding evaluated in numpy from the same texels (the shader computes
  the rule it states, the one the add-on's node group uses);
- against the exact filtered distribution, the mean of D_α(h·n_q) over each texel's fine normals
  (relative L2 over the 16 directions, per texel, averaged): the lobes must be within half the
  error of shading the texel's averaged normal (plain MIP-mapping), and within 0.3.

Run: xvfb-run -a blender --factory-startup --python tests/blender/test_glsl_export.py -- LIB
The process exits 0 when every check holds, 1 otherwise.
"""
import math
import os
import sys
import traceback

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import test_addon_helpers as h  # noqa: E402

LEVEL = 3
GGX_ALPHA = 0.2
DIRECTIONS = 16
MAX_CONE = math.radians(40.0)
WIDENING = 1.5  # native/src/math/brdf.h kGgxVmfWidening

VERTEX = """
in vec2 pos;
void main() { gl_Position = vec4(pos, 0.0, 1.0); }
"""

FRAGMENT = """
uniform sampler2D lobe0, lobe1, lobe2, lobe3, directions;
uniform float ggx_alpha;
uniform int direction_count;
out vec4 result;
void main()
{
    ivec2 pixel = ivec2(gl_FragCoord.xy);
    ivec2 texel = ivec2(pixel.x / direction_count, pixel.y);
    vec3 h = texelFetch(directions, ivec2(pixel.x % direction_count, 0), 0).xyz;
    vec4 texels[NDFB_LOBES];
    texels[0] = texelFetch(lobe0, texel, 0);
    texels[1] = texelFetch(lobe1, texel, 0);
    texels[2] = texelFetch(lobe2, texel, 0);
    texels[3] = texelFetch(lobe3, texel, 0);
    result = vec4(ndfb_filtered_ggx_d(texels, ggx_alpha, h), ndfb_lambert_cosine(texels, h), 0.0, 1.0);
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


def documented_rule(texels, directions):
    """(filtered D, Lambert cosine) per texel and direction, as ndfbake.glsl's header states them."""
    weight = np.maximum(texels[..., 0], 0.0)                       # (lobes, H, W)
    r = texels[..., 1:] / np.maximum(texels[..., :1], 1e-6)
    R = np.minimum(np.linalg.norm(r, axis=-1), 0.9999)
    mu = r + np.array([0.0, 0.0, 1e-5])
    mu /= np.linalg.norm(mu, axis=-1, keepdims=True)
    inv_kappa = (1.0 - R * R) / np.maximum(R * (3.0 - R * R), 1e-6)
    alpha = np.sqrt(np.minimum(GGX_ALPHA ** 2 + WIDENING * inv_kappa, 1.0))
    cos = np.einsum("lyxc,dc->lyxd", mu, directions)
    total = weight.sum(axis=0)[..., None]
    d = (weight[..., None] * ggx_d(cos, alpha[..., None])).sum(axis=0) / total
    lambert = (weight[..., None] * np.maximum(cos, 0.0)).sum(axis=0) / total
    return d, lambert


def run_shader(shader_source, lobes, directions):
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
        shader.uniform_float("ggx_alpha", GGX_ALPHA)
        shader.uniform_int("direction_count", count)
        batch.draw(shader)
        buffer = framebuffer.read_color(0, 0, width * count, height, 4, 0, "FLOAT")
    offscreen.free()
    buffer.dimensions = width * count * height * 4
    out = np.array(buffer, dtype=np.float32).reshape(height, width, count, 4)
    return out[..., 0], out[..., 1]


def fine_normals(path, level):
    """The fine normals of each level texel: (H, W, texels per footprint, 3), rows bottom-up."""
    rgb = image_pixels(path)[..., :3].astype(np.float64) * 2.0 - 1.0
    n = rgb / np.linalg.norm(rgb, axis=-1, keepdims=True)
    span = 1 << level
    rows, columns = n.shape[0] // span, n.shape[1] // span
    return n.reshape(rows, span, columns, span, 3).transpose(0, 2, 1, 3, 4).reshape(rows, columns, span * span, 3)


def relative_l2(approximation, exact):
    return np.sqrt(((approximation - exact) ** 2).sum(axis=-1) / (exact ** 2).sum(axis=-1))


def check(directory):
    from ndfbake import native
    normal_map = h.write_normal_map(os.path.join(directory, "bumps.png"), "bumps", 64)
    out = os.path.join(directory, "bake")
    with native.load().context() as ctx:
        ctx.bake(normal_map, out, max_lobes=4)
    shader_path = os.path.join(out, "ndfbake.glsl")
    h.expect(os.path.isfile(shader_path), "the bake wrote no ndfbake.glsl: %s" % sorted(os.listdir(out)))
    source = open(shader_path).read()
    h.expect("#define NDFB_LOBES 4" in source, "ndfbake.glsl is not for 4 lobes")

    lobes = [image_pixels(os.path.join(out, "level%02d_lobe%d.exr" % (LEVEL, j))) for j in range(4)]
    directions = cap_directions(DIRECTIONS, MAX_CONE)
    gpu_d, gpu_lambert = run_shader(source, lobes, directions)
    rule_d, rule_lambert = documented_rule(np.stack(lobes), directions)
    d_gap = float(np.max(np.abs(gpu_d - rule_d) / np.maximum(rule_d, 1e-3)))
    lambert_gap = float(np.max(np.abs(gpu_lambert - rule_lambert)))
    print("GLSL against its documented rule: filtered D relative %.2e, Lambert cosine %.2e" % (d_gap, lambert_gap))
    h.expect(d_gap < 1e-3 and lambert_gap < 1e-4, "the shader does not compute the rule it documents")

    normals = fine_normals(normal_map, LEVEL)                                   # (H, W, Q, 3)
    exact = ggx_d(np.einsum("yxqc,dc->yxqd", normals, directions), GGX_ALPHA).mean(axis=2)
    mean = normals.mean(axis=2)
    mean /= np.linalg.norm(mean, axis=-1, keepdims=True)
    naive = ggx_d(np.einsum("yxc,dc->yxd", mean, directions), GGX_ALPHA)
    lobes_error = float(relative_l2(gpu_d, exact).mean())
    naive_error = float(relative_l2(naive, exact).mean())
    print("filtered GGX distribution at level %d (α = %g) against the fine normals' mean: lobes %.3f, "
          "averaged normal %.3f" % (LEVEL, GGX_ALPHA, lobes_error, naive_error))
    h.expect(lobes_error < 0.5 * naive_error and lobes_error < 0.3,
             "the exported shader is not closer to the exact distribution than plain MIP-mapping")


def main():
    h.import_addon(register=False)
    directory = h.temp_dir("ndfb-glsl-")
    try:
        check(directory)
        print("PASS test_glsl_export", flush=True)
        code = 0
    except Exception:
        traceback.print_exc()
        print("FAIL test_glsl_export", flush=True)
        code = 1
    finally:
        h.cleanup(directory)
    os._exit(code)


bpy.app.timers.register(main, first_interval=0.5)
