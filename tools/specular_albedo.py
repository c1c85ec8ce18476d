"""Tabulates what a Principled BSDF v2 (Blender 4.0+) takes out of its diffuse for its dielectric
specular layer, for the specular split's base (addon/ndfbake/shading/specular_split.py):

    python3 tools/specular_albedo.py           # writes addon/ndfbake/shading/specular_albedo_table.py
    python3 tools/specular_albedo.py --check   # exit status 1 where that file is not what this writes

Cycles darkens a Principled's diffuse by the layer's directional albedo as it estimates it
(bsdf_microfacet_estimate_albedo, closure_layering_weight): mix(F0·t, 1, s)·M, with s the
lobe-averaged position of the dielectric Fresnel between F0 and 1,

    s(r, μ, z) = (E_F / E − F0) / (1 − F0),  E_F = ∫ f_GGX(μ, l) F(h·v, η) (n·l) dl,  E = E_F at F = 1,

F the exact dielectric Fresnel of the IOR η = (1 + z²) / (1 − z²) (z⁴ = F0, Cycles' own axis), and
M = E + F_ms·(1 − E) for Multiscatter GGX (the energy its compensation adds back; Kulla and
Conty 2017's F_ms = F_ss·E_avg / (1 − F_ss·(1 − E_avg)), F_ss the hemispherical average of F and
E_avg that of E), 1 for GGX. EEVEE (4.2+) darkens it by its own split-sum estimate instead,
F0·t·A + F90·B (Karis 2013), with its GGX's separable Smith term G1(v)·G1(l), for which this
also tabulates

    A(r, μ) = ∫ f(μ, l) (1 − (1 − h·v)⁵) (n·l) dl,   B(r, μ) = ∫ f(μ, l) (1 − h·v)⁵ (n·l) dl.

This computes s, E, F_ms, A and B from those definitions (Walter et al. 2007's GGX with the height-correlated
Smith term, Heitz 2014; Heitz 2018's visible-normal sampling), on a 16 x 16 x 16 grid of roughness r,
√μ (dense at grazing views, where s moves fastest) and z. Deterministic: a fixed seed."""
import argparse
import os
import sys

import numpy as np

# grazing.ggx: the GGX model (visible normals, masking) the grazing study built and checked.
sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "studies"))

from grazing.ggx import lambda_local, reflect_kernel, strat2  # noqa: E402

ROUGHNESS_SIZE = MU_SIZE = Z_SIZE = 16
SAMPLES = 128 * 128   # stratified visible normals per (r, μ): the table's error is under 1e-4
MU_MIN = 1e-3         # the first column's view cosine: exactly grazing, a view sees no microfacet
AVERAGE_NODES = 32    # Gauss-Legendre nodes in μ of the hemispherical averages
AVERAGE_SAMPLES = 64 * 64
Z_MAX = 0.98          # F0 = 0.92: at z = 1 (F0 = 1) s is 0/0, and mix(F0, 1, s) = 1 whatever s is
OUTPUT = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "addon", "ndfbake", "shading",
                      "specular_albedo_table.py")


def fresnel_dielectric(c, eta):
    """Exact unpolarised Fresnel reflectance at cos θ = c from outside a dielectric of IOR eta."""
    g2 = eta * eta - 1.0 + c * c
    g = np.sqrt(np.maximum(g2, 0.0))
    a = (g - c) / np.maximum(g + c, 1e-30)   # g = c = 0 only at η = 1 and grazing, where F = 0
    b = (c * (g + c) - 1.0) / (c * (g - c) + 1.0)
    return np.where(g2 > 0.0, 0.5 * a * a * (1.0 + b * b), 1.0)


def axes():
    """The grid's r, μ and z values."""
    grid = np.linspace(0.0, 1.0, 16)
    mu = np.maximum(grid ** 2, MU_MIN)
    z = np.minimum(grid, Z_MAX)
    return grid, mu, z


def hemispherical_average(values_at):
    """2∫ f(μ) μ dμ over μ in [0, 1] by AVERAGE_NODES-point Gauss-Legendre; values_at(μ) gives f
    at an array of μ, along its last axis."""
    nodes, weights = np.polynomial.legendre.leggauss(AVERAGE_NODES)
    mu = 0.5 * (nodes + 1.0)
    return (weights * values_at(mu) * mu).sum(-1)


