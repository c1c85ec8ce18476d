"""The far ground of the demo, as texels of lobes: the bump lattice split into lobes as ndfbake does,
the rings of vMF lobes, and the evaluation set (view angles FAR_THETAS, sun azimuths FAR_AZIMUTHS,
the material's BASE_ALPHA). Calls numpy only."""
import numpy as np


# ---------------------------------------------------------------------------------------------
# The demo's ground texel: a lattice of cos² bumps (native/src/synth/patterns.cpp bumps_heights:
# radius 0.4 of the period, 45° steepest slope), seen at a coarse MIP level where one texel holds
# whole bump periods, its NDF split into lobes as ndfbake does (here: the flat half as one lobe
# about +Z, the ring of bump normals in azimuth sectors, each a vMF with ndfbake's
# κ = (3R − R³)/(1 − R²)).
BUMP_RADIUS = 0.4
BUMP_MAX_TILT = np.radians(45.0)


def bump_normals(k=96):
    x = (np.arange(k) + 0.5) / k - 0.5
    dx, dy = np.meshgrid(x, x)
    d = np.hypot(dx, dy)
    amp = 2 * BUMP_RADIUS * np.tan(BUMP_MAX_TILT) / np.pi
    slope = np.where(d < BUMP_RADIUS, -amp * 0.5 * np.pi / BUMP_RADIUS * np.sin(np.pi * d / BUMP_RADIUS), 0.0)
    gx = slope * dx / np.maximum(d, 1e-12)
    gy = slope * dy / np.maximum(d, 1e-12)
    n = np.stack([-gx, -gy, np.ones_like(gx)], -1).reshape(-1, 3)
    return n / np.linalg.norm(n, axis=-1, keepdims=True)


def kappa_of(rbar):
    rbar = np.clip(rbar, 1e-6, 1 - 1e-9)
    return (3 * rbar - rbar ** 3) / (1 - rbar * rbar)


def bump_lobes(rotation=0.0, sectors=7):
    """[(weight, mu, kappa)], the bump texel's NDF split into 1 + `sectors` lobes; `rotation`
    turns the lattice about z (radians)."""
    n = bump_normals()
    c, s = np.cos(rotation), np.sin(rotation)
    n = n @ np.array([[c, s, 0], [-s, c, 0], [0, 0, 1.0]])
    flat = n[:, 2] > 1 - 1e-9
    lobes = [(flat.mean(), np.array([0, 0, 1.0]), 1e9)]
    az = (np.arctan2(n[:, 1], n[:, 0]) - rotation) % (2 * np.pi)
    sector = np.minimum((az / (2 * np.pi) * sectors).astype(int), sectors - 1)
    for j in range(sectors):
        sel = (~flat) & (sector == j)
        r = n[sel].mean(0)
        lobes.append((sel.mean(), r / np.linalg.norm(r), float(kappa_of(np.linalg.norm(r)))))
    return n, lobes



def ring_lobes(tilt_deg, kappa, nring=8, offset=0.25, flat=0.5):
    """A texel of `flat` weight of flat normals plus a ring of nring vMF(κ) lobes tilted tilt_deg."""
    lobes = [(flat, np.array([0, 0, 1.0]), 1e9)]
    t = np.radians(tilt_deg)
    for j in range(nring):
        ph = 2 * np.pi * (j + offset) / nring
        lobes.append(((1 - flat) / nring, np.array([np.sin(t) * np.cos(ph), np.sin(t) * np.sin(ph), np.cos(t)]),
                      kappa))
    return lobes



# ---------------------------------------------------------------------------------------------
# Evaluation sets
FAR_THETAS = (80.0, 82.0, 84.0, 86.0, 87.0)     # the demo's far ground: 80-87° from the normal
FAR_AZIMUTHS = (-10.0, 4.0, 15.0)               # sun relative to the mirror azimuth across its pixels
BASE_ALPHA = 0.04                               # roughness 0.2


def far_texels():
    out = [("bumps rot 0", bump_lobes(0.0)), ("bumps rot 26", bump_lobes(np.pi / 7))]
    for tilt, kappa in ((15, 5), (15, 50), (30, 20), (30, 100), (45, 10), (45, 200)):
        out.append(("ring %d° κ%d" % (tilt, kappa), (None, ring_lobes(tilt, kappa))))
    return out
