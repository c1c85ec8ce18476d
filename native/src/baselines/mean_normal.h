// Baselines that store only the averaged normal n̄ = Σ w_q n_q / Σ w_q (3 floats, linear): they
// differ only in what the shader makes of it (Bruneton & Neyret 2012, §1.1 and §1.6 of the digest).
#pragma once

#include <memory>

#include "ndf/ndf_pyramid.h"

namespace ndfbake {

// n̄ as x, y, z.
inline constexpr int kMeanNormalFloats = 3;

// Plain MIP-mapping of a normal map: f(ω · n̄/|n̄|), the base BRDF about the renormalized mean,
// whatever the spread of the normals under the texel.
std::unique_ptr<NdfPyramid> make_naive_pyramid(const NormalMap& map, WrapMode wrap);

// Toksvig 2005: the length R = |n̄| gives σ² = (1 − R)/R, used as one lobe of κ = 1/σ² = R/(1 − R)
// about n̄/|n̄| and convolved with the base BRDF (eq. 20–21): for Blinn-Phong exactly Toksvig's
// s' = sR/(R + s(1 − R)). Same κ as toksvig_lobe (ndf/moments.h).
std::unique_ptr<NdfPyramid> make_toksvig_pyramid(const NormalMap& map, WrapMode wrap);

// One vMF lobe from the mean resultant (Xu et al. 2017, eq. 8–10 with one lobe): μ = n̄/|n̄|,
// κ = (3R − R³)/(1 − R²) (Banerjee, clamped as kappa_from_resultant), convolved with the base BRDF.
std::unique_ptr<NdfPyramid> make_single_vmf_pyramid(const NormalMap& map, WrapMode wrap);

// κ = R/(1 − R) clamped to [kKappaMin, kKappaMax]: Toksvig's σ² = (1 − R)/R as a concentration.
float toksvig_kappa(double mean_length);

}  // namespace ndfbake
