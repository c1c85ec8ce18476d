#include "baselines/xu_partitions.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "baselines/footprint_means.h"
#include "baselines/linear_pyramid.h"
#include "error.h"
#include "ndf/effective_brdf.h"

namespace ndfbake {

namespace {

constexpr int kSectors = 4;

// Azimuthal sector centred on +X (0), +Y (1), −X (2), −Y (3); the pole and the diagonals go to
// the X sectors.
int sector(const Vec3& n)
{
    if (std::abs(n.x) >= std::abs(n.y)) return n.x >= 0.0f ? 0 : 2;
    return n.y > 0.0f ? 1 : 3;
}

double cell_length(const double* cell) { return std::sqrt(cell[1] * cell[1] + cell[2] * cell[2] + cell[3] * cell[3]); }

void append_cell(const double* cell, std::vector<float>& out)
{
    if (!(cell[0] > 0.0)) return;  // empty cells carry no lobe
    for (int k = 0; k < kXuFloatsPerCell; ++k) out.push_back(float(cell[k]));
}

class XuPyramid final : public LinearNdfPyramid {
public:
    XuPyramid(const NormalMap& map, WrapMode wrap, XuPartition partition)
        : LinearNdfPyramid(map, wrap, kXuFloatsPerCell * xu_cell_count(partition),
                           [partition](const Vec3& n, float* out) {
                               std::fill(out, out + kXuFloatsPerCell * xu_cell_count(partition), 0.0f);
                               float* cell = out + kXuFloatsPerCell * xu_cell(partition, n);
                               cell[0] = 1.0f;
                               cell[1] = n.x;
                               cell[2] = n.y;
                               cell[3] = n.z;
                           }),
          partition_(partition)
    {
    }

    std::string name() const override
    {
        switch (partition_) {
        case XuPartition::whole: return "xu-1x1";
        case XuPartition::sectors: return "xu-1x4";
        case XuPartition::sectors_bands: return "xu-2x4";
        }
        return "";
    }

