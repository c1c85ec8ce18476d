#include "ndf/moments.h"

#include <algorithm>

namespace ndfbake {

VmfLobe toksvig_lobe(std::span<const WeightedNormal> samples)
{
    const MeanNormal mean = mean_normal(samples);
    const double r = mean.length;
    const double kappa = r >= 1.0 ? double(kKappaMax) : r / (1.0 - r);
    return {1.0f, mean.direction, float(std::clamp(kappa, double(kKappaMin), double(kKappaMax)))};
}

}  // namespace ndfbake
