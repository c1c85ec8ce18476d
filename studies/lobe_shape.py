"""What a texel's lobes reflect against what its fine normals reflect, light direction by light
direction (docs/rendering.md, "The lobes' shape under a sun"):

    python3 studies/lobe_shape.py [--library build/native/libndfbake.so]

A texel of a normal map is fitted by the library (ndfb_fit with its defaults, at most 8 lobes; 4
for the cosine bumps) and these are evaluated for one view at every light direction of the upper
hemisphere (2° × 3° grid), as the studies/grazing study models them (Multiscatter GGX, F = 1,
Cycles' normal bending, no masking between fine normals):
- map: the texel's fine normals, each shading with its own GGX of the material's roughness;
- vMF: the fitted lobes exactly, fine normals drawn from each vMF (what the fit stands for);
- GGX W: one GGX closure per lobe with α'² = α² + W/κ (W = 1.5 is the add-on's, brdf.h
  kGgxVmfWidening; 1.0 and 0.75 narrower), not narrowed: what EEVEE Next draws;
- Cycles: the same with W = 1.5, narrowed toward grazing views with Cycles' C = 4
  (grazing.correction.corrected_alpha2, nodes.default_grazing_narrowing): what Cycles draws;
- Beckmann: one Beckmann closure per lobe with m'² = α² + 2/κ (Han 2007, eq. 21), single scatter.
Printed per texel and view: each one's reflectance (∫ f cos dω) and, split by how strongly the map
itself reflects a light (its core: above 10% of its peak; shoulder 1-10%; tail 0.1-1%; far tail
below 0.1%), each one's integral there over the map's. Under an environment the parts add up and
the differences mostly cancel; under a sun, a pixel sees one light direction. With Cycles' bending
the map's core at low views is a spike of light from just above the horizon (the fine normals that
face away from the view, all bent to reflect it there), which no closure draws.

Texels: the demo's fbm (seed 7, roughness 0.15: "Silver Hammered") and bumps (seed 8, 0.2: "Steel
Bumps"), 64², at level 3 (8×8 fine normals) and 6 (the whole map); one vMF lobe (κ = 100, normal
to the surface, roughness 0.15) with fine normals drawn from it, so the lobe is exact and only the
closure's shape differs; and a 128² map of cosine bumps, n ∝ (−0.6 cos 16πx, −0.6 cos 16πy, 1),
roughness 0.2, at level 3 (half a period) and 7 (whole), whose normals pile up along the edges of
a square 31° wide, fitted with the Bake panel's default 4 lobes. Calls the library through the
add-on's ctypes module (native.py, plus the pyramid calls it does not make) and studies/grazing
(numpy). 15 s on a 2-core machine; its pieces are checked by tests/tools/test_lobe_shape.py."""
import argparse
import ctypes
import math
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "..", "addon"))  # ndfbake.core needs no bpy

from ndfbake.core import native, native_abi  # noqa: E402
from grazing.correction import corrected_alpha2  # noqa: E402
from grazing.ggx import WIDENING, basis, bend, ggx_eval, sample_vmf, strat2  # noqa: E402
from grazing.texels import kappa_of  # noqa: E402

MAX_LOBES = 8                 # what the demo bakes (demo_scene.MAX_LOBES), the library's limit
ARTIST_LOBES = 4              # the Bake panel's default Maximum Lobes
WIDENINGS = (WIDENING, 1.0, 0.75)  # the add-on's, then narrower
CYCLES_NARROWING = 4.0        # nodes.CYCLES_GRAZING_NARROWING: what Cycles draws by default
BUCKETS = ((0.1, np.inf, "core"), (0.01, 0.1, "shoulder"), (0.001, 0.01, "tail"), (0.0, 0.001, "far tail"))
VIEWS = (30.0, 10.0)          # degrees above the surface


# ---- the library ----------------------------------------------------------------------------

