#include "ndf/moments.h"

#include <algorithm>

namespace ndfbake {

VmfLobe toksvig_lobe(std::span<const WeightedNormal> samples)
{
    Vec3d sum;
    double total = 0.0;
    for (const WeightedNormal& s : samples) {
        sum.add(s.n, s.weight);
        total += s.weight;
    }
    VmfLobe lobe;
    lobe.alpha = 1.0f;
    if (total <= 0.0) return lobe;
    const double r = std::min(1.0, sum.length() / total);
    const double kappa = r >= 1.0 ? double(kKappaMax) : r / (1.0 - r);
    lobe.kappa = float(std::clamp(kappa, double(kKappaMin), double(kKappaMax)));
    lobe.mu = normalize_or(sum.to_float(), Vec3{0.0f, 0.0f, 1.0f});
    return lobe;
}

}  // namespace ndfbake
