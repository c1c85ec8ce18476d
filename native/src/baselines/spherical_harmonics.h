// Real spherical harmonics and the zonal coefficients of a base BRDF: the two halves of Han et
// al. 2007's SH filtering (§5, eq. 9–13).
//
// Conventions. Y_lm are orthonormal on S² (∫ Y_lm Y_l'm' dω = δ_ll' δ_mm'), real, without the
// Condon–Shortley phase: with K_lm = √((2l+1)/(4π) · (l−m)!/(l+m)!),
//   Y_l0 = K_l0 P_l(cos θ),  Y_lm = √2 K_lm P_l^m(cos θ) cos mφ,  Y_l,−m = √2 K_lm P_l^m(cos θ) sin mφ
// (so Y_1,1 = √(3/4π) x). A zonal function f(ω·n) expands as Σ_l f_l Y_l0 with
// f_l = 2π ∫₋₁¹ f(c) Y_l0(c) dc, and the Funk–Hecke theorem gives
//   ∫ f(ω·n) Y_lm(n) dn = Λ_l f_l Y_lm(ω),  Λ_l = √(4π/(2l+1)),
// because Λ_l Y_l0(c) = P_l(c). Hence Han's ρ̂_l = Λ_l f_l = 2π ∫₋₁¹ f(c) P_l(c) dc, and for an NDF
// with coefficients γ_lm the effective BRDF is ρ_eff(ω) = Σ_lm ρ̂_l γ_lm Y_lm(ω) (eq. 11–12).
#pragma once

#include <vector>

#include "math/brdf.h"
#include "math/vec3.h"

namespace ndfbake {

// Highest order the SH code and the sh-N baselines accept: 289 coefficients, enough for
// Blinn-Phong s ≈ 64 by Han's rule l* ≈ √(4s) (§5.1); beyond that SH is the wrong tool (vMF).
inline constexpr int kMaxShOrder = 16;

constexpr int sh_count(int order) { return (order + 1) * (order + 1); }
constexpr int sh_index(int l, int m) { return l * (l + 1) + m; }

// Y_lm(direction) for every l ≤ order into out[sh_index(l, m)]. The direction is normalized
// first; a zero vector is taken as +Z. Stable for any order: the associated Legendre functions
// run on the fully normalized three-term recurrence, and cos mφ, sin mφ come from (x + iy)^m.
void real_sh(const Vec3& direction, int order, double* out);

// ρ̂_l = 2π ∫₋₁¹ f(c) P_l(c) dc for l = 0..order, by composite 16-point Gauss–Legendre on panels
// that halve towards c = 1 (where the specular peaks live) and meet at c = 0 (Lambert's kink).
// brdf.eval takes c in float, which resolves 1 − c only down to 6e-8 (θ ≈ 3.5e-4 rad): lobes
// narrower than that (GGX roughness below about 0.03) are integrated as brdf.eval defines them on
// that grid, not as their formula would in exact arithmetic.
std::vector<double> zonal_brdf_coefficients(const BaseBrdf& brdf, int order);

}  // namespace ndfbake
