"""Offline study: a per-lobe correction for ndfbake's vMF lobes at grazing views (issue 24, points 2-3).

What is modelled (all in the tangent frame of the flat geometric surface, Ng = +z; F = 1, i.e. a
white metal; the view v = (sin θv, 0, cos θv)):

Reference, the normal map ("the map"): a texel's fine normals n are distributed vMF(μ, κ) over the
surface (Han et al. 2007, eq. 4: the vMF lobe fitted to the texel's NDF). Every fine normal shades
with its own narrow GGX BSDF about itself and nothing masks one fine normal from another; each fine
normal's 1/(n·v) cancels its own projected area, so the pixel's radiance is the plain surface
average

    L_map(v) = E_{n ~ vMF(μ,κ)} [ ∫ f_α(n'; l, v) (n'·l)+ [l·Ng > 0] L(l) dl ],

    f_α(n; l, v) = D_α(h) G2_α(l, v) / (4 (n·l)(n·v)) · 1/E_α(n·v)     (Walter et al. 2007, eq. 20;
                                                                        D eq. 33 (GGX))
    G2 = 1 / (1 + Λ(v) + Λ(l)),  Λ(x) = (sqrt(1 + α² tan²θx) − 1)/2   (Heitz 2014, eq. 99 and
                                                                        eq. 72: height-correlated
                                                                        Smith, as Cycles 4.x)
    1/E_α(n·v): Cycles 4.x's Multiscatter GGX energy compensation for F = 1 (bsdf_microfacet.h,
                microfacet_ggx_preserve_energy: weight·(1 + (1−E)/E)); E_α(μ) the single-scatter
                directional albedo, tabulated here by Monte Carlo.

n' is n after Cycles' ensure_valid_specular_reflection(Ng, v, n) (kernel/closure/bsdf_util.h,
applied to every glossy closure's normal when the material's bump-map correction is on, the
default): a fine normal whose mirror direction falls below min(0.9·v·Ng, 0.01) above the geometric
horizon is rotated toward Ng, in the plane of n and Ng, until its mirror direction is at that
height. So no fine normal faces away from the view (n'·v > 0 follows), and fine normals tilted away
from the view at grazing views all reflect the horizon. Light from below the geometric horizon
(l·Ng ≤ 0) is dropped, as Cycles' reflection closures do (and the plane itself occludes it).

Closure, what ndfbake draws: one Multiscatter GGX closure about μ' = bend(μ) with
α'² = min(α² + 1.5/κ, 1) (Han 2007 eq. 10-12: convolving the NDF with the vMF; ndfbake's
kGgxVmfWidening = 1.5), same f, same horizon rule, weight 1 per lobe (the lobe weight α_j
multiplies both sides alike).

Both are linear in the lighting, so each is sampled once as a weighted set of light directions
("kernel": f·cos/pdf weights, visible-normal sampling, Heitz 2018) and evaluated under Blender's
8 studio worlds (rotated so that the brightest spot lies at a chosen azimuth relative to the
mirror direction) and probe lights.

The correction (docs/grazing-fit.md; corrected_alpha2, make_correction): narrow each lobe as the
view grazes it, α_c² = max(α'² / (1 + C·α'²·tan²θμ), α²), θμ between the view and the lobe's
normal, cos θμ floored at 1e-3; C = 1 is the EEVEE rule nodes.grazing_roughness_group draws today,
the fit gives C = 4 for Cycles. Weight and normal unchanged. Also fitted: the same narrowing in the
plane of incidence only (anisotropic; Cycles only).

Fit: one constant per family minimizing, over far-ground texels (the demo's bump lattice split
into lobes, and rings of vMF lobes) × view angles 80-87°, the mean over the 8 worlds of
log²(closure/map), plus the far-ground aggregate's log² per world (objective()). Validation: the
far ground per world and view angle, the white furnace (flat map) at 0-88°, a finiteness sweep of
the formula, and single vMF lobes over θv 0-88°, κ 2-1e4, α 0.02-0.5, tilts up to 45°.

Run: python3 studies/grazing_fit.py --out DIR   (a few minutes on 2 cores)

The package (issue 26: one idea per module), lowest layer first; a module may call only the ones
listed above it:
  ggx         GGX and vMF math: sampling, Smith, the albedo table, Cycles' bending, ggx_eval
  lighting    the 8 studio worlds (load, cache, lookup) and Lighting.radiance; calls nothing here
  models      MapModel (the normal map), ClosureModel and lobe_closure (what ndfbake draws)
  correction  the narrowing α_c (corrected_alpha2, make_correction)
  texels      the far ground's texels (bump lattice, rings), view angles and sun azimuths
  fit         the far-ground references, the objective, and the checks (furnace, finite, lobes)
  report      main: the fit, the tables, report.md / fit.json / lobes.json
This file owns only this description and imports nothing; studies/grazing_fit.py is the command.
"""
