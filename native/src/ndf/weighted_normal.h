// The samples every NDF fit consumes: fine normals with a weight (footprint multiplicity).
#pragma once

#include <algorithm>
#include <span>

#include "math/vec3.h"

namespace ndfbake {

// A fine normal (unit n), or a summary of many: the mean resultant vector of a bin of normals
// (|n| ≤ 1, pyramid/normal_bins.h). EM treats both alike, since a lobe's expected log-likelihood
// over a set of normals depends on them only through their mean (log γ is linear in n).
struct WeightedNormal {
    Vec3 n;
    float weight;    // > 0: how many fine normals this stands for
};

// The weighted mean of the normals, split into its direction and its length R ∈ [0, 1] (the
// mean resultant length every moment-based lobe is built from).
struct MeanNormal {
    Vec3 direction{0.0f, 0.0f, 1.0f};  // +Z, the neutral normal, when the normals cancel
    double length = 0.0;
};

inline MeanNormal mean_normal(std::span<const WeightedNormal> samples)
{
    Vec3d sum;
    double total = 0.0;
    for (const WeightedNormal& s : samples) {
        sum.add(s.n, s.weight);
        total += s.weight;
    }
    MeanNormal mean;
    if (total <= 0.0) return mean;
    mean.length = std::min(1.0, sum.length() / total);
    mean.direction = normalize_or(sum.to_float(), mean.direction);
    return mean;
}

}  // namespace ndfbake
