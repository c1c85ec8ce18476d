// von Mises-Fisher lobes on S² (Han et al. 2007, §7): the value type and its scalar functions.
#pragma once

#include <cmath>
#include <limits>
#include <vector>

#include "math/vec3.h"

namespace ndfbake {

// κ below this is a uniform distribution to float precision (A(κ) ≈ κ/3 < 4e-4); it also keeps
// the direction of a lobe meaningful in storage, where r = A(κ)·μ must not round to zero.
inline constexpr float kKappaMin = 1e-3f;
// κ at which identical normals saturate (R → 1 makes A⁻¹ diverge). 1e4 is a 0.6° spread and
// 1 − 1/κ is still exact in float. A lobe at the cap stands for one direction: every level-0
// texel is one, and so is a texel of identical normals. The lobe files store it as |r| = 1.
inline constexpr float kKappaMax = 1e4f;

// The concentration the convolution rules use for a lobe of κ: κ itself below the cap, +∞ at
// it. A lobe at the cap stands for one direction, so convolving with it must leave the base
// BRDF as it is, which matters for GGX roughness ≲ 0.2, Blinn-Phong s ≳ 1e3 and Beckmann m ≲ 0.1
// (widened by 1/κ = 1e-4, a single normal was 0.26 off in relative L2 at GGX roughness 0.1, 8.95
// at 0.05). A lobe just below the cap is a real spread and keeps all of it (taking the cap's
// 1e-4 off every lobe instead, to be continuous, left Blinn-Phong 512 at κ = 5000 3.4% off).
inline float convolution_kappa(float kappa)
{
    return kappa >= kKappaMax ? std::numeric_limits<float>::infinity() : kappa;
}

// The resultant length a lobe of κ stands for, as the lobe files store it: 1 at the cap (one
// direction, the limit EM stops short of), resultant_from_kappa below.
double lobe_resultant(float kappa);

// A normalized vMF lobe scaled by its mixture weight: α · γ(n; μ, κ).
// Invariants: α ∈ [0, 1], |μ| = 1, κ ∈ [kKappaMin, kKappaMax].
struct VmfLobe {
    float alpha = 0.0f;
    Vec3 mu{0.0f, 0.0f, 1.0f};
    float kappa = kKappaMin;
};

// A(κ) = coth κ − 1/κ, the mean resultant length of a vMF (eq. 16).
double mean_resultant_length(double kappa);

// κ ≈ (3R − R³)/(1 − R²) (Banerjee et al. 2005; Algorithm 1 line 12), clamped to
// [kKappaMin, kKappaMax]: the guard for R → 1 (identical normals) and R → 0 (normals cancel).
float kappa_from_resultant(double resultant_length);

// The inverse of kappa_from_resultant on [kKappaMin, kKappaMax]: the |r| whose Banerjee κ is
// exactly `kappa`. Textures store r at this length so that a shader evaluating Algorithm 2
// line 9 recovers the fitted κ bit for bit, not A(κ)'s slightly different value.
double resultant_from_kappa(float kappa);

// log C(κ) + κ, where C(κ) = κ / (4π sinh κ) is the vMF normalizer (eq. 15). Shifted by κ so
// that log γ(n) = shifted + κ(μ·n − 1) never adds two huge terms of opposite sign.
double log_vmf_normalizer_shifted(double kappa);

// log γ(n; μ, κ), the log density of the normalized lobe.
inline float log_vmf_density(const VmfLobe& lobe, const Vec3& n, float log_norm_shifted)
{
    return log_norm_shifted + lobe.kappa * (dot(lobe.mu, n) - 1.0f);
}

// log α + log C(κ) + κ: a mixture component's weighted, shifted normalizer, so that
// log(α γ(n)) = log_vmf_density(lobe, n, this); −∞ for an empty lobe (α = 0).
inline float log_weighted_normalizer(const VmfLobe& lobe)
{
    if (!(lobe.alpha > 0.0f)) return -std::numeric_limits<float>::infinity();
    return std::log(lobe.alpha) + float(log_vmf_normalizer_shifted(lobe.kappa));
}

// The Legendre coefficient A_l(κ) = I_{l+1/2}(κ) / I_{1/2}(κ) of a normalized vMF for l = 0..lmax
// (Funk-Hecke: convolving a zonal function with the lobe scales its degree-l band by A_l).
// A_1 = A(κ); A_l → exp(−l(l+1)/(2κ)) for large κ (cf. eq. 19), which it returns from κ =
// kKappaMax on (within 5e-6 there for l ≤ 48, and closer beyond), up to κ = ∞ (every A_l = 1).
void vmf_legendre_coefficients(double kappa, int lmax, double* out);

// Removes the lobes whose weight is not at least `min_alpha` (and every α ≤ 0 or NaN), then
// rescales the rest so that Σα = 1 again: a mixture's dead or negligible lobes, pruned.
void drop_light_lobes(std::vector<VmfLobe>& lobes, float min_alpha);

}  // namespace ndfbake