def fitted_levels(library, normals, roughness, max_lobes):
    """Every level's lobes of `normals` fitted with the library's defaults: [level] -> (H, W, slots,
    4) of ndfb_pyramid_read_lobe's RGBA. Declares the pyramid calls, which the add-on does not make."""
    lib, vp, u32, floats = library.lib, ctypes.c_void_p, ctypes.c_uint32, ctypes.POINTER(ctypes.c_float)
    for name, restype, argtypes in (
            ("ndfb_fit", ctypes.c_int, [vp, vp, ctypes.POINTER(native_abi.FitOptions), native_abi.PROGRESS_FN, vp,
                                        ctypes.POINTER(vp)]),
            ("ndfb_pyramid_destroy", None, [vp]),
            ("ndfb_pyramid_level_size", ctypes.c_int, [vp, u32, ctypes.POINTER(u32), ctypes.POINTER(u32)]),
            ("ndfb_pyramid_read_lobe", ctypes.c_int, [vp, u32, u32, floats, ctypes.c_size_t])):
        getattr(lib, name).restype, getattr(lib, name).argtypes = restype, argtypes
    height, width, _ = normals.shape
    options = library.init_options(native_abi.FitOptions, lib.ndfb_fit_options_init)
    options.max_lobes, options.brdf_parameter = max_lobes, roughness
    pyramid, levels = vp(), []
    with library.context() as context, context.normal_map(normals, width, height, 3, True) as normal_map:
        context.check(lib.ndfb_fit(context.handle, normal_map.handle, ctypes.byref(options), native_abi.PROGRESS_FN(),
                                   None, ctypes.byref(pyramid)))
        w, h = u32(), u32()
        while lib.ndfb_pyramid_level_size(pyramid, len(levels), ctypes.byref(w), ctypes.byref(h)) == native_abi.OK:
            slots = [np.zeros((h.value, w.value, 4), np.float32) for _ in range(max_lobes)]
            for j, rgba in enumerate(slots):
                context.check(lib.ndfb_pyramid_read_lobe(pyramid, len(levels), j, rgba.ctypes.data_as(floats),
                                                         rgba.size))
            levels.append(np.stack(slots, 2))
        lib.ndfb_pyramid_destroy(pyramid)
    return levels


def texel_lobes(level, y=0, x=0):
    """[(weight, μ, κ)] of one texel: R = |r|, κ = (3R − R³)/(1 − R²) (ndfbake.h)."""
    lobes = []
    for weight, *moment in level[y, x]:
        if weight <= 1e-6:
            continue
        r = np.array(moment, float) / weight
        lobes.append((float(weight), r / np.linalg.norm(r), float(kappa_of(np.linalg.norm(r)))))
    return lobes


# ---- what is evaluated ----------------------------------------------------------------------

def beckmann_eval(n, v, m, ls):
    """f·(n·l) of a single-scatter Beckmann BSDF (F = 1) about normals n[M,3], slope RMS m, at
    lights ls[S,3] (Walter et al. 2007, §5.1: D and the rational fit of G1, here as Λ = 1/G1 − 1)."""
    t, b = basis(n)
    vloc = np.stack([t @ v, b @ v, n @ v], -1)
    lloc = np.stack([(ls @ t.T).T, (ls @ b.T).T, (ls @ n.T).T], -1)
    h = lloc + vloc[:, None, :]
    h /= np.linalg.norm(h, axis=-1, keepdims=True)
    c2 = np.clip(h[..., 2], 1e-6, 1.0) ** 2
    d = np.exp(-(1 - c2) / (c2 * m * m)) / (np.pi * m * m * c2 * c2)

    def smith_lambda(cos_theta):
        c = np.clip(cos_theta, 1e-6, 1.0)
        a = c / (m * np.sqrt(1 - c * c) + 1e-12)
        return np.where(a < 1.6, (1 - 1.259 * a + 0.396 * a * a) / (3.535 * a + 2.181 * a * a), 0.0)

    g2 = 1 / (1 + smith_lambda(vloc[:, 2])[:, None] + smith_lambda(lloc[..., 2]))
    f = d * g2 / (4 * np.clip(vloc[:, 2], 1e-7, 1.0)[:, None])
    return np.where((lloc[..., 2] > 0) & (ls[None, :, 2] > 0) & (h[..., 2] > 0), f, 0.0)


