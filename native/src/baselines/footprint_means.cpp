#include "baselines/footprint_means.h"

#include <algorithm>
#include <cstdint>

namespace ndfbake {

AxisFootprints axis_footprints(int extent, int level, WrapMode wrap)
{
    // The same rule as gather_footprint (pyramid/footprint.cpp): coarse index i covers fine
    // indices [i·2^L, (i+1)·2^L), dropped past the edge in clamp mode and taken modulo the extent
    // in wrap mode, where a span wider than the image repeats every fine index.
    const int64_t span = int64_t(1) << level;
    const int count = level_size(extent, 1, level).width;
    AxisFootprints out;
    out.begin.reserve(size_t(count) + 1);
    out.weight.reserve(size_t(count));
    for (int i = 0; i < count; ++i) {
        out.begin.push_back(int(out.taps.size()));
        const int64_t start = int64_t(i) * span;
        double weight = 0.0;
        auto tap = [&](int64_t index, int64_t multiplicity) {
            out.taps.push_back({int(index), int(multiplicity)});
            weight += double(multiplicity);
        };
        if (wrap == WrapMode::clamp) {
            for (int64_t k = start; k < std::min<int64_t>(start + span, extent); ++k) tap(k, 1);
        } else if (span < extent) {
            for (int64_t k = 0; k < span; ++k) tap((start + k) % extent, 1);
        } else {
            const int64_t repeats = span / extent, extra = span % extent;
            for (int64_t k = 0; k < extent; ++k) {
                const int64_t offset = ((k - start) % extent + extent) % extent;
                tap(k, repeats + (offset < extra ? 1 : 0));
            }
        }
        out.weight.push_back(weight);
    }
    out.begin.push_back(int(out.taps.size()));
    return out;
}

std::optional<AxisFootprints> child_footprints(int extent, int level, WrapMode wrap)
{
    const AxisFootprints parents = axis_footprints(extent, level, wrap);
    const AxisFootprints children = axis_footprints(extent, level - 1, wrap);
    AxisFootprints out;
    // Per fine index: parent multiplicity minus the children's; zero everywhere iff they tile.
    std::vector<int64_t> balance(size_t(extent), 0);
    for (int i = 0; i < parents.targets(); ++i) {
        out.begin.push_back(int(out.taps.size()));
        for (int t = parents.begin[size_t(i)]; t < parents.begin[size_t(i) + 1]; ++t)
            balance[size_t(parents.taps[size_t(t)].index)] += parents.taps[size_t(t)].multiplicity;
        double weight = 0.0;
        for (int child = 2 * i; child <= 2 * i + 1 && child < children.targets(); ++child) {
            for (int t = children.begin[size_t(child)]; t < children.begin[size_t(child) + 1]; ++t)
                balance[size_t(children.taps[size_t(t)].index)] -= children.taps[size_t(t)].multiplicity;
            out.taps.push_back({child, int(children.weight[size_t(child)])});
            weight += children.weight[size_t(child)];
        }
        out.weight.push_back(weight);
        for (int t = parents.begin[size_t(i)]; t < parents.begin[size_t(i) + 1]; ++t)
            if (balance[size_t(parents.taps[size_t(t)].index)] != 0) return std::nullopt;
        // A child tap outside the parent's footprint leaves a negative balance there.
        for (int child = 2 * i; child <= 2 * i + 1 && child < children.targets(); ++child)
            for (int t = children.begin[size_t(child)]; t < children.begin[size_t(child) + 1]; ++t)
                if (balance[size_t(children.taps[size_t(t)].index)] != 0) return std::nullopt;
    }
    out.begin.push_back(int(out.taps.size()));
    return out;
}

}  // namespace ndfbake
