#include "export/lobe_shader.h"

#include <cstdio>

#include "math/brdf.h"

namespace ndfbake {

namespace {

// @SLOTS@: lobe slots, @WIDENING@: kGgxVmfWidening, @RESOLUTION@: kHalfInvKappaResolution or 0,
// @NARROWING@: kGrazingNarrowing. The decoding is addon/ndfbake/shading/lobe_nodes.py's lobe group; tests/blender/test_glsl_export.py runs this
// file against the same rule with the add-on's constants.
constexpr std::string_view kShader = R"glsl(// ndfbake.glsl: shading with the filtered normal distribution stored in this folder's lobe
// textures (Han et al. 2007, "Frequency Domain Normal Map Filtering"), for real-time engines.
//
// Textures. Lobe slot j is one RGBA texture: R = alpha_j, the lobe's weight; GBA = alpha_j * r_j,
// where r_j is the lobe's mean resultant vector in tangent space (+Z the surface normal, +X along
// the tangent, +Y along the bitangent: OpenGL's convention, whatever the source map's was), |r_j|
// <= 1 (= 1: a single direction). An empty slot is all zeros. Keep the data as it is: linear,
// never sRGB; RGBA16F or RGBA32F, not block-compressed (BC6H drops A and negative values).
// Load levelNN_lobeJ.exr the way the source normal map is loaded (row 0 of the file is its top
// row) as mip level NN of texture J, and sample with trilinear or anisotropic filtering: the
// encoding is linear, so the hardware's averages are averages of the distributions, which is what
// a coarser texel stands for.
// - Level sizes halve rounding up, as the bake's footprints do (100 -> 50 -> 25 -> 13 -> 7 -> 4 ->
//   2 -> 1); GPU mip chains round down. For a power-of-two map they agree; for others, resample
//   or use the atlas (atlas_lobeJ.exr, written with --atlas: every level in one image, its
//   layout in report.json). A bake of fewer levels (--levels) needs the sampler's maximum level
//   (GL_TEXTURE_MAX_LEVEL, maxLod) set to the last one.
// - Mips the engine builds from level 0 by box filtering are usable (the lobe slots are aligned
//   across texels for that) but less accurate than the baked levels.
// - In a -Y (DirectX) tangent frame, negate the decoded normal's y (the B channel).
//
// Shading. Each lobe j is a microfacet BRDF about its own mean normal mu_j with GGX roughness
// widened by the lobe's spread kappa_j: alpha_j'^2 = alpha^2 + NDFB_GGX_VMF_WIDENING / kappa_j,
// alpha' <= 1, where alpha is the material's GGX alpha (roughness^2 in Blender's and Disney's
// convention); kappa_j comes from |r_j| = R by Banerjee's approximation
// kappa = R(3 - R^2) / (1 - R^2), with NDFB_INV_KAPPA_RESOLUTION (the storage's rounding of |r|)
// taken off 1/kappa. The lobes are weighted by alpha_j / sum(alpha). Like the Blender add-on's
// node group, each lobe is normalized about its own normal; the library's error measure also
// scales a widened lobe by the integral ratio of D_alpha and D_alpha' (brdf.h), which changes
// the filtered distribution by a few percent (relative L2 0.100 with it against 0.106 without,
// measured at alpha = 0.2) and which NDFB_GGX_VMF_WIDENING was chosen with. ndfb_ggx_specular
// narrows each lobe toward grazing views, alpha_c^2 = max(alpha'^2 / (1 + NDFB_GRAZING_NARROWING
// * alpha'^2 * tan^2(theta)), alpha^2), theta between the view and the lobe's normal: a microfacet
// lobe weights its facets by their area seen from the view, the normal map it stands for does not
// (ndfbake's docs/grazing-fit.md; a flat texel is left as it is). Directions are in tangent space.

#ifdef GL_ES
precision highp float;
#endif

#define NDFB_LOBES @SLOTS@
#define NDFB_GGX_VMF_WIDENING @WIDENING@
#define NDFB_INV_KAPPA_RESOLUTION @RESOLUTION@
#define NDFB_GRAZING_NARROWING @NARROWING@
#define NDFB_PI 3.14159265358979

struct NdfbLobe {
    float weight;   // alpha_j (not normalized: divide by the sum over lobes)
    vec3 normal;    // mu_j, unit, tangent space
    float alpha;    // widened GGX alpha_j'
};

// One lobe from its texel (a texture sample of slot j) and the material's GGX alpha.
NdfbLobe ndfb_lobe(vec4 texel, float ggx_alpha)
{
    NdfbLobe lobe;
    lobe.weight = max(texel.r, 0.0);
    vec3 r = texel.gba / max(texel.r, 1e-6);
    float R = min(length(r), 1.0);
    lobe.normal = normalize(r + vec3(0.0, 0.0, 1e-5)); // R -> 0 (normals cancel): +Z
    float inv_kappa = (1.0 - R * R) / max(R * (3.0 - R * R), 1e-6);
    inv_kappa = max(inv_kappa - NDFB_INV_KAPPA_RESOLUTION, 0.0);
    lobe.alpha = sqrt(min(ggx_alpha * ggx_alpha + NDFB_GGX_VMF_WIDENING * inv_kappa, 1.0));
    return lobe;
}

// GGX (Trowbridge-Reitz) distribution of microfacet normals, D(h) for cos = n.h.
float ndfb_ggx_d(float cos_theta, float alpha)
{
    if (cos_theta <= 0.0) return 0.0;
    float a2 = alpha * alpha;
    // c²(α² − 1) + 1, written so that α² − 1 cannot round to −1 at small α (d = 0 at the peak).
    float d = a2 * cos_theta * cos_theta + (1.0 - cos_theta) * (1.0 + cos_theta);
    return a2 / (NDFB_PI * d * d);
}

// A lobe's widened alpha' narrowed for a view at cos = n.v from its normal (n.v floored at 1e-3,
// about 89.94 degrees, so that tan^2 stays finite), never below the material's alpha.
float ndfb_grazing_alpha(float widened_alpha, float ggx_alpha, float cos_view)
{
    float c = max(cos_view, 1e-3);
    float tan2 = (1.0 - c * c) / (c * c);
    float w2 = widened_alpha * widened_alpha;
    return sqrt(max(w2 / (1.0 + NDFB_GRAZING_NARROWING * w2 * tan2), ggx_alpha * ggx_alpha));
}

// Smith's masking for GGX, G1(v) for cos = n.v > 0.
float ndfb_ggx_g1(float cos_theta, float alpha)
{
    float a2 = alpha * alpha;
    return 2.0 * cos_theta / (cos_theta + sqrt(a2 + (1.0 - a2) * cos_theta * cos_theta));
}

// A texel whose weights sum to 0 (no data) shades as the flat surface.
float ndfb_total_weight(vec4 texels[NDFB_LOBES], inout vec4 flat_texels[NDFB_LOBES])
{
    float total = 0.0;
    for (int j = 0; j < NDFB_LOBES; ++j) total += max(texels[j].r, 0.0);
    for (int j = 0; j < NDFB_LOBES; ++j) flat_texels[j] = total > 0.0 ? texels[j] : vec4(0.0);
    if (total <= 0.0) flat_texels[0] = vec4(1.0, 0.0, 0.0, 1.0);
    return total > 0.0 ? total : 1.0;
}

// The filtered distribution of normals at half vector h (unit, tangent space): the lobes' GGX
// distributions, weighted.
float ndfb_filtered_ggx_d(vec4 texels[NDFB_LOBES], float ggx_alpha, vec3 h)
{
    vec4 t[NDFB_LOBES];
    float total = ndfb_total_weight(texels, t);
    float sum = 0.0;
    for (int j = 0; j < NDFB_LOBES; ++j) {
        NdfbLobe lobe = ndfb_lobe(t[j], ggx_alpha);
        sum += lobe.weight * ndfb_ggx_d(dot(lobe.normal, h), lobe.alpha);
    }
    return sum / total;
}

// Specular reflection for view v and light l (unit, tangent space, pointing away from the
// surface): each lobe's GGX BRDF (Smith masking, Schlick Fresnel from f0; its alpha narrowed
// toward grazing views, ndfb_grazing_alpha) times the cosine of l about that lobe's normal, weighted. Multiply by the light's radiance; do not multiply by a
// cosine again.
vec3 ndfb_ggx_specular(vec4 texels[NDFB_LOBES], float ggx_alpha, vec3 f0, vec3 v, vec3 l)
{
    vec4 t[NDFB_LOBES];
    float total = ndfb_total_weight(texels, t);
    vec3 h = normalize(v + l);
    vec3 fresnel = f0 + (1.0 - f0) * pow(1.0 - clamp(dot(v, h), 0.0, 1.0), 5.0);
    float sum = 0.0;
    for (int j = 0; j < NDFB_LOBES; ++j) {
        NdfbLobe lobe = ndfb_lobe(t[j], ggx_alpha);
        float nv = dot(lobe.normal, v), nl = dot(lobe.normal, l);
        if (lobe.weight <= 0.0 || nv <= 0.0 || nl <= 0.0) continue;
        float alpha = ndfb_grazing_alpha(lobe.alpha, ggx_alpha, nv);
        sum += lobe.weight * ndfb_ggx_d(dot(lobe.normal, h), alpha) * ndfb_ggx_g1(nv, alpha) *
               ndfb_ggx_g1(nl, alpha) / (4.0 * nv);
    }
    return fresnel * (sum / total);
}

// The cosine factor of Lambertian shading, max(n.l, 0), averaged over the lobes' mean normals:
// diffuse = albedo / pi * ndfb_lambert_cosine(texels, l) * light. (The lobes' spread, which
// softens the terminator a little, is left out.)
float ndfb_lambert_cosine(vec4 texels[NDFB_LOBES], vec3 l)
{
    vec4 t[NDFB_LOBES];
    float total = ndfb_total_weight(texels, t);
    float sum = 0.0;
    for (int j = 0; j < NDFB_LOBES; ++j) {
        NdfbLobe lobe = ndfb_lobe(t[j], 0.0);
        sum += lobe.weight * max(dot(lobe.normal, l), 0.0);
    }
    return sum / total;
}
)glsl";

void replace_all(std::string& text, std::string_view token, const std::string& value)
{
    for (size_t at = text.find(token); at != std::string::npos; at = text.find(token, at + value.size()))
        text.replace(at, token.size(), value);
}

std::string glsl_float(float value)
{
    char text[32];
    std::snprintf(text, sizeof text, "%.6g", double(value));
    std::string result(text);
    if (result.find_first_of(".e") == std::string::npos) result += ".0";  // GLSL ES: no int for float
    return result;
}

}  // namespace

std::string lobe_shader_glsl(int slots, PixelPrecision precision)
{
    std::string shader(kShader);
    replace_all(shader, "@SLOTS@", std::to_string(slots));
    replace_all(shader, "@WIDENING@", glsl_float(kGgxVmfWidening));
    replace_all(shader, "@NARROWING@", glsl_float(kGrazingNarrowing));
    replace_all(shader, "@RESOLUTION@",
                glsl_float(precision == PixelPrecision::half ? kHalfInvKappaResolution : 0.0f));
    return shader;
}

}  // namespace ndfbake
