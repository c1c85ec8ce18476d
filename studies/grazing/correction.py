"""The correction fitted by the grazing study: narrow each lobe as the view grazes it
(corrected_alpha2), isotropic or in the plane of incidence only (make_correction), with its clamps.
Calls grazing.ggx (WIDENING) only."""
import numpy as np

from .ggx import WIDENING


# ---------------------------------------------------------------------------------------------
# The correction
GRAZING_MIN_COSINE = 1e-3     # cos θμ floor (θμ ≈ 89.94°): tan²θμ ≤ 1e6, finite; lobes facing away
                              # from the view (μ·v ≤ 0) get the full narrowing (α_c → α)
MAX_WIDENED_ALPHA2 = 1.0      # α'² ≤ 1 as the lobe group already clamps


def corrected_alpha2(cos_mu_v, inv_kappa, alpha, c, q=1.0):
    """Isotropic narrowing: α_c² = max(α'² / (1 + c·α'²·tan²θμ)^q, α²), α'² = min(α² + 1.5/κ, 1).
    Vectorized; finite and positive for every input (cos clamped, 1/κ ≥ 0, α ≥ 1e-4)."""
    a2 = np.maximum(np.asarray(alpha, float), 1e-4) ** 2
    aw2 = np.minimum(a2 + WIDENING * np.maximum(inv_kappa, 0.0), MAX_WIDENED_ALPHA2)
    cm = np.clip(cos_mu_v, GRAZING_MIN_COSINE, 1.0)
    tan2 = (1.0 - cm * cm) / (cm * cm)
    return np.maximum(aw2 / (1.0 + c * aw2 * tan2) ** q, a2)


def make_correction(kind, c=1.0, q=1.0, ratio_max=10.0):
    """corr(cos_mu_v, cos_g_v, inv_kappa, alpha) -> (weight factor, α in the plane of incidence,
    tilt, [α across]) for lobe_closure; kind 'none', 'iso' (EEVEE's rule when c = q = 1) or
    'aniso' (the narrowing in the plane of incidence only; α across kept at α', aspect ≤ ratio_max
    as Blender's Anisotropic input allows)."""
    if kind == "none":
        return None

    def corr(cos_mu_v, cos_g_v, inv_kappa, alpha):
        ac = float(np.sqrt(corrected_alpha2(cos_mu_v, inv_kappa, alpha, c, q)))
        if kind == "iso":
            return 1.0, ac, 0.0
        ap = float(np.sqrt(min(alpha * alpha + WIDENING * inv_kappa, MAX_WIDENED_ALPHA2)))
        return 1.0, max(ac, ap / ratio_max), 0.0, ap
    return corr
