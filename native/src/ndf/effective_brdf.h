// The exact effective BRDF of a texel (Han et al. 2007, eq. 4–5) and the error of a fitted NDF
// against it: the ground truth every representation is measured by.
#pragma once

#include <span>
#include <vector>

#include "math/brdf.h"
#include "math/vmf.h"
#include "ndf/weighted_normal.h"

namespace ndfbake {

// Directions sampled per texel: spacing of at most half the BRDF's angular width on the
// hemisphere (2π / count ≤ (w/2)²), within these bounds so that broad lobes are still resolved
// and mirror-like lobes stay affordable.
inline constexpr int kMinErrorDirections = 256;
inline constexpr int kMaxErrorDirections = 4096;
int error_direction_count(const BaseBrdf& brdf);

// ρ_eff(ω) = Σ w_q f(ω·n_q) / Σ w_q at each direction (eq. 4).
void reference_effective_brdf(std::span<const WeightedNormal> normals, const BaseBrdf& brdf,
                              std::span<const Vec3> directions, std::span<float> out);

// Σ_j α_j (f ⊗ γ_j)(ω·μ_j): what a shader computes from the fitted lobes (eq. 20–21, Algorithm 2).
void mixture_effective_brdf(std::span<const VmfLobe> lobes, const BaseBrdf& brdf,
                            std::span<const Vec3> directions, std::span<float> out);

// ‖fit − ref‖₂ / ‖ref‖₂ over the directions.
float relative_l2_error(std::span<const float> fit, std::span<const float> reference);

// Holds one texel's reference effective BRDF so that many candidate fits are scored against it
// for the cost of one reference evaluation.
class TexelErrorMeter {
public:
    TexelErrorMeter(std::span<const WeightedNormal> normals, const BaseBrdf& brdf,
                    std::span<const Vec3> directions);
    float error(std::span<const VmfLobe> lobes) const;
    std::span<const float> reference() const { return reference_; }

private:
    const BaseBrdf* brdf_;
    std::span<const Vec3> directions_;
    std::vector<float> reference_;
    mutable std::vector<float> scratch_;
};

}  // namespace ndfbake
