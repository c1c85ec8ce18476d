#include "pyramid/footprint.h"

#include <algorithm>
#include <cstdint>

namespace ndfbake {

namespace {

struct AxisCell {
    int index;
    int multiplicity;
};

// The fine indices of one axis under coarse index `i` of a level with span 2^level.
void axis_footprint(int extent, int level, int i, WrapMode wrap, std::vector<AxisCell>& out)
{
    out.clear();
    const int64_t span = int64_t(1) << level;
    const int64_t start = int64_t(i) * span;
    if (wrap == WrapMode::clamp) {
        const int64_t end = std::min<int64_t>(start + span, extent);
        for (int64_t k = start; k < end; ++k) out.push_back({int(k), 1});
        return;
    }
    if (span < extent) {
        // Only a footprint that runs past the edge wraps (and pays a division per index).
        const bool wraps = start + span > extent;
        for (int64_t k = 0; k < span; ++k) out.push_back({int(wraps ? (start + k) % extent : start + k), 1});
        return;
    }
    // Every fine index repeats span / extent times, and span mod extent of them once more,
    // counting from where the footprint starts.
    const int64_t repeats = span / extent, extra = span % extent;
    for (int k = 0; k < extent; ++k) {
        const int64_t offset = ((k - start) % extent + extent) % extent;
        out.push_back({k, int(repeats + (offset < extra ? 1 : 0))});
    }
}

}  // namespace

int level_count(int width, int height)
{
    int levels = 1;
    while ((int64_t(1) << (levels - 1)) < std::max(width, height)) ++levels;
    return levels;
}

LevelSize level_size(int width, int height, int level)
{
    const int64_t span = int64_t(1) << level;
    return {int(std::max<int64_t>(1, (width + span - 1) / span)),
            int(std::max<int64_t>(1, (height + span - 1) / span))};
}

void gather_footprint(const NormalMap& map, int level, int x, int y, WrapMode wrap,
                      std::vector<WeightedNormal>& out)
{
    thread_local std::vector<AxisCell> columns, rows;
    axis_footprint(map.width, level, x, wrap, columns);
    axis_footprint(map.height, level, y, wrap, rows);
    out.clear();
    out.reserve(columns.size() * rows.size());
    for (const AxisCell& row : rows)
        for (const AxisCell& column : columns)
            out.push_back({map.at(column.index, row.index), float(row.multiplicity * column.multiplicity)});
}

uint64_t largest_footprint(int width, int height, int level)
{
    const uint64_t span = uint64_t(1) << std::min(level, 62);
    return std::min<uint64_t>(span, uint64_t(width)) * std::min<uint64_t>(span, uint64_t(height));
}

double footprint_weight(int width, int height, int level, int x, int y, WrapMode wrap)
{
    const int64_t span = int64_t(1) << level;
    if (wrap == WrapMode::wrap) return double(span) * double(span);
    const auto extent = [&](int extent, int i) {
        return double(std::max<int64_t>(0, std::min<int64_t>(span, extent - int64_t(i) * span)));
    };
    return extent(width, x) * extent(height, y);
}

void subsample_footprint(std::vector<WeightedNormal>& samples, int cap)
{
    if (cap <= 0 || samples.size() <= size_t(cap)) return;
    constexpr double kGoldenFraction = 0.6180339887498949;
    std::vector<WeightedNormal> kept;
    kept.reserve(size_t(cap));
    double position = 0.5;
    for (int i = 0; i < cap; ++i) {
        kept.push_back(samples[size_t(position * double(samples.size()))]);
        position += kGoldenFraction;
        if (position >= 1.0) position -= 1.0;
    }
    samples = std::move(kept);
}

}  // namespace ndfbake
