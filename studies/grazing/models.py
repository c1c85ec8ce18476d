"""What is compared, per lobe: MapModel (the normal map: fine vMF normals, each bent as Cycles bends
it and shaded with its own GGX) and ClosureModel / lobe_closure (the one GGX closure ndfbake draws,
widened, optionally corrected), plus Sum. Calls grazing.ggx only."""
import numpy as np

from .ggx import WIDENING, albedo, basis, bend, ggx_eval, reflect_kernel, sample_vmf, strat2, view_dir


class MapModel:
    """The normal map: fine normals vMF(mu, kappa), each bent (Cycles) and shaded with GGX alpha."""

    def __init__(self, theta_v, mu, kappa, alpha, m=2048, k=32, seed=0, use_bend=True, normals=None):
        rng = np.random.default_rng(seed)
        self.v = view_dir(theta_v)
        self.alpha = alpha
        if normals is None:
            un, pn = strat2(m, rng)
            n = sample_vmf(np.asarray(mu, float) / np.linalg.norm(mu), kappa, un, pn)
        else:
            n = np.asarray(normals, float)
        if use_bend:
            n = bend(np.broadcast_to(self.v, n.shape), n)
        self.n = n
        u1, u2 = strat2(k, rng)
        nv = np.repeat(n, len(u1), 0)
        s1, s2 = rng.random((len(n), 1)), rng.random((len(n), 1))
        u1 = ((u1[None, :] + s1) % 1).ravel()
        u2 = ((u2[None, :] + s2) % 1).ravel()
        vv = np.broadcast_to(self.v, nv.shape)
        l, w = reflect_kernel(vv, nv, np.full(len(nv), alpha), u1, u2)
        cos_nv = np.clip((nv * vv).sum(-1), 0, 1)
        self.l = l
        self.w = np.where(cos_nv > 0, w / albedo(cos_nv, np.full(len(nv), alpha)), 0.0)
        self.neval = n[:: max(1, len(n) // 512)]   # 512 fine normals for the point lights

    def eval(self, ls):
        return ggx_eval(self.neval, self.v, self.alpha, ls).mean(0)


class ClosureModel:
    """One GGX closure about mu (bent as Cycles bends it) with alpha_c, times `weight`; with
    alpha_perp, anisotropic: alpha_c in the plane of incidence, alpha_perp across it."""

    def __init__(self, theta_v, mu, alpha_c, weight=1.0, n=65536, seed=1, use_bend=True, alpha_perp=None):
        rng = np.random.default_rng(seed)
        self.v = view_dir(theta_v)
        self.alpha = float(np.clip(alpha_c, 1e-4, 1.0))
        self.alpha_perp = self.alpha if alpha_perp is None else float(np.clip(alpha_perp, 1e-4, 1.0))
        m = np.asarray(mu, float) / np.linalg.norm(mu)
        if use_bend:
            m = bend(self.v[None], m[None])[0]
        self.mu, self.weight = m, weight
        tx = self.v - (self.v @ m) * m
        if np.linalg.norm(tx) < 1e-9:
            tx = basis(m[None])[0][0]
        tx = tx / np.linalg.norm(tx)
        self.frame = (tx[None], np.cross(m, tx)[None])
        u1, u2 = strat2(n, rng)
        nv = np.broadcast_to(m, (len(u1), 3))
        vv = np.broadcast_to(self.v, nv.shape)
        fr = (np.broadcast_to(self.frame[0], nv.shape), np.broadcast_to(self.frame[1], nv.shape))
        al = np.broadcast_to(np.array([self.alpha, self.alpha_perp]), (len(u1), 2))
        l, w = reflect_kernel(vv, nv, al, u1, u2, frame=fr)
        cnv = max(float(m @ self.v), 0.0)
        e = albedo(np.array([cnv]), np.array([np.sqrt(self.alpha * self.alpha_perp)]))[0]
        self.l = l
        self.w = w * weight / e if cnv > 0 else 0 * w

    def eval(self, ls):
        return self.weight * ggx_eval(self.mu[None], self.v, (self.alpha, self.alpha_perp), ls, frame=self.frame)[0]


def rotate_in_incidence(mu, v, delta):
    """Turns mu by delta radians about the axis normal to the plane of mu and v (+: toward v);
    where mu ∥ v it is left as is."""
    axis = np.cross(mu, v)
    ln = np.linalg.norm(axis)
    if ln < 1e-9 or delta == 0:
        return mu
    axis /= ln
    return mu * np.cos(delta) + np.cross(axis, mu) * np.sin(delta)


def lobe_closure(theta_v, weight, mu, kappa, alpha, corr=None, n=16384, seed=1):
    """ClosureModel for one lobe with ndfbake's widening and optionally a correction
    corr(cos_mu_v, cos_g_v, inv_kappa, alpha) -> (weight factor, alpha_c, tilt toward v)."""
    v = view_dir(theta_v)
    inv_kappa = 0.0 if kappa >= 1e8 else 1.0 / kappa
    alpha_w = np.sqrt(min(alpha * alpha + WIDENING * inv_kappa, 1.0))
    wf, ac, tilt = 1.0, alpha_w, 0.0
    if corr is not None:
        out = corr(float(mu @ v), float(v[2]), inv_kappa, alpha)
        wf, ac, tilt = out[:3]
        perp = out[3] if len(out) > 3 else None
    else:
        perp = None
    m = rotate_in_incidence(mu, v, tilt)
    return ClosureModel(theta_v, m, ac, weight=weight * wf, n=n, seed=seed, alpha_perp=perp)


class Sum:
    def __init__(self, models):
        self.models = models

    def radiance(self, lighting, azimuth):
        tot = {}
        for m in self.models:
            for k, val in lighting.radiance(m, azimuth).items():
                tot[k] = tot.get(k, 0.0) + val
        return tot
