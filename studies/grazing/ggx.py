"""GGX and vMF math of the grazing study: Smith Λ, frames, visible-normal sampling, the sampled
reflection kernel, the single-scatter albedo table, Cycles' ensure_valid_specular_reflection
(bend), vMF sampling, and ggx_eval (the BSDF at point lights). Owns WIDENING (ndfbake's
kGgxVmfWidening). Calls numpy only; the base layer of studies/grazing/."""
import numpy as np

WIDENING = 1.5                 # native/src/math/brdf.h kGgxVmfWidening


# ---------------------------------------------------------------------------------------------
# GGX pieces
def smith_lambda(alpha2, c):
    c = np.clip(c, 1e-7, 1.0)
    return 0.5 * (np.sqrt(1.0 + alpha2 * (1.0 - c * c) / (c * c)) - 1.0)


def basis(n):
    """Orthonormal (t, b) for unit vectors n[..., 3] (Duff et al. 2017)."""
    s = np.where(n[..., 2] >= 0, 1.0, -1.0)
    a = -1.0 / (s + n[..., 2])
    b = n[..., 0] * n[..., 1] * a
    t = np.stack([1 + s * n[..., 0] ** 2 * a, s * b, -s * n[..., 0]], -1)
    bb = np.stack([b, s + n[..., 1] ** 2 * a, -n[..., 1]], -1)
    return t, bb


def sample_vndf(vl, alpha, u1, u2):
    """Heitz 2018 visible-normal sampling of isotropic GGX; vl: local view (z = normal)."""
    alpha = np.asarray(alpha)
    if alpha.ndim == vl.ndim - 1:
        alpha = np.stack([alpha, alpha], -1)   # isotropic
    vh = np.concatenate([alpha * vl[..., :2], vl[..., 2:]], -1)
    vh = vh / np.linalg.norm(vh, axis=-1, keepdims=True)
    l2 = vh[..., 0] ** 2 + vh[..., 1] ** 2
    inv = np.where(l2 > 1e-14, 1.0 / np.sqrt(np.maximum(l2, 1e-30)), 0.0)
    t1v = np.stack([-vh[..., 1] * inv, vh[..., 0] * inv, 0 * l2], -1)
    t1v[..., 0] = np.where(l2 > 1e-14, t1v[..., 0], 1.0)
    t2v = np.cross(vh, t1v)
    r = np.sqrt(u1)
    phi = 2 * np.pi * u2
    p1 = r * np.cos(phi)
    s = 0.5 * (1 + vh[..., 2])
    p2 = (1 - s) * np.sqrt(np.maximum(1 - p1 * p1, 0)) + s * r * np.sin(phi)
    p3 = np.sqrt(np.maximum(0.0, 1 - p1 * p1 - p2 * p2))
    nh = p1[..., None] * t1v + p2[..., None] * t2v + p3[..., None] * vh
    ne = np.concatenate([alpha * nh[..., :2], np.maximum(1e-7, nh[..., 2:])], -1)
    return ne / np.linalg.norm(ne, axis=-1, keepdims=True)


def strat2(n, rng):
    """n = k*k jittered-stratified points in [0,1)^2."""
    k = int(round(np.sqrt(n)))
    i, j = np.meshgrid(np.arange(k), np.arange(k), indexing="ij")
    return ((i.ravel() + rng.random(k * k)) / k, (j.ravel() + rng.random(k * k)) / k)


def lambda_local(alpha, d):
    """Smith Λ for local directions d[..., 3]; alpha isotropic [...] or (αx, αy) [..., 2]
    (Heitz 2014, eq. 86 with the projected roughness of eq. 80)."""
    alpha = np.asarray(alpha)
    if alpha.ndim == d.ndim:
        xy2 = np.maximum(d[..., 0] ** 2 + d[..., 1] ** 2, 1e-30)
        a2 = (alpha[..., 0] ** 2 * d[..., 0] ** 2 + alpha[..., 1] ** 2 * d[..., 1] ** 2) / xy2
    else:
        a2 = alpha ** 2
    return smith_lambda(a2, np.clip(d[..., 2], 1e-7, 1))


