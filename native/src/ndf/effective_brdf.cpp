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
    // The normals in structure-of-arrays form: f at every normal, for one direction at a time,
    // in BaseBrdf::eval_many's vectorized loop.
    const size_t N = normals.size();
    std::vector<float> nx(N), ny(N), nz(N), cosines(N), values(N);
    double total_weight = 0.0;
    for (size_t q = 0; q < N; ++q) {
        nx[q] = normals[q].n.x, ny[q] = normals[q].n.y, nz[q] = normals[q].n.z;
        total_weight += normals[q].weight;
    }
    const double inv_weight = total_weight > 0.0 ? 1.0 / total_weight : 0.0;
    for (size_t d = 0; d < directions.size(); ++d) {
        const Vec3 omega = directions[d];
        for (size_t q = 0; q < N; ++q) cosines[q] = nx[q] * omega.x + ny[q] * omega.y + nz[q] * omega.z;
        brdf.eval_many(cosines, values);
        double sum = 0.0;
        for (size_t q = 0; q < N; ++q) sum += double(normals[q].weight) * values[q];
        out[d] = float(sum * inv_weight);
    }
}

void mixture_effective_brdf(std::span<const VmfLobe> lobes, const BaseBrdf& brdf,
                            std::span<const Vec3> directions, std::span<float> out)
{
    std::fill(out.begin(), out.end(), 0.0f);
    std::vector<float> cosines(directions.size()), values(directions.size());
    for (const VmfLobe& lobe : lobes) {
        if (lobe.alpha <= 0.0f) continue;
        dot_each(directions, lobe.mu, cosines);
        brdf.convolved(lobe.kappa).eval_many(cosines, values, {});
        for (size_t d = 0; d < directions.size(); ++d) out[d] += lobe.alpha * values[d];
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
