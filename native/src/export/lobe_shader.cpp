#include "export/lobe_shader.h"

#include <cstdio>

#include "math/brdf.h"

namespace ndfbake {

namespace {

// @SLOTS@: lobe slots, @WIDENING@: kGgxVmfWidening. The decoding mirrors addon/ndfbake/nodes.py's
// group, which the add-on's tests check against this file.
constexpr std::string_view kShader = R"glsl(// ndfbake.glsl: shading with the filtered normal distribution stored in this folder's lobe
// textures (Han et al. 2007, "Frequency Domain Normal Map Filtering"), for real-time engines.
//
// Textures. Lobe slot j is one RGBA texture whose mip level n is levelNN_lobeJ.exr (NN = n, two
// digits): linear data, never sRGB. R = alpha_j, the lobe's weight; GBA = alpha_j * r_j, where
// r_j is the lobe's mean resultant vector in tangent space (+Z the surface normal, +Y OpenGL
// convention), |r_j| < 1. Upload every level as that mip level and sample with trilinear or
// anisotropic filtering: the encoding is linear, so the hardware's averages are averages of the
// distributions, which is what a coarser texel stands for. An empty slot is all zeros. (The
// atlas_lobeJ.exr files, written with --atlas, frame every level in one image for engines that
// cannot upload their own mip levels; their layout is in report.json.)
//
// Shading. Each lobe j is a microfacet BRDF about its own mean normal mu_j with GGX roughness
// widened by the lobe's spread kappa_j: alpha_j'^2 = alpha^2 + NDFB_GGX_VMF_WIDENING / kappa_j,
// alpha' <= 1, where alpha is the material's GGX alpha (roughness^2 in Blender's and Disney's
// convention). The lobes are weighted by alpha_j / sum(alpha). Directions are in tangent space.
// kappa_j comes from |r_j| = R by Banerjee's approximation kappa = R(3 - R^2) / (1 - R^2).

#define NDFB_LOBES @SLOTS@
#define NDFB_GGX_VMF_WIDENING @WIDENING@
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
    float R = min(length(r), 0.9999);                 // R -> 1: kappa stays finite
    lobe.normal = normalize(r + vec3(0.0, 0.0, 1e-5)); // R -> 0 (normals cancel): +Z
    float inv_kappa = (1.0 - R * R) / max(R * (3.0 - R * R), 1e-6);
    lobe.alpha = sqrt(min(ggx_alpha * ggx_alpha + NDFB_GGX_VMF_WIDENING * inv_kappa, 1.0));
    return lobe;
}

// GGX (Trowbridge-Reitz) distribution of microfacet normals, D(h) for cos = n.h.
float ndfb_ggx_d(float cos_theta, float alpha)
{
    if (cos_theta <= 0.0) return 0.0;
    float a2 = alpha * alpha;
    float d = cos_theta * cos_theta * (a2 - 1.0) + 1.0;
    return a2 / (NDFB_PI * d * d);
}

// Smith's masking for GGX, G1(v) for cos = n.v > 0.
float ndfb_ggx_g1(float cos_theta, float alpha)
{
    float a2 = alpha * alpha;
    return 2.0 * cos_theta / (cos_theta + sqrt(a2 + (1.0 - a2) * cos_theta * cos_theta));
}

// The filtered distribution of normals at half vector h (unit, tangent space): what the texel's
// fine normals' GGX distributions average to.
float ndfb_filtered_ggx_d(vec4 texels[NDFB_LOBES], float ggx_alpha, vec3 h)
{
    float sum = 0.0, total = 0.0;
    for (int j = 0; j < NDFB_LOBES; ++j) {
        NdfbLobe lobe = ndfb_lobe(texels[j], ggx_alpha);
        sum += lobe.weight * ndfb_ggx_d(dot(lobe.normal, h), lobe.alpha);
        total += lobe.weight;
    }
    return total > 0.0 ? sum / total : ndfb_ggx_d(h.z, ggx_alpha);
}

// Specular BRDF value (without the cosine of l) for view v and light l (unit, tangent space,
// pointing away from the surface), Fresnel by Schlick from f0.
vec3 ndfb_ggx_specular(vec4 texels[NDFB_LOBES], float ggx_alpha, vec3 f0, vec3 v, vec3 l)
{
    vec3 h = normalize(v + l);
    vec3 fresnel = f0 + (1.0 - f0) * pow(1.0 - clamp(dot(v, h), 0.0, 1.0), 5.0);
    float sum = 0.0, total = 0.0;
    for (int j = 0; j < NDFB_LOBES; ++j) {
        NdfbLobe lobe = ndfb_lobe(texels[j], ggx_alpha);
        total += lobe.weight;
        float nv = dot(lobe.normal, v), nl = dot(lobe.normal, l);
        if (lobe.weight <= 0.0 || nv <= 0.0 || nl <= 0.0) continue;
        sum += lobe.weight * ndfb_ggx_d(dot(lobe.normal, h), lobe.alpha) * ndfb_ggx_g1(nv, lobe.alpha) *
               ndfb_ggx_g1(nl, lobe.alpha) / (4.0 * nv * nl);
    }
    return total > 0.0 ? fresnel * (sum / total) : vec3(0.0);
}

// The cosine factor of Lambertian shading, max(n.l, 0), averaged over the lobes' mean normals:
// diffuse = albedo / pi * ndfb_lambert_cosine(texels, l) * light. (The lobes' spread, which
// softens the terminator a little, is left out.)
float ndfb_lambert_cosine(vec4 texels[NDFB_LOBES], vec3 l)
{
    float sum = 0.0, total = 0.0;
    for (int j = 0; j < NDFB_LOBES; ++j) {
        NdfbLobe lobe = ndfb_lobe(texels[j], 0.0);
        sum += lobe.weight * max(dot(lobe.normal, l), 0.0);
        total += lobe.weight;
    }
    return total > 0.0 ? sum / total : max(l.z, 0.0);
}
)glsl";

void replace_all(std::string& text, std::string_view token, const std::string& value)
{
    for (size_t at = text.find(token); at != std::string::npos; at = text.find(token, at + value.size()))
        text.replace(at, token.size(), value);
}

}  // namespace

std::string lobe_shader_glsl(int slots)
{
    char widening[32];
    std::snprintf(widening, sizeof widening, "%.6f", double(kGgxVmfWidening));
    std::string shader(kShader);
    replace_all(shader, "@SLOTS@", std::to_string(slots));
    replace_all(shader, "@WIDENING@", widening);
    return shader;
}

}  // namespace ndfbake
