"""Fit and validation of the grazing study: the far ground's map references and closure sums
(FarGround), aggregate and objective, and the checks: white furnace, finiteness of the formula, the
single-lobe table and its summary. Calls grazing.ggx, grazing.models, grazing.correction and
grazing.texels; a Lighting is passed in."""
import time

import numpy as np

from .correction import corrected_alpha2
from .ggx import WIDENING, view_dir
from .models import ClosureModel, MapModel, lobe_closure
from .texels import BASE_ALPHA, FAR_AZIMUTHS, FAR_THETAS, far_texels


def texel_map(theta_v, normals, lobes, alpha, lighting, azimuths):
    """The map's radiance per azimuth: explicit fine normals, or fine normals drawn from the lobes."""
    per = [dict() for _ in azimuths]
    if normals is not None:
        parts = [(1.0, MapModel(theta_v, None, None, alpha, k=16, normals=normals))]
    else:
        parts = []
        for w, mu, kappa in lobes:
            if kappa >= 1e8:
                parts.append((w, ClosureModel(theta_v, mu, alpha, n=4096)))   # flat: exact
            else:
                parts.append((w, MapModel(theta_v, mu, kappa, alpha, m=400, k=9)))
    for w, model in parts:
        for i, az in enumerate(azimuths):
            for key, val in lighting.radiance(model, np.radians(az)).items():
                per[i][key] = per[i].get(key, 0.0) + w * val
    return per


def texel_closures(theta_v, lobes, alpha, corr, lighting, azimuths):
    per = [dict() for _ in azimuths]
    for w, mu, kappa in lobes:
        model = lobe_closure(theta_v, w, mu, kappa, alpha, corr, n=4096)
        for i, az in enumerate(azimuths):
            for key, val in lighting.radiance(model, np.radians(az)).items():
                per[i][key] = per[i].get(key, 0.0) + val
    return per


class FarGround:
    """The map's radiance for far_texels() × FAR_THETAS × FAR_AZIMUTHS, computed once; `ratios`
    gives closure/map for a correction."""

    def __init__(self, lighting, alpha=BASE_ALPHA, log=print):
        self.lighting, self.alpha = lighting, alpha
        self.texels = far_texels()
        self.ref = {}
        t0 = time.time()
        for name, (normals, lobes) in self.texels:
            for th in FAR_THETAS:
                self.ref[name, th] = texel_map(np.radians(th), normals, lobes, alpha, lighting, FAR_AZIMUTHS)
        log("far-ground references: %.0f s" % (time.time() - t0))

    def evaluate(self, corr):
        """{(texel, θ): [per azimuth {light: (closure, map)}]}"""
        out = {}
        for name, (_, lobes) in self.texels:
            for th in FAR_THETAS:
                cl = texel_closures(np.radians(th), lobes, self.alpha, corr, self.lighting, FAR_AZIMUTHS)
                out[name, th] = [{k: (c[k], r[k]) for k in r} for c, r in zip(cl, self.ref[name, th])]
        return out


def aggregate(result, keys, select=lambda name, th: True):
    """Σ closure / Σ map over the selected (texel, θ) and all azimuths, per light."""
    out = {}
    for k in keys:
        num = sum(d[k][0] for (name, th), per in result.items() if select(name, th) for d in per)
        den = sum(d[k][1] for (name, th), per in result.items() if select(name, th) for d in per)
        out[k] = num / den
    return out


def objective(result, worlds):
    """Mean over (texel, θ) of the mean over worlds of log²(closure/map), azimuths summed, plus the
    far ground's aggregate log² per world."""
    per = []
    for key, lst in result.items():
        for wname in worlds:
            num = sum(d[wname][0] for d in lst)
            den = sum(d[wname][1] for d in lst)
            per.append(np.log(num / den) ** 2)
    agg = aggregate(result, worlds)
    return float(np.mean(per) + np.mean([np.log(agg[w]) ** 2 for w in worlds]))


# ---------------------------------------------------------------------------------------------
# Checks and validation
def furnace_check(corr, thetas=(0, 30, 60, 75, 80, 85, 88), alphas=(0.02, 0.04, 0.2, 0.5)):
    """Flat map (κ → ∞, 1/κ = 0) under a uniform white sky: corrected closure / plain material
    (one GGX about +z with α) and / the map, per view angle (2° above the horizon at 88°)."""
    rows = []
    for a in alphas:
        for th in thetas:
            plain = ClosureModel(np.radians(th), [0, 0, 1.0], a, n=16384).w.mean()
            mp = MapModel(np.radians(th), [0, 0, 1.0], 1e9, a, m=64, k=256).w.mean()
            if corr is None:
                cl = plain
            else:
                cl = lobe_closure(np.radians(th), 1.0, np.array([0, 0, 1.0]), 1e9, a, corr, n=16384).w.mean()
            rows.append((a, th, cl / plain, cl / mp))
    return rows


