#include "ndf/effective_brdf.h"

#include <algorithm>
#include <cmath>

namespace ndfbake {

int error_direction_count(const BaseBrdf& brdf)
{
    const double half_width = 0.5 * brdf.angular_width();
    const double count = 2.0 * 3.14159265358979 / (half_width * half_width);
    return int(std::clamp(std::ceil(count), double(kMinErrorDirections), double(kMaxErrorDirections)));
}

void reference_effective_brdf(std::span<const WeightedNormal> normals, const BaseBrdf& brdf,
                              std::span<const Vec3> directions, std::span<float> out)
{
    double total_weight = 0.0;
    for (const WeightedNormal& s : normals) total_weight += s.weight;
    const double inv_weight = total_weight > 0.0 ? 1.0 / total_weight : 0.0;
    for (size_t d = 0; d < directions.size(); ++d) {
        const Vec3 omega = directions[d];
        double sum = 0.0;
        for (const WeightedNormal& s : normals) sum += double(s.weight) * brdf.eval(dot(omega, s.n));
        out[d] = float(sum * inv_weight);
    }
}

void mixture_effective_brdf(std::span<const VmfLobe> lobes, const BaseBrdf& brdf,
                            std::span<const Vec3> directions, std::span<float> out)
{
    std::fill(out.begin(), out.end(), 0.0f);
    for (const VmfLobe& lobe : lobes) {
        if (lobe.alpha <= 0.0f) continue;
        const ConvolvedLobe shape = brdf.convolved(lobe.kappa);
        for (size_t d = 0; d < directions.size(); ++d)
            out[d] += lobe.alpha * shape.eval(dot(directions[d], lobe.mu));
    }
}

float relative_l2_error(std::span<const float> fit, std::span<const float> reference)
{
    double diff2 = 0.0, ref2 = 0.0;
    for (size_t i = 0; i < reference.size(); ++i) {
        const double d = double(fit[i]) - double(reference[i]);
        diff2 += d * d;
        ref2 += double(reference[i]) * double(reference[i]);
    }
    // A texel whose effective BRDF vanishes on every direction (all normals at the horizon, seen
    // from above) has nothing to get wrong: report the absolute error instead of dividing by 0.
    if (ref2 <= 0.0) return float(std::sqrt(diff2));
    return float(std::sqrt(diff2 / ref2));
}

TexelErrorMeter::TexelErrorMeter(std::span<const WeightedNormal> normals, const BaseBrdf& brdf,
                                 std::span<const Vec3> directions)
    : brdf_(&brdf), directions_(directions), reference_(directions.size()), scratch_(directions.size())
{
    reference_effective_brdf(normals, brdf, directions, reference_);
}

float TexelErrorMeter::error(std::span<const VmfLobe> lobes) const
{
    mixture_effective_brdf(lobes, *brdf_, directions_, scratch_);
    return relative_l2_error(scratch_, reference_);
}

}  // namespace ndfbake
