#include "pyramid/normal_bins.h"

#include <algorithm>
#include <bit>
#include <cmath>

namespace ndfbake {

namespace {

// See accumulate_texel_bins.
bool children_cover_footprint(LevelSize finer, int x, int y, WrapMode wrap)
{
    return wrap == WrapMode::clamp || (2 * x + 1 < finer.width && 2 * y + 1 < finer.height);
}

}  // namespace

uint32_t normal_bin_index(const Vec3& n)
{
    // Hemi-octahedral map: project onto |x| + |y| + z = 1, then turn the diamond by 45° to fill
    // the unit square, so that cells have nearly equal solid angle.
    const float l1 = std::abs(n.x) + std::abs(n.y) + std::max(n.z, 0.0f);
    const float px = l1 > 0.0f ? n.x / l1 : 0.0f, py = l1 > 0.0f ? n.y / l1 : 0.0f;
    const auto cell = [](float t) { return std::clamp(int(t * float(kNormalBinsPerAxis)), 0, kNormalBinsPerAxis - 1); };
    return uint32_t(cell(0.5f * (px - py + 1.0f)) * kNormalBinsPerAxis + cell(0.5f * (px + py + 1.0f)));
}

BinAccumulator::BinAccumulator() : weight_(kNormalBinCount, 0.0f), sum_(kNormalBinCount) {}

void BinAccumulator::add(uint32_t index, float weight, const Vec3& sum)
{
    occupied_[index / 64] |= uint64_t(1) << (index % 64);
    weight_[index] += weight;
    sum_[index] += sum;
}

void BinAccumulator::add(std::span<const WeightedNormal> normals)
{
    for (const WeightedNormal& s : normals) add(normal_bin_index(s.n), s.weight, s.weight * s.n);
}

void BinAccumulator::add(std::span<const NormalBin> bins)
{
    for (const NormalBin& b : bins) add(b.index, b.weight, b.sum);
}

std::span<const NormalBin> BinAccumulator::finish()
{
    bins_.clear();
    for (size_t word = 0; word < occupied_.size(); ++word) {
        for (uint64_t bits = occupied_[word]; bits != 0; bits &= bits - 1) {
            const uint32_t index = uint32_t(64 * word) + uint32_t(std::countr_zero(bits));
            if (weight_[index] > 0.0f) bins_.push_back({index, weight_[index], sum_[index]});
            weight_[index] = 0.0f;
            sum_[index] = {};
        }
        occupied_[word] = 0;
    }
    return bins_;
}

BinnedLevel::BinnedLevel(LevelSize size) : size_(size), rows_(size_t(size.height)) {}

void BinnedLevel::append_texel(int y, std::span<const NormalBin> bins)
{
    Row& row = rows_[size_t(y)];
    row.bins.insert(row.bins.end(), bins.begin(), bins.end());
    row.offsets.push_back(uint32_t(row.bins.size()));
}

std::span<const NormalBin> BinnedLevel::texel(int x, int y) const
{
    const Row& row = rows_[size_t(y)];
    return std::span(row.bins).subspan(row.offsets[size_t(x)], row.offsets[size_t(x) + 1] - row.offsets[size_t(x)]);
}

bool binned_level(int level) { return level < 31 && (uint64_t(1) << (2 * level)) > uint64_t(kMinBinnedFootprint); }

bool accumulate_texel_bins(const NormalMap& map, const BinnedLevel& finer, int level, int x, int y, WrapMode wrap,
                           BinAccumulator& bins, std::vector<WeightedNormal>& gathered)
{
    if (!finer.empty() && children_cover_footprint(finer.size(), x, y, wrap)) {
        for (int cy = 2 * y; cy < std::min(2 * y + 2, finer.size().height); ++cy)
            for (int cx = 2 * x; cx < std::min(2 * x + 2, finer.size().width); ++cx) bins.add(finer.texel(cx, cy));
        return true;
    }
    gather_footprint(map, level, x, y, wrap, gathered);
    bins.add(gathered);
    return false;
}

void bin_samples(std::span<const NormalBin> bins, int max_samples, std::vector<WeightedNormal>& out)
{
    out.clear();
    if (bins.size() <= size_t(max_samples)) {
        for (const NormalBin& bin : bins) out.push_back({bin.sum / bin.weight, bin.weight});
        return;
    }
    // Halve the grid until the occupied cells fit: cell (row, column) of the fine grid lies in
    // cell (row >> shift, column >> shift) of the coarse one.
    std::vector<float> weight;
    std::vector<Vec3> sum;
    std::vector<uint32_t> occupied;
    for (int shift = 1; (kNormalBinsPerAxis >> shift) > 0; ++shift) {
        const uint32_t axis = uint32_t(kNormalBinsPerAxis >> shift);
        weight.assign(size_t(axis) * axis, 0.0f);
        sum.assign(size_t(axis) * axis, Vec3{});
        occupied.clear();
        for (const NormalBin& bin : bins) {
            const uint32_t row = bin.index / kNormalBinsPerAxis, column = bin.index % kNormalBinsPerAxis;
            const uint32_t cell = (row >> shift) * axis + (column >> shift);
            if (weight[cell] == 0.0f) occupied.push_back(cell);
            weight[cell] += bin.weight;
            sum[cell] += bin.sum;
        }
        if (occupied.size() <= size_t(max_samples)) break;
    }
    for (uint32_t cell : occupied) out.push_back({sum[cell] / weight[cell], weight[cell]});
}

}  // namespace ndfbake