def finite_check(c, q, ratio_max):
    """Every output of the correction over cos θμ in [-1, 1], 1/κ in [0, 1e6] (the lobe group's
    range: 1/κ ≤ 1/1e-6), α in [0, 1]: finite, positive."""
    cos = np.concatenate([np.linspace(-1, 1, 401), [0.0, -0.0, 1e-9, -1e-9, 1e-3, 1 - 1e-9]])
    ik = np.concatenate([[0.0], np.logspace(-9, 6, 61)])
    al = np.concatenate([[0.0, 1e-6], np.linspace(0.001, 1, 40)])
    C, K, A = np.meshgrid(cos, ik, al, indexing="ij")
    with np.errstate(all="raise"):
        ac2 = corrected_alpha2(C, K, A, c, q)
        aw = np.sqrt(np.minimum(np.maximum(A, 1e-4) ** 2 + WIDENING * K, 1.0))
        ain = np.maximum(np.sqrt(ac2), aw / ratio_max)
        rough_iso = np.sqrt(np.sqrt(ac2))
        rough_aniso = np.sqrt(np.sqrt(aw * ain))
        aniso = np.clip((1 - ain / aw) / 0.9, 0, 1)
    out = dict(alpha_c2=ac2, rough_iso=rough_iso, rough_aniso=rough_aniso, anisotropic=aniso)
    bad = {k: int((~np.isfinite(v) | (v < 0)).sum()) for k, v in out.items()}
    ranges = {k: (float(v.min()), float(v.max())) for k, v in out.items()}
    return bad, ranges


LOBE_THETAS = (0.0, 60.0, 80.0, 85.0, 88.0)
LOBE_KAPPAS = (2.0, 10.0, 50.0, 1e4)
LOBE_ALPHAS = (0.02, 0.04, 0.2, 0.5)
LOBE_TILTS = (("flat", 0.0, 0.0), ("45° toward", 45.0, 0.0), ("45° away", 45.0, 180.0))


def lobe_table(lighting, corrs, azimuth=4.0, log=print):
    """Single vMF lobes: closure/map per light for each correction."""
    rows = []
    t0 = time.time()
    for th in LOBE_THETAS:
        v = view_dir(np.radians(th))
        for kappa in LOBE_KAPPAS:
            for a in LOBE_ALPHAS:
                for tname, tilt, taz in LOBE_TILTS:
                    t, p = np.radians(tilt), np.radians(taz)
                    mu = np.array([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)])
                    ref = lighting.radiance(MapModel(np.radians(th), mu, kappa, a, m=400, k=9), np.radians(azimuth))
                    row = dict(theta=th, kappa=kappa, alpha=a, tilt=tname,
                               theta_mu=float(np.degrees(np.arccos(mu @ v))))
                    for cname, corr in corrs.items():
                        cl = lighting.radiance(lobe_closure(np.radians(th), 1.0, mu, kappa, a, corr, n=4096),
                                               np.radians(azimuth))
                        row[cname] = {k: cl[k] / ref[k] if ref[k] > 0 else float("nan") for k in ref}
                    rows.append(row)
    log("single-lobe table: %.0f s" % (time.time() - t0))
    return rows


def lobe_summary(rows, worlds, names=("none", "iso", "aniso")):
    """Per view angle: median and 90th percentile over (κ, α, lobe, world) of |log(closure/map)|
    as a factor, and the share within 10%; κ ≥ 10 only (κ = 2 is a near-uniform lobe that no GGX
    closure matches at any angle)."""
    lines = ["| θv | " + " | ".join("%s median / p90 factor, within 10%%" % n for n in names) + " |",
             "|---:|" + "---|" * len(names)]
    for th in LOBE_THETAS:
        cells = []
        for n in names:
            e = np.abs(np.log([r[n][w] for r in rows if r["theta"] == th and r["kappa"] >= 10 for w in worlds]))
            cells.append("%.2f / %.2f, %.0f%%" % (np.exp(np.median(e)), np.exp(np.percentile(e, 90)),
                                                  100 * (e < np.log(1.1)).mean()))
        lines.append("| %g | " % th + " | ".join(cells) + " |")
    return "\n".join(lines)