def reflect_kernel(v, n, alpha, u1, u2, frame=None):
    """GGX sampled about normals n[..., 3] for view v[..., 3] (same shape); returns light dirs l
    and weights f·(n·l)/pdf = G2/G1(v) (F = 1), 0 where l is below n's or Ng's horizon.
    alpha: isotropic [...] or (αx, αy) [..., 2] along frame = (t, b)."""
    t, b = basis(n) if frame is None else frame
    vl = np.stack([(v * t).sum(-1), (v * b).sum(-1), (v * n).sum(-1)], -1)
    h = sample_vndf(vl, alpha, u1, u2)
    hw = h[..., :1] * t + h[..., 1:2] * b + h[..., 2:] * n
    l = 2 * (v * hw).sum(-1, keepdims=True) * hw - v
    ll = np.stack([(l * t).sum(-1), (l * b).sum(-1), (l * n).sum(-1)], -1)
    lv = lambda_local(alpha, vl)
    w = (1 + lv) / (1 + lv + lambda_local(alpha, np.concatenate([ll[..., :2], np.maximum(ll[..., 2:], 1e-7)], -1)))
    w = np.where((ll[..., 2] > 0) & (l[..., 2] > 0), w, 0.0)
    return l, w


_E_TABLE = None
E_MU = np.linspace(0.0, 1.0, 33)
E_ROUGH = np.linspace(0.0, 1.0, 33)    # sqrt(α), as Cycles' table


def albedo_table():
    """Single-scatter albedo E(μ, r), r = sqrt(α), of GGX with F = 1 (no geometric horizon)."""
    global _E_TABLE
    if _E_TABLE is not None:
        return _E_TABLE
    rng = np.random.default_rng(7)
    u1, u2 = strat2(4096, rng)
    tab = np.zeros((len(E_MU), len(E_ROUGH)))
    for i, mu in enumerate(E_MU):
        mu = max(mu, 1e-3)
        v = np.array([np.sqrt(1 - mu * mu), 0.0, mu])
        for j, r in enumerate(E_ROUGH):
            a = max(r * r, 1e-4)
            vv = np.broadcast_to(v, (len(u1), 3))
            n = np.broadcast_to(np.array([0, 0, 1.0]), (len(u1), 3))
            _, w = reflect_kernel(vv, n, np.full(len(u1), a), u1, u2)
            tab[i, j] = w.mean()
    _E_TABLE = tab
    return tab


def albedo(mu, alpha):
    tab = albedo_table()
    x = np.clip(mu, 0, 1) * (len(E_MU) - 1)
    y = np.clip(np.sqrt(alpha), 0, 1) * (len(E_ROUGH) - 1)
    x0 = np.minimum(x.astype(int), len(E_MU) - 2)
    y0 = np.minimum(y.astype(int), len(E_ROUGH) - 2)
    fx, fy = x - x0, y - y0
    return ((tab[x0, y0] * (1 - fx) + tab[x0 + 1, y0] * fx) * (1 - fy)
            + (tab[x0, y0 + 1] * (1 - fx) + tab[x0 + 1, y0 + 1] * fx) * fy)


def bend(ng_v, n):
    """Cycles' ensure_valid_specular_reflection(Ng = +z, I = v, N = n) (bsdf_util.h)."""
    v = ng_v
    r = 2 * (n * v).sum(-1, keepdims=True) * n - v
    iz = v[..., 2]
    thr = np.minimum(0.9 * iz, 0.01)
    ok = r[..., 2] >= thr
    x = n.copy()
    x[..., 2] = 0
    ln = np.linalg.norm(x, axis=-1, keepdims=True)
    x = np.where(ln > 1e-12, x / np.maximum(ln, 1e-30), n)
    ix = (v * x).sum(-1)
    a = ix * ix + iz * iz
    b = 2 * (a + iz * thr)
    c = (thr + iz) ** 2
    d = np.sqrt(np.maximum(b * b - 4 * a * c, 0))
    nz2 = np.where(ix < 0, 0.25 * (b + d) / a, 0.25 * (b - d) / a)
    nb = np.sqrt(np.maximum(1 - nz2, 0))[..., None] * x + np.sqrt(np.maximum(nz2, 0))[..., None] * np.array([0, 0, 1.0])
    return np.where(ok[..., None], n, nb)