def directional_albedos(r, mu, eta, u1, u2):
    """E, E_F / E per IOR in eta, and EEVEE's split sum (A, B) for roughness r at view cosine mu."""
    count = len(u1)
    normal = np.broadcast_to(np.array([0.0, 0.0, 1.0]), (count, 3))
    view = np.broadcast_to(np.array([np.sqrt(1.0 - mu * mu), 0.0, mu]), (count, 3))
    light, weight = reflect_kernel(view, normal, np.full(count, max(r * r, 1e-4)), u1, u2)
    half = view + light
    cos_hv = np.clip((half * view).sum(-1) / np.linalg.norm(half, axis=-1), 0.0, 1.0)
    e = weight.mean()
    e_f = (weight[None, :] * fresnel_dielectric(cos_hv[None, :], eta[:, None])).mean(-1)
    # EEVEE's GGX has the separable Smith term G1(v)·G1(l): a visible normal's weight is G1(l)
    # (the normal is +z, so the light is already in local coordinates; kept above the horizon).
    above = np.concatenate([light[:, :2], np.maximum(light[:, 2:], 1e-7)], -1)
    separable = np.where(weight > 0.0, 1.0 / (1.0 + lambda_local(max(r * r, 1e-4), above)), 0.0)
    schlick = (1.0 - cos_hv) ** 5
    return e, e_f / max(e, 1e-8), ((1.0 - schlick) * separable).mean(), (schlick * separable).mean()


def tabulate():
    """s[r, z, μ], E[r, μ], F_ms[r, z], and A[r, μ] and B[r, μ] on axes()."""
    roughness, mu, z = axes()
    eta = (1.0 + z * z) / (1.0 - z * z)
    f0 = z ** 4
    u1, u2 = strat2(SAMPLES, np.random.default_rng(2026))
    shape = np.zeros((ROUGHNESS_SIZE, Z_SIZE, MU_SIZE))
    albedo = np.zeros((ROUGHNESS_SIZE, MU_SIZE))
    scale = np.zeros((ROUGHNESS_SIZE, MU_SIZE))
    bias = np.zeros((ROUGHNESS_SIZE, MU_SIZE))
    for i, r in enumerate(roughness):
        for k, m in enumerate(mu):
            albedo[i, k], fresnel, scale[i, k], bias[i, k] = directional_albedos(r, m, eta, u1, u2)
            shape[i, :, k] = np.clip((fresnel - f0) / (1.0 - f0), 0.0, 1.0)
    # F_ss = 2∫F μ dμ per IOR; E_avg = 2∫E μ dμ per roughness (fewer samples: a smooth average).
    f_ss = hemispherical_average(lambda m: fresnel_dielectric(m[None, :], eta[:, None]))
    u1, u2 = strat2(AVERAGE_SAMPLES, np.random.default_rng(2027))
    e_avg = np.array([hemispherical_average(lambda m: np.array([directional_albedos(r, c, eta[:1], u1, u2)[0]
                                                                for c in m])) for r in roughness])
    f_ms = f_ss[None, :] * e_avg[:, None] / (1.0 - f_ss[None, :] * (1.0 - e_avg[:, None]))
    return shape, albedo, f_ms, scale, bias


def _rows(values):
    flat = ["%.4f" % v for v in np.asarray(values).ravel()]
    return "\n".join("    " + ", ".join(flat[i:i + 16]) + "," for i in range(0, len(flat), 16))


def module_text(shape, albedo, f_ms, scale, bias):
    return '''"""Generated by tools/specular_albedo.py (which says what these are and how they are computed);
do not edit. The specular layer of a Principled BSDF v2 on a 16 x 16 x 16 grid: roughness r, then
the dielectric's z = F0^(1/4), then √μ (μ the view cosine), each 0 to 1 in 15 steps."""
ROUGHNESS_SIZE, Z_SIZE, MU_SIZE = %d, %d, %d
# s(r, z, √μ): where the layer's albedo lies between F0 and 1 (mix(F0, 1, s)); index (r·16 + z)·16 + √μ.
FRESNEL_SHAPE = (
%s
)
# E(r, √μ): GGX's single-scatter albedo with no Fresnel; index r·16 + √μ.
GGX_ALBEDO = (
%s
)
# F_ms(r, z): the Fresnel of light Multiscatter GGX scatters more than once (white tint); index r·16 + z.
MULTISCATTER_FRESNEL = (
%s
)
# A(r, √μ), B(r, √μ): EEVEE's split sum (separable Smith term), the albedo weighted by 1 − (1 − h·v)^5
# and by (1 − h·v)^5; index r·16 + √μ.
EEVEE_SPLIT_SCALE = (
%s
)
EEVEE_SPLIT_BIAS = (
%s
)
''' % (ROUGHNESS_SIZE, Z_SIZE, MU_SIZE, _rows(shape), _rows(albedo), _rows(f_ms), _rows(scale), _rows(bias))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--check", action="store_true", help="compare with the file instead of writing it")
    args = parser.parse_args()
    text = module_text(*tabulate())
    if args.check:
        with open(OUTPUT, encoding="utf-8") as f:
            same = f.read() == text
        print("%s is %s" % (OUTPUT, "what tools/specular_albedo.py writes" if same else "NOT what it writes"))
        sys.exit(0 if same else 1)
    with open(OUTPUT + ".tmp", "w", encoding="utf-8") as f:
        f.write(text)
    os.replace(OUTPUT + ".tmp", OUTPUT)
    print("wrote", OUTPUT)


if __name__ == "__main__":
    main()
