"""The specular layer's table (addon/ndfbake/shading/specular_albedo_table.py: Cycles' s, E and F_ms and
EEVEE's split sum A and B) against its definition,
integrated another way (tools/specular_albedo.py samples visible normals; this integrates the BRDF
over the outgoing hemisphere on a Gauss-Legendre grid) and against its mirror limit (r = 0: the
lobe is the Fresnel of the view itself, E = 1), and the file against what the tool writes.

    python3 tests/tools/test_specular_albedo.py"""
import os
import sys

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "tools"))
sys.path.insert(0, os.path.join(ROOT, "studies"))  # the tool's grazing.ggx
sys.path.insert(0, os.path.join(ROOT, "addon"))

import specular_albedo as tool  # noqa: E402
from ndfbake.shading import specular_albedo_table as table  # noqa: E402

SHAPE = np.array(table.FRESNEL_SHAPE).reshape(table.ROUGHNESS_SIZE, table.Z_SIZE, table.MU_SIZE)
ALBEDO = np.array(table.GGX_ALBEDO).reshape(table.ROUGHNESS_SIZE, table.MU_SIZE)
MULTISCATTER = np.array(table.MULTISCATTER_FRESNEL).reshape(table.ROUGHNESS_SIZE, table.Z_SIZE)
SPLIT_SCALE = np.array(table.EEVEE_SPLIT_SCALE).reshape(table.ROUGHNESS_SIZE, table.MU_SIZE)
SPLIT_BIAS = np.array(table.EEVEE_SPLIT_BIAS).reshape(table.ROUGHNESS_SIZE, table.MU_SIZE)
TOLERANCE = 2e-3   # the table's 4 decimals, its sampling (< 1e-4) and this quadrature's error


def hemisphere_albedos(r, mu, eta, n=768):
    """E and E_F / E of GGX (height-correlated Smith) at view cosine mu, and EEVEE's split sum
    (A, B: the separable Smith term, weighted by 1 − (1 − h·v)^5 and (1 − h·v)^5), integrated over
    the outgoing hemisphere: Gauss-Legendre in the light's cosine, uniform in its azimuth."""
    alpha2 = max(r * r, 1e-4) ** 2
    nodes, weights = np.polynomial.legendre.leggauss(n)
    cos_l, w_l = 0.5 * (nodes + 1.0), 0.5 * weights
    phi = (np.arange(2 * n) + 0.5) * np.pi / n
    cos_l, phi = np.meshgrid(cos_l, phi, indexing="ij")
    sin_l = np.sqrt(1.0 - cos_l ** 2)
    light = np.stack([sin_l * np.cos(phi), sin_l * np.sin(phi), cos_l], -1)
    view = np.array([np.sqrt(1.0 - mu * mu), 0.0, mu])
    half = light + view
    half /= np.linalg.norm(half, axis=-1, keepdims=True)
    cos_h = half[..., 2]
    d = alpha2 / (np.pi * (cos_h ** 2 * (alpha2 - 1.0) + 1.0) ** 2)

    def smith_lambda(c):
        return 0.5 * (np.sqrt(1.0 + alpha2 * (1.0 - c * c) / (c * c)) - 1.0)
    g2 = 1.0 / (1.0 + smith_lambda(mu) + smith_lambda(cos_l))

    def smith_g1(c):
        return 1.0 / (1.0 + smith_lambda(c))
    integrand = d * g2 / (4.0 * mu)        # f·(n·l) = D G2 / (4 μ_v μ_l)·μ_l
    measure = w_l[:, None] * (np.pi / n)  # dω = dμ_l dφ
    e = (integrand * measure).sum()
    cos_hv = np.clip((half * view).sum(-1), 0.0, 1.0)
    fresnel = tool.fresnel_dielectric(cos_hv, eta)
    separable = d * smith_g1(mu) * smith_g1(cos_l) / (4.0 * mu)
    schlick = (1.0 - cos_hv) ** 5
    return (e, (integrand * fresnel * measure).sum() / e, (separable * (1.0 - schlick) * measure).sum(),
            (separable * schlick * measure).sum())