def map_response(normals, v, alpha, ls, most=4096):
    bent = bend(np.broadcast_to(v, normals.shape), normals)
    return ggx_eval(bent[::max(1, len(bent) // most)], v, alpha, ls).mean(0)


def vmf_response(lobes, v, alpha, ls, per_lobe=4096):
    rng = np.random.default_rng(0)
    total = 0.0
    for weight, mu, kappa in lobes:
        u, phi = strat2(per_lobe, rng)
        total = total + weight * map_response(sample_vmf(mu, min(kappa, 1e7), u, phi), v, alpha, ls)
    return total


def _closures(lobes, v, ls, evaluate, alpha_of):
    """Σ weight · evaluate(μ bent as Cycles bends it, v, alpha_of(μ, κ), ls) over the lobes."""
    total = 0.0
    for weight, mu, kappa in lobes:
        total = total + weight * evaluate(bend(v[None], mu[None]), v, alpha_of(mu, kappa), ls)[0]
    return total


def ggx_closures(lobes, v, alpha, ls, widening=WIDENING):
    """One GGX closure per lobe, α'² = min(α² + widening/κ, 1): EEVEE Next's with the add-on's."""
    return _closures(lobes, v, ls, ggx_eval, lambda mu, kappa: math.sqrt(min(alpha ** 2 + widening / kappa, 1)))


def cycles_closures(lobes, v, alpha, ls):
    """Cycles' lobes: the add-on's widening narrowed toward grazing views with CYCLES_NARROWING."""
    return _closures(lobes, v, ls, ggx_eval, lambda mu, kappa: math.sqrt(float(
        corrected_alpha2(float(mu @ v), 1 / kappa, alpha, CYCLES_NARROWING))))


def beckmann_closures(lobes, v, alpha, ls):
    """One Beckmann closure per lobe, m'² = min(α² + 2/κ, 1)."""
    return _closures(lobes, v, ls, beckmann_eval, lambda mu, kappa: math.sqrt(min(alpha ** 2 + 2 / kappa, 1)))


def light_grid():
    elevation, azimuth = np.meshgrid(np.radians(np.arange(1, 90, 2.0)), np.radians(np.arange(0, 360, 3.0)))
    ls = np.stack([np.cos(elevation) * np.cos(azimuth), np.cos(elevation) * np.sin(azimuth), np.sin(elevation)], -1)
    return ls.reshape(-1, 3), (np.cos(elevation) * np.radians(2) * np.radians(3)).ravel()


def compare(name, normals, lobes, alpha, ls, dw):
    columns = {"vMF": lambda v: vmf_response(lobes, v, alpha, ls)}
    columns |= {"GGX %.2f" % w: (lambda v, w=w: ggx_closures(lobes, v, alpha, ls, w)) for w in WIDENINGS}
    columns["Cycles"] = lambda v: cycles_closures(lobes, v, alpha, ls)
    columns["Beckmann"] = lambda v: beckmann_closures(lobes, v, alpha, ls)
    for up in VIEWS:
        v = np.array([0.0, -math.cos(math.radians(up)), math.sin(math.radians(up))])
        reference = map_response(normals, v, alpha, ls)
        values = {key: fn(v) for key, fn in columns.items()}
        print("%s, %d lobes, view %.0f° up: reflectance map %.3f, %s" % (
            name, len(lobes), up, (reference * dw).sum(),
            ", ".join("%s %.3f" % (key, (val * dw).sum()) for key, val in values.items())))
        peak = reference.max()
        for low, high, label in BUCKETS:
            inside = (reference >= low * peak) & (reference < high * peak)
            part = (reference * dw)[inside].sum()
            print("  %-9s map %.4f | %s" % (label, part, " | ".join(
                "%s %5.2fx" % (key, (val * dw)[inside].sum() / part) for key, val in values.items())))


def cosine_bumps(size=128, periods=8, amplitude=0.6):
    y, x = np.mgrid[0:size, 0:size] / size
    n = np.stack([-amplitude * np.cos(2 * np.pi * periods * x), -amplitude * np.cos(2 * np.pi * periods * y),
                  np.ones((size, size))], -1)
    return (n / np.linalg.norm(n, axis=-1, keepdims=True)).astype(np.float32)


def main():
    parser = argparse.ArgumentParser(prog="studies/lobe_shape.py")
    parser.add_argument("--library", default=os.path.join(HERE, "..", "build", "native", "libndfbake.so"))
    args = parser.parse_args()
    library = native.Library(os.path.abspath(args.library))
    ls, dw = light_grid()
    for pattern, seed, roughness in (("fbm", 7, 0.15), ("bumps", 8, 0.2)):
        with library.context() as context, context.synthesize(pattern, 64, 64, seed) as normal_map:
            normals = normal_map.read()
        levels = fitted_levels(library, normals, roughness, MAX_LOBES)
        for level in (3, 6):
            side = 1 << level
            compare("%s-%d level %d (%d² fine normals)" % (pattern, seed, level, side),
                    normals[:side, :side].reshape(-1, 3).astype(float), texel_lobes(levels[level]),
                    roughness * roughness, ls, dw)
    # One vMF lobe known exactly (no fit): the closure's shape against the vMF's alone.
    mu, kappa = np.array([0.0, 0.0, 1.0]), 100.0
    u, phi = strat2(64 * 64, np.random.default_rng(1))
    compare("one vMF lobe, κ %.0f, roughness 0.15 (64² fine normals drawn from it)" % kappa,
            sample_vmf(mu, kappa, u, phi), [(1.0, mu, kappa)], 0.15 ** 2, ls, dw)
    normals = cosine_bumps()
    levels = fitted_levels(library, normals, 0.2, ARTIST_LOBES)
    for level in (3, 7):
        side = 1 << level
        compare("cosine bumps level %d (%d² fine normals)" % (level, side),
                normals[:side, :side].reshape(-1, 3).astype(float), texel_lobes(levels[level]), 0.04, ls, dw)


if __name__ == "__main__":
    main()
