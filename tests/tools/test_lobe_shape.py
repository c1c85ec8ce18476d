"""studies/lobe_shape.py's pieces against what they must give where the answer is known:

- a flat map: the library fits one lobe of κ → ∞ (decoded from the lobe texture as the add-on
  decodes it), so the exact vMF and the GGX closures, widened and narrowed, reflect what the map
  does;
- a map whose normals are drawn from one vMF: the one-lobe fit gives back its direction and κ, and
  the exact-vMF column reflects what the map does (the fine normals are such draws);
- the Beckmann closure conserves energy where it must (head-on, smooth: reflectance within 2% of
  1 on the tool's grid of lights) and never exceeds 1.

    python3 tests/tools/test_lobe_shape.py [LIBRARY]   (default build/native/libndfbake.so)"""
import math
import os
import sys

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "studies"))

import lobe_shape as tool  # noqa: E402
from grazing.ggx import sample_vmf, strat2  # noqa: E402

ALPHA = 0.04   # roughness 0.2
VIEW = np.array([0.0, -math.cos(math.radians(30)), math.sin(math.radians(30))])


def reflectance(values, dw):
    return float((values * dw).sum())


def main():
    library_path = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "build", "native", "libndfbake.so")
    library = tool.native.Library(os.path.abspath(library_path))
    ls, dw = tool.light_grid()
    failures = []

    def expect(ok, message):
        print("%s %s" % ("ok  " if ok else "FAIL", message), flush=True)
        if not ok:
            failures.append(message)

    flat = np.zeros((8, 8, 3), np.float32)
    flat[..., 2] = 1.0
    lobes = tool.texel_lobes(tool.fitted_levels(library, flat, 0.2, 4)[-1])
    expect(len(lobes) == 1 and lobes[0][2] > 1e5, "flat map: one lobe of κ > 1e5, got %s"
           % [(round(w, 3), round(k)) for w, _, k in lobes])
    reference = reflectance(tool.map_response(flat.reshape(-1, 3).astype(float), VIEW, ALPHA, ls), dw)
    columns = {"vMF": tool.vmf_response(lobes, VIEW, ALPHA, ls),
               "GGX 1.5": tool.ggx_closures(lobes, VIEW, ALPHA, ls),
               "Cycles": tool.cycles_closures(lobes, VIEW, ALPHA, ls)}
    for name, values in columns.items():
        got = reflectance(values, dw)
        expect(abs(got / reference - 1) < 1e-3, "flat map, %s: reflectance %.5f against the map's %.5f"
               % (name, got, reference))

    mu = np.array([math.sin(math.radians(20)), 0.0, math.cos(math.radians(20))])
    kappa = 50.0
    u, phi = strat2(64 * 64, np.random.default_rng(3))
    drawn = sample_vmf(mu, kappa, u, phi).reshape(64, 64, 3)
    lobes = tool.texel_lobes(tool.fitted_levels(library, drawn, 0.2, 1)[-1])
    _, fitted_mu, fitted_kappa = lobes[0]
    angle = math.degrees(math.acos(min(1.0, float(fitted_mu @ mu))))
    expect(len(lobes) == 1 and angle < 1.0 and abs(fitted_kappa / kappa - 1) < 0.1,
           "vMF-drawn map: one lobe %.2f° from the drawn direction, κ %.1f against %.0f" % (angle, fitted_kappa, kappa))
    reference = reflectance(tool.map_response(drawn.reshape(-1, 3).astype(float), VIEW, ALPHA, ls), dw)
    got = reflectance(tool.vmf_response(lobes, VIEW, ALPHA, ls), dw)
    expect(abs(got / reference - 1) < 0.02, "vMF-drawn map, exact vMF: reflectance %.4f against the map's %.4f"
           % (got, reference))

    up = np.array([[0.0, 0.0, 1.0]])
    head_on = np.array([0.0, 0.0, 1.0])
    got = reflectance(tool.beckmann_eval(up, head_on, 0.1, ls)[0], dw)
    expect(abs(got - 1) < 0.02, "Beckmann m 0.1 head-on: reflectance %.4f within 2%% of 1" % got)
    for m, view_up in ((0.3, 90.0), (0.3, 10.0)):
        view = np.array([0.0, -math.cos(math.radians(view_up)), math.sin(math.radians(view_up))])
        got = reflectance(tool.beckmann_eval(up, view, m, ls)[0], dw)
        expect(got <= 1.0 + 0.01, "Beckmann m %.1f, view %.0f° up: reflectance %.4f ≤ 1" % (m, view_up, got))

    print("%d failed" % len(failures) if failures else "all passed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
