#include "bake/lobe_atlas.h"

#include <algorithm>
#include <cstddef>

namespace ndfbake {

AtlasLayout atlas_layout(std::span<const LevelSize> sizes)
{
    AtlasLayout layout;
    if (sizes.empty()) return layout;
    layout.levels.push_back({0, 0, sizes[0].width, sizes[0].height});
    layout.width = sizes[0].width + 2;
    layout.height = sizes[0].height + 2;
    const int column = layout.width;
    int row = 0, column_width = 0;
    for (size_t l = 1; l < sizes.size(); ++l) {
        layout.levels.push_back({column, row, sizes[l].width, sizes[l].height});
        row += sizes[l].height + 2;
        column_width = std::max(column_width, sizes[l].width + 2);
    }
    layout.width += column_width;
    layout.height = std::max(layout.height, row);
    return layout;
}

namespace {

// The level texel a frame position −1..n shows: the opposite edge (repeat) or the edge (clamp).
int framed(int i, int n, WrapMode wrap)
{
    if (wrap == WrapMode::wrap) return (i + n) % n;
    return std::clamp(i, 0, n - 1);
}

}  // namespace

void place_atlas_level(const AtlasLayout& layout, int level, const float* rgba, WrapMode wrap, std::span<float> atlas)
{
    const AtlasLevel& place = layout.levels[size_t(level)];
    for (int y = -1; y <= place.height; ++y) {
        const int source_row = framed(y, place.height, wrap);
        for (int x = -1; x <= place.width; ++x) {
            const int source_column = framed(x, place.width, wrap);
            const float* from = rgba + (size_t(source_row) * size_t(place.width) + size_t(source_column)) * 4;
            float* to = atlas.data() + (size_t(place.y + 1 + y) * size_t(layout.width) + size_t(place.x + 1 + x)) * 4;
            std::copy(from, from + 4, to);
        }
    }
}

}  // namespace ndfbake