def sample_vmf(mu, kappa, u, phi):
    """Directions vMF(mu, kappa) from stratified (u, phi) in [0,1)^2 (Wood 1994 inversion)."""
    w = 1 + np.log(u + (1 - u) * np.exp(-2 * kappa)) / kappa if kappa < 1e7 else np.ones_like(u)
    w = np.clip(w, -1, 1)
    s = np.sqrt(np.maximum(1 - w * w, 0))
    t, b = basis(mu[None, :])
    a = 2 * np.pi * phi
    return (s * np.cos(a))[:, None] * t + (s * np.sin(a))[:, None] * b + w[:, None] * mu[None, :]


def view_dir(theta_v):
    return np.array([np.sin(theta_v), 0.0, np.cos(theta_v)])


def kernel_map(theta_v, mu, kappa, alpha, m=1024, k=16, seed=0, use_bend=True):
    """The normal map's kernel: light dirs l[N,3], weights w[N] (radiance = mean(w L(l)))."""
    rng = np.random.default_rng(seed)
    v = view_dir(theta_v)
    un, pn = strat2(m, rng)
    n = sample_vmf(mu, kappa, un, pn)
    if use_bend:
        n = bend(np.broadcast_to(v, n.shape), n)
    nv = np.repeat(n, k, 0)
    u1, u2 = strat2(k, rng)
    # rotate the per-normal stratification by a per-normal random shift (Cranley-Patterson)
    s1, s2 = rng.random((m, 1)), rng.random((m, 1))
    u1 = ((u1[None, :] + s1) % 1).ravel()
    u2 = ((u2[None, :] + s2) % 1).ravel()
    vv = np.broadcast_to(v, nv.shape)
    l, w = reflect_kernel(vv, nv, np.full(len(nv), alpha), u1, u2)
    cos_nv = np.clip((nv * vv).sum(-1), 0, 1)
    w = np.where(cos_nv > 0, w / albedo(cos_nv, np.full(len(nv), alpha)), 0.0)
    return l, w


def kernel_closure(theta_v, mu, alpha_c, n=4096, seed=1, use_bend=True):
    rng = np.random.default_rng(seed)
    v = view_dir(theta_v)
    m = mu / np.linalg.norm(mu)
    if use_bend:
        m = bend(v[None], m[None])[0]
    u1, u2 = strat2(n, rng)
    nv = np.broadcast_to(m, (len(u1), 3))
    vv = np.broadcast_to(v, nv.shape)
    l, w = reflect_kernel(vv, nv, np.full(len(u1), alpha_c), u1, u2)
    cnv = max(float(m @ v), 0.0)
    w = w / albedo(np.array([cnv]), np.array([alpha_c]))[0] if cnv > 0 else 0 * w
    return l, w

def ggx_eval(n, v, alpha, ls, frame=None):
    """f·(n·l)·[l·Ng > 0] of Multiscatter GGX (F = 1) about normals n[M,3] for view v[3] at light
    directions ls[S,3]; returns [M,S]. alpha scalar, or (αx, αy) with frame = (t[M,3], b[M,3])."""
    if frame is None:
        t, b = basis(n)
        ax = ay = float(alpha)
    else:
        t, b = frame
        ax, ay = alpha
    vloc = np.stack([t @ v, b @ v, n @ v], -1)                  # [M,3]
    lloc = np.stack([(ls @ t.T).T, (ls @ b.T).T, (ls @ n.T).T], -1)   # [M,S,3]
    h = lloc + vloc[:, None, :]
    h = h / np.linalg.norm(h, axis=-1, keepdims=True)
    q = (h[..., 0] / ax) ** 2 + (h[..., 1] / ay) ** 2 + h[..., 2] ** 2
    d = 1.0 / (np.pi * ax * ay * q * q)
    al = np.array([ax, ay])
    g2 = 1.0 / (1 + lambda_local(np.broadcast_to(al, vloc.shape[:-1] + (2,)), vloc)[:, None]
                + lambda_local(np.broadcast_to(al, lloc.shape[:-1] + (2,)), np.concatenate(
                    [lloc[..., :2], np.maximum(lloc[..., 2:], 1e-7)], -1)))
    cv = np.clip(vloc[:, 2], 0.0, 1.0)[:, None]
    e = albedo(cv, np.full(cv.shape, np.sqrt(ax * ay)))
    f = d * g2 / (4 * np.maximum(cv, 1e-7) * e)
    ok = (lloc[..., 2] > 0) & (ls[None, :, 2] > 0) & (cv > 0) & (h[..., 2] > 0)
    return np.where(ok, f, 0.0)
