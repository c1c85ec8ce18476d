#include "baselines/linear_pyramid.h"

#include <algorithm>
#include <string>

#include "baselines/footprint_means.h"
#include "error.h"

namespace ndfbake {

void check_normal_map(const NormalMap& map)
{
    if (map.width < 1 || map.height < 1 || map.normals.size() != size_t(map.width) * size_t(map.height))
        throw Error(Status::invalid_argument, "normal map must be non-empty with one normal per texel, got " +
                                                  std::to_string(map.width) + "x" + std::to_string(map.height) +
                                                  " with " + std::to_string(map.normals.size()) + " normals");
}

LinearNdfPyramid::LinearNdfPyramid(const NormalMap& map, WrapMode wrap, int floats, const Features& features)
    : floats_(floats)
{
    check_normal_map(map);
    const int levels = ndfbake::level_count(map.width, map.height);
    const size_t stride = size_t(floats);
    for (int level = 0; level < levels; ++level) sizes_.push_back(level_size(map.width, map.height, level));

    levels_.resize(size_t(levels));
    std::vector<float>& fine = levels_[0];
    fine.resize(map.normals.size() * stride);
    for (size_t i = 0; i < map.normals.size(); ++i) features(map.normals[i], fine.data() + i * stride);

    for (int level = 1; level < levels; ++level) {
        std::vector<float>& coarse = levels_[size_t(level)];
        const LevelSize s = sizes_[size_t(level)];
        coarse.resize(size_t(s.width) * size_t(s.height) * stride);
        const auto emit = [&](int y, std::span<const double> row) {
            std::transform(row.begin(), row.end(), coarse.begin() + std::ptrdiff_t(size_t(y) * size_t(s.width) * stride),
                           [](double v) { return float(v); });
        };
        // φ is linear in the samples: a level is the weighted mean of the level below where the
        // footprints nest, and of the stored level-0 features elsewhere.
        const auto column_children = child_footprints(map.width, level, wrap);
        const auto row_children = child_footprints(map.height, level, wrap);
        const bool nested = column_children && row_children;
        const std::vector<float>& source = nested ? levels_[size_t(level) - 1] : fine;
        const size_t source_width = size_t(nested ? sizes_[size_t(level) - 1].width : map.width);
        const auto add = [&](int sx, int sy, double w, double* acc) {
            const float* f = source.data() + (size_t(sy) * source_width + size_t(sx)) * stride;
            for (size_t k = 0; k < stride; ++k) acc[k] += w * double(f[k]);
        };
        if (nested)
            separable_means(*column_children, *row_children, floats, add, emit);
        else
            separable_means(axis_footprints(map.width, level, wrap), axis_footprints(map.height, level, wrap), floats,
                            add, emit);
    }
}

LevelSize LinearNdfPyramid::size(int level) const
{
    if (level < 0 || level >= level_count())
        throw Error(Status::invalid_argument, "level " + std::to_string(level) + " out of range");
    return sizes_[size_t(level)];
}

std::span<const float> LinearNdfPyramid::texel(int level, int x, int y) const
{
    const LevelSize s = size(level);
    if (x < 0 || y < 0 || x >= s.width || y >= s.height)
        throw Error(Status::invalid_argument, "texel (" + std::to_string(x) + ", " + std::to_string(y) +
                                                  ") outside level " + std::to_string(level));
    const size_t stride = size_t(floats_);
    return std::span<const float>(levels_[size_t(level)]).subspan((size_t(y) * size_t(s.width) + size_t(x)) * stride,
                                                                  stride);
}

void LinearNdfPyramid::check_output(std::span<const Vec3> directions, std::span<float> out)
{
    if (out.size() != directions.size())
        throw Error(Status::invalid_argument, "effective_brdf needs one output per direction");
}

}  // namespace ndfbake
