#include "ndf/spherical_kmeans.h"

#include <array>
#include <cstddef>

#include "error.h"
#include "ndf/spherical_em.h"

namespace ndfbake {

int spherical_kmeans(std::span<const WeightedNormal> samples, std::vector<VmfLobe>& lobes, int max_iterations)
{
    const size_t J = lobes.size();
    if (J == 0 || samples.empty()) return 0;
    if (J > size_t(kMaxLobes))
        throw Error(Status::invalid_argument, "k-means fits at most " + std::to_string(kMaxLobes) + " lobes at once");

    int iteration = 0;
    while (iteration < max_iterations) {
        ++iteration;
        std::array<double, kMaxLobes> weight{};
        std::array<Vec3d, kMaxLobes> sum{};
        double total = 0.0;
        for (const WeightedNormal& s : samples) {
            size_t nearest = 0;
            float best = dot(lobes[0].mu, s.n);
            for (size_t j = 1; j < J; ++j) {
                const float d = dot(lobes[j].mu, s.n);
                if (d > best) {
                    best = d;
                    nearest = j;
                }
            }
            weight[nearest] += s.weight;
            sum[nearest].add(s.n, s.weight);
            total += s.weight;
        }
        // Unchanged directions mean unchanged assignments from here on: the fit has converged.
        bool moved = false;
        for (size_t j = 0; j < J; ++j) {
            VmfLobe& lobe = lobes[j];
            if (!(weight[j] > 0.0)) {
                lobe.alpha = 0.0f;
                continue;
            }
            const Vec3 r = sum[j].to_float() / float(weight[j]);
            const Vec3 mu = normalize_or(r, lobe.mu);
            moved = moved || mu.x != lobe.mu.x || mu.y != lobe.mu.y || mu.z != lobe.mu.z;
            lobe = {float(weight[j] / total), mu, kappa_from_resultant(length(r))};
        }
        if (!moved) break;
    }
    return iteration;
}

}  // namespace ndfbake