def test_rough_grid_points_match_the_hemisphere_integral():
    roughness, mu, z = tool.axes()
    worst = 0.0
    for i in (6, 10, 15):            # r = 0.4, 0.67, 1: lobes the quadrature resolves
        for k in (4, 7, 11, 15):     # 4.1°, 12.6°, 32.5°, 90° above the surface
            for j in (3, 7, 11):
                eta = (1.0 + z[j] ** 2) / (1.0 - z[j] ** 2)
                e, fresnel, a, b = hemisphere_albedos(roughness[i], mu[k], eta)
                f0 = z[j] ** 4
                shape = (fresnel - f0) / (1.0 - f0)
                errors = (abs(SHAPE[i, j, k] - shape), abs(ALBEDO[i, k] - e), abs(SPLIT_SCALE[i, k] - a),
                          abs(SPLIT_BIAS[i, k] - b))
                worst = max(worst, *errors)
                assert max(errors) < TOLERANCE, (i, j, k, errors)
    print("  rough grid points: within %.1e of the hemisphere integral" % worst)


def test_mirror_row_is_the_fresnel_of_the_view():
    _, mu, z = tool.axes()
    eta = (1.0 + z ** 2) / (1.0 - z ** 2)
    f0 = z ** 4
    # Clamped as the table is: past η ≈ 4 the Fresnel dips below F0 around Brewster's angle.
    expected = np.clip((tool.fresnel_dielectric(mu[None, :], eta[:, None]) - f0[:, None]) / (1.0 - f0[:, None]),
                       0.0, 1.0)
    # Not the first column: at μ = 1e-3 even α = 1e-4 hides part of the lobe below the horizon.
    assert np.abs(SHAPE[0, :, 1:] - expected[:, 1:]).max() < TOLERANCE, np.abs(SHAPE[0] - expected).max()
    assert np.abs(ALBEDO[0, 1:] - 1.0).max() < TOLERANCE, ALBEDO[0]
    # EEVEE's split sum of a mirror: h = n, so (1 − h·v)^5 is the view's own Schlick weight.
    schlick = (1.0 - mu[1:]) ** 5
    assert np.abs(SPLIT_BIAS[0, 1:] - schlick).max() < TOLERANCE, SPLIT_BIAS[0]
    assert np.abs(SPLIT_SCALE[0, 1:] - (1.0 - schlick)).max() < TOLERANCE, SPLIT_SCALE[0]
    # E_avg = 1: F_ms is the hemispherical average of the Fresnel, here by the trapezoid rule.
    cosines = np.linspace(0.0, 1.0, 20001)
    integrand = 2.0 * cosines[None, :] * tool.fresnel_dielectric(cosines[None, :], eta[:, None])
    average = (0.5 * (integrand[:, 1:] + integrand[:, :-1]) * np.diff(cosines)).sum(-1)
    assert np.abs(MULTISCATTER[0] - average).max() < TOLERANCE, (MULTISCATTER[0], average)


def test_every_value_is_finite_and_in_the_unit_interval():
    for name, values in (("s", SHAPE), ("E", ALBEDO), ("F_ms", MULTISCATTER), ("A", SPLIT_SCALE), ("B", SPLIT_BIAS),
                         ("A + B", SPLIT_SCALE + SPLIT_BIAS)):
        assert np.all(np.isfinite(values)) and values.min() >= 0.0 and values.max() <= 1.0, name


def test_the_file_is_what_the_tool_writes():
    with open(tool.OUTPUT, encoding="utf-8") as f:
        assert f.read() == tool.module_text(*tool.tabulate()), "run python3 tools/specular_albedo.py"


if __name__ == "__main__":
    failed = 0
    for test in (test_rough_grid_points_match_the_hemisphere_integral, test_mirror_row_is_the_fresnel_of_the_view,
                 test_every_value_is_finite_and_in_the_unit_interval, test_the_file_is_what_the_tool_writes):
        try:
            test()
            print("PASS", test.__name__)
        except Exception as error:  # noqa: BLE001 (a test's error is its failure)
            failed += 1
            print("FAIL", test.__name__, error)
    sys.exit(1 if failed else 0)
