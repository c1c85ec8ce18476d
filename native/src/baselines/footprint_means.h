// Footprint-weighted means of per-texel features over every MIP level: how every linear baseline
// (mean normal, LEAN moments, Xu's cell sums, SH coefficients) builds its pyramid. A texel's
// footprint is a product of one column set and one row set (pyramid/footprint.h), so the mean is
// accumulated row by row over the source rows it covers, without gathering samples one by one.
#pragma once

#include <optional>
#include <span>
#include <vector>

#include "pyramid/footprint.h"
#include "pyramid/parallel.h"

namespace ndfbake {

// One source index of an axis under a target texel, with its weight along that axis.
struct AxisTap {
    int index;
    int multiplicity;
};

// The taps of every target index of one axis: index i covers taps[begin[i]] .. taps[begin[i + 1] − 1].
struct AxisFootprints {
    std::vector<AxisTap> taps;
    std::vector<int> begin;      // target count + 1 entries
    std::vector<double> weight;  // Σ multiplicity per target index
    int targets() const { return int(weight.size()); }
};

// The fine indices under each texel of `level` along an axis of `extent` texels, with their
// multiplicities: gather_footprint's per-axis footprints (the test suite checks every texel of
// odd sizes in both modes against it).
AxisFootprints axis_footprints(int extent, int level, WrapMode wrap);

// The same footprints over the texels of level − 1 instead of the fine ones, when each texel's fine
// footprint at `level` is exactly the union of its existing children's (multiplicities included);
// each child is weighted by its own fine weight along the axis. Always the case in clamp mode
// (children partition their parent); in wrap mode it fails where a footprint wider than the odd
// level below wraps onto a shifted window. nullopt then, and the level is summed from the fine
// texels instead.
std::optional<AxisFootprints> child_footprints(int extent, int level, WrapMode wrap);

// For every target texel (x, y): mean[k] = Σ w φ_k / Σ w over the source texels its footprint
// covers, w = column multiplicity × row multiplicity, for k < floats. `add(sx, sy, w, acc)` adds
// w·φ(sx, sy) into acc[0 .. floats); `emit(y, row)` receives row[x·floats + k] for one target row.
// Rows run in parallel on all cores, so `add` must be thread-safe and `emit` must only write row
// y's own storage.
template <class Add, class Emit>
void separable_means(const AxisFootprints& columns, const AxisFootprints& rows, int floats, const Add& add,
                     const Emit& emit)
{
    const int width = columns.targets();
    parallel_rows(rows.targets(), 0, [&](int y) {
        std::vector<double> row(size_t(width) * size_t(floats), 0.0);
        for (int r = rows.begin[size_t(y)]; r < rows.begin[size_t(y) + 1]; ++r) {
            const AxisTap row_tap = rows.taps[size_t(r)];
            for (int x = 0; x < width; ++x) {
                double* acc = row.data() + size_t(x) * size_t(floats);
                for (int c = columns.begin[size_t(x)]; c < columns.begin[size_t(x) + 1]; ++c) {
                    const AxisTap column_tap = columns.taps[size_t(c)];
                    add(column_tap.index, row_tap.index, double(row_tap.multiplicity) * column_tap.multiplicity, acc);
                }
            }
        }
        for (int x = 0; x < width; ++x) {
            const double inv_weight = 1.0 / (columns.weight[size_t(x)] * rows.weight[size_t(y)]);
            for (int k = 0; k < floats; ++k) row[size_t(x) * size_t(floats) + size_t(k)] *= inv_weight;
        }
        emit(y, std::span<const double>(row));
    }, {});
}

}  // namespace ndfbake
