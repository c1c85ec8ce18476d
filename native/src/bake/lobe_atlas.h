// Every MIP level of one lobe slot side by side in one image (a MIP atlas), for renderers that
// cannot be given MIP levels of their own: a shader picks the level from the scene and samples it
// with four point lookups. Each level is framed by a one-texel border holding the texels the wrap
// mode puts there (the opposite edge for repeat, the edge itself for clamp), so that bilinear
// interpolation inside a level is exact up to its edges and never reads a neighbouring level.
#pragma once

#include <span>
#include <vector>

#include "pyramid/footprint.h"
#include "pyramid/lobe_pyramid.h"

namespace ndfbake {

struct AtlasLevel {
    int x = 0;           // the level's frame starts at column x, row y (top row 0);
    int y = 0;           // its texels at (x + 1, y + 1)
    int width = 0;       // the level's size, without the frame
    int height = 0;
};

// Level 0 on the left; levels 1, 2, … stacked top-down in one column to its right (1.5× the
// texels of level 0, plus the frames).
struct AtlasLayout {
    int width = 0;
    int height = 0;
    std::vector<AtlasLevel> levels;
};

AtlasLayout atlas_layout(std::span<const LevelSize> sizes);

// Copies one level (width × height × 4 floats, top row first) and its frame into `atlas`
// (layout.width × layout.height × 4 floats, top row first; texels outside every frame stay 0).
void place_atlas_level(const AtlasLayout& layout, int level, const float* rgba, WrapMode wrap,
                       std::span<float> atlas);

}  // namespace ndfbake
