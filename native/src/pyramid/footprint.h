// MIP levels and the fine texels each coarse texel covers, for any size and both edge modes.
#pragma once

#include <cstdint>
#include <vector>

#include "ndf/weighted_normal.h"
#include "normal_map.h"

namespace ndfbake {

enum class WrapMode {
    clamp,  // the image ends at its edges: edge texels cover fewer fine texels
    wrap,   // the image tiles: footprints continue across the edges
};

struct LevelSize {
    int width = 0;
    int height = 0;
    friend bool operator==(const LevelSize&, const LevelSize&) = default;
};

// 1 + ⌈log₂ max(w, h)⌉ levels, down to 1×1.
int level_count(int width, int height);
// Level L is ⌈w / 2^L⌉ × ⌈h / 2^L⌉ (at least 1): texel x covers fine columns [x·2^L, (x+1)·2^L),
// so every fine texel belongs to exactly one texel per level and a texel's children partition it.
LevelSize level_size(int width, int height, int level);

// The fine normals under texel (x, y) of `level`, with weights. Clamp mode drops columns and
// rows past the edge; wrap mode takes them modulo the size, and a footprint wider than the image
// covers each fine texel as many times as it repeats (as weight, not as copies).
void gather_footprint(const NormalMap& map, int level, int x, int y, WrapMode wrap,
                      std::vector<WeightedNormal>& out);

// The most distinct fine texels one texel of `level` covers: min(2^L, w) × min(2^L, h).
uint64_t largest_footprint(int width, int height, int level);

// Σ of the weights gather_footprint would return for texel (x, y), without gathering.
double footprint_weight(int width, int height, int level, int x, int y, WrapMode wrap);

// Keeps at most `cap` of the gathered samples (cap ≤ 0: all), spread over the whole footprint by a
// golden-ratio sequence: a plain stride would alias with periodic content (every 4th column of a
// 2-texel V-groove is the same facet).
void subsample_footprint(std::vector<WeightedNormal>& samples, int cap);

}  // namespace ndfbake
