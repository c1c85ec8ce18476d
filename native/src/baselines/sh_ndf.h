// Spherical-harmonic NDF filtering (Han et al. 2007, §5): each texel stores the SH coefficients of
// its NDF up to order N, γ_lm = Σ_q w_q Y_lm(n_q) / Σ_q w_q (eq. 9, 13: the NDF is a weighted sum of
// Dirac deltas at the fine normals), (N+1)² floats, linear. The shader is eq. 11–12:
// ρ_eff(ω) = Σ_{l≤N} Σ_m ρ̂_l γ_lm Y_lm(ω), with ρ̂_l from zonal_brdf_coefficients.
#pragma once

#include <memory>

#include "ndf/ndf_pyramid.h"

namespace ndfbake {

// Throws Error(invalid_argument) unless 0 ≤ order ≤ kMaxShOrder.
std::unique_ptr<NdfPyramid> make_sh_pyramid(const NormalMap& map, WrapMode wrap, int order);

}  // namespace ndfbake
