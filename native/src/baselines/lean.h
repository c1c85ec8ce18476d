// LEAN mapping (Olano & Baker 2010, as Bruneton & Neyret 2012 §1.5 / eq. 19 describe it): the
// first and second moments of the normals' slopes, a single anisotropic lobe in slope space.
//
// Slopes use the survey's convention: a direction η projects onto the plane z = 1 above the
// surface, t(η) = (η_x, η_y)/η_z. Normals and half vectors are projected alike, so the sign
// convention of Olano & Baker's B = −n_xy/n_z would change nothing.
//
// Storage (5 floats, all linear): E[t_x], E[t_y], E[t_x²], E[t_y²], E[t_x t_y].
//
// Specular shader. The texel's slope covariance Σ = M − t̄t̄ᵀ is added to the base lobe's own slope
// scale matrix S_b (LEAN's rule "Cov += base variance"; exact when both are Gaussian), and the
// lobe is evaluated at the half vector's slope as a density over slopes turned into a density
// over directions by 1/cos⁴θ_h, like Beckmann:
//   f(h) = K · cos β̄ · P22(t_h − t̄; ν, Σ + S_b(t̄)) / h_z⁴,
//   P22(d; ν, S) = (1 / (2π √det S)) · (1 + dᵀS⁻¹d / ν)^−(ν+2)/2   (bivariate Student-t).
// Base lobes. Each is exactly such a slope distribution about a +Z normal (c = 1/√(1+|t|²)):
//   normalized Blinn-Phong (s+1)/(2π)·c^s = (s+1)/(s+2) · P22(t; ν = s+2, σ_b² I) / c⁴, σ_b² = 1/(s+2),
//     since c^s = (1+|t|²)^−s/2; P22's Gaussian limit exp(−(s+2)|t|²/2) is the familiar
//     "Blinn-Phong s ≈ Beckmann of slope variance 1/s per axis" (1/(s+2) is the exact scale);
//   GGX α (brdf.h) = P22(t; ν = 2, σ_b² I) / c⁴ with σ_b² = α²/2, which is also the per-axis
//     slope variance of the Beckmann lobe of equal α (m = α);
//   Beckmann m = P22(t; ν → ∞, σ_b² I) / c⁴ with σ_b² = m²/2: LEAN's own Gaussian, exactly.
// Keeping each base lobe's ν makes a texel of identical +Z normals reproduce brdf.eval exactly,
// which LEAN's Gaussian alone cannot do for GGX (Beckmann and GGX of equal α differ by tens of
// percent in the tails).
// Tilted texels. Olano & Baker add σ_b² I, the base lobe's spread about +Z. About a mean normal
// tilted by β̄ (tan β̄ = |t̄|) the same angular spread covers more slope: the slope map's Jacobian
// stretches it by 1/cos²β̄ radially and 1/cos β̄ tangentially, so
//   S_b(t̄) = σ_b² (1 + |t̄|²)(I + t̄t̄ᵀ),
// which is σ_b² I at t̄ = 0. And P22/cos⁴ counts fine normals by projected area (a microfacet D),
// while the ground truth (eq. 4) counts each fine texel once: the factor cos β̄ = 1/√(1+|t̄|²)
// converts one to the other at the mean normal. Together they make a texel of identical normals
// peak at exactly brdf.eval(1) at any tilt; away from the peak slope space still skews a tilted
// lobe (the 1/h_z⁴ factor changes across it), LEAN's inherent error, which grows with tilt × width.
// Diffuse: LEAN is specular-only (Olano & Baker filter the specular lobe). For Lambert the shader
// uses the cosine about the normal of the mean slope, normalize(t̄_x, t̄_y, 1): the averaged-normal
// cosine a LEAN shader shades diffuse with.
#pragma once

#include <memory>

#include "ndf/ndf_pyramid.h"

namespace ndfbake {

inline constexpr int kLeanFloats = 5;

// Slope magnitude at which normals at or below the horizon (n_z → 0, t → ∞) are clamped,
// keeping their azimuth. The second moment t² must fit the half-float textures the lobes are
// written to (largest finite half: 65504 ≥ 255² = 65025); 255 is a tilt of 89.78°, so only
// normals within 0.22° of the horizon are bent.
inline constexpr float kLeanMaxSlope = 255.0f;

struct Slope {
    double x = 0.0, y = 0.0;
};

// t(n) = (n_x, n_y)/n_z, with |t| clamped to kLeanMaxSlope (n_z ≤ 0 or a near-horizon normal goes
// to the clamp in the direction of (n_x, n_y); a normal with no tangential part has slope 0).
Slope lean_slope(const Vec3& n);

std::unique_ptr<NdfPyramid> make_lean_pyramid(const NormalMap& map, WrapMode wrap);

}  // namespace ndfbake