    void effective_brdf(int level, int x, int y, const BaseBrdf& brdf, std::span<const Vec3> directions,
                        std::span<float> out) const override
    {
        check_output(directions, out);
        std::vector<VmfLobe> lobes;
        xu_lobes(texel(level, x, y), lobes);
        mixture_effective_brdf(lobes, brdf, directions, out);  // eq. 15
    }

private:
    XuPartition partition_;
};

}  // namespace

int xu_cell_count(XuPartition partition)
{
    switch (partition) {
    case XuPartition::whole: return 1;
    case XuPartition::sectors: return kSectors;
    case XuPartition::sectors_bands: return 2 * kSectors;
    }
    return 1;
}

int xu_cell(XuPartition partition, const Vec3& n)
{
    switch (partition) {
    case XuPartition::whole: return 0;
    case XuPartition::sectors: return sector(n);
    case XuPartition::sectors_bands: return 2 * sector(n) + (n.z >= kXuPolarSplitCos ? 0 : 1);
    }
    return 0;
}

void xu_lobes(std::span<const float> cells, std::vector<VmfLobe>& out)
{
    out.clear();
    for (size_t j = 0; j + kXuFloatsPerCell <= cells.size(); j += kXuFloatsPerCell) {
        const float alpha = cells[j];
        if (!(alpha > 0.0f)) continue;
        const Vec3 r = Vec3{cells[j + 1], cells[j + 2], cells[j + 3]} / alpha;
        // eq. 8: μ = r/|r|, κ = (3|r| − |r|³)/(1 − |r|²), guarded at both ends.
        out.push_back({std::min(alpha, 1.0f), normalize_or(r, {0.0f, 0.0f, 1.0f}),
                       kappa_from_resultant(std::min(1.0, double(length(r))))});
    }
}

void xu_adaptive_leaves(std::span<const double> cells, std::vector<float>& out)
{
    constexpr int f = kXuFloatsPerCell;
    double whole[f] = {};
    double sectors[kSectors][f] = {};
    for (int s = 0; s < kSectors; ++s)
        for (int band = 0; band < 2; ++band)
            for (int k = 0; k < f; ++k) {
                sectors[s][k] += cells[size_t((2 * s + band) * f + k)];
                whole[k] += cells[size_t((2 * s + band) * f + k)];
            }
    // Algorithm 1 line 5: concentrated enough for one lobe.
    if (whole[0] > 0.0 && cell_length(whole) / whole[0] >= kXuSubdivideWhole) {
        append_cell(whole, out);
        return;
    }
    for (int s = 0; s < kSectors; ++s) {
        if (!(sectors[s][0] > 0.0)) continue;
        // Line 8: a sector whose normals still spread uses its two polar cells.
        if (cell_length(sectors[s]) / sectors[s][0] >= kXuSubdivideSector) {
            append_cell(sectors[s], out);
        } else {
            append_cell(cells.data() + size_t(2 * s * f), out);
            append_cell(cells.data() + size_t((2 * s + 1) * f), out);
        }
    }
}

LevelSize XuAdaptivePyramid::size(int level) const
{
    if (level < 0 || level >= level_count())
        throw Error(Status::invalid_argument, "level " + std::to_string(level) + " out of range");
    return levels_[size_t(level)].size;
}

std::span<const float> XuAdaptivePyramid::texel(int level, int x, int y) const
{
    const LevelSize s = size(level);
    if (x < 0 || y < 0 || x >= s.width || y >= s.height)
        throw Error(Status::invalid_argument, "texel (" + std::to_string(x) + ", " + std::to_string(y) +
                                                  ") outside level " + std::to_string(level));
    const Level& l = levels_[size_t(level)];
    const size_t i = size_t(y) * size_t(s.width) + size_t(x);
    return std::span<const float>(l.cells).subspan(l.begin[i], l.begin[i + 1] - l.begin[i]);
}

double XuAdaptivePyramid::mean_floats_per_texel() const
{
    double floats = 0.0, texels = 0.0;
    for (const Level& l : levels_) {
        floats += double(l.cells.size());
        texels += double(l.size.width) * l.size.height;
    }
    return floats / texels;
}

int XuAdaptivePyramid::floats_per_texel() const { return int(std::ceil(mean_floats_per_texel())); }

void XuAdaptivePyramid::effective_brdf(int level, int x, int y, const BaseBrdf& brdf,
                                       std::span<const Vec3> directions, std::span<float> out) const
{
    if (out.size() != directions.size())
        throw Error(Status::invalid_argument, "effective_brdf needs one output per direction");
    std::vector<VmfLobe> lobes;
    xu_lobes(texel(level, x, y), lobes);
    mixture_effective_brdf(lobes, brdf, directions, out);  // eq. 15 over the chosen cells
}

std::unique_ptr<NdfPyramid> make_xu_pyramid(const NormalMap& map, WrapMode wrap, XuPartition partition)
{
    return std::make_unique<XuPyramid>(map, wrap, partition);
}

std::unique_ptr<NdfPyramid> make_xu_adaptive_pyramid(const NormalMap& map, WrapMode wrap)
{
    check_normal_map(map);
    constexpr XuPartition finest = XuPartition::sectors_bands;
    const int floats = kXuFloatsPerCell * xu_cell_count(finest);
    auto pyramid = std::unique_ptr<XuAdaptivePyramid>(new XuAdaptivePyramid());
    for (int level = 0; level < level_count(map.width, map.height); ++level) {
        XuAdaptivePyramid::Level& out = pyramid->levels_.emplace_back();
        out.size = level_size(map.width, map.height, level);
        // The 2×4 cell sums of each texel, computed on the fly (never stored), then reduced to
        // the leaves the adaptive shader uses, row by row.
        std::vector<std::vector<float>> rows(size_t(out.size.height));
        std::vector<std::vector<uint32_t>> counts(size_t(out.size.height));
        const auto add = [&](int fx, int fy, double w, double* acc) {
            const Vec3& n = map.at(fx, fy);
            double* cell = acc + kXuFloatsPerCell * xu_cell(finest, n);
            cell[0] += w;
            cell[1] += w * n.x;
            cell[2] += w * n.y;
            cell[3] += w * n.z;
        };
        const auto emit = [&](int y, std::span<const double> row) {
            for (int x = 0; x < out.size.width; ++x) {
                const size_t before = rows[size_t(y)].size();
                xu_adaptive_leaves(row.subspan(size_t(x) * size_t(floats), size_t(floats)), rows[size_t(y)]);
                counts[size_t(y)].push_back(uint32_t(rows[size_t(y)].size() - before));
            }
        };
        separable_means(axis_footprints(map.width, level, wrap), axis_footprints(map.height, level, wrap), floats, add,
                        emit);
        out.begin.reserve(size_t(out.size.width) * size_t(out.size.height) + 1);
        out.begin.push_back(0);
        for (int y = 0; y < out.size.height; ++y) {
            for (uint32_t count : counts[size_t(y)]) out.begin.push_back(out.begin.back() + count);
            out.cells.insert(out.cells.end(), rows[size_t(y)].begin(), rows[size_t(y)].end());
        }
    }
    return pyramid;
}

}  // namespace ndfbake
